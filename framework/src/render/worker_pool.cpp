// WorkerPool: spin-then-sleep hand-off over C++20 atomic wait/notify.
#include "render/worker_pool.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace gtrack::render {

namespace {

// Long enough to bridge the caller's bookkeeping between two generations of
// a PSO, short enough not to burn a core while the tracker waits for a frame.
constexpr int kSpins = 4000;

inline void relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

template <class T, class Pred>
void spin_then_wait(const std::atomic<T>& a, Pred done) {
  for (int i = 0; i < kSpins; ++i) {
    if (done(a.load(std::memory_order_acquire))) return;
    relax();
  }
  for (T v = a.load(std::memory_order_acquire); !done(v); v = a.load(std::memory_order_acquire)) a.wait(v);
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
  generation_.fetch_add(1, std::memory_order_acq_rel);
  generation_.notify_all();
  for (auto& t : threads_) t.join();
}

void WorkerPool::drain(int worker) {
  for (int i = next_.fetch_add(1, std::memory_order_relaxed); i < items_;
       i = next_.fetch_add(1, std::memory_order_relaxed)) {
    call_(ctx_, worker, i);
  }
}

void WorkerPool::run_erased(int items, void* ctx, Trampoline call) {
  if (items <= 0) return;
  if (threads_.empty() || items == 1) {
    for (int i = 0; i < items; ++i) call(ctx, 0, i);
    return;
  }
  ctx_ = ctx;
  call_ = call;
  items_ = items;
  next_.store(0, std::memory_order_relaxed);
  busy_.store(static_cast<int>(threads_.size()), std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_acq_rel);
  generation_.notify_all();
  drain(0);
  // The job lives on the caller's stack: wait until no worker can touch it.
  spin_then_wait(busy_, [](int v) { return v == 0; });
}

void WorkerPool::work(int worker) {
  std::uint32_t seen = 0;
  for (;;) {
    spin_then_wait(generation_, [seen](std::uint32_t v) { return v != seen; });
    seen = generation_.load(std::memory_order_acquire);
    if (stop_.load(std::memory_order_acquire)) return;
    drain(worker);
    if (busy_.fetch_sub(1, std::memory_order_acq_rel) == 1) busy_.notify_one();
  }
}

}  // namespace gtrack::render
