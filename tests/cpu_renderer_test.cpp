// The cpu backend against the brute-force oracle (tests/support/reference_raster):
// masks must be equal pixel for pixel, counts must be those of the masks.
#include <gtest/gtest.h>
#include <gtrack/bench.hpp>
#include <gtrack/error.hpp>
#include <gtrack/renderer.hpp>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <limits>
#include <random>
#include <string>

#include "support/reference_raster.hpp"

// Counts heap allocations while `counting` is set, in every thread and in
// the framework library too (it calls the replaceable global operator new).
namespace {
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

using gtrack::ArticulatedModel;
using gtrack::PairCounts;
using gtrack::Projection;
using gtrack::RenderOptions;
using gtrack::testing::hydrogel_geometry;
using gtrack::testing::microscope_projection;
using gtrack::testing::reference_mask;

constexpr double kScale = 0.25;

// 1024x1024 camera rendered at 256x256; at z = 45 mm the gripper is ~114 px across.
Projection camera() { return microscope_projection(1024, 1024, 5120, 5120, 512, 512, 0.1); }

std::unique_ptr<gtrack::Renderer> cpu(const ArticulatedModel& model, const Projection& p, double scale,
                                      int threads) {
  RenderOptions o;
  o.backend = "cpu";
  o.threads = threads;
  auto r = gtrack::make_cpu_renderer(o);
  r->set_model(model);
  r->set_projection(p, scale);
  return r;
}

// Hypotheses that exercise the rasteriser: any orientation, fingers from
// slightly open to folded back over the palm, partly out of the image, and a
// few so close to the camera that the near plane and the guard band cut them.
Eigen::MatrixXd random_hypotheses(int n, std::uint32_t seed, int fingers) {
  std::mt19937 rng(seed);
  auto U = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  Eigen::MatrixXd H(6 + fingers, n);
  for (int i = 0; i < n; ++i) {
    const bool close = i % 10 == 9;
    H(0, i) = close ? U(-0.5, 0.5) : U(-5, 5);
    H(1, i) = close ? U(-0.5, 0.5) : U(-5, 5);
    H(2, i) = close ? U(-0.5, 2.0) : U(30, 60);
    H(3, i) = U(-80, 80);
    H(4, i) = U(-80, 80);
    H(5, i) = U(-180, 180);
    for (int f = 0; f < fingers; ++f) H(6 + f, i) = U(-10, 150);
  }
  return H;
}

int count(const cv::Mat& m) { return cv::countNonZero(m); }

::testing::AssertionResult same_mask(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat diff;
  cv::compare(a, b, diff, cv::CMP_NE);
  const int n = cv::countNonZero(diff);
  if (n == 0) return ::testing::AssertionSuccess();
  std::vector<cv::Point> where;
  cv::findNonZero(diff, where);
  return ::testing::AssertionFailure() << n << " pixels differ, first at (" << where[0].x << ", " << where[0].y
                                       << ")";
}

// A square palm of 1 mm and four straight arms of two 0.25 x 0.4 mm
// rectangles, seen from above at 20 px/mm: every vertex lands on a pixel
// centre or a pixel corner, so edges pass exactly through pixel centres.
ArticulatedModel plus_shape() {
  gtrack::RadialGripperSpec s;
  s.name = "plus";
  s.fingers = 4;
  s.palm_sides = 4;
  s.palm_circumradius_mm = std::sqrt(0.5);
  s.links = {{0.25, 0.4, 0.4}, {0.25, 0.4, 0.4}};
  return ArticulatedModel(gtrack::make_radial_gripper(s));
}

Projection top_view(double cu, double cv, int size = 128, double px_per_mm = 20) {
  Projection p;
  p.size = {size, size};
  p.world_to_image << px_per_mm, 0, 0, cu, 0, px_per_mm, 0, cv, 0, 0, 0, 1;
  return p;
}

TEST(ReferenceRaster, TopLeftRuleOnASquareThroughPixelCentres) {
  // Corners on pixel centres: the left and top edges keep their centres, the
  // right and bottom ones do not, so a 4 x 3 px square covers exactly 12 px,
  // however it is cut into triangles.
  gtrack::ScreenPolygon a, b;
  a.count = b.count = 3;
  a.v[0] = {1.5, 1.5}, a.v[1] = {5.5, 1.5}, a.v[2] = {5.5, 4.5};
  b.v[0] = {1.5, 1.5}, b.v[1] = {5.5, 4.5}, b.v[2] = {1.5, 4.5};
  const cv::Mat m = gtrack::testing::reference_raster({a, b}, {8, 8});
  EXPECT_EQ(count(m), 12);
  EXPECT_EQ(count(m(cv::Rect(1, 1, 4, 3))), 12);
}

TEST(CpuRenderer, MatchesAnalyticCountWithEdgesThroughPixelCentres) {
  const ArticulatedModel m = plus_shape();
  Eigen::VectorXd h = Eigen::VectorXd::Zero(10);
  // palm 20 x 20 px + four arms of 10 x 8 px, no pixel counted twice or lost
  // on the shared edges; the same for edges on pixel corners.
  for (double c : {64.5, 64.0}) {
    for (double rz : {0.0, 90.0, 180.0, -90.0}) {
      h[5] = rz;
      auto r = cpu(m, top_view(c, c), 1.0, 1);
      const cv::Mat got = r->render_mask(h);
      EXPECT_EQ(count(got), 720) << "centre " << c << " rz " << rz;
      EXPECT_TRUE(same_mask(got, reference_mask(m, top_view(c, c), h))) << "centre " << c << " rz " << rz;
    }
  }
}

TEST(CpuRenderer, MasksEqualTheReferenceOnRandomHypotheses) {
  const ArticulatedModel model(hydrogel_geometry());
  const Projection full = camera();
  const Projection p = gtrack::scaled_projection(full, kScale);
  ASSERT_EQ(p.size.width, 256);
  auto r = cpu(model, full, kScale, 1);
  const Eigen::MatrixXd H = random_hypotheses(400, 7, model.fingers());
  int nonempty = 0;
  for (int i = 0; i < H.cols(); ++i) {
    const Eigen::VectorXd h = H.col(i);
    const cv::Mat ref = reference_mask(model, p, h);
    nonempty += count(ref) > 0;
    ASSERT_TRUE(same_mask(r->render_mask(h), ref)) << "hypothesis " << i << ": " << h.transpose();
  }
  EXPECT_GT(nonempty, 300);
}

TEST(CpuRenderer, MasksEqualTheReferenceWithTiesOnTheTopView) {
  // Axis-aligned and diagonal poses of the plus shape, on centres and corners:
  // many pixel centres sit exactly on edges.
  const ArticulatedModel m = plus_shape();
  std::mt19937 rng(3);
  for (int i = 0; i < 200; ++i) {
    const double c = 60 + 0.25 * std::uniform_int_distribution<int>(0, 32)(rng);
    Eigen::VectorXd h = Eigen::VectorXd::Zero(10);
    h[5] = 45.0 * std::uniform_int_distribution<int>(-4, 4)(rng);
    h[0] = 0.05 * std::uniform_int_distribution<int>(-20, 20)(rng);
    h[1] = 0.05 * std::uniform_int_distribution<int>(-20, 20)(rng);
    for (int f = 0; f < 4; ++f) h[6 + f] = 30.0 * std::uniform_int_distribution<int>(0, 4)(rng);
    auto r = cpu(m, top_view(c, c), 1.0, 1);
    ASSERT_TRUE(same_mask(r->render_mask(h), reference_mask(m, top_view(c, c), h)))
        << "centre " << c << " h " << h.transpose();
  }
}

// padded_projection: the image's pixels are the padded canvas's, shifted by
// the margin, and the canvas also holds what lies beyond the image's borders.
// The render image covers the full image exactly, also when the scale does
// not give a whole number of pixels: the far edges (1024, 662) land on the
// rounded sizes (307, 199 at 0.3), as the observation is resized.
TEST(CpuRenderer, ScaledProjectionMapsEdgeToEdge) {
  const Projection full = microscope_projection(1024, 662, 4000, 4000, 512, 331, 0.1);
  const Projection p = gtrack::scaled_projection(full, 0.3);
  ASSERT_EQ(p.size.width, 307);
  ASSERT_EQ(p.size.height, 199);
  const double z = 50.0;
  for (const auto& [u, v] : {std::pair{0.0, 0.0}, std::pair{1024.0, 662.0}, std::pair{512.0, 331.0}}) {
    const Eigen::Vector4d X((u - 512) * z / 4000, (v - 331) * z / 4000, z, 1);
    const Eigen::Vector3d full_h = full.world_to_image * X, small_h = p.world_to_image * X;
    ASSERT_NEAR(full_h.x() / full_h.z(), u, 1e-9);
    EXPECT_NEAR(small_h.x() / small_h.z(), u * 307 / 1024, 1e-9);
    EXPECT_NEAR(small_h.y() / small_h.z(), v * 199 / 662, 1e-9);
  }
}

TEST(CpuRenderer, PaddedProjectionExtendsTheImage) {
  const ArticulatedModel model(hydrogel_geometry());
  const Projection p = gtrack::scaled_projection(camera(), kScale);
  const int mx = 40, my = 24;
  auto in_image = cpu(model, p, 1.0, 1);
  auto padded = cpu(model, gtrack::padded_projection(p, mx, my), 1.0, 1);
  ASSERT_EQ(padded->render_size().width, p.size.width + 2 * mx);
  ASSERT_EQ(padded->render_size().height, p.size.height + 2 * my);
  const Eigen::MatrixXd H = random_hypotheses(200, 9, model.fingers());
  int beyond = 0;
  for (int i = 0; i < H.cols(); ++i) {
    const cv::Mat small = in_image->render_mask(H.col(i));
    const cv::Mat large = padded->render_mask(H.col(i));
    ASSERT_TRUE(same_mask(large(cv::Rect(mx, my, p.size.width, p.size.height)), small)) << "hypothesis " << i;
    ASSERT_GE(count(large), count(small));
    beyond += count(large) > count(small);
  }
  EXPECT_GT(beyond, 10);  // some of them reach beyond a border
  EXPECT_THROW(gtrack::padded_projection(p, -1, 0), gtrack::Error);
}

// The hydrogel gripper at a nominal pose in front of the test camera.
struct NominalScene {
  ArticulatedModel model{hydrogel_geometry()};
  Projection full = camera();
  Projection p = gtrack::scaled_projection(full, kScale);
  Eigen::VectorXd nominal = (Eigen::VectorXd(12) << 0.2, -0.1, 45, 10, -15, 20, 30, 30, 30, 30, 30, 30).finished();
};

TEST(CpuRenderer, CountsAreIntersectionAndRenderedOfTheMasks) {
  const NominalScene s;
  const ArticulatedModel& model = s.model;
  const Projection& p = s.p;
  const Eigen::VectorXd& nominal = s.nominal;
  auto r = cpu(model, s.full, kScale, 2);

  // Observation: the gripper at a nominal pose, plus speckle far from it.
  cv::Mat obs = reference_mask(model, p, nominal);
  std::mt19937 rng(11);
  for (int k = 0; k < 500; ++k) obs.at<std::uint8_t>(rng() % 256, rng() % 256) = 255;
  r->set_observation(obs);
  EXPECT_EQ(r->observation_count(), static_cast<std::uint64_t>(count(obs)));

  Eigen::MatrixXd H = random_hypotheses(160, 5, model.fingers());
  H.col(0) = nominal;
  std::vector<PairCounts> got;
  r->evaluate(H, got);
  ASSERT_EQ(got.size(), 160u);
  for (int i = 0; i < H.cols(); ++i) {
    const cv::Mat ref = reference_mask(model, p, H.col(i));
    cv::Mat both;
    cv::bitwise_and(ref, obs, both);
    EXPECT_EQ(got[i].rendered, static_cast<std::uint32_t>(count(ref))) << "hypothesis " << i;
    EXPECT_EQ(got[i].intersection, static_cast<std::uint32_t>(count(both))) << "hypothesis " << i;
  }
  // The nominal pose is the observation minus the speckle.
  EXPECT_EQ(got[0].intersection, got[0].rendered);
}

// The three counts a renderer returned for hypothesis i are those of `mask`.
void expect_counts_of(const PairCounts& c, const cv::Mat& mask, const cv::Mat& obs, const cv::Mat& rim, int i) {
  cv::Mat both, near;
  cv::bitwise_and(mask, obs, both);
  cv::bitwise_and(mask, rim, near);
  EXPECT_EQ(c.rendered, static_cast<std::uint32_t>(count(mask))) << "hypothesis " << i;
  EXPECT_EQ(c.intersection, static_cast<std::uint32_t>(count(both))) << "hypothesis " << i;
  EXPECT_EQ(c.rim, static_cast<std::uint32_t>(count(near))) << "hypothesis " << i;
}

TEST(CpuRenderer, RimCountsAreTheRenderedPixelsInTheRim) {
  const NominalScene s;
  const ArticulatedModel& model = s.model;
  const Projection& p = s.p;
  auto r = cpu(model, s.full, kScale, 2);

  const cv::Mat obs = reference_mask(model, p, s.nominal);
  // The rim: a two-pixel ring around O, plus speckle elsewhere outside O
  // (the renderer counts whatever it is given, with any non-zero value).
  cv::Mat rim;
  cv::dilate(obs, rim, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)));
  std::mt19937 rng(5);
  for (int k = 0; k < 500; ++k) rim.at<std::uint8_t>(rng() % 256, rng() % 256) = 7;
  rim.setTo(0, obs);
  r->set_observation(obs);
  r->set_rim(rim);

  Eigen::MatrixXd H = random_hypotheses(120, 9, model.fingers());
  H.col(0) = s.nominal;
  std::vector<PairCounts> got;
  r->evaluate(H, got);
  int touching = 0;
  for (int i = 0; i < H.cols(); ++i) {
    expect_counts_of(got[i], reference_mask(model, p, H.col(i)), obs, rim, i);
    touching += got[i].rim > 0;
  }
  EXPECT_EQ(got[0].rim, 0u);  // the pose of O itself stays inside it
  EXPECT_GT(touching, 10);
  // The OpenCV baseline of the benchmarks counts the rim too.
  auto baseline = gtrack::make_opencv_baseline({});
  baseline->set_model(model);
  baseline->set_projection(s.full, kScale);
  baseline->set_observation(obs);
  baseline->set_rim(rim);
  std::vector<PairCounts> theirs;
  baseline->evaluate(H, theirs);
  ASSERT_EQ(theirs.size(), got.size());
  // Its own polygon fill covers edge pixels the pixel-centre rule leaves
  // out, so its masks are a little larger; its counts are those of its masks.
  for (int i = 0; i < H.cols(); i += 7) expect_counts_of(theirs[i], baseline->render_mask(H.col(i)), obs, rim, i);
  // A new observation clears the rim, and so does an empty one.
  r->set_observation(obs);
  r->evaluate(H, got);
  for (const PairCounts& c : got) EXPECT_EQ(c.rim, 0u);
  r->set_rim(rim);
  r->set_rim(cv::Mat());
  r->evaluate(H, got);
  for (const PairCounts& c : got) EXPECT_EQ(c.rim, 0u);
  EXPECT_THROW(r->set_rim(cv::Mat(255, 256, CV_8UC1, cv::Scalar(0))), gtrack::Error);
}

TEST(CpuRenderer, FoldedFingersOverThePalmAreCountedOnce) {
  // Seen from above with the hinges at 90 deg, the second and third links lie
  // over the palm: the mask is a union, so |P| is less than the sum of the
  // triangles' own pixels.
  const ArticulatedModel model(hydrogel_geometry());
  const Projection p = top_view(64, 64, 128, 25);
  Eigen::VectorXd h = Eigen::VectorXd::Zero(12);
  h.tail(6).setConstant(90);
  std::vector<Eigen::Vector3d> world;
  model.pose(h, world);
  std::vector<gtrack::ScreenPolygon> polys;
  gtrack::project_and_clip(world, p, polys);
  int sum = 0;
  for (const auto& poly : polys) sum += count(gtrack::testing::reference_raster({poly}, p.size));

  auto r = cpu(model, p, 1.0, 2);
  r->set_observation(cv::Mat(128, 128, CV_8UC1, cv::Scalar(255)));
  std::vector<PairCounts> got;
  r->evaluate(h, got);
  const int union_px = count(reference_mask(model, p, h));
  EXPECT_EQ(got[0].rendered, static_cast<std::uint32_t>(union_px));
  EXPECT_EQ(got[0].intersection, got[0].rendered);
  EXPECT_LT(union_px, sum - 200) << "the folded links should overlap the palm";
}

TEST(CpuRenderer, SlabOfTwoClipPlanesKeepsOnlyWhatIsInside) {
  // Looking along world x (u = 25 y, v = 25 z), the open gripper turned into
  // the YZ plane; the slab -0.51 <= z <= 0.79 keeps a band of rows.
  const ArticulatedModel model(hydrogel_geometry());
  Projection side;
  side.size = {128, 128};
  side.world_to_image << 0, 25, 0, 64, 0, 0, 25, 64, 0, 0, 0, 1;
  Projection slab = side;
  slab.clip_planes = {Eigen::Vector4d(0, 0, 1, 0.51), Eigen::Vector4d(0, 0, -1, 0.79)};
  Eigen::VectorXd h = Eigen::VectorXd::Zero(12);
  h[4] = 90;

  const cv::Mat all = cpu(model, side, 1.0, 1)->render_mask(h);
  const cv::Mat cut = cpu(model, slab, 1.0, 1)->render_mask(h);
  ASSERT_GT(count(all), 2000);
  EXPECT_TRUE(same_mask(cut, reference_mask(model, slab, h)));
  for (int j = 0; j < 128; ++j) {
    const double z = (j + 0.5 - 64) / 25.0;
    if (z > -0.51 + 0.04 && z < 0.79 - 0.04) {
      EXPECT_TRUE(same_mask(cut.row(j), all.row(j))) << "row " << j;
    } else if (z < -0.51 - 0.04 || z > 0.79 + 0.04) {
      EXPECT_EQ(count(cut.row(j)), 0) << "row " << j;
    }
  }

  // Random poses through the slab, against the oracle.
  const Eigen::MatrixXd H = random_hypotheses(100, 13, model.fingers());
  auto r = cpu(model, slab, 1.0, 1);
  for (int i = 0; i < H.cols(); ++i) {
    Eigen::VectorXd hh = H.col(i);
    hh.head<3>() = Eigen::Vector3d(0, 0.3 * hh[0] / 5, 0.3 * hh[1] / 5);
    ASSERT_TRUE(same_mask(r->render_mask(hh), reference_mask(model, slab, hh))) << "hypothesis " << i;
  }
}

// A six-finger radial gripper of one link per finger.
ArticulatedModel radial_model(double palm_circumradius_mm, const gtrack::LinkShape& link) {
  gtrack::RadialGripperSpec s;
  s.name = "radial";
  s.palm_circumradius_mm = palm_circumradius_mm;
  s.links = {link};
  return ArticulatedModel(gtrack::make_radial_gripper(s));
}

TEST(CpuRenderer, AGripperLargerThanTheImageCoversEveryPixel) {
  // Vertices far outside the image go through the guard band.
  const ArticulatedModel m = radial_model(50, {10, 5, 5});
  auto r = cpu(m, camera(), kScale, 1);
  Eigen::VectorXd h = Eigen::VectorXd::Zero(12);
  h[2] = 5;
  h[3] = 20;
  EXPECT_EQ(count(r->render_mask(h)), 256 * 256);
  h[2] = -5;  // behind the camera
  EXPECT_EQ(count(r->render_mask(h)), 0);
}

// A configuration sent absurdly far (gtrack render -p, a plugin's start)
// shows nothing: its vertices overflow u * w to inf, which must not make
// them inside the frustum, nor reach the rasteriser's integer snapping (run
// under the sanitizers in CI).
TEST(CpuRenderer, AConfigurationAbsurdlyFarShowsNothing) {
  const ArticulatedModel m = radial_model(1, {0.5, 0.4, 0.2});
  auto r = cpu(m, camera(), kScale, 1);
  Eigen::VectorXd h = Eigen::VectorXd::Zero(12);
  h[2] = 34;
  EXPECT_GT(count(r->render_mask(h)), 0);
  for (const double far : {1e300, 1e308, std::numeric_limits<double>::max()}) {
    h[2] = far;
    EXPECT_EQ(count(r->render_mask(h)), 0) << far;
    h[2] = 34;
    h[0] = far;
    EXPECT_EQ(count(r->render_mask(h)), 0) << far;
    h[0] = 0;
  }
}

TEST(CpuRenderer, ThreadsGiveTheSameCountsAsOneThread) {
  const ArticulatedModel model(hydrogel_geometry());
  const Projection full = camera();
  const Projection p = gtrack::scaled_projection(full, kScale);
  Eigen::VectorXd nominal(12);
  nominal << 0, 0, 45, 0, 0, 0, 20, 20, 20, 20, 20, 20;
  const cv::Mat obs = reference_mask(model, p, nominal);
  const Eigen::MatrixXd H = random_hypotheses(257, 17, model.fingers());

  std::vector<PairCounts> one, many;
  auto r1 = cpu(model, full, kScale, 1);
  r1->set_observation(obs);
  r1->evaluate(H, one);
  for (int threads : {2, 3, 8}) {
    auto rn = cpu(model, full, kScale, threads);
    rn->set_observation(obs);
    for (int round = 0; round < 5; ++round) {  // the pool is reused across batches
      rn->evaluate(H, many);
      ASSERT_EQ(many.size(), one.size());
      for (size_t i = 0; i < one.size(); ++i) {
        ASSERT_EQ(many[i].intersection, one[i].intersection) << threads << " threads, hypothesis " << i;
        ASSERT_EQ(many[i].rendered, one[i].rendered) << threads << " threads, hypothesis " << i;
      }
    }
  }
}

TEST(CpuRenderer, NothingIsAllocatedPerBatchAfterWarmUp) {
  const ArticulatedModel model(hydrogel_geometry());
  const Projection full = camera();
  auto r = cpu(model, full, kScale, 2);
  r->set_observation(reference_mask(model, gtrack::scaled_projection(full, kScale), random_hypotheses(1, 3, 6).col(0)));
  const Eigen::MatrixXd H = random_hypotheses(64, 23, 6);
  const Eigen::MatrixXd a = H.leftCols(32), b = H.rightCols(32);
  std::vector<PairCounts> out;
  r->evaluate(a, out);
  r->evaluate(b, out);
  allocations = 0;
  counting = true;
  for (int k = 0; k < 20; ++k) r->evaluate(k % 2 ? a : b, out);
  counting = false;
  EXPECT_EQ(allocations.load(), 0);
}

TEST(CpuRenderer, SubmitThenFinishAndEmptyBatches) {
  const ArticulatedModel model(hydrogel_geometry());
  auto r = cpu(model, camera(), kScale, 2);
  std::vector<PairCounts> out(3);
  r->submit(Eigen::MatrixXd(12, 0));
  r->finish(out);
  EXPECT_TRUE(out.empty());
  const Eigen::MatrixXd H = random_hypotheses(32, 19, 6);
  r->submit(H);
  r->finish(out);
  EXPECT_EQ(out.size(), 32u);
}

TEST(CpuRenderer, RejectsWhatItCannotUse) {
  const ArticulatedModel model(hydrogel_geometry());
  RenderOptions o;
  auto bare = gtrack::make_cpu_renderer(o);
  EXPECT_THROW(bare->render_mask(Eigen::VectorXd::Zero(12)), gtrack::Error);
  auto r = cpu(model, camera(), kScale, 1);
  EXPECT_EQ(r->render_size().width, 256);
  EXPECT_EQ(r->render_size().height, 256);
  EXPECT_THROW(r->render_mask(Eigen::VectorXd::Zero(11)), gtrack::Error);
  EXPECT_THROW(r->set_observation(cv::Mat(255, 256, CV_8UC1, cv::Scalar(0))), gtrack::Error);
  EXPECT_THROW(r->set_observation(cv::Mat(256, 256, CV_32FC1, cv::Scalar(0))), gtrack::Error);
}

TEST(RendererFactory, NamesTheValidBackends) {
  RenderOptions o;
  o.backend = "vulkan";
  try {
    gtrack::make_renderer(o);
    FAIL() << "an unknown backend must be an error";
  } catch (const gtrack::Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("vulkan"), std::string::npos) << what;
    EXPECT_NE(what.find("auto, gl, cpu"), std::string::npos) << what;
  }
  o.backend = "cpu";
  EXPECT_EQ(gtrack::make_renderer(o)->name(), "cpu");
  if (!gtrack::hardware_gpu_available()) {
    o.backend = "auto";
    EXPECT_EQ(gtrack::make_renderer(o)->name(), "cpu");
  }
}

TEST(Geometry, ScaledProjectionAndClipping) {
  const Projection full = camera();
  const Projection p = gtrack::scaled_projection(full, 0.25);
  EXPECT_EQ(p.size.width, 256);
  EXPECT_EQ(p.size.height, 256);
  EXPECT_EQ(p.clip_planes.size(), 1u);
  // A point keeps its place relative to the image.
  const Eigen::Vector3d X(0.3, -0.2, 40);
  const Eigen::Vector3d a = full.world_to_image * X.homogeneous(), b = p.world_to_image * X.homogeneous();
  EXPECT_NEAR(b.x() / b.z(), 0.25 * a.x() / a.z(), 1e-12);
  EXPECT_NEAR(b.y() / b.z(), 0.25 * a.y() / a.z(), 1e-12);
  EXPECT_THROW(gtrack::scaled_projection(full, 0), gtrack::Error);

  std::vector<gtrack::ScreenPolygon> out;
  // In front: one triangle. Behind the near plane: nothing. Across: a quad.
  gtrack::project_and_clip({{0, 0, 10}, {1, 0, 10}, {0, 1, 10}}, p, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].count, 3);
  EXPECT_NEAR(out[0].v[1].x(), 128 + 1280.0 / 10, 1e-9);
  gtrack::project_and_clip({{0, 0, 0.05}, {1, 0, 0.05}, {0, 1, 0.05}}, p, out);
  EXPECT_TRUE(out.empty());
  gtrack::project_and_clip({{0, 0, 0.05}, {0.01, 0, 5}, {0, 0.01, 5}}, p, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].count, 4);
}

}  // namespace
