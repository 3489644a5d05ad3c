#pragma once
// A minimal parallel loop for the CPU backend: chunks handed out in increasing order by an atomic
// counter, so the work each thread does varies but what is written per chunk does not.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace kdet_fcl {
namespace cpu {

/// Threads to use: `requested` (0 = hardware concurrency), at most one per chunk.
inline int resolveThreads(int requested, std::size_t chunks) {
  int t = requested > 0 ? requested : int(std::thread::hardware_concurrency());
  if (t < 1) t = 1;
  if (std::size_t(t) > chunks) t = int(std::max<std::size_t>(chunks, 1));
  return t;
}

/// Calls fn(chunk) for chunk = 0..num_chunks-1 on up to `threads` threads. fn returns false to
/// ask that no further chunks be started (chunks already running finish). The first exception
/// thrown by any fn is rethrown here after all threads joined.
template <class Fn>
void forEachChunk(std::size_t num_chunks, int threads, Fn&& fn) {
  const int t = resolveThreads(threads, num_chunks);
  if (t <= 1) {
    for (std::size_t c = 0; c < num_chunks; ++c)
      if (!fn(c)) break;
    return;
  }
  std::atomic<std::size_t> next{0};
  std::atomic<bool> stop{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&] {
    try {
      while (!stop.load(std::memory_order_relaxed)) {
        const std::size_t c = next.fetch_add(1);
        if (c >= num_chunks) break;
        if (!fn(c)) stop = true;
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      stop = true;
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(std::size_t(t - 1));
  for (int i = 1; i < t; ++i) pool.emplace_back(worker);
  worker();
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
}

/// Parallel loop over [0, n) in chunks of `chunk` indices: fn(begin, end).
template <class Fn>
void parallelFor(std::size_t n, std::size_t chunk, int threads, Fn&& fn) {
  const std::size_t chunks = (n + chunk - 1) / chunk;
  forEachChunk(chunks, threads, [&](std::size_t c) {
    fn(c * chunk, std::min(n, (c + 1) * chunk));
    return true;
  });
}

}  // namespace cpu
}  // namespace kdet_fcl
