// The benchmark scene and the timing loop behind bench.hpp.
#include "gtrack/bench.hpp"

#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

#include "gtrack/config.hpp"
#include "gtrack/cost.hpp"
#include "gtrack/error.hpp"
#include "gtrack/gripper.hpp"
#include "gtrack/observation.hpp"
#include "gtrack/plugin_loader.hpp"
#include "gtrack/pso.hpp"

namespace gtrack {

namespace {

// The hydrogel_six_finger plugin's default shape, for when it cannot be loaded.
GripperGeometry built_in_hydrogel() {
  RadialGripperSpec spec;
  spec.name = "hydrogel_six_finger";
  spec.palm_circumradius_mm = 0.65 / std::cos(std::numbers::pi / 6);
  const double lengths[] = {0.35, 0.35, 0.35, 0.30};
  const double widths[] = {0.60, 0.55, 0.50, 0.45, 0.0};
  for (int j = 0; j < 4; ++j) spec.links.push_back({lengths[j], widths[j], widths[j + 1]});
  return make_radial_gripper(spec);
}

}  // namespace

ArticulatedModel load_bench_gripper(const std::vector<std::filesystem::path>& plugin_paths, std::string& source) {
  try {
    PluginLoader loader(plugin_paths);
    const auto gripper = loader.make_gripper(ConfigTable::parse("plugin = \"hydrogel_six_finger\"\n", "<bench>"));
    source = "plugin hydrogel_six_finger";
    return gripper->model();  // a copy: the plugin may be unloaded afterwards
  } catch (const Error& e) {
    source = std::string("built-in hydrogel shape (plugin not loaded: ") + e.what() + ")";
    return ArticulatedModel(built_in_hydrogel());
  }
}

BenchScene make_bench_scene(const ArticulatedModel& model, int render_side, double gripper_px) {
  if (render_side < 16 || !(gripper_px > 0)) throw Error("bench scene: render side >= 16 and gripper size > 0 required");
  BenchScene s;
  s.model = model;
  s.scale = 0.25;
  const int full = static_cast<int>(std::lround(render_side / s.scale));
  const double z = 45.0;  // mm; only the ratio fx / z matters for the size
  const double fx = gripper_px / s.scale * z / (2.0 * model.radius_mm());
  s.projection.size = {full, full};
  s.projection.world_to_image << fx, 0, full / 2.0, 0, 0, fx, full / 2.0, 0, 0, 0, 1, 0;
  s.projection.clip_planes.push_back(Eigen::Vector4d(0, 0, 1, -1.0));
  s.gripper_px = gripper_px;
  s.nominal = Eigen::VectorXd::Zero(model.dims());
  s.nominal[2] = z;
  s.nominal.tail(model.fingers()).setConstant(20);
  RenderOptions one;
  one.threads = 1;
  auto r = make_cpu_renderer(one);
  r->set_model(model);
  r->set_projection(s.projection, s.scale);
  s.observation = r->render_mask(s.nominal);
  s.rim = occlusion_rim(s.observation, 1);
  return s;
}

Eigen::MatrixXd bench_hypotheses(const BenchScene& scene, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto U = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  const int dims = scene.model.dims();
  Eigen::MatrixXd H(dims, count);
  for (int i = 0; i < count; ++i) {
    H.col(i) = scene.nominal;
    H(0, i) += U(-0.3, 0.3);
    H(1, i) += U(-0.3, 0.3);
    H(2, i) += U(-2, 2);
    H(3, i) += U(-25, 25);
    H(4, i) += U(-25, 25);
    H(5, i) += U(-180, 180);
    for (int f = kPoseDims; f < dims; ++f) H(f, i) = U(-10, 80);
  }
  return H;
}

namespace {

using Clock = std::chrono::steady_clock;

void prepare(Renderer& renderer, const BenchScene& scene) {
  renderer.set_model(scene.model);
  renderer.set_projection(scene.projection, scene.scale);
  renderer.set_observation(scene.observation);
  renderer.set_rim(scene.rim);
}

double since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// K(H) from the model alone, for a cost without a plugin instance.
class ModelGripper final : public Gripper {
 public:
  explicit ModelGripper(const ArticulatedModel& model) : model_(model) {}
  const ArticulatedModel& model() const override { return model_; }

 private:
  const ArticulatedModel& model_;
};

}  // namespace

ThroughputResult measure_hypotheses(Renderer& renderer, const BenchScene& scene, double seconds, int batch) {
  if (batch < 1) throw Error("bench: the batch must hold at least one hypothesis");
  prepare(renderer, scene);
  // Distinct batches so that no backend can profit from a repeated input.
  constexpr int kBatches = 64;
  std::vector<Eigen::MatrixXd> batches;
  const Eigen::MatrixXd all = bench_hypotheses(scene, batch * kBatches, 1);
  for (int b = 0; b < kBatches; ++b) batches.push_back(all.middleCols(b * batch, batch));
  std::vector<PairCounts> out;
  for (int w = 0; w < 4; ++w) renderer.evaluate(batches[w], out);  // warm-up: pools, buffers, caches

  ThroughputResult r;
  r.backend = renderer.name();
  const auto start = Clock::now();
  size_t next = 0;
  do {
    for (int k = 0; k < 8; ++k) {
      renderer.evaluate(batches[next], out);
      next = (next + 1) % batches.size();
      r.count += static_cast<std::uint64_t>(batch);
    }
    r.seconds = since(start);
  } while (r.seconds < seconds);
  r.per_second = static_cast<double>(r.count) / r.seconds;
  return r;
}

ThroughputResult measure_pso_frames(Renderer& renderer, const BenchScene& scene, double seconds, int particles,
                                    int generations) {
  prepare(renderer, scene);
  const ArticulatedModel& m = scene.model;
  const Eigen::Vector3d p = scene.nominal.head<3>();
  const ParameterSpace space = ParameterSpace::make(
      m.fingers(), p - Eigen::Vector3d(1, 1, 5), p + Eigen::Vector3d(1, 1, 5), Eigen::Vector3d(-90, -90, -180),
      Eigen::Vector3d(90, 90, 180), m.geometry().joint_min_deg, m.geometry().joint_max_deg, true);
  PsoConfig config;
  config.particles = particles;
  config.generations = generations;
  const ParticleSwarm pso(config, space);
  ModelGripper gripper(m);
  CostEvaluator cost({&renderer}, gripper, nullptr, CostWeights{});
  const BatchObjective objective = [&](const Eigen::MatrixXd& h, Eigen::VectorXd& c) { cost.evaluate(h, c); };
  // The spread a tracker uses between frames: tenths of a millimetre, ten degrees.
  Eigen::VectorXd spread = Eigen::VectorXd::Constant(m.dims(), 10.0);
  spread.head<3>() << 0.2, 0.2, 1.0;
  std::mt19937_64 rng(1);
  auto frame = [&] {
    const Eigen::MatrixXd initial = biased_initial_swarm(scene.nominal, spread, 0.5, particles, space, rng);
    pso.run(initial, objective, rng);
  };
  frame();  // warm-up

  ThroughputResult r;
  r.backend = renderer.name();
  const auto start = Clock::now();
  do {
    frame();
    ++r.count;
    r.seconds = since(start);
  } while (r.seconds < seconds);
  r.per_second = static_cast<double>(r.count) / r.seconds;
  return r;
}

}  // namespace gtrack
