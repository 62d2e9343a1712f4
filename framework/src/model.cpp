// ArticulatedModel: the mesh, posing, K(H) and rotational symmetry.
#include "gtrack/model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "gtrack/error.hpp"

namespace gtrack {

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;

void add_triangle(std::vector<ModelVertex>& m, ModelVertex a, ModelVertex b, ModelVertex c) {
  m.push_back(a);
  m.push_back(b);
  m.push_back(c);
}
}  // namespace

Eigen::Matrix3d rotation_from_euler_deg(double rx, double ry, double rz) {
  return (Eigen::AngleAxisd(rz * kDeg, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(ry * kDeg, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rx * kDeg, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d euler_deg_from_rotation(const Eigen::Matrix3d& r) {
  // R = Rz Ry Rx: r(2,0) = -sin(ry).
  const double sy = std::clamp(-r(2, 0), -1.0, 1.0);
  const double ry = std::asin(sy);
  double rx, rz;
  if (std::abs(sy) < 1.0 - 1e-9) {
    rx = std::atan2(r(2, 1), r(2, 2));
    rz = std::atan2(r(1, 0), r(0, 0));
  } else {  // gimbal lock: put everything in rz
    rx = 0;
    rz = std::atan2(-r(0, 1), r(1, 1));
  }
  return Eigen::Vector3d(rx, ry, rz) / kDeg;
}

Eigen::VectorXd tilt_turned(const Eigen::VectorXd& h, double deg) {
  const double c = std::cos(deg * kDeg), s = std::sin(deg * kDeg);
  Eigen::VectorXd t = h;
  t[3] = c * h[3] - s * h[4];
  t[4] = s * h[3] + c * h[4];
  return t;
}

// The convex hull of points, counter-clockwise (Andrew's monotone chain).
std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> hull(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  hull.resize(k > 1 ? k - 1 : k);
  return hull;
}

// Twice the signed area of a closed polygon (the shoelace sum): positive
// when its points run counter-clockwise.
double twice_area(const std::vector<Eigen::Vector2d>& polygon) {
  double a = 0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d &p = polygon[i], &q = polygon[(i + 1) % polygon.size()];
    a += p.x() * q.y() - p.y() * q.x();
  }
  return a;
}

double distance_to_outline(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& polygon) {
  double d = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < polygon.size(); ++k) {
    const Eigen::Vector2d a = polygon[k], e = polygon[(k + 1) % polygon.size()] - a;
    const double t = e.squaredNorm() > 0 ? std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0) : 0.0;
    d = std::min(d, (a + t * e - p).norm());
  }
  return d;
}

std::string palm_shape_mismatch(const std::vector<Eigen::Vector2d>& points) {
  // Counter-clockwise and convex: every point within 2 % of the palm's size,
  // or 10 um, of its convex hull's outline (coordinates of a round palm
  // rounded to 0.01 mm lie a little inside), and the outline going once
  // around (a polygon that crosses itself turns more than once). A point
  // repeated in a row is one point.
  std::vector<Eigen::Vector2d> palm;
  for (const auto& p : points) {
    if (palm.empty() || (p - palm.back()).norm() > 1e-12) palm.push_back(p);
  }
  while (palm.size() > 1 && (palm.front() - palm.back()).norm() <= 1e-12) palm.pop_back();
  const size_t n = palm.size();
  const double area = twice_area(palm);
  double size = 0;
  for (const auto& p : palm) size = std::max(size, p.norm());
  if (n < 3 || !(area > 0)) {
    return area < 0 ? "the palm polygon's points run clockwise; expected them counter-clockwise, around a convex polygon"
                    : "the palm polygon has no area; expected a convex polygon, its points counter-clockwise";
  }
  const std::vector<Eigen::Vector2d> hull = convex_hull(palm);
  for (size_t i = 0; i < points.size(); ++i) {
    const double inside = distance_to_outline(points[i], hull);
    if (inside > std::max(0.02 * size, 0.01)) {
      char dent[64];
      std::snprintf(dent, sizeof dent, "%.3g mm", inside);
      return "the palm polygon is not convex: point " + std::to_string(i + 1) + " lies " + dent +
             " inside its convex outline; expected a convex polygon, its points counter-clockwise";
    }
  }
  double turned = 0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d in = palm[i] - palm[(i + n - 1) % n], out = palm[(i + 1) % n] - palm[i];
    turned += std::atan2(in.x() * out.y() - in.y() * out.x(), in.dot(out));
  }
  // Once around, in the hull's order: a polygon that crosses itself turns
  // other than once around (a bowtie not at all, a pentagram twice), or
  // covers less than its hull.
  if (std::abs(turned - 2 * std::numbers::pi) > 1e-6 || area < 0.9 * twice_area(hull)) {
    return "the palm polygon crosses itself (its outline does not go once around, in order); expected a convex "
           "polygon, its points counter-clockwise";
  }
  return "";
}

std::string symmetry_mismatch(const GripperGeometry& G, std::vector<int>* finger_shift) {
  const int F = static_cast<int>(G.fingers.size());
  std::vector<int> shift(F);
  for (int f = 0; f < F; ++f) shift[f] = f;
  if (finger_shift) *finger_shift = shift;
  if (G.symmetry_order <= 1) return "";
  // Positions agree to 2 % of the palm's size, and to 10 um at least
  // (hand-typed coordinates of a regular shape, rounded to 0.01 mm),
  // directions to 1 degree, links to 2 % of their size.
  double size = 0;
  for (const auto& p : G.palm_mm) size = std::max(size, p.norm());
  for (const auto& f : G.fingers) size = std::max(size, f.base_mm.norm());
  const double tol = std::max(0.02 * size, 0.01);
  const double step = 360.0 / G.symmetry_order;
  const double c = std::cos(step * kDeg), sn = std::sin(step * kDeg);
  const auto turned = [&](const Eigen::Vector2d& p) { return Eigen::Vector2d(c * p.x() - sn * p.y(), sn * p.x() + c * p.y()); };
  const auto shown = [](double v) { return std::abs(v) < 1e-9 ? 0.0 : v; };  // no -0 or 3.7e-17
  const auto point = [&](const Eigen::Vector2d& p) {
    char text[64];
    std::snprintf(text, sizeof text, "[%.4g, %.4g]", shown(p.x()), shown(p.y()));
    return std::string(text);
  };
  const auto close = [](double a, double b) { return std::abs(a - b) <= 0.02 * std::max(std::abs(a), std::abs(b)) + 1e-6; };
  const auto same_links = [&](const FingerShape& a, const FingerShape& b) {
    if (a.links.size() != b.links.size()) return false;
    for (size_t j = 0; j < a.links.size(); ++j) {
      if (!close(a.links[j].length_mm, b.links[j].length_mm) || !close(a.links[j].width_start_mm, b.links[j].width_start_mm) ||
          !close(a.links[j].width_end_mm, b.links[j].width_end_mm)) {
        return false;
      }
    }
    return true;
  };
  char turn[48];
  std::snprintf(turn, sizeof turn, "a turn by %g deg", step);
  const std::string head = std::string(turn) + " takes ";
  const std::string tail = "; expected the number of turns that map the palm and every finger onto themselves (1 for none)";
  // The palm: each turned point on the palm's outline (a round palm's
  // points need not land on points).
  const size_t n = G.palm_mm.size();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d p = turned(G.palm_mm[i]);
    const double off = distance_to_outline(p, G.palm_mm);
    if (off > tol) {
      char by[48];
      std::snprintf(by, sizeof by, ", %.3g mm off the palm's outline", off);
      return head + "palm point " + std::to_string(i + 1) + " " + point(G.palm_mm[i]) + " to " + point(p) + by + tail;
    }
  }
  // Finger f lands on finger shift[f]: its hinge, direction and links. A
  // finger that lands on none is named with the one nearest its hinge.
  std::vector<bool> taken(F, false);
  for (int f = 0; f < F; ++f) {
    const FingerShape& a = G.fingers[f];
    const Eigen::Vector2d base = turned(a.base_mm);
    const double direction = a.direction_deg + step;
    const auto hinge_apart = [&](int g) { return (G.fingers[g].base_mm - base).norm(); };
    const auto turned_apart = [&](int g) { return std::abs(std::remainder(direction - G.fingers[g].direction_deg, 360.0)); };
    // The finger it lands on: at the turned hinge, in the turned direction,
    // with the same links, not yet landed on.
    const auto lands_on = [&](int g) {
      return !taken[g] && hinge_apart(g) <= tol && turned_apart(g) <= 1.0 && same_links(a, G.fingers[g]);
    };
    int target = -1;
    for (int g = 0; g < F && target < 0; ++g) {
      if (lands_on(g)) target = g;
    }
    if (target < 0) {
      // Why not, said of the finger nearest the turned hinge.
      int nearest = 0;
      for (int g = 1; g < F; ++g) {
        if (hinge_apart(g) < hinge_apart(nearest)) nearest = g;
      }
      const FingerShape& b = G.fingers[nearest];
      std::string why;
      if (hinge_apart(nearest) > tol) {
        why = "'s hinge to " + point(base) + ", where no finger has its hinge (nearest: finger " +
              std::to_string(nearest + 1) + " at " + point(b.base_mm) + ")";
      } else if (turned_apart(nearest) > 1.0) {
        char text[128];
        std::snprintf(text, sizeof text, "'s direction to %g deg, where finger %d at its hinge points to %g deg",
                      shown(std::remainder(direction, 360.0)), nearest + 1, b.direction_deg);
        why = text;
      } else if (!same_links(a, b)) {
        why = " onto finger " + std::to_string(nearest + 1) + ", whose links differ";
      } else {
        why = " onto finger " + std::to_string(nearest + 1) + ", where another finger lands as well";
      }
      return head + "finger " + std::to_string(f + 1) + why + tail;
    }
    taken[target] = true;
    shift[f] = target;
  }
  if (finger_shift) *finger_shift = shift;
  return "";
}

ArticulatedModel::ArticulatedModel(GripperGeometry g) : geometry_(std::move(g)) {
  const auto& G = geometry_;
  if (G.palm_mm.size() < 3) throw Error("gripper '" + G.name + "': the palm polygon needs at least 3 points");
  if (const std::string bent = palm_shape_mismatch(G.palm_mm); !bent.empty()) {
    throw Error("gripper '" + G.name + "': " + bent);
  }
  if (G.fingers.empty()) throw Error("gripper '" + G.name + "': it has no fingers");
  if (!(G.joint_min_deg < G.joint_max_deg)) throw Error("gripper '" + G.name + "': joint_min must be below joint_max");
  if (G.symmetry_order < 1) throw Error("gripper '" + G.name + "': symmetry order must be >= 1");
  for (size_t f = 0; f < G.fingers.size(); ++f) {
    if (G.fingers[f].links.empty()) throw Error("gripper '" + G.name + "': finger " + std::to_string(f + 1) + " has no links");
    for (size_t k = 0; k < G.fingers[f].links.size(); ++k) {
      const auto& l = G.fingers[f].links[k];
      const std::string link = "gripper '" + G.name + "': finger " + std::to_string(f + 1) + ", link " +
                               std::to_string(k + 1) + ": ";
      if (!(l.length_mm > 0) || !std::isfinite(l.length_mm)) {
        throw Error(link + "length " + fmt::format("{}", l.length_mm) + " mm; expected a positive finite number");
      }
      if (!(l.width_start_mm >= 0) || !(l.width_end_mm >= 0) || !std::isfinite(l.width_start_mm) ||
          !std::isfinite(l.width_end_mm) || (l.width_start_mm <= 0 && l.width_end_mm <= 0)) {
        throw Error(link + "widths " + fmt::format("{} and {}", l.width_start_mm, l.width_end_mm) +
                    " mm; expected finite numbers, neither negative nor both 0");
      }
    }
  }
  for (auto [a, b] : G.collision.adjacent) {
    if (a < 0 || b < 0 || a >= fingers() || b >= fingers()) {
      throw Error(fmt::format("gripper '{}': the adjacent pair ({}, {}) names a finger that does not exist; expected "
                              "finger indices 0 to {} (CollisionRule::adjacent counts from 0)",
                              G.name, a, b, fingers() - 1));
    }
    if (a == b) throw Error("gripper '" + G.name + "': a finger cannot be adjacent to itself");
  }
  // What a compiled gripper is held to as a model file is (data_defined):
  // each finger's first hinge on the palm's outline (a finger elsewhere
  // is drawn floating beside the palm, or out of its middle), and the
  // reference folds within the joint limits.
  double palm_radius = 0;
  for (const auto& p : G.palm_mm) palm_radius = std::max(palm_radius, p.norm());
  for (size_t f = 0; f < G.fingers.size(); ++f) {
    const Eigen::Vector2d& base = G.fingers[f].base_mm;
    const double off = distance_to_outline(base, G.palm_mm);
    if (!(off <= 0.05 * palm_radius)) {
      throw Error(fmt::format("gripper '{}': finger {}'s base [{:g}, {:g}] is {:.3g} mm off the palm's outline; "
                              "expected its first hinge on it",
                              G.name, f + 1, base.x(), base.y(), off));
    }
  }
  for (const auto& [name, q] : {std::pair<const char*, double>{"unfolded_deg", G.unfolded_deg}, {"folded_deg", G.folded_deg}}) {
    if (!(q >= G.joint_min_deg && q <= G.joint_max_deg)) {
      throw Error(fmt::format("gripper '{}': {} is {:g}, outside the joint limits [{:g}, {:g}]; expected a fold the "
                              "joints can take",
                              G.name, name, q, G.joint_min_deg, G.joint_max_deg));
    }
  }
  int links = 0;
  double extent = 0;
  for (const auto& F : G.fingers) {
    links += static_cast<int>(F.links.size());
    for (const auto& l : F.links) extent = std::max({extent, l.width_start_mm, l.width_end_mm});
  }
  extent = std::max(extent, radius_mm());  // the palm and the fingertips, stretched out
  if (links > kMaxLinks) {
    throw Error("gripper '" + G.name + "': " + std::to_string(links) + " links over its " +
                std::to_string(fingers()) + " fingers; at most " + std::to_string(kMaxLinks) + " are supported");
  }
  if (!(extent <= kMaxSizeMm)) {
    char text[160];
    std::snprintf(text, sizeof text, "a part is %g mm long or away from the palm centre; at most %g mm is supported",
                  extent, kMaxSizeMm);
    throw Error("gripper '" + G.name + "': " + text);
  }

  // Palm: a fan over the convex polygon.
  for (size_t i = 1; i + 1 < G.palm_mm.size(); ++i) {
    auto pv = [](const Eigen::Vector2d& p) { return ModelVertex{float(p.x()), float(p.y()), -1, 0}; };
    add_triangle(mesh_, pv(G.palm_mm[0]), pv(G.palm_mm[i]), pv(G.palm_mm[i + 1]));
  }
  // Links: a trapezoid is two triangles, a pointed link one.
  for (int f = 0; f < fingers(); ++f) {
    const auto& links = G.fingers[f].links;
    for (int j = 0; j < static_cast<int>(links.size()); ++j) {
      const auto& l = links[j];
      const float L = float(l.length_mm), w0 = float(l.width_start_mm / 2), w1 = float(l.width_end_mm / 2);
      ModelVertex p0{0, -w0, f, j}, p1{L, -w1, f, j}, p2{L, w1, f, j}, p3{0, w0, f, j};
      if (w1 <= 0) {
        add_triangle(mesh_, p0, ModelVertex{L, 0, f, j}, p3);
      } else if (w0 <= 0) {
        add_triangle(mesh_, ModelVertex{0, 0, f, j}, p1, p2);
      } else {
        add_triangle(mesh_, p0, p1, p2);
        add_triangle(mesh_, p0, p2, p3);
      }
    }
  }

  const std::string broken = symmetry_mismatch(G, &finger_shift_);
  if (!broken.empty()) {
    throw Error("gripper '" + G.name + "': symmetry order " + std::to_string(G.symmetry_order) + " does not hold: " + broken);
  }
}

int ArticulatedModel::max_links() const {
  size_t m = 0;
  for (const auto& f : geometry_.fingers) m = std::max(m, f.links.size());
  return static_cast<int>(m);
}

void ArticulatedModel::pose_model(std::span<const double> joints, std::vector<Eigen::Vector3d>& out) const {
  const auto& G = geometry_;
  // Hinge points and link angles per finger, once per call.
  struct Link {
    double hr, hz, c, s;
  };
  thread_local std::vector<Link> links;
  thread_local std::vector<int> first;
  links.clear();
  first.assign(G.fingers.size() + 1, 0);
  for (size_t f = 0; f < G.fingers.size(); ++f) {
    first[f] = static_cast<int>(links.size());
    const double q = joints[f] * kDeg;
    double hr = 0, hz = 0;
    for (size_t j = 0; j < G.fingers[f].links.size(); ++j) {
      const double th = double(j + 1) * q;
      const double c = std::cos(th), s = std::sin(th);
      links.push_back({hr, hz, c, s});
      hr += G.fingers[f].links[j].length_mm * c;
      hz += G.fingers[f].links[j].length_mm * s;
    }
  }
  out.resize(mesh_.size());
  for (size_t i = 0; i < mesh_.size(); ++i) {
    const ModelVertex& v = mesh_[i];
    if (v.finger < 0) {
      out[i] = Eigen::Vector3d(v.a, v.b, 0);
      continue;
    }
    const FingerShape& F = G.fingers[v.finger];
    const Link& L = links[first[v.finger] + v.link];
    const double phi = F.direction_deg * kDeg;
    const Eigen::Vector2d d(std::cos(phi), std::sin(phi)), l(-std::sin(phi), std::cos(phi));
    const double r = L.hr + v.a * L.c, z = L.hz + v.a * L.s;
    const Eigen::Vector2d p = F.base_mm + r * d + double(v.b) * l;
    out[i] = Eigen::Vector3d(p.x(), p.y(), z);
  }
}

void ArticulatedModel::pose(const Eigen::Ref<const Eigen::VectorXd>& h, std::vector<Eigen::Vector3d>& out) const {
  pose_model(std::span<const double>(h.data() + kPoseDims, fingers()), out);
  const Eigen::Matrix3d R = rotation_from_euler_deg(h[3], h[4], h[5]);
  const Eigen::Vector3d t(h[0], h[1], h[2]);
  for (auto& p : out) p = R * p + t;
}

std::vector<Eigen::Vector3d> ArticulatedModel::link_endpoints(const Eigen::Ref<const Eigen::VectorXd>& h) const {
  const Eigen::Matrix3d R = rotation_from_euler_deg(h[3], h[4], h[5]);
  const Eigen::Vector3d t(h[0], h[1], h[2]);
  std::vector<Eigen::Vector3d> out;
  for (int f = 0; f < fingers(); ++f) {
    const FingerShape& F = geometry_.fingers[f];
    const double q = h[kPoseDims + f] * kDeg, phi = F.direction_deg * kDeg;
    const Eigen::Vector2d d(std::cos(phi), std::sin(phi));
    double hr = 0, hz = 0;
    for (size_t j = 0; j < F.links.size(); ++j) {
      hr += F.links[j].length_mm * std::cos(double(j + 1) * q);
      hz += F.links[j].length_mm * std::sin(double(j + 1) * q);
      const Eigen::Vector2d p = F.base_mm + hr * d;
      out.push_back(R * Eigen::Vector3d(p.x(), p.y(), hz) + t);
    }
  }
  return out;
}

std::vector<Eigen::Vector3d> ArticulatedModel::fingertips(const Eigen::Ref<const Eigen::VectorXd>& h) const {
  auto ends = link_endpoints(h);
  std::vector<Eigen::Vector3d> tips;
  size_t k = 0;
  for (const auto& F : geometry_.fingers) {
    k += F.links.size();
    tips.push_back(ends[k - 1]);
  }
  return tips;
}

double ArticulatedModel::kinematic_penalty(std::span<const double> q) const {
  const auto& G = geometry_;
  const double span = std::max(1e-9, G.joint_max_deg - G.joint_min_deg);
  double k = 0;
  for (int f = 0; f < fingers(); ++f) {
    k += std::max(0.0, G.joint_min_deg - q[f]) / span + std::max(0.0, q[f] - G.joint_max_deg) / span;
  }
  for (auto [a, b] : G.collision.adjacent) {
    k += std::max(0.0, std::abs(q[a] - q[b]) - G.collision.max_difference_deg) / span;
    k += std::max(0.0, q[a] + q[b] - G.collision.max_sum_deg) / span;
  }
  return k;
}

Eigen::VectorXd ArticulatedModel::symmetric_equivalent(const Eigen::Ref<const Eigen::VectorXd>& h, int k) const {
  const int order = geometry_.symmetry_order;
  k = ((k % order) + order) % order;
  Eigen::VectorXd out = h;
  if (k == 0) return out;
  // Turning the model by alpha = k*360/order about its Z maps it onto itself
  // with finger f moved to slot shift^k(f): R*M(q) = R*Rz(-alpha)*M(q') with
  // q'[shift^k(f)] = q[f].
  const double alpha = k * 360.0 / order;
  const Eigen::Matrix3d R = rotation_from_euler_deg(h[3], h[4], h[5]) *
                            rotation_from_euler_deg(0, 0, -alpha);
  out.segment<3>(3) = euler_deg_from_rotation(R);
  for (int f = 0; f < fingers(); ++f) {
    int g = f;
    for (int i = 0; i < k; ++i) g = finger_shift_[g];
    out[kPoseDims + g] = h[kPoseDims + f];
  }
  return out;
}

double ArticulatedModel::radius_mm() const {
  double r = 0;
  for (const auto& p : geometry_.palm_mm) r = std::max(r, p.norm());
  for (const auto& F : geometry_.fingers) {
    double len = 0;
    for (const auto& l : F.links) len += l.length_mm;
    r = std::max(r, F.base_mm.norm() + len);
  }
  return r;
}

std::vector<std::pair<int, int>> ring_adjacency(int fingers) {
  if (fingers < 3) return fingers == 2 ? std::vector<std::pair<int, int>>{{0, 1}} : std::vector<std::pair<int, int>>{};
  std::vector<std::pair<int, int>> pairs;
  for (int f = 0; f < fingers; ++f) pairs.emplace_back(f, (f + 1) % fingers);
  return pairs;
}

GripperGeometry make_radial_gripper(const RadialGripperSpec& s) {
  if (s.fingers < 1) throw Error("gripper '" + s.name + "': " + std::to_string(s.fingers) + " fingers; expected 1 or more");
  if (s.palm_sides < 3 || s.palm_sides % s.fingers != 0) {
    throw Error("gripper '" + s.name + "': palm_sides must be >= 3 and a multiple of the number of fingers");
  }
  GripperGeometry g;
  g.name = s.name;
  const double phase = s.finger_phase_deg * kDeg;
  const double half = std::numbers::pi / s.palm_sides;  // edge k is centred at angle phase + 2k*half
  for (int i = 0; i < s.palm_sides; ++i) {
    const double a = phase + (2 * i - 1) * half;
    g.palm_mm.emplace_back(s.palm_circumradius_mm * std::cos(a), s.palm_circumradius_mm * std::sin(a));
  }
  const double apothem = s.palm_circumradius_mm * std::cos(half);
  const int every = s.palm_sides / s.fingers;
  for (int f = 0; f < s.fingers; ++f) {
    const double dir = phase + 2 * half * f * every;
    FingerShape F;
    F.direction_deg = dir / kDeg;
    F.base_mm = apothem * Eigen::Vector2d(std::cos(dir), std::sin(dir));
    F.links = s.links;
    g.fingers.push_back(F);
  }
  g.collision.adjacent = ring_adjacency(s.fingers);
  g.symmetry_order = s.fingers;
  return g;
}

}  // namespace gtrack
