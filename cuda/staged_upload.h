#pragma once
// Copies between pageable host memory and the device through a pinned staging buffer, shared by
// the CUDA backend (vertex and triangle uploads, the pairs' read-back) and the suite's GPU BVH
// baseline (benchmarks/gpu_bvh.cu), so that both pay the same transfers.
//
// Upload. One host thread copying into pinned memory runs at about 10 GB/s, and only then can
// the bus transfer (about 50 GB/s on an H100's PCIe 5) start: a 6.7 MB vertex array took 0.72 ms
// that way. Here the data go in chunks. Several host threads fill the stage, and each chunk's DMA
// is enqueued as soon as that chunk is staged, so the transfers overlap the host copies: 0.37 ms
// for the same array with 8 threads, and 12.1 -> 2.0 ms for 67 MB (benchmarks/RESULTS-gpu.md,
// "Vertex upload").
//
// Download, the mirror image but on one thread: every chunk's DMA into the stage is enqueued at
// once, each followed by an event, and the calling thread appends each chunk to the destination
// as soon as its event has fired, so the copies out of the stage overlap the later transfers and
// the destination is written once (no zero-filled result to overwrite). The one copy out of the
// stage is what remains of the read-back's host time. Several host threads were slower at the
// sizes of a pair list: their start and the zero-fill of a presized std::vector cost more than
// they saved (benchmarks/RESULTS-gpu.md, "Read-back").
//
// Download into a result the caller keeps from frame to frame (pooledDownload): its storage is
// there and sized already, so no zero-fill stands in the way, and several threads of a
// persistent pool (CopyPool) copy the chunks out of the stage as they arrive. On an H100 host the
// one thread copies about 7 GB/s: 445,614 pairs took 0.48 ms by one thread into a fresh vector
// and 0.30 ms by four into a kept one, 1,000,000 pairs 0.90 against 0.38 ms; 61,530 pairs gained
// nothing (benchmarks/RESULTS-gpu.md, "Pairs into a result kept across frames").
//
// Chunks queued ahead: the CUDA backend may queue a download's chunks before it knows how many
// elements it needs (a forecast from the frame before, right behind the counts on the stream);
// stagedDownload, pooledDownload and downloadInto then take those chunks (`ahead`, at least the
// count's) instead of queueing their own.
//
// Knobs (environment, read at every call, for tests and comparisons; a value out of range or
// not a number throws InvalidInputError, kdet_fcl/detail/knobs.h):
// KDET_FCL_CUDA_UPLOAD_THREADS=n (1..64) forces the number of host threads (1: one thread,
// still chunked); KDET_FCL_CUDA_UPLOAD_CHUNK=b (4096 bytes to 4 GiB) sets the chunk size;
// KDET_FCL_CUDA_DOWNLOAD_CHUNK=b the same for downloads; KDET_FCL_CUDA_DOWNLOAD_THREADS=n
// (1..64) the threads of a pooled download (1: the calling thread alone).

#include <cuda_runtime.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "cpu/worker_pool.h"
#include "device_scope.h"
#include "kdet_fcl/detail/knobs.h"

namespace kdet_fcl {
namespace staging {

/// Default chunk: 1 MiB (256 KiB chunks were slower with several threads; 2 MiB was measured
/// with one thread only).
constexpr std::size_t kUploadChunk = std::size_t(1) << 20;
/// At most this many host threads by default (8 were 1.5x faster than 4 at 67 MB, level at
/// 6.7 MB).
constexpr int kMaxUploadThreads = 8;
/// Default chunk of a download: 256 KiB (on the UNC scenes' pair lists, up to 3.6 MB, 64 KiB
/// chunks were slower and 1 MiB level; benchmarks/RESULTS-gpu.md, "Read-back").
constexpr std::size_t kDownloadChunk = std::size_t(1) << 18;

/// Chunk size from the knob `name` (4096 bytes to 4 GiB), else `fallback`; any other value
/// throws InvalidInputError (kdet_fcl/detail/knobs.h).
inline std::size_t chunkFrom(const char* name, std::size_t fallback) {
  return static_cast<std::size_t>(
      detail::numberKnob(name, 4096, std::uint64_t(1) << 32, fallback));
}

/// Chunk size of a staged upload (KDET_FCL_CUDA_UPLOAD_CHUNK, else kUploadChunk).
inline std::size_t uploadChunk() { return chunkFrom("KDET_FCL_CUDA_UPLOAD_CHUNK", kUploadChunk); }

/// Chunk size of a staged download (KDET_FCL_CUDA_DOWNLOAD_CHUNK, else kDownloadChunk).
inline std::size_t downloadChunk() {
  return chunkFrom("KDET_FCL_CUDA_DOWNLOAD_CHUNK", kDownloadChunk);
}

/// A download chunk in elements of `bytes` bytes: downloadChunk() rounded down to whole
/// elements, at least one.
inline std::size_t downloadChunkElements(std::size_t bytes) {
  return std::max<std::size_t>(1, downloadChunk() / bytes);
}

/// Host threads for `chunks` chunks: the knob `name` (1..64; any other value throws), else up
/// to `most` and the hardware's thread count; never more than the chunks, at least one.
inline int threadsFor(const char* name, int most, std::size_t chunks) {
  long long t = static_cast<long long>(detail::numberKnob(name, 1, 64, 0));
  if (t == 0) {
    // (Asked once: glibc answers it anew at every call, 1.9 us on the CI machine and 2.3 on an
    // H200 machine's host, and every upload and read-back asks.)
    static const unsigned hw = std::thread::hardware_concurrency();
    t = std::min<long long>(most, hw == 0 ? 1 : hw);
  }
  const long long per_chunk = static_cast<long long>(std::max<std::size_t>(chunks, 1));
  return static_cast<int>(std::max<long long>(1, std::min(t, per_chunk)));
}

/// Host threads of an upload of `chunks` chunks: KDET_FCL_CUDA_UPLOAD_THREADS, else one per
/// chunk up to kMaxUploadThreads (threadsFor).
inline int uploadThreads(std::size_t chunks) {
  return threadsFor("KDET_FCL_CUDA_UPLOAD_THREADS", kMaxUploadThreads, chunks);
}

/// Vertex arrays from this size up may be uploaded straight from their own buffer, registered as
/// page-locked memory once (pinHostMemory), instead of through a staging copy: on an H100 host
/// 6.7 MB took 0.13 ms by DMA alone and 0.37-0.41 ms staged by 2-8 threads, and the cloth ball's
/// 0.55 MB 0.021 ms against 0.055 staged (benchmarks/RESULTS-gpu.md, "Vertex upload"). Below
/// 64 pages the staged copy costs little, and a registration would cover few whole pages.
constexpr std::size_t kPinMinBytes = std::size_t(256) << 10;

/// KDET_FCL_CUDA_PIN_VERTICES=0 keeps every vertex upload on the staged path (for comparisons;
/// read at every upload). Any value but 0 or 1 throws InvalidInputError.
inline bool pinVerticesOn() { return detail::switchKnob("KDET_FCL_CUDA_PIN_VERTICES", true); }

/// The whole pages inside [src, src + bytes), as offsets [begin, end) from src (begin == end:
/// none). Those pages hold no other buffer, so registering them never collides with another
/// buffer's registration (cudaHostRegister refuses a page registered twice).
struct PageInterior {
  std::size_t begin = 0, end = 0;
};
inline PageInterior pageInterior(const void* src, std::size_t bytes) {
  static const std::uintptr_t page = [] {
    const long p = sysconf(_SC_PAGESIZE);
    return std::uintptr_t(p > 0 ? p : 4096);
  }();
  const std::uintptr_t a = reinterpret_cast<std::uintptr_t>(src), b = a + bytes;
  const std::uintptr_t lo = (a + page - 1) / page * page, hi = b / page * page;
  if (hi <= lo) return {};
  return {std::size_t(lo - a), std::size_t(hi - a)};
}

/// Registers the whole pages of the `bytes` at `src` (pageInterior) as page-locked memory.
/// Returns the registration, whose last copy unregisters it when dropped, or nullptr (the
/// runtime's error cleared: it is not sticky) when there is no whole page or the runtime refuses.
/// The caller must drop it before the memory is freed, and must not change the memory while a
/// copy from it may be in flight.
inline std::shared_ptr<void> pinHostMemory(const void* src, std::size_t bytes) {
  const PageInterior in = pageInterior(src, bytes);
  if (in.end == in.begin) return nullptr;
  void* p = const_cast<char*>(static_cast<const char*>(src)) + in.begin;
  if (cudaHostRegister(p, in.end - in.begin, cudaHostRegisterDefault) != cudaSuccess) {
    (void)cudaGetLastError();
    return nullptr;
  }
  int device = 0;
  if (cudaGetDevice(&device) != cudaSuccess) {
    (void)cudaGetLastError();
    device = 0;
  }
  // Unregistered in the device's context it was registered in, whatever the calling thread's
  // (which keeps its own: cuda::DeviceScope); an error there is cleared, so that it never reaches
  // a later check.
  return std::shared_ptr<void>(p, [device](void* q) {
    cudaError_t entered = cudaSuccess;
    const cuda::DeviceScope scope(device, &entered);
    (void)cudaHostUnregister(q);
    (void)cudaGetLastError();
  });
}

/// Copies bytes [lo, hi) of the `bytes` at `src`, whose whole pages pinHostMemory registered, to
/// the same offsets of device memory `dst` on stream `s`: what lies in those pages by one DMA
/// from `src` itself, what lies in the partial pages at the buffer's ends (under 4 KiB each)
/// through `stage` (pinned, at least `bytes` long, at the same offsets). The caller synchronises
/// `s` before that part of `src` or of the stage changes again.
inline cudaError_t pinnedUploadRange(void* dst, const void* src, std::size_t bytes,
                                     std::size_t lo, std::size_t hi, void* stage,
                                     cudaStream_t s) {
  const PageInterior in = pageInterior(src, bytes);
  auto* d = static_cast<char*>(dst);
  const auto* from = static_cast<const char*>(src);
  auto* h = static_cast<char*>(stage);
  // [0, in.begin) and [in.end, bytes) through the stage, [in.begin, in.end) straight.
  const std::size_t parts[3][2] = {{0, in.begin}, {in.end, bytes}, {in.begin, in.end}};
  for (int k = 0; k < 3; ++k) {
    const std::size_t a = std::max(lo, parts[k][0]), b = std::min(hi, parts[k][1]);
    if (b <= a) continue;
    const char* p = from + a;
    if (k < 2) {
      std::memcpy(h + a, p, b - a);
      p = h + a;
    }
    const cudaError_t e = cudaMemcpyAsync(d + a, p, b - a, cudaMemcpyHostToDevice, s);
    if (e != cudaSuccess) return e;
  }
  return cudaSuccess;
}

/// Copies `bytes` from `src`, whose whole pages pinHostMemory registered, to device memory
/// `dst` on stream `s` (pinnedUploadRange over the whole buffer).
inline cudaError_t pinnedUpload(void* dst, const void* src, std::size_t bytes, void* stage,
                                cudaStream_t s) {
  return pinnedUploadRange(dst, src, bytes, 0, bytes, stage, s);
}

/// The first CUDA error of a job that several threads share, and whether one was met (the others
/// then stop taking chunks).
struct JobError {
  std::atomic<bool> failed{false};
  std::mutex mutex;
  cudaError_t first = cudaSuccess;
  void record(cudaError_t e) {
    std::lock_guard<std::mutex> lock(mutex);
    if (first == cudaSuccess) first = e;
    failed = true;
  }
};

/// Runs `work` on `threads` threads of `pool` (the calling one among them), each on the calling
/// thread's CUDA device (cuda::DeviceScope: a fresh worker's first CUDA call would otherwise make a
/// context on device 0, whichever device the caller works on); a thread that cannot make it
/// current records the error in `error` and leaves its share to the others.
inline void runOnCallersDevice(cpu::WorkerPool& pool, int threads, JobError& error,
                               const std::function<void()>& work) {
  const int device = cuda::threadDevice();
  pool.run(threads, [&] {
    cudaError_t entered = cudaSuccess;
    const cuda::DeviceScope scope(device, &entered);
    if (entered != cudaSuccess) {
      error.record(entered);
      return;
    }
    work();
  });
}

/// Copies `bytes` from pageable host memory `src` to device memory `dst` through the pinned
/// buffer `stage` (at least `bytes` long), enqueueing the transfers on stream `s`. The stage must
/// not be written again until those transfers have run (the caller synchronises `s` first).
/// Returns the first CUDA error, or cudaSuccess. Chunk c goes to stage + c*chunk and
/// dst + c*chunk, whichever thread copies it, so the result does not depend on the scheduling.
/// The threads are the calling one and kept workers of the library's pool
/// (cpu::WorkerPool::shared()); one that is busy or cannot be started leaves its share to the
/// others (the calling thread alone finishes every chunk if need be).
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
  JobError error;
  runOnCallersDevice(cpu::WorkerPool::shared(), threads, error, [&] {
    while (!error.failed.load(std::memory_order_relaxed)) {
      const std::size_t c = next.fetch_add(1);
      if (c >= chunks) return;
      const std::size_t off = c * chunk, n = std::min(chunk, bytes - off);
      std::memcpy(h + off, from + off, n);
      const cudaError_t e = cudaMemcpyAsync(d + off, h + off, n, cudaMemcpyHostToDevice, s);
      if (e != cudaSuccess) error.record(e);
    }
  });
  return error.first;
}

/// The events of a download's chunks (downloadChunks). Destroyed on every way out (a pending
/// event's resources are freed once it has fired), after the stream has drained, so that nothing
/// leaves while a transfer into the stage is pending.
struct ChunkEvents {
  cudaStream_t s = nullptr;
  std::vector<cudaEvent_t> ev;
  std::size_t chunk = 0;  ///< elements per chunk
  ChunkEvents() = default;
  ChunkEvents(const ChunkEvents&) = delete;
  ChunkEvents& operator=(const ChunkEvents&) = delete;
  ~ChunkEvents() {
    if (!ev.empty()) (void)cudaStreamSynchronize(s);
    for (cudaEvent_t e : ev) (void)cudaEventDestroy(e);
  }
};

/// Enqueues on stream `s` the transfer of `count` elements (count > 0) from device memory `src`
/// into `stage`, in chunks of downloadChunk() bytes rounded down to whole elements (at least
/// one), each followed by an event in `out`. Returns the first CUDA error, or cudaSuccess.
template <class T>
cudaError_t downloadChunks(const T* src, std::size_t count, T* stage, cudaStream_t s,
                           ChunkEvents& out) {
  out.s = s;
  out.chunk = downloadChunkElements(sizeof(T));
  const std::size_t chunks = (count + out.chunk - 1) / out.chunk;
  out.ev.reserve(chunks);
  for (std::size_t c = 0; c < chunks; ++c) {
    const std::size_t off = c * out.chunk, n = std::min(out.chunk, count - off);
    cudaEvent_t e = nullptr;
    cudaError_t err = cudaEventCreateWithFlags(&e, cudaEventDisableTiming);
    if (err != cudaSuccess) return err;
    out.ev.push_back(e);
    err = cudaMemcpyAsync(stage + off, src + off, n * sizeof(T), cudaMemcpyDeviceToHost, s);
    if (err == cudaSuccess) err = cudaEventRecord(e, s);
    if (err != cudaSuccess) return err;
  }
  return cudaSuccess;
}

/// The chunk events of a download of `count` elements: `ahead` where the caller enqueued the
/// transfers before (downloadChunks of at least `count` elements from the same `src` into the
/// same `stage`: a read-back queued before the count was known, sized from a forecast), else
/// those of `own`, enqueued now. Returns the first CUDA error, or cudaSuccess.
template <class T>
cudaError_t chunksOf(const T* src, std::size_t count, T* stage, cudaStream_t s, ChunkEvents* ahead,
                     ChunkEvents& own, ChunkEvents*& use) {
  use = ahead != nullptr ? ahead : &own;
  return ahead != nullptr ? cudaSuccess : downloadChunks(src, count, stage, s, own);
}

/// Copies `count` elements from device memory `src` into host memory through the pinned buffer
/// `stage` (at least `count` elements). What the caller enqueued on stream `s` before (the kernel
/// that writes `src`) runs first. Every chunk's transfer into the stage is enqueued on `s`, each
/// followed by an event (or was already, `ahead`: chunksOf); then `append(first, n)` is called on
/// the calling thread for each chunk in order, as soon as its event has fired: the chunk's n
/// elements at `first` (in the stage). A chunk is a whole number of elements (downloadChunk()
/// bytes rounded down, at least one element). Returns the first CUDA error, or cudaSuccess; the
/// transfers have run when it returns (those of `ahead` when its owner drains it), also on an
/// error and when append throws (then its exception propagates). For count 0 no CUDA call is
/// made and append is not called.
template <class T, class Append>
cudaError_t stagedDownload(const T* src, std::size_t count, T* stage, cudaStream_t s,
                           Append&& append, ChunkEvents* ahead = nullptr) {
  if (count == 0) return cudaSuccess;
  ChunkEvents own;
  ChunkEvents* events = nullptr;
  const cudaError_t enq = chunksOf(src, count, stage, s, ahead, own, events);
  if (enq != cudaSuccess) return enq;
  const std::size_t chunks = (count + events->chunk - 1) / events->chunk;
  for (std::size_t c = 0; c < chunks; ++c) {
    const cudaError_t err = cudaEventSynchronize(events->ev[c]);
    if (err != cudaSuccess) return err;
    const std::size_t off = c * events->chunk;
    append(static_cast<const T*>(stage + off), std::min(events->chunk, count - off));
  }
  return cudaSuccess;
}

/// Host threads of a pooled download of `chunks` chunks: KDET_FCL_CUDA_DOWNLOAD_THREADS, else up
/// to kDownloadThreads (threadsFor).
constexpr int kDownloadThreads = 4;  // 4 beat 2 and 8 at 445,614 pairs, 8 level at 1M (H100)
inline int downloadThreads(std::size_t chunks) {
  return threadsFor("KDET_FCL_CUDA_DOWNLOAD_THREADS", kDownloadThreads, chunks);
}

/// A pooled download pays for its threads only from this many chunks on (4: 1 MiB with the
/// default chunk; 61,530 pairs, 0.5 MB, gained nothing from threads).
constexpr std::size_t kPooledDownloadMinChunks = 4;

/// Worker threads kept from one call to the next (starting threads per call cost more than they
/// saved: "Read-back" in benchmarks/RESULTS-gpu.md): the library's pool (cpu/worker_pool.h). The
/// CUDA backend keeps one per context for its read-backs, whose workers wait on CUDA events.
using CopyPool = cpu::WorkerPool;

/// stagedDownload into destinations the caller has storage for (a result kept across frames):
/// every chunk's transfer is enqueued at once (or was already, `ahead`: chunksOf); `ready()` runs
/// on the calling thread once the first chunk has arrived (so that what the stream copied before
/// it, such as counts, is there: the caller sizes its destinations then; it may throw, and the
/// transfers have run when the exception leaves); then `threads` threads of `pool` (the calling
/// one included) take the chunks, each waiting for its chunk's event and calling
/// `place(offset, first, n)`: the chunk's n elements at `first` (in the stage) are those from
/// element `offset` on. place is called concurrently for disjoint ranges and must not throw.
/// Returns the first CUDA error, or cudaSuccess; the transfers have run when it returns (those of
/// `ahead` when its owner drains it). For count 0 no CUDA call is made, and neither ready nor
/// place is called.
template <class T, class Ready, class Place>
cudaError_t pooledDownload(const T* src, std::size_t count, T* stage, cudaStream_t s,
                           CopyPool& pool, int threads, Ready&& ready, Place&& place,
                           ChunkEvents* ahead = nullptr) {
  if (count == 0) return cudaSuccess;
  ChunkEvents own;
  ChunkEvents* events = nullptr;
  cudaError_t err = chunksOf(src, count, stage, s, ahead, own, events);
  if (err != cudaSuccess) return err;
  err = cudaEventSynchronize(events->ev[0]);
  if (err != cudaSuccess) return err;
  ready();
  const std::size_t chunk = events->chunk, chunks = (count + chunk - 1) / chunk;
  std::atomic<std::size_t> next{0};
  JobError error;
  runOnCallersDevice(pool, threads, error, [&] {
    while (!error.failed.load(std::memory_order_relaxed)) {
      const std::size_t c = next.fetch_add(1);
      if (c >= chunks) return;
      const cudaError_t e = cudaEventSynchronize(events->ev[c]);
      if (e != cudaSuccess) {
        error.record(e);
        return;
      }
      const std::size_t off = c * chunk;
      place(off, static_cast<const T*>(stage + off), std::min(chunk, count - off));
    }
  });
  return error.first;
}

/// Whether a download of `count` elements into destinations that hold `held` elements now (a
/// result kept from the frame before) goes by several threads (pooledDownload): at least
/// kPooledDownloadMinChunks chunks, more than one thread (downloadThreads()), and at least half
/// of the elements there already, so that sizing the destinations zero-fills at most the other
/// half (a new result would be zero-filled whole first, which costs what the threads save).
/// Returns the threads, or 0 for a download by the calling thread alone.
inline int pooledThreads(std::size_t count, std::size_t held) {
  const std::size_t chunk = downloadChunkElements(sizeof(std::uint64_t));
  const std::size_t chunks = (count + chunk - 1) / chunk;
  const int threads = downloadThreads(chunks);
  const bool pooled = chunks >= kPooledDownloadMinChunks && threads > 1 && 2 * held >= count;
  return pooled ? threads : 0;
}

/// The download of `count` elements into `out`, a vector whose storage the caller keeps (its
/// old contents are replaced): by several threads of `pool` into `out` sized first where
/// pooledThreads() says so, else by stagedDownload appended to `out` cleared (`ahead`: transfers
/// enqueued before, chunksOf).
template <class T>
cudaError_t downloadInto(const T* src, std::size_t count, T* stage, cudaStream_t s,
                         CopyPool& pool, std::vector<T>& out, ChunkEvents* ahead = nullptr) {
  static_assert(sizeof(T) == sizeof(std::uint64_t), "chunks counted in 8-byte elements");
  const int threads = pooledThreads(count, out.size());
  if (threads == 0) {
    out.clear();
    out.reserve(count);
    return stagedDownload(
        src, count, stage, s,
        [&](const T* first, std::size_t n) { out.insert(out.end(), first, first + n); }, ahead);
  }
  return pooledDownload(
      src, count, stage, s, pool, threads, [&] { out.resize(count); },
      [&](std::size_t off, const T* first, std::size_t n) {
        std::memcpy(static_cast<void*>(out.data() + off), first, n * sizeof(T));
      },
      ahead);
}

}  // namespace staging
}  // namespace kdet_fcl
