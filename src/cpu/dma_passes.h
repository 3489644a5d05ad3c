#pragma once
// Passes over a host buffer that the GPU reads by DMA right after: a HashedMesh's vertex buffer
// once the CUDA backend has registered it as page-locked memory (detail::HostPin), read by one
// cudaMemcpy at the next query.
//
// Such a DMA is slow while the buffer's lines sit in the cores' private caches. On the 16-thread
// Xeon host of an H200 (benchmarks/RESULTS-gpu.md, "The DMA after a pass in threads"), a 13.5 MB
// array (a 1M-triangle cloth's positions in double) took 0.58-0.69 ms to copy to the device after
// 16 threads had checked or copied it, against 0.25 ms after non-temporal stores or after each
// line had been demoted to the shared L3 once read. So the vertex passes over such a buffer
// leave its lines out of the private caches where that paid in kdet_bench and the probes:
//   - updateVertices copies into it with non-temporal stores (streamCopy) where it copies in
//     several threads (1.5 MB and up, cpu::vertexPassThreads): the 250k and 1M cloths' inter
//     query after updateVertices 0.44-0.52 -> 0.34-0.35 and 1.21-1.41 -> 1.00 ms, the copy
//     level;
//   - commitVertices (and the FCL entry points, which commit) demotes each line of it after the
//     check has read it (demoteLines), from kDemoteMinBytes: demoting cost the check 0.05-0.08
//     ms in several threads, against a DMA that saved 0.25-0.35 ms at 13.5 MB (kdet_bench's 1M
//     cloth: 2.15-2.21 -> 1.90-1.96 ms a frame), but only 0.02-0.1 ms at 1.8-3 MB (the UNC
//     n-body's frame 0.04 ms slower, the 181k n-body and the 200k and 250k cloths level).
// On one thread neither paid: a 1.1 MB copy took 0.18 ms by non-temporal stores against 0.07 by
// memcpy, and kdet_bench's commit of the cloth ball's positions 0.16-0.20 ms demoting against
// 0.05-0.09, more than the DMA saved (0.03 ms). The rule's switch is dmaPasses(); a buffer the
// GPU does not read keeps its lines in the caches, where the CPU backend's re-hash reads them.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "kdet_fcl/detail/knobs.h"

namespace kdet_fcl {
namespace cpu {

/// Whether the vertex passes leave a buffer's lines out of the cores' private caches:
/// KDET_FCL_DMA_PASSES=0 never, =1 always (for tests and comparisons), unset or empty `dma` (the
/// caller's rule: the buffer is read by DMA next). Read at every call; another value throws
/// InvalidInputError naming the knob.
inline bool dmaPasses(bool dma) { return detail::switchKnob("KDET_FCL_DMA_PASSES", dma); }

constexpr std::size_t kCacheLineBytes = 64;

/// The smallest buffer whose check in commitVertices demotes its lines (see above).
constexpr std::size_t kDemoteMinBytes = std::size_t(4) << 20;

/// The rule for updateVertices' copy into a buffer that the GPU reads by DMA next (`dma`) on
/// `threads` threads: non-temporal stores where it copies in several (subject to dmaPasses).
inline bool streamCopyInto(bool dma, int threads) { return dmaPasses(dma && threads > 1); }

/// The rule for commitVertices' check of `bytes` of such a buffer on `threads` threads: each line
/// demoted once read where it checks kDemoteMinBytes or more in several (subject to dmaPasses).
inline bool demoteWhileChecking(bool dma, int threads, std::size_t bytes) {
  return dmaPasses(dma && threads > 1 && bytes >= kDemoteMinBytes);
}

/// Demotes the cache lines that hold [p, p + bytes) from this core's private caches to the shared
/// last-level cache: CLDEMOTE, a hint that changes no data (on x86-64 processors without it, it
/// runs as a NOP; elsewhere this does nothing). Every line it names holds a byte of the range, so
/// no address outside the range's pages is named.
inline void demoteLines(const void* p, std::size_t bytes) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  if (bytes == 0) return;
  const std::uintptr_t end = reinterpret_cast<std::uintptr_t>(p) + bytes;
  for (std::uintptr_t a = reinterpret_cast<std::uintptr_t>(p) & ~std::uintptr_t(kCacheLineBytes - 1);
       a < end; a += kCacheLineBytes)
    asm volatile("cldemote %0" : : "m"(*reinterpret_cast<const char*>(a)));
#else
  (void)p;
  (void)bytes;
#endif
}

/// Copies `bytes` from src to dst (not overlapping) with non-temporal stores: with SSE2, the
/// 16-byte-aligned middle of dst by streaming stores and its ends by memcpy, then a store fence, so
/// that the copy has left this core (in memory, in no cache) when it returns. Without SSE2,
/// memcpy.
inline void streamCopy(void* dst, const void* src, std::size_t bytes) {
  if (bytes == 0) return;
#if defined(__SSE2__)
  char* d = static_cast<char*>(dst);
  const char* s = static_cast<const char*>(src);
  const std::size_t head =
      std::min(bytes, (16 - (reinterpret_cast<std::uintptr_t>(d) & 15)) & std::size_t(15));
  std::memcpy(d, s, head);
  std::size_t i = head;
  for (; i + 64 <= bytes; i += 64) {
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s + i));
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s + i + 16));
    const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s + i + 32));
    const __m128i e = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s + i + 48));
    _mm_stream_si128(reinterpret_cast<__m128i*>(d + i), a);
    _mm_stream_si128(reinterpret_cast<__m128i*>(d + i + 16), b);
    _mm_stream_si128(reinterpret_cast<__m128i*>(d + i + 32), c);
    _mm_stream_si128(reinterpret_cast<__m128i*>(d + i + 48), e);
  }
  for (; i + 16 <= bytes; i += 16)
    _mm_stream_si128(reinterpret_cast<__m128i*>(d + i),
                     _mm_loadu_si128(reinterpret_cast<const __m128i*>(s + i)));
  std::memcpy(d + i, s + i, bytes - i);
  _mm_sfence();
#else
  std::memcpy(dst, src, bytes);
#endif
}

}  // namespace cpu
}  // namespace kdet_fcl
