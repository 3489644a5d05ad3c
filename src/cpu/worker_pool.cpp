#include "cpu/worker_pool.h"

#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <new>
#include <system_error>

namespace kdet_fcl {
namespace cpu {

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(m_);
    stop_ = true;
  }
  wake_.notify_all();
  for (auto& t : threads_) t.join();
}

void WorkerPool::loop() {
  std::unique_lock<std::mutex> lock(m_);
  while (true) {  // (counted idle from its start: run() counts it so before it gets here)
    wake_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    if (stop_) return;
    --idle_;
    Job* job = queue_.front();
    if (--job->wanted == 0) queue_.pop_front();
    ++job->active;
    lock.unlock();
    (*job->work)();
    lock.lock();
    // (Under the lock: the caller leaves, and its Job with it, only after it has seen 0.)
    if (--job->active == 0) job->done.notify_one();
    ++idle_;
  }
}

void WorkerPool::run(int threads, const std::function<void()>& work) {
  const int helpers = std::min(threads, kMaxWorkers + 1) - 1;
  if (helpers <= 0) {
    work();
    return;
  }
  Job job{&work, helpers};
  bool queued = false;
  {
    std::lock_guard<std::mutex> lock(m_);
    // Workers already promised to queued jobs are not free for this one.
    int spare = idle_;
    for (const Job* q : queue_) spare -= q->wanted;
    int start = std::min(helpers - std::max(spare, 0),
                         kMaxWorkers - static_cast<int>(threads_.size()));
    for (; start > 0; --start) {
      try {
        threads_.emplace_back([this] { loop(); });
        ++idle_;  // (free for a job from now on, though it has yet to take the lock)
      } catch (const std::system_error&) {
        break;  // no more threads: the ones there (and the caller) do the work
      } catch (const std::bad_alloc&) {
        break;
      }
    }
    if (!threads_.empty()) {
      queue_.push_back(&job);
      queued = true;
    }
  }
  if (queued)
    for (int i = 0; i < helpers; ++i) wake_.notify_one();
  std::exception_ptr error;  // (the contract says none; if one comes, the job closes first)
  try {
    work();
  } catch (...) {
    error = std::current_exception();
  }
  if (queued) {
    std::unique_lock<std::mutex> lock(m_);
    if (job.wanted > 0) {  // still queued: close it to workers that have not taken it
      const auto at = std::find(queue_.begin(), queue_.end(), &job);
      if (at != queue_.end()) queue_.erase(at);
    }
    job.done.wait(lock, [&] { return job.active == 0; });
  }
  if (error) std::rethrow_exception(error);
}

int WorkerPool::workers() const {
  std::lock_guard<std::mutex> lock(m_);
  return static_cast<int>(threads_.size());
}

namespace {

std::atomic<WorkerPool*> shared_pool{nullptr};

/// In a child of fork(): the parent's workers do not exist here, and the pool's mutex may have
/// been held by one of them; the child starts a new pool. The old one is left as it is (freeing
/// it would join threads that are not there).
void newPoolInChild() { shared_pool.store(new WorkerPool, std::memory_order_release); }

}  // namespace

WorkerPool& WorkerPool::shared() {
  static const bool ready = [] {
    shared_pool.store(new WorkerPool, std::memory_order_release);
    (void)pthread_atfork(nullptr, nullptr, newPoolInChild);
    return true;
  }();
  (void)ready;
  return *shared_pool.load(std::memory_order_acquire);
}

}  // namespace cpu
}  // namespace kdet_fcl
