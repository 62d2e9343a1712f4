// Drawing one planned frame: background, gripper, occluder, degradations.
//
// The gripper is drawn on a canvas that extends one image size beyond every
// border, so that the share of its shape inside the view is measured, not
// guessed. Triangles are painted far to near with a shade from their normal
// (a matt object lit along the optical axis), supersampled 4x4 per pixel.
// The occluder's size is solved per frame by bisection so that it hides the
// planned share of the in-view shape; it never hides more than the preset's
// maximum.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "gtrack/renderer.hpp"
#include "gtrack/synth.hpp"
#include "synth/appearance.hpp"
#include "synth/coverage_raster.hpp"
#include "synth/hinge_pose.hpp"

namespace gtrack {

namespace {

using synth::SampleGrid;

constexpr int kSupersample = 4;
constexpr int kDriftMargin = 24;

struct ShadedPolygon {
  ScreenPolygon poly;
  std::uint8_t shade;
};

std::vector<ShadedPolygon> gripper_polygons(const ArticulatedModel& model, const SynthFrame& fr,
                                            const Projection& canvas) {
  std::vector<Eigen::Vector3d> tris;
  synth::pose_hinges(model, fr.truth, fr.hinge_deg, tris);
  const int n = static_cast<int>(tris.size() / 3);
  std::vector<double> depth(n);
  std::vector<int> order(n);
  const Eigen::RowVector4d w_row = canvas.world_to_image.row(2);
  for (int t = 0; t < n; ++t) {
    const Eigen::Vector3d c = (tris[3 * t] + tris[3 * t + 1] + tris[3 * t + 2]) / 3.0;
    depth[t] = w_row.head<3>().dot(c) + w_row[3];
  }
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return depth[a] > depth[b]; });
  const Eigen::Vector3d view = w_row.head<3>().transpose().normalized();

  std::vector<ShadedPolygon> out;
  std::vector<Eigen::Vector3d> one(3);
  std::vector<ScreenPolygon> polys;
  for (int t : order) {
    for (int k = 0; k < 3; ++k) one[k] = tris[3 * t + k];
    const Eigen::Vector3d nrm = (one[1] - one[0]).cross(one[2] - one[0]).normalized();
    const double shade = 0.68 + 0.32 * std::abs(nrm.dot(view));
    project_and_clip(one, canvas, polys);
    for (const auto& p : polys) out.push_back({p, static_cast<std::uint8_t>(std::lround(255 * shade))});
  }
  return out;
}

// The occluder's outline: a star-shaped blob, as a fan of triangles.
using Triangle2 = std::array<Eigen::Vector2d, 3>;

std::vector<Triangle2> blob(const Eigen::Vector2d& centre, double radius, double phase) {
  constexpr int kSides = 48;
  std::vector<Eigen::Vector2d> ring;
  for (int i = 0; i < kSides; ++i) {
    const double a = 2 * std::numbers::pi * i / kSides;
    const double r = radius * (1 + 0.22 * std::sin(2 * a + phase) + 0.12 * std::sin(3 * a + 1.7 * phase) +
                               0.06 * std::sin(5 * a + 2.3 * phase));
    ring.push_back(centre + r * Eigen::Vector2d(std::cos(a), std::sin(a)));
  }
  std::vector<Triangle2> fan;
  for (int i = 0; i < kSides; ++i) fan.push_back({centre, ring[i], ring[(i + 1) % kSides]});
  return fan;
}

cv::Mat blob_coverage(const std::vector<Triangle2>& fan, cv::Rect region, int ss) {
  SampleGrid g(region, ss);
  for (const auto& p : fan) g.fill_convex(p.data(), 3, 255);
  cv::Mat cov;
  g.resolve(cov);
  return cov;
}

std::uint64_t frame_seed(std::uint64_t seed, int index) {
  std::uint64_t x = seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(index) * 0xBF58476D1CE4E5B9ull + 1;
  x ^= x >> 31;
  return x * 0x94D049BB133111EBull;
}

}  // namespace

cv::Mat render_frame(const Setup& setup, const SynthPlan& plan, int index, SynthVisibility* visibility) {
  const SynthFrame& fr = plan.frames.at(index);
  const SynthPreset& p = plan.preset;
  const ArticulatedModel& model = setup.model();
  const Sensor& sensor = *setup.sensor;
  const ImageSize size = sensor.image_size();
  const int W = size.width, H = size.height, margin = std::max(W, H);

  // Background, drifting slowly as a stage would.
  auto bg = synth::tissue_background(plan.options.seed, p, {W, H}, kDriftMargin);
  const int dx = kDriftMargin + static_cast<int>(std::lround(0.8 * kDriftMargin * std::sin(0.31 * fr.time_s)));
  const int dy = kDriftMargin + static_cast<int>(std::lround(0.8 * kDriftMargin * std::cos(0.23 * fr.time_s + 1)));
  cv::Mat image = (*bg)(cv::Rect(dx, dy, W, H)).clone();

  // Gripper on the enlarged canvas.
  const Projection proj = sensor.projection();
  const Projection canvas = padded_projection(proj, margin, margin);
  const auto shaded = gripper_polygons(model, fr, canvas);
  std::vector<Eigen::Vector2d> all;
  for (const auto& s : shaded) all.insert(all.end(), s.poly.v, s.poly.v + s.poly.count);
  const cv::Rect canvas_rect(0, 0, canvas.size.width, canvas.size.height);
  const cv::Rect roi = synth::bounding_rect(all.data(), static_cast<int>(all.size())) & canvas_rect;
  const cv::Rect image_in_canvas(margin, margin, W, H);
  const cv::Rect inter = roi & image_in_canvas;

  SynthVisibility vis;
  cv::Mat alpha, shade;
  double full_area = 0, in_view_area = 0;
  if (roi.area() > 0) {
    SampleGrid grid(roi, kSupersample);
    for (const auto& s : shaded) grid.fill_convex(s.poly.v, s.poly.count, s.shade);
    grid.resolve(alpha, &shade);
    full_area = cv::sum(alpha)[0];
  }
  // The shares are of the gripper's whole shape: a slice's slab (its clip
  // planes) images only part of it, and what lies outside the slab is not
  // seen, as what lies outside the image is not.
  double whole_area = full_area;
  if (!canvas.clip_planes.empty()) {
    Projection unclipped = canvas;
    unclipped.clip_planes.clear();
    const auto whole = gripper_polygons(model, fr, unclipped);
    // Nothing cut (a camera's near plane, which never reaches the gripper;
    // a slice that holds all of it): the whole shape is the one drawn, and
    // is not drawn again.
    const auto same = [](const ShadedPolygon& a, const ShadedPolygon& b) {
      return a.poly.count == b.poly.count && std::equal(a.poly.v, a.poly.v + a.poly.count, b.poly.v);
    };
    if (!std::equal(whole.begin(), whole.end(), shaded.begin(), shaded.end(), same)) {
      std::vector<Eigen::Vector2d> corners;
      for (const auto& s : whole) corners.insert(corners.end(), s.poly.v, s.poly.v + s.poly.count);
      const cv::Rect box = synth::bounding_rect(corners.data(), static_cast<int>(corners.size())) & canvas_rect;
      if (box.area() > 0) {
        SampleGrid grid(box, kSupersample);
        for (const auto& s : whole) grid.fill_convex(s.poly.v, s.poly.count, 255);
        cv::Mat whole_alpha;
        grid.resolve(whole_alpha);
        whole_area = std::max(full_area, cv::sum(whole_alpha)[0]);
      }
    }
  }
  const cv::Rect in_roi = inter - roi.tl();
  const cv::Rect in_image = inter - image_in_canvas.tl();
  if (inter.area() > 0) {
    in_view_area = cv::sum(alpha(in_roi))[0];
    const cv::Vec3f colour = synth::bgr_from_hsv(p.gripper_hsv);
    cv::Mat a = alpha(in_roi), s = shade(in_roi) / 255.0f, a3, col;
    cv::merge(std::vector<cv::Mat>{a, a, a}, a3);
    cv::merge(std::vector<cv::Mat>{s * colour[0], s * colour[1], s * colour[2]}, col);
    cv::Mat dst = image(in_image);
    cv::Mat mixed = a3.mul(col) + (cv::Scalar::all(1.0) - a3).mul(dst);
    mixed.copyTo(dst);
  }
  if (whole_area > 0) vis.in_view = in_view_area / whole_area;

  // Occluder, sized to hide the planned share of what is in view.
  const OccluderPlan& occ = fr.occluder;
  double covered = 0;
  if (occ.active && occ.target > 0 && full_area > 0 && in_view_area > 0.05 * full_area) {
    const Eigen::Vector3d c = proj.world_to_image * fr.truth.head<3>().homogeneous();
    const double radius_px = model.radius_mm() / sensor.mm_per_pixel();
    const Eigen::Vector2d centre = c.head<2>() / c.z() + radius_px * occ.offset_px;
    const cv::Mat a_in = alpha(in_roi);
    auto share = [&](double scale) {
      // One sample per pixel is enough to size the blob; it is drawn at 4x4.
      const cv::Mat beta = blob_coverage(blob(centre, scale * radius_px, occ.shape_phase), in_image, 1);
      return cv::sum(a_in.mul(beta))[0] / in_view_area;
    };
    const double target = std::min(occ.target, p.max_occlusion);
    double lo = 0, hi = 3;
    for (int it = 0; it < 11; ++it) {
      const double mid = 0.5 * (lo + hi);
      (share(mid) <= target ? lo : hi) = mid;
    }
    const auto fan = blob(centre, lo * radius_px, occ.shape_phase);
    std::vector<Eigen::Vector2d> pts;
    for (const auto& f : fan) pts.insert(pts.end(), f.begin(), f.end());
    const cv::Rect box = synth::bounding_rect(pts.data(), static_cast<int>(pts.size())) & cv::Rect(0, 0, W, H);
    if (box.area() > 0) {
      cv::Mat beta = blob_coverage(fan, box, kSupersample), b3, col;
      cv::merge(std::vector<cv::Mat>{beta, beta, beta}, b3);
      if (occ.tissue_coloured) {
        // A flap of tissue: the same texture from elsewhere, a little lighter.
        const cv::Rect src(kDriftMargin * 2 - dx, kDriftMargin * 2 - dy, W, H);
        col = (*bg)(src)(box) * 1.04;
      } else {
        const cv::Vec3f pale = synth::bgr_from_hsv({22, 14, 228});
        col = cv::Mat(box.size(), CV_32FC3, cv::Scalar(pale[0], pale[1], pale[2]));
      }
      cv::Mat dst = image(box);
      cv::Mat mixed = b3.mul(col) + (cv::Scalar::all(1.0) - b3).mul(dst);
      mixed.copyTo(dst);
      // Measure what was really hidden, at the drawn resolution.
      const cv::Rect ov = box & in_image;
      if (ov.area() > 0) covered = cv::sum(alpha(ov + image_in_canvas.tl() - roi.tl()).mul(beta(ov - box.tl())))[0];
    }
  }
  if (in_view_area > 0) vis.occluded = covered / in_view_area;
  if (whole_area > 0) vis.visible = (in_view_area - covered) / whole_area;
  if (visibility) *visibility = vis;

  // Through the lens: the tracker undistorts the frame back (Sensor::rectify).
  // What falls outside the linear image repeats its border.
  if (!plan.lens_map.empty()) {
    cv::Mat through;
    cv::remap(image, through, plan.lens_map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    image = through;
  }
  const double defocus = p.blur_sigma_px + p.defocus_px_per_mm * std::abs(fr.truth[2] - sensor.nominal_position_mm().z());
  return synth::degrade(image, defocus, p, frame_seed(plan.options.seed, index));
}

}  // namespace gtrack
