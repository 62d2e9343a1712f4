// WorkerPool: claims by compare-and-swap, spin-then-sleep over C++20 atomic wait.
#include "render/worker_pool.hpp"

#include <algorithm>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace gtrack::render {

namespace {

// job_ = generation (24 bits) | items (20 bits) | next item (20 bits).
constexpr int kIndexBits = 20;
constexpr std::uint64_t kIndexMask = (std::uint64_t{1} << kIndexBits) - 1;
constexpr int kMaxBatch = static_cast<int>(kIndexMask);
constexpr std::uint64_t kGenerationMask = (std::uint64_t{1} << 24) - 1;

std::uint64_t generation_of(std::uint64_t job) { return job >> (2 * kIndexBits); }
int items_of(std::uint64_t job) { return static_cast<int>((job >> kIndexBits) & kIndexMask); }
int next_of(std::uint64_t job) { return static_cast<int>(job & kIndexMask); }

// Long enough (~0.2 ms here) to bridge the caller's bookkeeping between two
// generations of a PSO, short enough not to burn a core between frames.
constexpr int kSpins = 4000;

inline void relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

template <class T, class Pred>
T spin_then_wait(const std::atomic<T>& a, Pred done) {
  for (int i = 0; i < kSpins; ++i) {
    const T v = a.load(std::memory_order_acquire);
    if (done(v)) return v;
    relax();
  }
  for (;;) {
    const T v = a.load(std::memory_order_acquire);
    if (done(v)) return v;
    a.wait(v, std::memory_order_acquire);
  }
}

}  // namespace

WorkerPool::WorkerPool(int threads) {
  if (threads <= 0) threads = static_cast<int>(std::thread::hardware_concurrency());
  if (threads <= 0) threads = 1;
  threads_.reserve(threads - 1);
  for (int w = 1; w < threads; ++w) threads_.emplace_back([this, w] { work(w); });
}

WorkerPool::~WorkerPool() {
  stop_.store(true, std::memory_order_release);
  job_.fetch_add(std::uint64_t{1} << (2 * kIndexBits), std::memory_order_acq_rel);  // a new generation wakes all
  job_.notify_all();
  for (auto& t : threads_) t.join();
}

void WorkerPool::drain(int worker, std::uint64_t generation) {
  std::uint64_t job = job_.load(std::memory_order_acquire);
  for (;;) {
    if (generation_of(job) != generation || next_of(job) >= items_of(job)) return;
    if (!job_.compare_exchange_weak(job, job + 1, std::memory_order_acq_rel, std::memory_order_acquire)) continue;
    // The claim orders this after the batch was published, and the caller
    // waits for this item, so ctx_ and call_ are the batch's.
    call_(ctx_, worker, offset_ + next_of(job));
    const int items = items_of(job);
    if (done_.fetch_add(1, std::memory_order_acq_rel) + 1 == items) done_.notify_one();
    job = job_.load(std::memory_order_acquire);
  }
}

void WorkerPool::run_batch(int first, int items) {
  offset_ = first;
  done_.store(0, std::memory_order_relaxed);
  generation_ = (generation_ + 1) & kGenerationMask;
  job_.store((generation_ << (2 * kIndexBits)) | (static_cast<std::uint64_t>(items) << kIndexBits),
             std::memory_order_release);
  job_.notify_all();
  drain(0, generation_);
  spin_then_wait(done_, [items](int v) { return v == items; });
}

void WorkerPool::run_erased(int items, void* ctx, Trampoline call) {
  if (items <= 0) return;
  if (threads_.empty() || items == 1) {
    for (int i = 0; i < items; ++i) call(ctx, 0, i);
    return;
  }
  ctx_ = ctx;
  call_ = call;
  for (int first = 0; first < items; first += kMaxBatch) run_batch(first, std::min(kMaxBatch, items - first));
}

void WorkerPool::work(int worker) {
  std::uint64_t seen = 0;
  for (;;) {
    const std::uint64_t job =
        spin_then_wait(job_, [seen](std::uint64_t v) { return generation_of(v) != seen; });
    if (stop_.load(std::memory_order_acquire)) return;
    seen = generation_of(job);
    drain(worker, seen);
  }
}

}  // namespace gtrack::render
