// Reading and writing beside the search: the next frame is decoded, and the
// last overlay encoded, on threads of their own while the tracker works on
// the current frame (a 1024x1024 PNG takes about 23 ms to decode, as long as
// a frame's search at N = 32, G = 25 on two cores; on a GPU the search is the
// shorter). The frames, their order and every estimate are the same as read
// and written in turn; a reader's error reaches the tracker at the frame it
// stopped at, after the frames before it.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "gtrack/frame_source.hpp"

namespace gtrack::detail {

// A bounded queue between one producer and one consumer. push() waits while
// it is full, pop() while it is empty; close() ends both waits: push() then
// refuses, pop() gives what is left and then nothing.
template <class T>
class Handoff {
 public:
  explicit Handoff(std::size_t capacity) : capacity_(capacity > 0 ? capacity : 1) {}

  bool push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    space_.wait(lock, [&] { return closed_ || items_.size() < capacity_; });
    if (closed_) return false;
    items_.push_back(std::move(item));
    ready_.notify_one();
    return true;
  }

  // As push(), but a full queue has its newest item replaced instead of
  // being waited on. `replaced`: whether one was.
  bool push_over(T item, bool& replaced) {
    std::lock_guard<std::mutex> lock(mutex_);
    replaced = false;
    if (closed_) return false;
    if (items_.size() >= capacity_) {
      items_.back() = std::move(item);
      replaced = true;
    } else {
      items_.push_back(std::move(item));
    }
    ready_.notify_one();
    return true;
  }

  // `tick`, when given, is called every 50 ms of waiting (without the lock).
  std::optional<T> pop(const std::function<void()>& tick = {}) {
    std::unique_lock<std::mutex> lock(mutex_);
    while (items_.empty() && !closed_) {
      if (!tick) {
        ready_.wait(lock);
        continue;
      }
      if (!ready_.wait_for(lock, std::chrono::milliseconds(50), [&] { return closed_ || !items_.empty(); })) {
        lock.unlock();
        tick();
        lock.lock();
      }
    }
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    space_.notify_one();
    return item;
  }

  void close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    ready_.notify_all();
    space_.notify_all();
  }

 private:
  std::size_t capacity_;
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  std::deque<T> items_;
  bool closed_ = false;
};

// A frame source read ahead on a thread of its own: one frame waiting for
// the tracker, the next being read. `halt` is the flag the source was
// opened to stop waiting at (FollowOptions::cancel): it is raised when
// `cancel` is, while the tracker waits for a frame, and when the reader is
// stopped. The source's fps, length and description do not
// change as it is read; ended_early() is read once stop() has returned.
// `newest`: the reader does not wait for the tracker; a frame read while the
// one before it is still waiting takes its place (a live source faster than
// the tracker: the tracker then always gets the newest frame, and the frames
// left out are counted in skipped()).
class ReadAhead {
 public:
  ReadAhead(FrameSource& source, std::atomic<bool>& halt, const std::atomic<bool>* cancel, bool newest = false)
      : source_(source), halt_(halt), cancel_(cancel), newest_(newest), thread_([this] { run(); }) {}
  ~ReadAhead() { stop(); }
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;

  // The next frame, nullopt at the source's end; the reader's error is
  // thrown here, in its place among the frames. `waited_s`: how long this
  // call waited for the reader.
  std::optional<Frame> next(double& waited_s) {
    const auto t0 = std::chrono::steady_clock::now();
    std::optional<Item> item = queue_.pop([this] {
      if (cancel_ && cancel_->load()) halt_.store(true);
    });
    waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!item) return std::nullopt;
    if (item->error) std::rethrow_exception(item->error);
    return std::move(item->frame);
  }

  void stop() {
    halt_.store(true);
    queue_.close();
    if (thread_.joinable()) thread_.join();
  }

  // Frames read and left out for a newer one (`newest`).
  int skipped() const { return skipped_.load(); }

 private:
  struct Item {
    std::optional<Frame> frame;
    std::exception_ptr error;
  };

  void run() {
    for (;;) {
      Item item;
      try {
        item.frame = source_.next();
        if (item.frame) {
          item.frame->read_unix_s =
              std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
        }
      } catch (...) {
        item.error = std::current_exception();
      }
      const bool last = !item.frame;
      // The end and an error wait their turn: they never take a frame's place.
      bool replaced = false;
      if (!(newest_ && !last ? queue_.push_over(std::move(item), replaced) : queue_.push(std::move(item))) || last) {
        break;
      }
      if (replaced) skipped_.fetch_add(1);
    }
    queue_.close();
  }

  FrameSource& source_;
  std::atomic<bool>& halt_;
  const std::atomic<bool>* cancel_;
  const bool newest_;
  std::atomic<int> skipped_{0};
  Handoff<Item> queue_{1};
  std::thread thread_;  // last: started once the rest is set up
};

// Work handed to a thread of its own, a few items at a time (the overlay's
// frames to encode): `consume` runs there, in order. An error it throws is
// thrown by the next give() or by finish(), and what comes after it is
// dropped.
template <class T>
class Behind {
 public:
  Behind(std::size_t depth, std::function<void(T&)> consume)
      : consume_(std::move(consume)), queue_(depth), thread_([this] { run(); }) {}
  ~Behind() {
    queue_.close();
    if (thread_.joinable()) thread_.join();
  }
  Behind(const Behind&) = delete;
  Behind& operator=(const Behind&) = delete;

  void give(T item) {
    rethrow();
    queue_.push(std::move(item));
  }
  // Waits for what was given to be consumed.
  void finish() {
    queue_.close();
    if (thread_.joinable()) thread_.join();
    rethrow();
  }

 private:
  void run() {
    while (std::optional<T> item = queue_.pop()) {
      try {
        consume_(*item);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!error_) error_ = std::current_exception();
        queue_.close();
        return;  // what is still queued is dropped with the queue
      }
    }
  }
  void rethrow() {
    std::exception_ptr error;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      std::swap(error, error_);
    }
    if (error) std::rethrow_exception(error);
  }

  std::function<void(T&)> consume_;
  Handoff<T> queue_;
  std::mutex mutex_;
  std::exception_ptr error_;
  std::thread thread_;  // last: started once the rest is set up
};

}  // namespace gtrack::detail
