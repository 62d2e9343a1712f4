// The gl backend against the cpu backend and the brute-force oracle
// (tests/support/reference_raster): on a microscope camera, on an ultrasound
// slab (orthographic, two clip planes), across layer boundaries of the
// 32-hypotheses-per-layer packing, and its errors.
//
// The GPU computes vertices in float and snaps them to 1/256 pixel itself,
// the oracle in double, so a pixel centre within float noise of an edge may
// fall either way: masks are compared by IoU and counts with a tolerance.
// Skipped only when no EGL context can be made at all.
#include <gtest/gtest.h>
#include <gtrack/error.hpp>
#include <gtrack/log.hpp>
#include <gtrack/engine_config.hpp>
#include <gtrack/renderer.hpp>
#include <gtrack/setup.hpp>
#include <gtrack/tracker.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <future>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <random>
#include <spdlog/sinks/ostream_sink.h>
#include <sstream>
#include <string>
#include <thread>
#include <unistd.h>
#include <utility>
#include <vector>

#include "support/logged.hpp"
#include "support/plugins.hpp"
#include "support/reference_raster.hpp"
#include "support/scoped_env.hpp"

namespace {

namespace fs = std::filesystem;
using gtrack::ArticulatedModel;
using gtrack::PairCounts;
using gtrack::Projection;
using gtrack::RenderOptions;
using gtrack::Renderer;
using gtrack::testing::hydrogel_geometry;
using gtrack::testing::microscope_projection;
using gtrack::testing::reference_mask;
using gtrack::testing::ScopedEnv;

constexpr double kScale = 0.25;
constexpr char kNoContext[] = "gl backend: no EGL context";

// The renderer, or the reason there is no EGL context on this machine.
std::unique_ptr<Renderer> make_gl(std::string& skip, const RenderOptions& options = {}) {
  try {
    return gtrack::make_gl_renderer(options);
  } catch (const gtrack::Error& e) {
    if (std::string(e.what()).rfind(kNoContext, 0) != 0) throw;
    skip = e.what();
    return nullptr;
  }
}

#define GL_OR_SKIP(var, ...)                                      \
  std::string var##_skip;                                         \
  auto var = make_gl(var##_skip __VA_OPT__(, ) __VA_ARGS__);      \
  if (!var) GTEST_SKIP() << "no EGL context: " << var##_skip

std::unique_ptr<Renderer> make_cpu() {
  RenderOptions o;
  o.backend = "cpu";
  o.threads = 1;
  return gtrack::make_cpu_renderer(o);
}

// 1024x1024 camera rendered at 256x256; at z = 45 mm the gripper is ~114 px across.
Projection camera() { return microscope_projection(1024, 1024, 5120, 5120, 512, 512, 0.1); }

// An ultrasound-like slice: an oblique imaging plane through (0, 0, 40) mm,
// 0.02 mm per pixel at full resolution, orthographic along the plane normal,
// and a slab of `thickness_mm` around the plane (two clip planes).
// `shift` moves the probe and the hypotheses (slab_hypotheses) alike.
Projection ultrasound_slab(double thickness_mm, const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
  const Eigen::Matrix3d axes = gtrack::rotation_from_euler_deg(25, -15, 10);
  const Eigen::Vector3d e1 = axes.col(0), e2 = axes.col(1), n = axes.col(2);
  const Eigen::Vector3d origin = Eigen::Vector3d(0.3, -0.2, 40) + shift;
  const double mm_per_px = 0.02;
  Projection p;
  p.size = {1024, 768};
  p.world_to_image.row(0) << e1.transpose() / mm_per_px, -e1.dot(origin) / mm_per_px + 512;
  p.world_to_image.row(1) << e2.transpose() / mm_per_px, -e2.dot(origin) / mm_per_px + 384;
  p.world_to_image.row(2) << 0, 0, 0, 1;
  p.clip_planes.emplace_back(n.x(), n.y(), n.z(), -n.dot(origin) + thickness_mm / 2);
  p.clip_planes.emplace_back(-n.x(), -n.y(), -n.z(), n.dot(origin) + thickness_mm / 2);
  return p;
}

// Any orientation, fingers from slightly open to folded back over the palm,
// some partly out of the image and some cut by the near plane.
Eigen::MatrixXd camera_hypotheses(int n, std::uint32_t seed, int fingers) {
  std::mt19937 rng(seed);
  auto U = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  Eigen::MatrixXd H(6 + fingers, n);
  for (int i = 0; i < n; ++i) {
    const bool close = i % 25 == 24;
    H(0, i) = close ? U(-0.5, 0.5) : U(-4, 4);
    H(1, i) = close ? U(-0.5, 0.5) : U(-4, 4);
    H(2, i) = close ? U(0.5, 3.0) : U(35, 60);
    H(3, i) = U(-80, 80);
    H(4, i) = U(-80, 80);
    H(5, i) = U(-180, 180);
    for (int f = 0; f < fingers; ++f) H(6 + f, i) = U(-10, 150);
  }
  return H;
}

// Around the slab's plane, so that the slab cuts most of them.
Eigen::MatrixXd slab_hypotheses(int n, std::uint32_t seed, int fingers,
                                const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
  std::mt19937 rng(seed);
  auto U = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  Eigen::MatrixXd H(6 + fingers, n);
  for (int i = 0; i < n; ++i) {
    H(0, i) = shift.x() + U(-2, 2);
    H(1, i) = shift.y() + U(-2, 2);
    H(2, i) = shift.z() + 40 + U(-1.5, 1.5);
    H(3, i) = U(-90, 90);
    H(4, i) = U(-90, 90);
    H(5, i) = U(-180, 180);
    for (int f = 0; f < fingers; ++f) H(6 + f, i) = U(-10, 120);
  }
  return H;
}

double iou(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat i, u;
  cv::bitwise_and(a, b, i);
  cv::bitwise_or(a, b, u);
  const int nu = cv::countNonZero(u);
  return nu == 0 ? 1.0 : double(cv::countNonZero(i)) / nu;
}

// Masks agree when their IoU is >= 0.995; a mask too small for that to mean
// anything (a sliver at the image border) may differ by 2 pixels.
::testing::AssertionResult masks_agree(const cv::Mat& got, const cv::Mat& want) {
  cv::Mat diff;
  cv::compare(got, want, diff, cv::CMP_NE);
  const int differ = cv::countNonZero(diff);
  const double v = iou(got, want);
  if (v >= 0.995 || differ <= 2) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "IoU " << v << ", " << differ << " pixels differ of "
                                       << cv::countNonZero(want);
}

// Within 0.5%, with 2 pixels of slack for small counts.
::testing::AssertionResult counts_agree(std::uint32_t got, std::uint32_t want) {
  const double slack = std::max(2.0, 0.005 * want);
  if (std::abs(double(got) - double(want)) <= slack) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << got << " vs " << want;
}

// Both counts of a hypothesis, each within counts_agree's slack.
::testing::AssertionResult pair_counts_agree(const PairCounts& got, const PairCounts& want) {
  if (auto r = counts_agree(got.rendered, want.rendered); !r) return r << " (|P|)";
  if (auto r = counts_agree(got.intersection, want.intersection); !r) return r << " (|O&P|)";
  return ::testing::AssertionSuccess();
}

PairCounts mask_counts(const cv::Mat& mask, const cv::Mat& observation) {
  cv::Mat both;
  cv::bitwise_and(mask, observation, both);
  return {static_cast<std::uint32_t>(cv::countNonZero(both)), static_cast<std::uint32_t>(cv::countNonZero(mask))};
}

struct Scene {
  ArticulatedModel model;
  Projection projection;  // full resolution
  cv::Mat observation;    // at render size
};

// The scene given to each renderer: model, projection at kScale,
// observation, and the occlusion rim when one is given.
void set_scene(std::initializer_list<Renderer*> renderers, const Scene& s, const cv::Mat& rim = {}) {
  for (Renderer* r : renderers) {
    r->set_model(s.model);
    r->set_projection(s.projection, kScale);
    r->set_observation(s.observation);
    if (!rim.empty()) r->set_rim(rim);
  }
}

// The one-pixel ring around an observation, as an occlusion rim.
cv::Mat ring_around(const cv::Mat& observation) {
  cv::Mat rim;
  cv::dilate(observation, rim, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  rim.setTo(0, observation);
  return rim;
}

// An observation that overlaps many hypotheses: the union of a few posed
// grippers, as the oracle renders them.
cv::Mat observation_for(const Scene& s, const Eigen::MatrixXd& poses) {
  const Projection p = gtrack::scaled_projection(s.projection, kScale);
  cv::Mat obs = cv::Mat::zeros(p.size.height, p.size.width, CV_8UC1);
  for (int i = 0; i < poses.cols(); ++i) cv::bitwise_or(obs, reference_mask(s.model, p, poses.col(i)), obs);
  return obs;
}

// Renders every hypothesis with gl, cpu and the oracle; checks masks and the
// batched counts of gl against the cpu's.
void expect_agreement(Renderer& gl, const Scene& s, const Eigen::MatrixXd& H, int oracle_every) {
  auto cpu = make_cpu();
  set_scene({&gl, cpu.get()}, s);
  ASSERT_EQ(gl.render_size().width, cpu->render_size().width);
  ASSERT_EQ(gl.render_size().height, cpu->render_size().height);
  EXPECT_EQ(gl.observation_count(), cpu->observation_count());
  const Projection p = gtrack::scaled_projection(s.projection, kScale);

  std::vector<PairCounts> from_gl, from_cpu;
  gl.evaluate(H, from_gl);
  cpu->evaluate(H, from_cpu);
  ASSERT_EQ(from_gl.size(), static_cast<size_t>(H.cols()));
  ASSERT_EQ(from_cpu.size(), static_cast<size_t>(H.cols()));

  int nonempty = 0, overlapping = 0, failures = 0;
  double total_gl = 0, total_cpu = 0;
  for (int i = 0; i < H.cols() && failures < 10; ++i) {
    const Eigen::VectorXd h = H.col(i);
    const cv::Mat mg = gl.render_mask(h);
    const cv::Mat mc = cpu->render_mask(h);
    ASSERT_EQ(mg.type(), CV_8UC1);
    ASSERT_EQ(mg.size(), mc.size());
    nonempty += cv::countNonZero(mc) > 0;
    overlapping += from_cpu[i].intersection > 0;
    total_gl += from_gl[i].rendered;
    total_cpu += from_cpu[i].rendered;

    bool ok = true;
    auto check = [&](::testing::AssertionResult r, const char* what) {
      if (!r) {
        ADD_FAILURE() << what << ", hypothesis " << i << " (" << h.transpose() << "): " << r.message();
        ok = false;
      }
    };
    check(masks_agree(mg, mc), "gl mask vs cpu mask");
    if (i % oracle_every == 0) check(masks_agree(mg, reference_mask(s.model, p, h)), "gl mask vs oracle");
    check(counts_agree(from_gl[i].rendered, from_cpu[i].rendered), "|P| gl vs cpu");
    check(counts_agree(from_gl[i].intersection, from_cpu[i].intersection), "|O&P| gl vs cpu");
    // The batch counts are those of the mask the same backend renders.
    const PairCounts own = mask_counts(mg, s.observation);
    check(counts_agree(from_gl[i].rendered, own.rendered), "|P| batch vs own mask");
    check(counts_agree(from_gl[i].intersection, own.intersection), "|O&P| batch vs own mask");
    failures += !ok;
  }
  EXPECT_GT(nonempty, H.cols() * 3 / 5);
  EXPECT_GT(overlapping, H.cols() / 10);
  EXPECT_NEAR(total_gl, total_cpu, 0.001 * total_cpu);
}

TEST(GlRenderer, OpensAHeadlessContext) {
  GL_OR_SKIP(r);
  EXPECT_EQ(r->name(), "gl");
  EXPECT_EQ(r->render_size().width, 0);
  r->set_projection(camera(), kScale);
  EXPECT_EQ(r->render_size().width, 256);
  EXPECT_EQ(r->render_size().height, 256);
  // Cached and harmless without a GPU: just ask twice.
  EXPECT_EQ(gtrack::hardware_gpu_available(), gtrack::hardware_gpu_available());
}

TEST(GlRenderer, AgreesWithCpuAndOracleOnAPerspectiveCamera) {
  GL_OR_SKIP(gl);
  Scene s{ArticulatedModel(hydrogel_geometry()), camera(), {}};
  const Eigen::MatrixXd H = camera_hypotheses(1000, 11, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(12));
  expect_agreement(*gl, s, H, 1);
}

TEST(GlRenderer, AgreesWithCpuAndOracleOnAnUltrasoundSlab) {
  GL_OR_SKIP(gl);
  Scene s{ArticulatedModel(hydrogel_geometry()), ultrasound_slab(0.6), {}};
  const Eigen::MatrixXd H = slab_hypotheses(400, 5, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(12));
  expect_agreement(*gl, s, H, 1);
}

// A probe placed metres from the world's origin (a robot's base frame):
// the gl backend's float works on offsets from a point of the slice, not on
// world coordinates, whose float steps (0.5 um at 9 m) had moved pixels of
// the masks and the slab's planes (2 of these 400 hypotheses outside the
// agreement's tolerance, 11 pixels at worst).
TEST(GlRenderer, AgreesWithCpuOnAnUltrasoundSlabFarFromTheWorldsOrigin) {
  GL_OR_SKIP(gl);
  const Eigen::Vector3d far(3000, -2000, 9000);
  Scene s{ArticulatedModel(hydrogel_geometry()), ultrasound_slab(0.6, far), {}};
  const Eigen::MatrixXd H = slab_hypotheses(400, 5, s.model.fingers(), far);
  s.observation = observation_for(s, H.leftCols(12));
  expect_agreement(*gl, s, H, 4);
}

TEST(GlRenderer, RimCountsAgreeWithCpu) {
  GL_OR_SKIP(gl);
  Scene s{ArticulatedModel(hydrogel_geometry()), camera(), {}};
  const Eigen::MatrixXd H = camera_hypotheses(300, 17, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(3));
  auto cpu = make_cpu();
  set_scene({gl.get(), cpu.get()}, s, ring_around(s.observation));
  std::vector<PairCounts> from_gl, from_cpu;
  gl->evaluate(H, from_gl);
  cpu->evaluate(H, from_cpu);
  ASSERT_EQ(from_gl.size(), from_cpu.size());
  int touching = 0;
  for (size_t i = 0; i < from_gl.size(); ++i) {
    EXPECT_TRUE(counts_agree(from_gl[i].rim, from_cpu[i].rim)) << "hypothesis " << i;
    EXPECT_TRUE(counts_agree(from_gl[i].intersection, from_cpu[i].intersection)) << "hypothesis " << i;
    EXPECT_TRUE(counts_agree(from_gl[i].rendered, from_cpu[i].rendered)) << "hypothesis " << i;
    touching += from_cpu[i].rim > 0;
  }
  EXPECT_GT(touching, 30);
  // A new observation clears the rim; the observed pixels are unchanged.
  gl->set_observation(s.observation);
  gl->evaluate(H, from_gl);
  for (size_t i = 0; i < from_gl.size(); ++i) {
    EXPECT_EQ(from_gl[i].rim, 0u) << "hypothesis " << i;
    EXPECT_TRUE(counts_agree(from_gl[i].intersection, from_cpu[i].intersection)) << "hypothesis " << i;
  }
  EXPECT_THROW(gl->set_rim(cv::Mat::zeros(8, 8, CV_8UC1)), gtrack::Error);
}

// A new projection starts without an observation or a rim on either backend,
// whether or not the render size changes.
TEST(GlRenderer, ANewProjectionClearsTheObservationAndRimAsCpuDoes) {
  GL_OR_SKIP(gl);
  Scene s{ArticulatedModel(hydrogel_geometry()), camera(), {}};
  const Eigen::MatrixXd H = camera_hypotheses(100, 23, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(4));
  auto cpu = make_cpu();
  std::vector<PairCounts> from_gl, from_cpu;
  set_scene({gl.get(), cpu.get()}, s, ring_around(s.observation));
  // Uploaded to the GPU by a batch before the projection is set again.
  gl->evaluate(H, from_gl);
  ASSERT_GT(gl->observation_count(), 0u);
  for (Renderer* r : {gl.get(), cpu.get()}) r->set_projection(s.projection, kScale);
  EXPECT_EQ(gl->observation_count(), cpu->observation_count());
  EXPECT_EQ(gl->observation_count(), 0u);
  gl->evaluate(H, from_gl);
  cpu->evaluate(H, from_cpu);
  ASSERT_EQ(from_gl.size(), from_cpu.size());
  int rendered = 0;
  for (size_t i = 0; i < from_gl.size(); ++i) {
    EXPECT_EQ(from_gl[i].intersection, from_cpu[i].intersection) << "hypothesis " << i;
    EXPECT_EQ(from_gl[i].rim, from_cpu[i].rim) << "hypothesis " << i;
    EXPECT_EQ(from_gl[i].intersection, 0u) << "hypothesis " << i;
    EXPECT_EQ(from_gl[i].rim, 0u) << "hypothesis " << i;
    EXPECT_TRUE(counts_agree(from_gl[i].rendered, from_cpu[i].rendered)) << "hypothesis " << i;
    rendered += from_gl[i].rendered > 0;
  }
  EXPECT_GT(rendered, 50);
}

TEST(GlRenderer, TheSlabKeepsOnlyWhatIsInsideIt) {
  GL_OR_SKIP(gl);
  const ArticulatedModel model(hydrogel_geometry());
  Eigen::VectorXd h = Eigen::VectorXd::Zero(model.dims());
  h.head<3>() << 0.3, -0.2, 40;  // on the plane, lying in it
  const Eigen::Matrix3d axes = gtrack::rotation_from_euler_deg(25, -15, 10);
  h.segment<3>(3) = gtrack::euler_deg_from_rotation(axes);
  gl->set_model(model);
  gl->set_projection(ultrasound_slab(0.6), kScale);
  const int flat = cv::countNonZero(gl->render_mask(h));
  EXPECT_GT(flat, 200);
  // Folded fingers rise out of the slab: less is imaged.
  for (int f = 0; f < model.fingers(); ++f) h[6 + f] = 80;
  EXPECT_LT(cv::countNonZero(gl->render_mask(h)), flat);
  // Moved off the plane by more than its own reach: nothing.
  h.head<3>() += axes.col(2) * 3.0;
  EXPECT_EQ(cv::countNonZero(gl->render_mask(h)), 0);
}

TEST(GlRenderer, BatchesOfAnySizeMatchOneAtATime) {
  GL_OR_SKIP(gl);
  Scene s{ArticulatedModel(hydrogel_geometry()), camera(), {}};
  const Eigen::MatrixXd H = camera_hypotheses(100, 3, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(8));
  gl->set_model(s.model);
  gl->set_projection(s.projection, kScale);
  gl->set_observation(s.observation);

  std::vector<PairCounts> single(static_cast<size_t>(H.cols())), out;
  for (int i = 0; i < H.cols(); ++i) {
    gl->evaluate(H.col(i), out);
    ASSERT_EQ(out.size(), 1u);
    single[static_cast<size_t>(i)] = out[0];
  }
  // Sizes around the 32-hypothesis layers, and empty.
  for (int n : {0, 1, 31, 32, 33, 64, 65, 100}) {
    gl->evaluate(H.leftCols(n), out);
    ASSERT_EQ(out.size(), static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(out[i].rendered, single[i].rendered) << "batch " << n << ", hypothesis " << i;
      EXPECT_EQ(out[i].intersection, single[i].intersection) << "batch " << n << ", hypothesis " << i;
    }
  }
}

// A batch larger than the render target's memory budget is drawn and
// counted in chunks: the counts are those of one draw, exactly. 1 MiB holds
// 4 layers of 256x256, 128 hypotheses.
TEST(GlRenderer, ABatchBeyondTheTargetBudgetIsCountedInChunks) {
  Scene s{ArticulatedModel(hydrogel_geometry()), camera(), {}};
  const Eigen::MatrixXd H = camera_hypotheses(300, 5, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(8));
  std::vector<PairCounts> whole, chunked;
  {
    GL_OR_SKIP(gl);
    gl->set_model(s.model);
    gl->set_projection(s.projection, kScale);
    gl->set_observation(s.observation);
    gl->evaluate(H, whole);
  }
  ScopedEnv budget("GTRACK_GL_TARGET_MB", "1");
  GL_OR_SKIP(gl);
  gl->set_model(s.model);
  gl->set_projection(s.projection, kScale);
  gl->set_observation(s.observation);
  for (int n : {300, 128, 129, 257, 40}) {
    gl->evaluate(H.leftCols(n), chunked);
    ASSERT_EQ(chunked.size(), static_cast<size_t>(n));
    int overlapping = 0;
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(chunked[i].rendered, whole[i].rendered) << "batch " << n << ", hypothesis " << i;
      EXPECT_EQ(chunked[i].intersection, whole[i].intersection) << "batch " << n << ", hypothesis " << i;
      EXPECT_EQ(chunked[i].rim, whole[i].rim) << "batch " << n << ", hypothesis " << i;
      overlapping += whole[i].intersection > 0;
    }
    EXPECT_GT(overlapping, 0) << "batch " << n;
  }
  ScopedEnv bad("GTRACK_GL_TARGET_MB", "0");
  EXPECT_THROW(gtrack::make_gl_renderer({}), gtrack::Error);
}

// A sensor may clip with up to 8 planes on either backend: a box around the
// gripper's volume (the near plane and six faces) cuts many hypotheses.
TEST(GlRenderer, AgreesWithCpuWithEightClipPlanes) {
  GL_OR_SKIP(gl);
  Projection p = camera();
  p.clip_planes.emplace_back(1, 0, 0, 3.0);    // x >= -3
  p.clip_planes.emplace_back(-1, 0, 0, 3.0);   // x <= 3
  p.clip_planes.emplace_back(0, 1, 0, 2.5);    // y >= -2.5
  p.clip_planes.emplace_back(0, -1, 0, 3.5);   // y <= 3.5
  p.clip_planes.emplace_back(0, 0, 1, -36);    // z >= 36
  p.clip_planes.emplace_back(0, 0, -1, 58);    // z <= 58
  p.clip_planes.emplace_back(0.6, 0.8, 0, 3);  // an oblique face
  ASSERT_EQ(p.clip_planes.size(), 8u);
  Scene s{ArticulatedModel(hydrogel_geometry()), p, {}};
  const Eigen::MatrixXd H = camera_hypotheses(64, 31, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(6));
  expect_agreement(*gl, s, H, 8);
}

// A gripper whose link table is smaller than the smallest buffer (two fingers
// of one link: 8 bytes) renders as the cpu backend does.
TEST(GlRenderer, AgreesWithCpuOnATwoFingerOneLinkGripper) {
  GL_OR_SKIP(gl);
  gtrack::RadialGripperSpec spec;
  spec.name = "two_single_links";
  spec.fingers = 2;
  spec.palm_sides = 4;
  spec.palm_circumradius_mm = 0.5;
  spec.links.push_back({0.6, 0.5, 0.3});
  gtrack::GripperGeometry g = gtrack::make_radial_gripper(spec);
  g.joint_min_deg = -10;
  g.joint_max_deg = 120;
  Scene s{ArticulatedModel(g), camera(), {}};
  const Eigen::MatrixXd H = camera_hypotheses(64, 21, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(6));
  expect_agreement(*gl, s, H, 8);
}

// The render target keeps the layers of the largest batch: a smaller batch
// after it, and a mask, see nothing of what the larger one drew there.
TEST(GlRenderer, ABatchAfterALargerOneSeesNothingOfIt) {
  GL_OR_SKIP(gl);
  Scene s{ArticulatedModel(hydrogel_geometry()), camera(), {}};
  const Eigen::MatrixXd H = camera_hypotheses(130, 5, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(8));
  auto cpu = make_cpu();
  set_scene({gl.get(), cpu.get()}, s);
  std::vector<PairCounts> want, got;
  cpu->evaluate(H, want);
  // Large, smaller, one, larger again, and the layer boundaries in between.
  for (int n : {130, 40, 1, 33, 130, 7}) {
    // A different slice each time, so that stale bits would change the counts.
    const int first = (n * 7) % (130 - n + 1);
    gl->evaluate(H.middleCols(first, n), got);
    ASSERT_EQ(got.size(), static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      EXPECT_TRUE(pair_counts_agree(got[i], want[first + i])) << "batch " << n << ", hypothesis " << i;
    }
    const cv::Mat mask = gl->render_mask(H.col(first));
    EXPECT_TRUE(masks_agree(mask, cpu->render_mask(H.col(first)))) << "mask after a batch of " << n;
  }
}

// The count pass is built with the rows per invocation the device wants
// (255 on llvmpipe, 32 on a GPU): every choice counts the same.
TEST(GlRenderer, CountsAreTheSameForAnyRowsPerInvocation) {
  Scene s{ArticulatedModel(hydrogel_geometry()), camera(), {}};
  const Eigen::MatrixXd H = camera_hypotheses(70, 8, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(6));
  auto cpu = make_cpu();
  cpu->set_model(s.model);
  cpu->set_projection(s.projection, kScale);
  cpu->set_observation(s.observation);
  std::vector<PairCounts> want, got;
  cpu->evaluate(H, want);
  for (const char* rows : {"1", "7", "32", "255"}) {
    ScopedEnv env("GTRACK_GL_COUNT_ROWS", rows);
    GL_OR_SKIP(gl);
    gl->set_model(s.model);
    gl->set_projection(s.projection, kScale);
    gl->set_observation(s.observation);
    gl->evaluate(H, got);
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < got.size(); ++i) {
      EXPECT_TRUE(pair_counts_agree(got[i], want[i])) << rows << " rows, hypothesis " << i;
    }
  }
  ScopedEnv bad("GTRACK_GL_COUNT_ROWS", "256");
  EXPECT_THROW(gtrack::make_gl_renderer({}), gtrack::Error);
}

TEST(GlRenderer, SubmitReturnsAndFinishCollects) {
  GL_OR_SKIP(gl);
  Scene s{ArticulatedModel(hydrogel_geometry()), camera(), {}};
  const Eigen::MatrixXd H = camera_hypotheses(64, 9, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(4));
  gl->set_model(s.model);
  gl->set_projection(s.projection, kScale);
  gl->set_observation(s.observation);
  std::vector<PairCounts> a, b;
  gl->evaluate(H, a);

  gl->submit(H);
  EXPECT_THROW(gl->submit(H), gtrack::Error);
  // The buffers the counts come back through may not be replaced meanwhile.
  EXPECT_THROW(gl->set_model(s.model), gtrack::Error);
  // A mask may be rendered while a batch is in flight; the batch keeps its counts.
  const cv::Mat m = gl->render_mask(H.col(5));
  gl->finish(b);
  EXPECT_THROW(gl->finish(b), gtrack::Error);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].rendered, b[i].rendered);
    EXPECT_EQ(a[i].intersection, b[i].intersection);
  }
  EXPECT_EQ(static_cast<std::uint32_t>(cv::countNonZero(m)), a[5].rendered);
}

TEST(GlRenderer, TwoRenderersInOneThreadKeepTheirOwnState) {
  GL_OR_SKIP(first);
  GL_OR_SKIP(second);
  const ArticulatedModel model(hydrogel_geometry());
  const Eigen::MatrixXd H = camera_hypotheses(40, 21, model.fingers());
  first->set_model(model);
  second->set_model(model);
  first->set_projection(camera(), kScale);
  second->set_projection(ultrasound_slab(0.6), kScale);
  std::vector<PairCounts> a1, b1, a2;
  first->evaluate(H, a1);
  second->evaluate(H, b1);
  first->evaluate(H, a2);
  ASSERT_EQ(a1.size(), a2.size());
  for (size_t i = 0; i < a1.size(); ++i) EXPECT_EQ(a1[i].rendered, a2[i].rendered);
  second.reset();  // the display stays up for the first
  first->evaluate(H, a2);
  for (size_t i = 0; i < a1.size(); ++i) EXPECT_EQ(a1[i].rendered, a2[i].rendered);
}

// The context is left current on no thread when the renderer is made: the
// first thread that uses the renderer takes it, even once its maker has ended.
TEST(GlRenderer, ARendererMadeOnAThreadThatEndedWorksOnAnother) {
  std::string skip;
  std::unique_ptr<Renderer> gl;
  std::exception_ptr error;
  std::thread([&] {
    try {
      gl = make_gl(skip);
    } catch (...) {
      error = std::current_exception();
    }
  }).join();
  if (error) std::rethrow_exception(error);
  if (!gl) GTEST_SKIP() << "no EGL context: " << skip;
  Scene s{ArticulatedModel(hydrogel_geometry()), camera(), {}};
  const Eigen::MatrixXd H = camera_hypotheses(40, 25, s.model.fingers());
  s.observation = observation_for(s, H.leftCols(4));
  auto cpu = make_cpu();
  set_scene({gl.get(), cpu.get()}, s);
  std::vector<PairCounts> from_gl, from_cpu;
  gl->evaluate(H, from_gl);
  cpu->evaluate(H, from_cpu);
  ASSERT_EQ(from_gl.size(), from_cpu.size());
  for (size_t i = 0; i < from_gl.size(); ++i) {
    EXPECT_TRUE(pair_counts_agree(from_gl[i], from_cpu[i])) << "hypothesis " << i;
  }
  EXPECT_TRUE(masks_agree(gl->render_mask(H.col(0)), cpu->render_mask(H.col(0))));
}

// A renderer works on a thread other than its maker's. Destroyed there, it
// says nothing; destroyed on another thread while the one that used it still
// holds its context, it cannot delete its objects: nothing is thrown, and a
// warning says so.
TEST(GlRenderer, ARendererUsedOnAnotherThreadMayBeDestroyedOnAThird) {
  const ArticulatedModel model(hydrogel_geometry());
  const Eigen::MatrixXd H = camera_hypotheses(40, 27, model.fingers());
  std::ostringstream log;
  gtrack::logger().sinks().push_back(std::make_shared<spdlog::sinks::ostream_sink_mt>(log));
  struct PopSink {
    ~PopSink() { gtrack::logger().sinks().pop_back(); }
  } pop_sink;
  for (const bool destroy_elsewhere : {false, true}) {
    SCOPED_TRACE(destroy_elsewhere ? "destroyed on a third thread" : "destroyed by its user");
    GL_OR_SKIP(gl);
    log.str("");
    std::vector<PairCounts> out;
    std::string error;
    std::promise<void> used, destroyed;
    std::thread user([&] {
      try {
        gl->set_model(model);
        gl->set_projection(camera(), kScale);
        gl->evaluate(H, out);
        if (!destroy_elsewhere) gl.reset();
      } catch (const std::exception& e) {
        error = e.what();
      }
      used.set_value();
      destroyed.get_future().wait();  // the context stays current here meanwhile
    });
    used.get_future().wait();
    if (destroy_elsewhere) std::thread([&] { gl.reset(); }).join();
    destroyed.set_value();
    user.join();
    EXPECT_EQ(error, "");
    EXPECT_EQ(gl, nullptr);
    ASSERT_EQ(out.size(), static_cast<size_t>(H.cols()));
    int rendered = 0;
    for (const PairCounts& c : out) rendered += c.rendered > 0;
    EXPECT_GT(rendered, 20);
    if (destroy_elsewhere) {
      EXPECT_NE(log.str().find("cannot be made current here (destroyed on a thread other than the one that used "
                               "it"),
                std::string::npos)
          << log.str();
    } else {
      EXPECT_EQ(log.str().find("[warning]"), std::string::npos) << log.str();
    }
  }
}

// A thread that used a renderer and ended lets its context go: another
// thread uses the renderer and destroys it, without a warning.
TEST(GlRenderer, ARendererUsedOnAThreadThatEndedWorksOnAnother) {
  const ArticulatedModel model(hydrogel_geometry());
  const Eigen::MatrixXd H = camera_hypotheses(40, 29, model.fingers());
  GL_OR_SKIP(gl);
  std::vector<PairCounts> there, here;
  std::string error;
  std::thread([&] {
    try {
      gl->set_model(model);
      gl->set_projection(camera(), kScale);
      gl->evaluate(H, there);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }).join();
  ASSERT_EQ(error, "");
  const std::string log = gtrack::testing::logged([&] {
    gl->evaluate(H, here);  // threw EGL_BAD_ACCESS while the ended thread held the context
    gl.reset();
  });
  ASSERT_EQ(here.size(), there.size());
  for (size_t i = 0; i < here.size(); ++i) EXPECT_EQ(here[i].rendered, there[i].rendered) << "hypothesis " << i;
  EXPECT_EQ(log.find("[warning]"), std::string::npos) << log;
}

TEST(GlRenderer, ReusesItsObjectsWhenSizesChange) {
  GL_OR_SKIP(gl);
  const ArticulatedModel model(hydrogel_geometry());
  const Eigen::MatrixXd H = camera_hypotheses(70, 4, model.fingers());
  auto cpu = make_cpu();
  std::vector<PairCounts> g, c;
  for (double scale : {0.25, 0.5, 0.125}) {
    for (Renderer* r : {gl.get(), cpu.get()}) {
      r->set_model(model);
      r->set_projection(camera(), scale);
    }
    gl->evaluate(H, g);
    cpu->evaluate(H, c);
    for (size_t i = 0; i < g.size(); ++i) {
      EXPECT_TRUE(counts_agree(g[i].rendered, c[i].rendered)) << "scale " << scale << ", hypothesis " << i;
    }
  }
}

TEST(GlRenderer, RejectsMisuseWithOneLine) {
  GL_OR_SKIP(gl);
  const ArticulatedModel model(hydrogel_geometry());
  std::vector<PairCounts> out;
  EXPECT_THROW(gl->submit(Eigen::MatrixXd::Zero(model.dims(), 1)), gtrack::Error);  // no model yet
  gl->set_model(model);
  EXPECT_THROW(gl->set_observation(cv::Mat::zeros(8, 8, CV_8UC1)), gtrack::Error);   // no projection yet
  gl->set_projection(camera(), kScale);
  EXPECT_THROW(gl->submit(Eigen::MatrixXd::Zero(model.dims() + 1, 2)), gtrack::Error);
  EXPECT_THROW(gl->set_observation(cv::Mat::zeros(8, 8, CV_8UC1)), gtrack::Error);
  EXPECT_THROW(gl->set_observation(cv::Mat::zeros(256, 256, CV_32FC1)), gtrack::Error);
  try {
    gl->finish(out);
    ADD_FAILURE() << "finish() without submit() was accepted";
  } catch (const gtrack::Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
}

TEST(GlRenderer, NamesAnUnknownDevice) {
  RenderOptions o;
  o.egl_device = "97";
  try {
    gtrack::make_gl_renderer(o);
    ADD_FAILURE() << "device 97 was accepted";
  } catch (const gtrack::Error& e) {
    const std::string m = e.what();
    if (m.rfind(kNoContext, 0) == 0) GTEST_SKIP() << m;
    EXPECT_NE(m.find("97"), std::string::npos) << m;
    EXPECT_NE(m.find("does not exist"), std::string::npos) << m;
  }
  o.egl_device = "gpu-please";
  EXPECT_THROW(gtrack::make_gl_renderer(o), gtrack::Error);
}

TEST(GlRenderer, SurfacelessCanBeChosen) {
  RenderOptions o;
  o.egl_device = "surfaceless";
  GL_OR_SKIP(gl, o);
  gl->set_model(ArticulatedModel(hydrogel_geometry()));
  gl->set_projection(camera(), kScale);
  Eigen::VectorXd h = Eigen::VectorXd::Zero(12);
  h[2] = 45;
  EXPECT_GT(cv::countNonZero(gl->render_mask(h)), 1000);
}

// Shader problems name the file, the driver's log, or the folders searched.
class ShaderFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("gtrack_gl_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_ / "shaders");
    fs::create_directories(dir_ / "empty");
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(ShaderFolder, AMissingShaderListsThePathsSearched) {
  ScopedEnv shaders("GTRACK_SHADER_DIR", (dir_ / "shaders").string());
  ScopedEnv data("GTRACK_DATA_DIR", (dir_ / "empty").string());
  try {
    std::string skip;
    auto r = make_gl(skip);
    if (!r) GTEST_SKIP() << skip;
    ADD_FAILURE() << "made a renderer without shaders";
  } catch (const gtrack::Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("not found"), std::string::npos) << m;
    EXPECT_NE(m.find((dir_ / "shaders").string()), std::string::npos) << m;
    EXPECT_NE(m.find((dir_ / "empty" / "shaders").string()), std::string::npos) << m;
  }
}

TEST_F(ShaderFolder, ACompileErrorNamesTheFileAndCarriesTheLog) {
  const fs::path source = fs::path(GTRACK_TEST_SOURCE_DIR) / "shaders";
  for (const auto& f : fs::directory_iterator(source)) fs::copy_file(f.path(), dir_ / "shaders" / f.path().filename());
  std::ofstream(dir_ / "shaders" / "hypotheses.frag", std::ios::app) << "\nthis is not glsl;\n";
  ScopedEnv shaders("GTRACK_SHADER_DIR", (dir_ / "shaders").string());
  try {
    std::string skip;
    auto r = make_gl(skip);
    if (!r) GTEST_SKIP() << skip;
    ADD_FAILURE() << "a broken shader compiled";
  } catch (const gtrack::Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("hypotheses.frag"), std::string::npos) << m;
    EXPECT_NE(m.find("compile"), std::string::npos) << m;
    EXPECT_NE(m.find("error"), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

// A stage is compiled from the prelude and several files: an error is named
// by the file it is in and its line there, whichever of the stage's files
// that is (pose.glsl comes before hypotheses.vert in the vertex stage).
TEST_F(ShaderFolder, ACompileErrorNamesTheFileAndLineOfTheError) {
  const fs::path source = fs::path(GTRACK_TEST_SOURCE_DIR) / "shaders";
  ScopedEnv shaders("GTRACK_SHADER_DIR", (dir_ / "shaders").string());
  for (const auto& [name, line] : {std::pair<std::string, int>{"pose.glsl", 13}, {"hypotheses.vert", 12}}) {
    SCOPED_TRACE(name);
    for (const auto& f : fs::directory_iterator(source)) {
      fs::copy_file(f.path(), dir_ / "shaders" / f.path().filename(), fs::copy_options::overwrite_existing);
    }
    // The broken line becomes line `line` of the file.
    std::vector<std::string> lines;
    {
      std::ifstream in(dir_ / "shaders" / name);
      for (std::string l; std::getline(in, l);) lines.push_back(l);
    }
    ASSERT_GT(lines.size(), static_cast<size_t>(line));
    lines.insert(lines.begin() + (line - 1), "this is not glsl;");
    {
      std::ofstream out(dir_ / "shaders" / name, std::ios::trunc);
      for (const std::string& l : lines) out << l << "\n";
    }
    try {
      std::string skip;
      auto r = make_gl(skip);
      if (!r) GTEST_SKIP() << skip;
      ADD_FAILURE() << "a broken shader compiled";
    } catch (const gtrack::Error& e) {
      const std::string m = e.what();
      const std::string where = (dir_ / "shaders" / name).string() + ":" + std::to_string(line);
      EXPECT_NE(m.find("cannot compile vertex shader " + where + ":"), std::string::npos) << m;
      EXPECT_NE(m.find("error"), std::string::npos) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
  }
}

// A tracker on the gl backend (its previous estimate's mask drawn on the
// CPU, its hypotheses on the GPU) follows a moving gripper as the cpu
// backend's does.
TEST(GlRenderer, ATrackerOnTheGlBackendFollowsTheGripperAsTheCpuOneDoes) {
  GL_OR_SKIP(gl);
  const gtrack::Setup setup = gtrack::testing::small_microscope_setup();
  const gtrack::EngineConfig config = gtrack::engine_config(setup);
  auto cpu = make_cpu();
  cpu->set_model(setup.model());
  cpu->set_projection(setup.sensor->projection(), 1.0);
  const auto truth = [](int i) {
    Eigen::VectorXd h(12);
    h << 0.2 + 0.04 * i, -0.1 + 0.02 * i, 100, 8, -5, 20 + 2 * i, 10, 12, 14, 10, 12, 14;
    return h;
  };
  gtrack::Tracker on_gl(setup, config, std::move(gl));
  gtrack::Tracker on_cpu(setup, config, make_cpu());
  for (int i = 0; i < 4; ++i) {
    const cv::Mat mask = cpu->render_mask(truth(i));
    cv::Mat image(mask.size(), CV_8UC3, cv::Scalar(120, 125, 130));
    image.setTo(cv::Scalar(60, 70, 200), mask);
    const gtrack::Estimate g = on_gl.process(image, i, i / 30.0, std::nullopt);
    const gtrack::Estimate c = on_cpu.process(image, i, i / 30.0, std::nullopt);
    EXPECT_NE(g.status, gtrack::TrackStatus::Lost) << "frame " << i;
    EXPECT_LT((g.hypothesis.head<2>() - truth(i).head<2>()).norm(), 0.05) << "frame " << i;
    EXPECT_LT((g.hypothesis.head<2>() - c.hypothesis.head<2>()).norm(), 0.05) << "frame " << i;
  }
}

}  // namespace
