// A small persistent thread pool for batches of independent items.
//
// A PSO generation is ~32 hypotheses of a few microseconds each, so handing
// out a batch must cost far less than the batch: the caller takes part as
// worker 0, items are claimed one at a time from one atomic word (so uneven
// hypotheses balance themselves: a folded gripper is smaller), and idle
// workers spin briefly before sleeping on that word. The caller waits only
// for the items to be finished, never for a worker to check in, so a worker
// that the OS has not scheduled yet (a busy machine) does not hold a batch
// up: the others take its share. Nothing is allocated per batch.
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
  void run_batch(int first, int items);
  void work(int worker);
  void drain(int worker, std::uint64_t generation);

  std::vector<std::thread> threads_;
  // The batch: generation, item count and next unclaimed item in one word,
  // so that a claim is one compare-and-swap that also checks the generation.
  alignas(64) std::atomic<std::uint64_t> job_{0};
  alignas(64) std::atomic<int> done_{0};
  // Written by the caller before a batch is published in job_.
  void* ctx_ = nullptr;
  Trampoline call_ = nullptr;
  int offset_ = 0;  // item number of the batch's first item
  std::uint64_t generation_ = 0;
  std::atomic<bool> stop_{false};
};

}  // namespace gtrack::render
