#pragma once
// Worker threads kept from one parallel loop to the next.
//
// Starting and joining a thread costs tens of microseconds (20 us for clone3 alone on the CI's
// VM), and the library used to pay that for every thread of every parallel loop: the CPU hash's
// passes, the CPU query, updateVertices' and commitVertices' check, the CUDA backend's staged
// uploads. On small meshes that made two threads slower than one (benchmarks/RESULTS.md, "Kept
// worker threads"). A pool's workers wait on a condition variable between jobs instead.
//
// run(threads, work) runs `work` on the calling thread and on up to threads - 1 workers, each
// at most once. `work` is a loop over shared items that ends when they run out (an atomic
// counter, as forEachChunk deals chunks): it must give the same result whoever runs how much of
// it, since a worker that joins late, or never (all busy with other callers' jobs, or no thread
// could be started), simply leaves its share to the others. So the caller never waits for a
// worker to wake: when its own work() returns, the job closes, and the caller waits only for the
// workers already inside it. That also makes every use safe to nest and to call from several
// threads at once: each caller finishes its own job alone if need be.
//
// The process-wide pool (shared()) is never destroyed (its workers wait in the library until the
// process ends; the library is linked with -z nodelete, so dlclose cannot unmap their code), and
// a child of fork() gets a new, empty one (its parent's workers do not exist there).

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace kdet_fcl {
namespace cpu {

class WorkerPool {
 public:
  /// At most this many workers per pool (a request for more threads runs on fewer).
  static constexpr int kMaxWorkers = 256;

  WorkerPool() = default;
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;
  /// Stops and joins the workers. No run() may be in progress.
  ~WorkerPool();

  /// Runs `work` on the calling thread and on up to threads - 1 of this pool's workers (each at
  /// most once), and returns when every one that started it has returned. Workers are started
  /// as needed (so that an idle pool has threads - 1 free for this job) and kept; where one
  /// cannot be started, fewer run. `work` must not throw on a worker (that ends the process);
  /// an exception on the calling thread comes out once the job has closed and its workers have
  /// left it. Safe to call from several threads at once and from inside a job of this pool.
  void run(int threads, const std::function<void()>& work);

  /// Workers started so far.
  int workers() const;

  /// The process-wide pool of the library's parallel loops (forEachChunk, the staged uploads).
  static WorkerPool& shared();

 private:
  struct Job {
    Job(const std::function<void()>* w, int n) : work(w), wanted(n) {}
    const std::function<void()>* work;
    int wanted;      // workers it may still take (it is queued while > 0)
    int active = 0;  // workers inside work()
    std::condition_variable done;
  };

  void loop();

  mutable std::mutex m_;
  std::condition_variable wake_;
  std::deque<Job*> queue_;
  std::vector<std::thread> threads_;
  int idle_ = 0;  // workers not inside a job (waiting, or started and yet to wait)
  bool stop_ = false;
};

}  // namespace cpu
}  // namespace kdet_fcl
