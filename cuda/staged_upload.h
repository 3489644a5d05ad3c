#pragma once
// Host-to-device copy of pageable memory through a pinned staging buffer, shared by the CUDA
// backend (vertex and triangle uploads) and the suite's GPU BVH baseline
// (benchmarks/gpu_bvh.cu), so that both pay the same upload.
//
// One host thread copying into pinned memory runs at about 10 GB/s, and only then can the bus
// transfer (about 50 GB/s on an H100's PCIe 5) start: a 6.7 MB vertex array took 0.72 ms that
// way. Here the data go in chunks. Several host threads fill the stage, and each chunk's DMA is
// enqueued as soon as that chunk is staged, so the transfers overlap the host copies: 0.37 ms for
// the same array with 8 threads, and 12.1 -> 2.0 ms for 67 MB (benchmarks/RESULTS-gpu.md,
// "Vertex upload").
//
// Knobs (environment, read at every call, for tests and comparisons):
// KDET_FCL_CUDA_UPLOAD_THREADS=n (1..64) forces the number of host threads (1: one thread,
// still chunked); KDET_FCL_CUDA_UPLOAD_CHUNK=b (4096 bytes or more) sets the chunk size.

#include <cuda_runtime.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

namespace kdet_fcl {
namespace staging {

/// Default chunk: 1 MiB (256 KiB chunks were slower with several threads; 2 MiB was measured
/// with one thread only).
constexpr std::size_t kUploadChunk = std::size_t(1) << 20;
/// At most this many host threads by default (8 were 1.5x faster than 4 at 67 MB, level at
/// 6.7 MB).
constexpr int kMaxUploadThreads = 8;

/// A positive integer from the environment variable `name` within [lo, hi], else 0.
inline long long uploadKnob(const char* name, long long lo, long long hi) {
  const char* e = std::getenv(name);
  if (e == nullptr || *e == 0) return 0;
  char* end = nullptr;
  const long long v = std::strtoll(e, &end, 10);
  return (end != nullptr && *end == 0 && v >= lo && v <= hi) ? v : 0;
}

/// Chunk size of a staged upload (KDET_FCL_CUDA_UPLOAD_CHUNK, else kUploadChunk).
inline std::size_t uploadChunk() {
  const long long v = uploadKnob("KDET_FCL_CUDA_UPLOAD_CHUNK", 4096, 1LL << 32);
  return v > 0 ? std::size_t(v) : kUploadChunk;
}

/// Host threads for `chunks` chunks: KDET_FCL_CUDA_UPLOAD_THREADS, else one per chunk up to
/// kMaxUploadThreads and the hardware's thread count; never more than the chunks.
inline int uploadThreads(std::size_t chunks) {
  long long t = uploadKnob("KDET_FCL_CUDA_UPLOAD_THREADS", 1, 64);
  if (t == 0) {
    const unsigned hw = std::thread::hardware_concurrency();
    t = std::min<long long>(kMaxUploadThreads, hw == 0 ? 1 : hw);
  }
  const long long most = static_cast<long long>(std::max<std::size_t>(chunks, 1));
  return static_cast<int>(std::max<long long>(1, std::min(t, most)));
}

/// Copies `bytes` from pageable host memory `src` to device memory `dst` through the pinned
/// buffer `stage` (at least `bytes` long), enqueueing the transfers on stream `s`. The stage must
/// not be written again until those transfers have run (the caller synchronises `s` first).
/// Returns the first CUDA error, or cudaSuccess. Chunk c goes to stage + c*chunk and
/// dst + c*chunk, whichever thread copies it, so the result does not depend on the scheduling.
/// A thread that cannot be started leaves its share to the others (the calling thread alone
/// finishes every chunk if need be).
inline cudaError_t stagedUpload(void* dst, const void* src, std::size_t bytes, void* stage,
                                cudaStream_t s) {
  if (bytes == 0) return cudaSuccess;
  const std::size_t chunk = uploadChunk();
  const std::size_t chunks = (bytes + chunk - 1) / chunk;
  const int threads = uploadThreads(chunks);
  auto* d = static_cast<char*>(dst);
  auto* h = static_cast<char*>(stage);
  const auto* from = static_cast<const char*>(src);
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::mutex error_mutex;
  cudaError_t error = cudaSuccess;
  auto work = [&] {
    while (!failed.load(std::memory_order_relaxed)) {
      const std::size_t c = next.fetch_add(1);
      if (c >= chunks) return;
      const std::size_t off = c * chunk, n = std::min(chunk, bytes - off);
      std::memcpy(h + off, from + off, n);
      const cudaError_t e = cudaMemcpyAsync(d + off, h + off, n, cudaMemcpyHostToDevice, s);
      if (e != cudaSuccess) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (error == cudaSuccess) error = e;
        failed = true;
      }
    }
  };
  std::vector<std::thread> pool;
  if (threads > 1) {
    try {
      pool.reserve(std::size_t(threads - 1));
      for (int i = 1; i < threads; ++i) pool.emplace_back(work);
    } catch (...) {
      // No more threads (std::system_error or bad_alloc): the ones running and this one finish.
    }
  }
  work();
  for (auto& t : pool) t.join();
  return error;
}

}  // namespace staging
}  // namespace kdet_fcl
