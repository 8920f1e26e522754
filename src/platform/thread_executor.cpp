// A std::thread pool behind the Executor interface (hosted builds only).
#include "splintcore/platform.h"

namespace splintcore {

ThreadExecutor::ThreadExecutor(unsigned threads) {
  threads_ = threads == 0 ? 1 : (threads > kMaxThreads ? kMaxThreads : threads);
  executor_.run = &ThreadExecutor::run;
  executor_.self = this;
  executor_.concurrency = threads_;
  // The calling thread works too, so threads_ - 1 helpers.
  for (unsigned i = 0; i + 1 < threads_; ++i) {
    workers_[i] = std::thread([this] { worker_loop(); });
  }
}

ThreadExecutor::~ThreadExecutor() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (unsigned i = 0; i + 1 < threads_; ++i) workers_[i].join();
}

void ThreadExecutor::drain() {
  for (;;) {
    uint32_t i = next_.fetch_add(1, std::memory_order_relaxed);
    if (i >= count_) return;
    task_(context_, i);
  }
}

void ThreadExecutor::worker_loop() {
  uint64_t seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
    }
    drain();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++finished_workers_;
    }
    done_.notify_one();
  }
}

void ThreadExecutor::run(void* self, uint32_t count, TaskFunction task, void* context) {
  ThreadExecutor* pool = static_cast<ThreadExecutor*>(self);
  if (pool->threads_ == 1) {
    for (uint32_t i = 0; i < count; ++i) task(context, i);
    return;
  }
  std::lock_guard<std::mutex> run_lock(pool->run_mutex_);
  {
    std::lock_guard<std::mutex> lock(pool->mutex_);
    pool->task_ = task;
    pool->context_ = context;
    pool->count_ = count;
    pool->next_.store(0, std::memory_order_relaxed);
    pool->finished_workers_ = 0;
    ++pool->generation_;
  }
  pool->wake_.notify_all();
  pool->drain();
  std::unique_lock<std::mutex> lock(pool->mutex_);
  pool->done_.wait(lock, [&] { return pool->finished_workers_ == pool->threads_ - 1; });
}

}  // namespace splintcore
