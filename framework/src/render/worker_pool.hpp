// A small persistent thread pool for batches of independent items.
//
// A PSO generation is ~32 hypotheses of a few microseconds each, so waking
// threads must cost far less than a batch: workers spin briefly on an atomic
// generation counter before sleeping on it, the caller takes part as worker
// 0, and items are handed out one at a time from an atomic counter so that
// uneven hypotheses (a folded gripper is smaller) balance themselves. Nothing
// is allocated per batch.
#pragma once

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace gtrack::render {

class WorkerPool {
 public:
  // `threads` participants in all, the caller included; 0 = hardware concurrency.
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return static_cast<int>(threads_.size()) + 1; }

  // Calls fn(worker, item) for every item in [0, items), spread over the
  // workers; returns when all are done. Not re-entrant.
  template <class Fn>
  void run(int items, Fn& fn) {
    run_erased(items, &fn, [](void* ctx, int worker, int item) { (*static_cast<Fn*>(ctx))(worker, item); });
  }

 private:
  using Trampoline = void (*)(void*, int, int);
  void run_erased(int items, void* ctx, Trampoline call);
  void work(int worker);
  void drain(int worker);

  std::vector<std::thread> threads_;
  // Job of the current generation; written before `generation_` is bumped.
  void* ctx_ = nullptr;
  Trampoline call_ = nullptr;
  int items_ = 0;
  alignas(64) std::atomic<int> next_{0};
  alignas(64) std::atomic<std::uint32_t> generation_{0};
  alignas(64) std::atomic<int> busy_{0};
  std::atomic<bool> stop_{false};
};

}  // namespace gtrack::render
