// Grid of hypotheses at the observation's centroid (and at its largest blob's,
// when that is apart), each also tried with its own outline centred there;
// then a PSO per candidate.
#include "coarse_search.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <numbers>
#include <numeric>
#include <optional>
#include <utility>
#include <opencv2/imgproc.hpp>

#include "gtrack/log.hpp"
#include "render/clip.hpp"

namespace gtrack::detail {

namespace {

constexpr double kBackwardFoldDeg = 10.0;
constexpr double kBorderStepRadii = 0.3;  // the coarse grid's step out across a border
// O's blobs the coarse grid is also placed on, the largest first, each
// after it of at least this share of the area of a disc of the model's
// radius.
constexpr int kBlobsTried = 3;
constexpr double kBlobShare = 0.05;

struct OutlineScratch {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<ScreenPolygon> polygons;
  bool cut = false;  // the last outline crossed the image's border
};

// The renderers' frustum for `projection`, but bounded by the image itself
// instead of a guard band around it.
render::Frustum image_frustum(const Projection& projection) {
  render::Frustum image = render::frustum_of(projection);
  image.u_lo = 0;
  image.u_hi = projection.size.width;
  image.v_lo = 0;
  image.v_hi = projection.size.height;
  return image;
}

// Where the visible part of hypothesis h's outline is centred, in render
// pixels: the centroid of its mesh's projected triangles, clipped as the
// renderers clip them (render::clip_triangle: the sensor's clip planes) but
// to `image` (image_frustum), and weighted by their area. Surfaces facing
// the camera and facing away both count, and so do overlaps, twice: close
// enough to place a grid point, and no image is rendered or read back. None
// when nothing is in view.
std::optional<Eigen::Vector2d> outline_centroid(const ArticulatedModel& model, const Projection& projection,
                                                const render::Frustum& image,
                                                const Eigen::Ref<const Eigen::VectorXd>& h, OutlineScratch& scratch) {
  model.pose(h, scratch.vertices);
  const std::vector<Eigen::Vector3d>& x = scratch.vertices;
  scratch.polygons.clear();
  scratch.cut = false;
  for (size_t t = 0; t + 2 < x.size(); t += 3) {
    for (size_t k = t; k < t + 3; ++k) scratch.cut |= !image.contains(render::project(projection, x[k]));
    render::clip_triangle(x[t], x[t + 1], x[t + 2], projection, image, scratch.polygons);
  }
  Eigen::Vector2d sum(0, 0);
  double area = 0;
  for (const ScreenPolygon& q : scratch.polygons) {
    // A convex polygon: a fan of triangles from its first vertex.
    for (int k = 1; k + 1 < q.count; ++k) {
      const Eigen::Vector2d a = q.v[k] - q.v[0], b = q.v[k + 1] - q.v[0];
      const double w = 0.5 * std::abs(a.x() * b.y() - a.y() * b.x());
      sum += w * (q.v[0] + q.v[k] + q.v[k + 1]) / 3.0;
      area += w;
    }
  }
  if (area <= 0) return std::nullopt;
  return sum / area;
}

// The outward direction across the image's borders that `mask` touches,
// each border weighted by the mask's pixels on it; zero when it touches none.
Eigen::Vector2d border_outward(const cv::Mat& mask) {
  Eigen::Vector2d out(0, 0);
  out.y() -= cv::countNonZero(mask.row(0));
  out.y() += cv::countNonZero(mask.row(mask.rows - 1));
  out.x() -= cv::countNonZero(mask.col(0));
  out.x() += cv::countNonZero(mask.col(mask.cols - 1));
  return out.norm() > 0 ? Eigen::Vector2d(out.normalized()) : out;
}

// Scores `tried` in one batch, `per_point` columns for each column of
// `grid` in order; each grid point takes the lowest of its tried places
// where that scores below it.
void keep_better_places(Eigen::MatrixXd& grid, Eigen::VectorXd& scores, const Eigen::MatrixXd& tried, int per_point,
                        CostEvaluator& cost, std::uint64_t& evaluations) {
  Eigen::VectorXd tried_scores;
  cost.evaluate(tried, tried_scores);
  evaluations += static_cast<std::uint64_t>(tried.cols());
  for (Eigen::Index i = 0; i < grid.cols(); ++i) {
    for (int k = 0; k < per_point; ++k) {
      const Eigen::Index j = i * per_point + k;
      if (tried_scores[j] < scores[i]) {
        grid.col(i) = tried.col(j);
        scores[i] = tried_scores[j];
      }
    }
  }
}

}  // namespace

Eigen::Vector3d lift_pixel(const Projection& p, double u, double v, const Eigen::Vector3d& near) {
  // The pixel's line of sight is {X : (p1 - u p3).[X;1] = 0, (p2 - v p3).[X;1] = 0};
  // the minimum-norm correction from `near` onto it solves the 2x3 system.
  const Eigen::Matrix<double, 3, 4>& m = p.world_to_image;
  Eigen::Matrix<double, 2, 4> rows;
  rows.row(0) = m.row(0) - u * m.row(2);
  rows.row(1) = m.row(1) - v * m.row(2);
  const Eigen::Matrix<double, 2, 3> a = rows.leftCols<3>();
  const Eigen::Vector2d r = -(a * near + rows.col(3));
  const Eigen::Matrix2d aat = a * a.transpose();
  if (std::abs(aat.determinant()) < 1e-18) return near;
  return near + a.transpose() * aat.ldlt().solve(r);
}

// The centroids (pixel centres at +0.5) of a mask's 8-connected blobs, the
// largest first: at most `most`, each after the largest of `min_area` pixels
// or more; none for a mask of one blob or none.
std::vector<Eigen::Vector2d> blob_centres(const cv::Mat& mask, int most, double min_area) {
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  if (n <= 2) return {};  // the background and at most one blob
  std::vector<int> order(static_cast<size_t>(n - 1));
  std::iota(order.begin(), order.end(), 1);
  const auto area = [&](int i) { return stats.at<int>(i, cv::CC_STAT_AREA); };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return area(a) > area(b); });
  std::vector<Eigen::Vector2d> centres;
  for (int i : order) {
    if (static_cast<int>(centres.size()) == most || (!centres.empty() && area(i) < min_area)) break;
    centres.emplace_back(centroids.at<double>(i, 0) + 0.5, centroids.at<double>(i, 1) + 0.5);
  }
  return centres;
}

CoarseSearchResult coarse_search(const CoarseSearchInput& in, const EngineConfig& config, CostEvaluator& cost,
                                 std::mt19937_64& rng) {
  CoarseSearchResult result;
  const ArticulatedModel& model = *in.model;
  const int dims = config.space.dims();
  // The refinements may fold the fingers up to kBackwardFoldDeg the wrong
  // way (K(H) still charges for it). A nearly flat, strongly tilted gripper
  // is matched on both tilt branches, the mirror one by a slightly reversed
  // fold (the truth seen through a mirror in the image plane); kept to
  // forward folds, a refinement on that branch settles on a poor fit. The
  // result is brought back within the limits, and the tracker's mirror
  // check then refines the other branch.
  ParameterSpace space = config.space;
  space.lower.tail(dims - kPoseDims).array() -= kBackwardFoldDeg;

  const TrackerConfig& tc = config.tracker;
  const double period = 360.0 / std::max(1, model.geometry().symmetry_order);
  const int rz_steps = tc.coarse_rz_steps;
  const double tilt = 25.0;
  // Flat, then two rings of tilts: 25 deg towards 4 directions of the image
  // and 50 deg towards 8 (strongly tilted, folded grippers have compact
  // outlines that the first ring does not reach). Each tilt is combined with
  // every turn of the gripper about its own axis over one symmetry period:
  // R = Rz(a) Rx(theta) Rz(tau), a the tilt's direction in the image, tau the
  // turn. (A grid over the Euler angles' rz instead would turn a tilted
  // gripper about the optical axis, which is not a symmetry: it would reach
  // only a third of the tilted configurations.)
  struct Ring {
    double theta;
    int directions;
  };
  std::vector<Ring> rings = {{0.0, 1}, {tilt, 4}};
  if (tc.coarse_wide_tilts) rings.push_back({2 * tilt, 8});
  std::vector<Eigen::Vector3d> rotations;  // (rx, ry, rz), degrees
  for (const Ring& ring : rings) {
    for (int a = 0; a < ring.directions; ++a) {
      const double azimuth = 360.0 * a / ring.directions;
      for (int r = 0; r < rz_steps; ++r) {
        const double turn = period * r / rz_steps;
        const Eigen::Matrix3d R = rotation_from_euler_deg(0, 0, azimuth) * rotation_from_euler_deg(ring.theta, 0, 0) *
                                  rotation_from_euler_deg(0, 0, turn - azimuth);
        rotations.push_back(euler_deg_from_rotation(R));
      }
    }
  }
  std::vector<double> joints;
  for (int j = 0; j < 4; ++j) joints.push_back(in.joint_lo + (in.joint_hi - in.joint_lo) * j / 3.0);

  // The grid around the observed pixel (u, v), each point at its best place
  // (below), with the cost of each.
  const cv::Moments mo = cv::moments(*in.observation, true);
  const bool observed = mo.m00 > 0;
  // The model's radius in render pixels at a point.
  const auto radius_px_at = [&](const Eigen::Vector3d& point) {
    const Eigen::Vector3d aside = point + Eigen::Vector3d(model.radius_mm(), 0, 0);
    return (render::dehomogenise(render::project(in.render_projection, aside)) -
            render::dehomogenise(render::project(in.render_projection, point)))
        .norm();
  };
  const auto grid_at = [&](double u, double v) {
    Eigen::MatrixXd grid(dims, static_cast<Eigen::Index>(rotations.size() * joints.size()));
    const Eigen::Vector3d centre = lift_pixel(in.render_projection, u, v, in.nominal_mm);
    int col = 0;
    for (const Eigen::Vector3d& rotation : rotations) {
      for (double q : joints) {
        Eigen::VectorXd h(dims);
        h.head<3>() = centre;
        h.segment<3>(3) = rotation;
        h.tail(dims - kPoseDims).setConstant(q);
        space.clamp(h);
        grid.col(col++) = h;
      }
    }
    Eigen::VectorXd scores;
    cost.evaluate(grid, scores);
    result.evaluations += static_cast<std::uint64_t>(grid.cols());

    // The palm centre is not the outline's centroid: a tilted, folded
    // gripper's outline lies to one side of it, by up to a third of its size.
    // Every grid point is also tried moved so that its outline's centroid
    // falls on the observed one (one more batch), and keeps the better place.
    if (observed) {
      const render::Frustum image = image_frustum(in.render_projection);
      Eigen::MatrixXd centred = grid;
      OutlineScratch scratch;
      for (Eigen::Index i = 0; i < grid.cols(); ++i) {
        // Where the outline crosses the image's border, moving it changes its
        // visible part: then a second pass.
        for (int pass = 0; pass < 2; ++pass) {
          auto h = centred.col(i);
          const auto c = outline_centroid(model, in.render_projection, image, h, scratch);
          if (!c) break;
          const Eigen::Vector2d shift = Eigen::Vector2d(u, v) - *c;
          if (shift.norm() < 0.25) break;
          const Eigen::Vector2d target =
              render::dehomogenise(render::project(in.render_projection, h.head<3>())) + shift;
          h.head<3>() = lift_pixel(in.render_projection, target[0], target[1], centre);
          space.clamp(h);
          if (!scratch.cut) break;
        }
      }
      keep_better_places(grid, scores, centred, 1, cost, result.evaluations);

      // Coming into view (or leaving it), the gripper shows a sliver: the
      // centred grid point, which shows about half of its outline, covers far
      // more than O. Where O touches the image's border, each grid point is
      // also tried moved out across it by 1..n steps of 0.3 model radii, and
      // centred again along the border only (one more batch of n per point);
      // each point keeps its best place.
      const int steps = tc.coarse_border_steps;
      const Eigen::Vector2d outward = steps > 0 ? border_outward(*in.observation) : Eigen::Vector2d::Zero();
      if (outward.norm() > 0) {
        const Eigen::Vector2d along(-outward.y(), outward.x());
        const double step = kBorderStepRadii * radius_px_at(centre);
        Eigen::MatrixXd moved(dims, grid.cols() * steps);
        for (Eigen::Index i = 0; i < grid.cols(); ++i) {
          for (int k = 0; k < steps; ++k) {
            Eigen::VectorXd h = grid.col(i);
            Eigen::Vector2d p =
                render::dehomogenise(render::project(in.render_projection, h.head<3>())) + outward * step * (k + 1);
            h.head<3>() = lift_pixel(in.render_projection, p[0], p[1], h.head<3>());
            if (const auto c = outline_centroid(model, in.render_projection, image, h, scratch)) {
              p += along * (Eigen::Vector2d(u, v) - *c).dot(along);
              h.head<3>() = lift_pixel(in.render_projection, p[0], p[1], h.head<3>());
            }
            space.clamp(h);
            moved.col(i * steps + k) = h;
          }
        }
        keep_better_places(grid, scores, moved, steps, cost, result.evaluations);
      }
    }

    return std::make_pair(std::move(grid), std::move(scores));
  };
  // Around the centroid of O; and, when O holds blobs apart (the gripper
  // beside a bright reflector, a caliper mark or clutter that passes the
  // bounds), around its largest blobs too, each farther than the model's
  // radius from every place tried: the centroid of all of them can lie on
  // none, and the gripper need not be the largest (a tank's wall, a dish's
  // rim).
  const double u = observed ? mo.m10 / mo.m00 + 0.5 : in.observation->cols * 0.5;
  const double v = observed ? mo.m01 / mo.m00 + 0.5 : in.observation->rows * 0.5;
  auto [grid, scores] = grid_at(u, v);
  const double apart = radius_px_at(lift_pixel(in.render_projection, u, v, in.nominal_mm));
  std::vector<Eigen::Vector2d> tried{Eigen::Vector2d(u, v)};
  for (const Eigen::Vector2d& blob : blob_centres(*in.observation, kBlobsTried, kBlobShare * std::numbers::pi * apart * apart)) {
    if (std::any_of(tried.begin(), tried.end(), [&](const Eigen::Vector2d& t) { return (blob - t).norm() <= apart; })) {
      continue;
    }
    logger().debug("coarse search: also from a blob of O at ({:.0f}, {:.0f}) render pixels, {:.0f} from O's centroid",
                   blob.x(), blob.y(), (blob - tried.front()).norm());
    tried.push_back(blob);
    auto [more, more_scores] = grid_at(blob.x(), blob.y());
    grid.conservativeResize(Eigen::NoChange, grid.cols() + more.cols());
    grid.rightCols(more.cols()) = more;
    scores.conservativeResize(scores.size() + more_scores.size());
    scores.tail(more_scores.size()) = more_scores;
  }

  std::vector<int> order(static_cast<size_t>(grid.cols()));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return scores[a] < scores[b]; });

  // Wide spreads: the centroid of a partly hidden gripper is off by a fraction
  // of its size, and the grid's steps bound the angular error.
  const double radius = model.radius_mm();
  Eigen::VectorXd spread(dims);
  spread << 0.3 * radius, 0.3 * radius, tc.init_spread[2], tilt, tilt, 0.75 * period / rz_steps,
      Eigen::VectorXd::Constant(dims - kPoseDims, std::max(5.0, (in.joint_hi - in.joint_lo) / 3.0));
  ParticleSwarm pso(config.pso, space);
  pso.set_randomization_spread(spread);
  result.cost = std::numeric_limits<double>::infinity();
  const int candidates = std::min<int>(tc.coarse_candidates, static_cast<int>(order.size()));
  const BatchObjective objective = [&](const Eigen::MatrixXd& x, Eigen::VectorXd& c) { cost.evaluate(x, c); };
  for (int c = 0; c < candidates; ++c) {
    const Eigen::VectorXd start = grid.col(order[static_cast<size_t>(c)]);
    const Eigen::MatrixXd init = biased_initial_swarm(start, spread, 0.5, config.pso.particles, space, rng);
    const PsoResult r = pso.run(init, objective, rng);
    result.evaluations += r.evaluations;
    if (r.best_cost < result.cost) {
      result.cost = r.best_cost;
      result.best = r.best;
    }
  }
  if (result.best.size() == dims) {
    const Eigen::VectorXd found = result.best;
    config.space.clamp(result.best);
    if (result.best != found) {
      Eigen::VectorXd c;
      cost.evaluate(result.best, c);
      result.cost = c[0];
      result.evaluations += 1;
    }
  }
  return result;
}

}  // namespace gtrack::detail
