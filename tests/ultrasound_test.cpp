// ultrasound_slice against an independent computation of the mesh-slab
// intersection: a pixel is imaged when the segment through its centre along
// the elevation normal, as thick as the slab, hits a triangle of the posed
// model (segment-triangle test per pixel, no clipping, no projection matrix).
#include <gtest/gtest.h>

#include <gtrack/engine_config.hpp>
#include <gtrack/renderer.hpp>
#include <gtrack/setup.hpp>
#include <random>

#include "support/plugins.hpp"

using gtrack::testing::make_gripper;
using gtrack::testing::make_sensor;

namespace {

bool segment_hits_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& dir, double half,
                           const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d pv = dir.cross(e2);
  const double det = e1.dot(pv);
  if (std::abs(det) < 1e-14) return false;  // edge-on: no area in the image
  const Eigen::Vector3d tv = p - a;
  const double u = tv.dot(pv) / det;
  if (u < 0 || u > 1) return false;
  const Eigen::Vector3d qv = tv.cross(e1);
  const double v = dir.dot(qv) / det;
  if (v < 0 || u + v > 1) return false;
  const double s = e2.dot(qv) / det;
  return std::abs(s) <= half;
}

TEST(UltrasoundSlice, ImagesExactlyTheMeshInsideTheSlab) {
  // A small image at a coarse spacing keeps the brute force quick.
  const double s = 0.05, slab = 0.4;
  auto sensor = make_sensor(
      "plugin = \"ultrasound_slice\"\nwidth = 120\nheight = 100\nmm_per_pixel = 0.05\nslab_thickness_mm = 0.4\n"
      "probe_position_mm = [0.2, -1.0, 0.1]\nprobe_rotation_deg = [5, -8, 12]");
  auto gripper = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& model = gripper->model();
  auto renderer = gtrack::make_cpu_renderer({});
  renderer->set_model(model);
  renderer->set_projection(sensor->projection(), 1.0);
  ASSERT_EQ(renderer->render_size().width, 120);

  const Eigen::Matrix3d R = gtrack::rotation_from_euler_deg(5, -8, 12);
  const Eigen::Vector3d origin(0.2, -1.0, 0.1), ex = R.col(0), ey = R.col(1), ez = R.col(2);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> ang(-40, 40), rz(-180, 180), q(0, 70), off(-0.15, 0.15);
  int checked = 0, total_both = 0, total_either = 0;
  for (int trial = 0; trial < 12; ++trial) {
    // Gripper about 2.5 mm deep in the image, tilted so the slab cuts it.
    Eigen::VectorXd h(12);
    const Eigen::Vector3d c = origin + ey * 2.5 + ex * off(rng) + ez * off(rng);
    h << c, 90 + ang(rng), ang(rng), rz(rng), q(rng), q(rng), q(rng), q(rng), q(rng), q(rng);
    const cv::Mat mask = renderer->render_mask(h);
    std::vector<Eigen::Vector3d> tris;
    model.pose(h, tris);
    int both = 0, either = 0;
    for (int v = 0; v < 100; ++v) {
      for (int u = 0; u < 120; ++u) {
        const Eigen::Vector3d p = origin + ex * ((u + 0.5 - 60) * s) + ey * ((v + 0.5) * s);
        bool hit = false;
        for (size_t t = 0; t < tris.size() && !hit; t += 3) {
          hit = segment_hits_triangle(p, ez, slab / 2, tris[t], tris[t + 1], tris[t + 2]);
        }
        const bool rendered = mask.at<uint8_t>(v, u) != 0;
        both += hit && rendered;
        either += hit || rendered;
      }
    }
    if (either < 20) continue;  // the slab missed this pose: nothing to compare
    ++checked;
    total_both += both;
    total_either += either;
    // Only pixels whose centre lies on an edge may differ (tie rules).
    EXPECT_LE(either - both, 2 + 0.03 * either) << "trial " << trial << ": " << both << " / " << either;
  }
  EXPECT_GE(checked, 6);
  EXPECT_GE(double(total_both) / total_either, 0.98);
}

TEST(UltrasoundSlice, ProjectAgreesWithTheProjectionAndTheSlab) {
  auto sensor = make_sensor("plugin = \"ultrasound_slice\"\nslab_thickness_mm = 0.5");
  const auto p = sensor->projection();
  EXPECT_EQ(p.size.width, 1024);
  EXPECT_EQ(p.size.height, 662);
  EXPECT_DOUBLE_EQ(sensor->mm_per_pixel(), 0.09);
  const Eigen::Vector3d inside(1.0, 20.0, 0.2), outside(1.0, 20.0, 0.3);
  auto q = sensor->project(inside);
  ASSERT_TRUE(q);
  Eigen::Vector3d hq = p.world_to_image * inside.homogeneous();
  EXPECT_NEAR(q->x(), hq.x() / hq.z(), 1e-9);
  EXPECT_NEAR(q->y(), 20.0 / 0.09, 1e-9);
  EXPECT_FALSE(sensor->project(outside));
  for (const auto& plane : p.clip_planes) EXPECT_GE(plane.dot(inside.homogeneous()), 0);
  bool clipped = false;
  for (const auto& plane : p.clip_planes) clipped |= plane.dot(outside.homogeneous()) < 0;
  EXPECT_TRUE(clipped);
  EXPECT_EQ(sensor->segmentation_defaults().color_space, "luminance");
}

// Pixels that are not square: the depth's spacing scales the rows, the
// lateral one the columns, in the projection and in project() alike.
TEST(UltrasoundSlice, ADepthSpacingOfItsOwnScalesTheRows) {
  auto sensor = make_sensor("plugin = \"ultrasound_slice\"\nmm_per_pixel = 0.1\nmm_per_pixel_depth = 0.12");
  const Eigen::Vector3d x(2.0, 24.0, 0.0);
  const auto q = sensor->project(x);
  ASSERT_TRUE(q);
  EXPECT_NEAR(q->x(), 2.0 / 0.1 + 512, 1e-9);
  EXPECT_NEAR(q->y(), 24.0 / 0.12, 1e-9);
  const Eigen::Vector3d hq = sensor->projection().world_to_image * x.homogeneous();
  EXPECT_NEAR(hq.x() / hq.z(), q->x(), 1e-9);
  EXPECT_NEAR(hq.y() / hq.z(), q->y(), 1e-9);
  EXPECT_DOUBLE_EQ(sensor->mm_per_pixel(), 0.1);
  // The nominal position is at the image's middle row.
  EXPECT_NEAR(sensor->project(sensor->nominal_position_mm())->y(), 331, 1e-9);
  const Eigen::Vector2d pixel = gtrack::pixel_size_mm(*sensor);
  EXPECT_DOUBLE_EQ(pixel.x(), 0.1);
  EXPECT_NEAR(pixel.y(), 0.12, 1e-12);
  EXPECT_EQ(gtrack::pixel_size_mm(*make_sensor("plugin = \"ultrasound_slice\"")), Eigen::Vector2d(0.09, 0.09))
      << "square pixels stay exactly mm_per_pixel";
  // A tall image of tall pixels: the default search box holds its whole
  // depth (1024 rows of 0.12 mm), not just its width's extent.
  auto root = gtrack::ConfigTable::parse(
      "[sensor]\nplugin = \"ultrasound_slice\"\nwidth = 512\nheight = 1024\nmm_per_pixel = 0.1\n"
      "mm_per_pixel_depth = 0.12\n[gripper]\nplugin = \"hydrogel_six_finger\"\n",
      "<test>");
  const gtrack::Setup tall = gtrack::load_setup(root, {});
  const gtrack::EngineConfig config = gtrack::engine_config(tall);
  EXPECT_LE(config.search.position_min_mm.y(), 0.0);
  EXPECT_GE(config.search.position_max_mm.y(), 1024 * 0.12);
}

}  // namespace
