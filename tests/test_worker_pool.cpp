// The library's kept worker threads (src/cpu/worker_pool.h) and the parallel loop on top of them
// (src/cpu/parallel.h): every item once whoever runs it, helpers that join a job that waits for
// them, workers kept and never more than asked for, callers on several threads at once, nested
// jobs, exceptions, a child of fork(), and threads that cannot be started.

#include <gtest/gtest.h>
#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "cpu/parallel.h"
#include "cpu/worker_pool.h"
#include "oom_util.h"

namespace {

using kdet_fcl::cpu::WorkerPool;
using Clock = std::chrono::steady_clock;

/// Work that waits (up to 20 s) until `threads` threads are inside it, recording each one's id:
/// a job that keeps its caller busy until every helper asked for has joined.
struct Rendezvous {
  explicit Rendezvous(int n) : threads(n), ids(static_cast<std::size_t>(n)) {}
  int threads;
  std::atomic<int> arrived{0};
  std::vector<std::thread::id> ids;
  std::atomic<int> recorded{0};

  std::function<void()> work() {
    return [this] {
      const int me = arrived.fetch_add(1);
      if (me < threads) ids[std::size_t(me)] = std::this_thread::get_id();
      recorded.fetch_add(1);
      const auto until = Clock::now() + std::chrono::seconds(20);
      while (recorded.load() < threads && Clock::now() < until) std::this_thread::yield();
    };
  }
  int distinct() {
    std::vector<std::thread::id> v(ids.begin(), ids.begin() + std::min(arrived.load(), threads));
    std::sort(v.begin(), v.end());
    return int(std::unique(v.begin(), v.end()) - v.begin());
  }
};

/// A chunked sum over [0, n) on `threads` threads of `pool`, each item claimed once by an
/// atomic counter (the shape of every job in the library).
std::uint64_t pooledSum(WorkerPool& pool, int threads, std::uint64_t n, std::atomic<int>* runs) {
  std::atomic<std::uint64_t> next{0}, sum{0};
  const std::function<void()> work = [&] {
    if (runs) runs->fetch_add(1);
    std::uint64_t mine = 0;
    for (std::uint64_t i = next.fetch_add(1); i < n; i = next.fetch_add(1)) mine += i;
    sum.fetch_add(mine);
  };
  pool.run(threads, work);
  return sum.load();
}

}  // namespace

TEST(WorkerPool, EveryThreadAskedForJoinsAJobThatWaitsForThemAndWorkersAreKept) {
  WorkerPool pool;
  int most = 1;
  for (int threads : {1, 3, 4, 2, 4, 6}) {
    most = std::max(most, threads);
    Rendezvous r(threads);
    pool.run(threads, r.work());
    EXPECT_EQ(r.arrived.load(), threads) << threads << " threads: each runs the work once";
    EXPECT_EQ(r.distinct(), threads) << "each on its own thread";
    EXPECT_EQ(pool.workers(), most - 1) << "workers are kept, never more than asked for";
  }
}

TEST(WorkerPool, EveryItemOnceWhateverTheThreadsAndTheWorkRunsAtMostThreadsTimes) {
  WorkerPool pool;
  for (int round = 0; round < 200; ++round) {
    const int threads = 1 + round % 7;
    const std::uint64_t n = std::uint64_t(round) * 37 % 1000;
    std::atomic<int> runs{0};
    ASSERT_EQ(pooledSum(pool, threads, n, &runs), n * (n - 1) / 2)  // (0 for n = 0)
        << "round " << round;
    EXPECT_GE(runs.load(), 1);
    EXPECT_LE(runs.load(), threads);
  }
  EXPECT_LE(pool.workers(), 6);
}

TEST(WorkerPool, CallersOnSeveralThreadsAtOnceEachGetTheirWholeResult) {
  WorkerPool pool;
  constexpr int kCallers = 8, kJobs = 150;
  std::atomic<int> wrong{0};
  std::vector<std::thread> callers;
  for (int c = 0; c < kCallers; ++c)
    callers.emplace_back([&, c] {
      for (int j = 0; j < kJobs; ++j) {
        const std::uint64_t n = 500 + std::uint64_t(c * kJobs + j) % 300;
        if (pooledSum(pool, 2 + (c + j) % 4, n, nullptr) != n * (n - 1) / 2) wrong.fetch_add(1);
      }
    });
  for (auto& t : callers) t.join();
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_GE(pool.workers(), 1);
  EXPECT_LE(pool.workers(), kCallers * 4);
}

TEST(WorkerPool, AJobInsideAJobFinishes) {
  WorkerPool pool;
  std::atomic<std::uint64_t> total{0};
  std::atomic<int> next{0};
  const std::function<void()> outer = [&] {
    for (int k = next.fetch_add(1); k < 40; k = next.fetch_add(1))
      total.fetch_add(pooledSum(pool, 3, 1000 + std::uint64_t(k), nullptr));
  };
  pool.run(4, outer);
  std::uint64_t want = 0;
  for (std::uint64_t k = 0; k < 40; ++k) want += (1000 + k) * (999 + k) / 2;
  EXPECT_EQ(total.load(), want);
}

TEST(WorkerPool, AThrowOnTheCallingThreadComesOutAfterTheJobClosed) {
  // The caller throws while three helpers are inside the job: it comes out only once they have
  // left (their counter reads 0), and the pool runs the next job.
  WorkerPool pool;
  std::atomic<int> inside{0}, arrived{0};
  const std::thread::id caller = std::this_thread::get_id();
  const std::function<void()> work = [&] {
    inside.fetch_add(1);
    arrived.fetch_add(1);
    const auto until = Clock::now() + std::chrono::seconds(20);
    while (arrived.load() < 4 && Clock::now() < until) std::this_thread::yield();
    if (std::this_thread::get_id() == caller) {
      inside.fetch_sub(1);
      throw std::runtime_error("caller");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    inside.fetch_sub(1);
  };
  EXPECT_THROW(pool.run(4, work), std::runtime_error);
  EXPECT_EQ(arrived.load(), 4);
  EXPECT_EQ(inside.load(), 0) << "the helpers had left";
  EXPECT_EQ(pooledSum(pool, 4, 1000, nullptr), 1000u * 999u / 2);
}

TEST(ParallelLoop, EveryChunkOnceAndTheSameResultOnAnyThreadCount) {
  const std::size_t n = 100003;
  std::vector<std::uint32_t> reference(n);
  for (std::size_t i = 0; i < n; ++i) reference[i] = std::uint32_t(i * 2654435761u);
  for (int threads : {1, 2, 3, 8, 0}) {
    std::vector<std::uint32_t> out(n, 0);
    std::vector<std::atomic<int>> seen((n + 999) / 1000);
    kdet_fcl::cpu::parallelFor(n, 1000, threads, [&](std::size_t lo, std::size_t hi) {
      seen[lo / 1000].fetch_add(1);
      for (std::size_t i = lo; i < hi; ++i) out[i] = std::uint32_t(i * 2654435761u);
    });
    EXPECT_EQ(out, reference) << threads << " threads";
    int twice = 0;
    for (auto& s : seen) twice += s.load() != 1;
    EXPECT_EQ(twice, 0) << threads << " threads";
  }
}

TEST(ParallelLoop, AnExceptionComesOutOnceEveryThreadHasLeftAndAFalseStopsNewChunks) {
  std::atomic<int> running{0};
  EXPECT_THROW(kdet_fcl::cpu::forEachChunk(64, 4,
                                           [&](std::size_t c) {
                                             running.fetch_add(1);
                                             std::this_thread::sleep_for(std::chrono::microseconds(200));
                                             running.fetch_sub(1);
                                             if (c == 5) throw std::runtime_error("chunk 5");
                                             return true;
                                           }),
               std::runtime_error);
  EXPECT_EQ(running.load(), 0) << "no chunk still runs when the exception comes out";
  // A false from chunk 3 stops the loop: far fewer than the 10,000 chunks ran.
  std::atomic<int> ran{0};
  kdet_fcl::cpu::forEachChunk(10000, 4, [&](std::size_t c) {
    ran.fetch_add(1);
    return c != 3;
  });
  EXPECT_GE(ran.load(), 4);
  EXPECT_LT(ran.load(), 10000);
}

TEST(WorkerPool, AChildOfForkGetsANewPoolWhoseWorkersRun) {
  // The parent's shared pool has workers; a child of fork() has none of them (only the thread
  // that forked), so it must start its own: a job that waits for three helpers would otherwise
  // wait for threads that are not there (the alarm ends such a child).
  Rendezvous warm(4);
  WorkerPool::shared().run(4, warm.work());
  ASSERT_EQ(warm.arrived.load(), 4);
  ASSERT_GE(WorkerPool::shared().workers(), 3);
  const int code = kdet_test::runInChild(
      [] {
        ::alarm(30);
        if (WorkerPool::shared().workers() != 0) return 2;  // the parent's pool
        Rendezvous r(4);
        WorkerPool::shared().run(4, r.work());
        if (r.arrived.load() != 4 || r.distinct() != 4) return 3;
        // The library's loop on it too.
        std::atomic<std::uint64_t> sum{0};
        kdet_fcl::cpu::parallelFor(100000, 1000, 4, [&](std::size_t lo, std::size_t hi) {
          std::uint64_t s = 0;
          for (std::size_t i = lo; i < hi; ++i) s += i;
          sum.fetch_add(s);
        });
        return sum.load() == std::uint64_t(100000) * 99999 / 2 ? 0 : 4;
      },
      5);
  EXPECT_EQ(code, 0) << "2: the parent's pool; 3: helpers did not run; 4: a wrong sum; "
                        "negative: a signal (the alarm: a wait for workers that do not exist)";
}

TEST(WorkerPool, ThreadsThatCannotStartLeaveTheWorkToTheCaller) {
  // In a child whose address space cannot hold another thread's stack, a new pool starts no
  // worker: the caller runs the whole job, and nothing throws or aborts.
  const int code = kdet_test::runInChild(
      [] {
        ::alarm(30);
        WorkerPool pool;
        // A new thread's stack of 64 GiB: never in glibc's cache of freed stacks, and past the
        // limit below.
        pthread_attr_t big;
        if (::pthread_attr_init(&big) != 0 ||
            ::pthread_attr_setstacksize(&big, std::size_t(64) << 30) != 0 ||
            ::pthread_setattr_default_np(&big) != 0)
          return 5;
        kdet_test::limitAddressSpace(std::size_t(1) << 20);
        std::atomic<int> runs{0};
        const std::uint64_t sum = pooledSum(pool, 8, 5000, &runs);
        const int workers = pool.workers();
        kdet_test::unlimitAddressSpace();
        if (sum != std::uint64_t(5000) * 4999 / 2) return 2;
        if (workers != 0 || runs.load() != 1) return 3;
        return 0;
      },
      4);
  EXPECT_EQ(code, 0) << "2: a wrong sum; 3: a worker started after all; 4: an exception; 5: "
                        "the default stack size could not be set";
}
