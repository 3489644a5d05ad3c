#pragma once
// A minimal parallel loop for the CPU backend: chunks handed out in increasing order by an atomic
// counter, so the work each thread does varies but what is written per chunk does not. The
// threads are the process-wide pool's kept workers (worker_pool.h), not started per loop.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

#include "cpu/worker_pool.h"

namespace kdet_fcl {
namespace cpu {

/// Threads to use: `requested` (0 = hardware concurrency), at most one per chunk.
inline int resolveThreads(int requested, std::size_t chunks) {
  // (The hardware's count is read once: glibc reads it from /sys, tens of microseconds that a
  // 5.9 MB updateVertices measured.)
  static const int hardware = int(std::thread::hardware_concurrency());
  int t = requested > 0 ? requested : hardware;
  if (t < 1) t = 1;
  if (std::size_t(t) > chunks) t = int(std::max<std::size_t>(chunks, 1));
  return t;
}

/// Vertex arrays of at least this many bytes are passed over by several threads (HashedMesh's
/// updateVertices and commitVertices, the FCL entry points' conversion of a deformed model's
/// positions and its local AABB, and the checksum of a plain model's arrays at each query,
/// src/fcl/checksum.h): one per kVertexBytesPerThread, at most the threads asked for,
/// and only where that makes at least kMinVertexThreads. The threads are the library's kept
/// workers (worker_pool.h), woken in microseconds rather than started in tens of them, which is
/// what let the split go from 2 MB a thread (4 MB and up) to 512 KB (1.5 MB and up). On the
/// 16-thread host of an H200, commitVertices of a 980k-triangle cloth took 705-882 us (float,
/// 5.9 MB, one thread) and 530-617 (double, 11.8 MB, 5 threads started per call) before, 169-180
/// and 256-271 now; 250k in double 202-216 -> 124-131 (update_bench, benchmarks/RESULTS.md). Two
/// threads still do not pay: on a 2-thread VM waking the second one for a 1.1 MB array cost more
/// than it saved (35 -> 140 us), so such machines pass on one thread, as before.
constexpr std::size_t kParallelVertexBytes = std::size_t(1536) << 10;
constexpr std::size_t kVertexBytesPerThread = std::size_t(512) << 10;
constexpr int kMinVertexThreads = 3;

/// The threads for a pass over `bytes` of vertex data: 1 below kParallelVertexBytes, else one per
/// kVertexBytesPerThread, at most `threads` (0: the hardware's); 1 where that is fewer than
/// kMinVertexThreads.
inline int vertexPassThreads(std::size_t bytes, int threads) {
  if (bytes < kParallelVertexBytes) return 1;
  const int t = resolveThreads(threads, bytes / kVertexBytesPerThread);
  return t >= kMinVertexThreads ? t : 1;
}

/// Each of t threads' share of n items (at least 1, so that an empty array is one empty chunk).
inline std::size_t shareOf(std::size_t n, int t) {
  return std::max<std::size_t>(1, (n + std::size_t(t) - 1) / std::size_t(t));
}

/// Calls fn(chunk) for chunk = 0..num_chunks-1 on up to `threads` threads (the calling one and
/// workers of WorkerPool::shared()). fn returns false to ask that no further chunks be started
/// (chunks already running finish). The first exception thrown by any fn is rethrown here after
/// every thread has left the loop.
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
  const std::function<void()> worker = [&] {
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
  WorkerPool::shared().run(t, worker);
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
