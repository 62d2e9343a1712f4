// Hypotheses per second of the cpu backend (1 thread and all threads), the
// gl backend when one can be made, and the OpenCV baseline: the hydrogel
// gripper ~114 px across at 256x256, batches of 32 random hypotheses near a
// nominal pose. items_per_second is hypotheses per second.
#include <benchmark/benchmark.h>

#include <functional>
#include <gtrack/bench.hpp>
#include <gtrack/error.hpp>
#include <gtrack/renderer.hpp>
#include <thread>

namespace {

const gtrack::BenchScene& scene() {
  static const gtrack::BenchScene s = [] {
    std::string source;
    gtrack::ArticulatedModel model = gtrack::load_bench_gripper({}, source);
    return gtrack::make_bench_scene(model, 256, 114);
  }();
  return s;
}

using Factory = std::function<std::unique_ptr<gtrack::Renderer>(const gtrack::RenderOptions&)>;

void run(benchmark::State& state, const Factory& make, int threads) {
  gtrack::RenderOptions options;
  options.threads = threads;
  std::unique_ptr<gtrack::Renderer> renderer;
  try {
    renderer = make(options);
  } catch (const gtrack::Error& e) {
    state.SkipWithError(e.what());
    return;
  }
  const auto& s = scene();
  renderer->set_model(s.model);
  renderer->set_projection(s.projection, s.scale);
  renderer->set_observation(s.observation);
  renderer->set_rim(s.rim);
  constexpr int kBatch = 32, kBatches = 64;
  const Eigen::MatrixXd all = gtrack::bench_hypotheses(s, kBatch * kBatches, 1);
  std::vector<Eigen::MatrixXd> batches;
  for (int b = 0; b < kBatches; ++b) batches.push_back(all.middleCols(b * kBatch, kBatch));
  std::vector<gtrack::PairCounts> out;
  renderer->evaluate(batches[0], out);
  size_t next = 0;
  for (auto _ : state) {
    renderer->evaluate(batches[next], out);
    benchmark::DoNotOptimize(out.data());
    next = (next + 1) % batches.size();
  }
  state.SetItemsProcessed(state.iterations() * kBatch);
  state.counters["threads"] = threads;
}

int all_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

void BM_cpu_1_thread(benchmark::State& st) { run(st, gtrack::make_cpu_renderer, 1); }
void BM_cpu_all_threads(benchmark::State& st) { run(st, gtrack::make_cpu_renderer, all_threads()); }
void BM_gl(benchmark::State& st) { run(st, gtrack::make_gl_renderer, 0); }
void BM_opencv_baseline_1_thread(benchmark::State& st) { run(st, gtrack::make_opencv_baseline, 1); }
void BM_opencv_baseline_all_threads(benchmark::State& st) { run(st, gtrack::make_opencv_baseline, all_threads()); }

}  // namespace

BENCHMARK(BM_cpu_1_thread)->UseRealTime()->MinTime(1.0);
BENCHMARK(BM_cpu_all_threads)->UseRealTime()->MinTime(1.0);
BENCHMARK(BM_gl)->UseRealTime()->MinTime(1.0);
BENCHMARK(BM_opencv_baseline_1_thread)->UseRealTime()->MinTime(1.0);
BENCHMARK(BM_opencv_baseline_all_threads)->UseRealTime()->MinTime(1.0);

BENCHMARK_MAIN();
