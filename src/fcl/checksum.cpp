// The checksum of a model's arrays (checksum.h): one vector body, compiled for the baseline and,
// on x86-64, for SSE4.1 and AVX2, picked at run time.

#include "fcl/checksum.h"

#include <algorithm>
#include <cstring>
#include <vector>

#include "cpu/parallel.h"
#include "kdet_fcl/errors.h"

namespace kdet_fcl::detail {
namespace {

using Lanes = std::uint32_t __attribute__((vector_size(32)));  // 8 lanes of 32 bits
constexpr int kAccumulators = 12;
constexpr std::size_t kBlock = sizeof(Lanes) * kAccumulators;  // 384 bytes a step of each chain
constexpr std::size_t kPage = kBlock * 256;  // 96 KiB: pages are hashed apart (and in threads)
constexpr std::uint32_t kLaneFactor = 0x9E3779B1u;             // odd: the multiply is a bijection
constexpr std::uint64_t kFoldFactor = 0x9E3779B97F4A7C15ull;

constexpr std::uint64_t mix64(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xBF58476D1CE4E5B9ull;
  x ^= x >> 27;
  x *= 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// One step of a chain: a bijection of the 256-bit state for each word w. The multiply is one per
// lane (odd factor); x ^ ((x ^ rot(x)) >> 15) is x + N x over GF(2) with N nilpotent (a shift
// right by 15 applied three times clears a lane, and it commutes with the lane rotation), so it is
// invertible too.
// (By reference: a 32-byte vector passed by value draws GCC's ABI note without AVX.)
__attribute__((always_inline)) inline void step(Lanes& h, const Lanes& w) {
  const Lanes x = (h ^ w) * kLaneFactor;
  const Lanes r = __builtin_shufflevector(x, x, 1, 2, 3, 0, 5, 6, 7, 4);
  h = x ^ ((x ^ r) >> 15);
}

__attribute__((always_inline)) inline std::uint64_t checksumBody(const void* data,
                                                                 std::size_t bytes,
                                                                 std::uint64_t seed) {
  Lanes h[kAccumulators];
  for (int a = 0; a < kAccumulators; ++a)
    for (int l = 0; l < 8; ++l)
      h[a][l] = std::uint32_t(mix64(seed + kFoldFactor * std::uint64_t(8 * a + l + 1)));
  const unsigned char* p = static_cast<const unsigned char*>(data);
  std::size_t i = 0;
  for (; i + kBlock <= bytes; i += kBlock) {
    for (int a = 0; a < kAccumulators; ++a) {
      Lanes w;
      std::memcpy(&w, p + i + sizeof(Lanes) * a, sizeof(Lanes));
      step(h[a], w);
    }
  }
  if (i < bytes) {  // the last, partial block, padded with zeros
    unsigned char tail[kBlock] = {};
    std::memcpy(tail, p + i, bytes - i);
    for (int a = 0; a < kAccumulators; ++a) {
      Lanes w;
      std::memcpy(&w, tail + sizeof(Lanes) * a, sizeof(Lanes));
      step(h[a], w);
    }
  }
  std::uint64_t r = mix64(std::uint64_t(bytes) ^ mix64(seed));
  for (int a = 0; a < kAccumulators; ++a)
    for (int l = 0; l < 8; l += 2) {
      r = (r ^ (std::uint64_t(h[a][l]) | std::uint64_t(h[a][l + 1]) << 32)) * kFoldFactor;
      r ^= r >> 31;
    }
  return mix64(r);
}

std::uint64_t portableKernel(const void* data, std::size_t bytes, std::uint64_t seed) {
  return checksumBody(data, bytes, seed);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define KDET_FCL_X86_CHECKSUM 1
__attribute__((target("sse4.1"))) std::uint64_t sse41Kernel(const void* data, std::size_t bytes,
                                                            std::uint64_t seed) {
  return checksumBody(data, bytes, seed);
}
__attribute__((target("avx2"))) std::uint64_t avx2Kernel(const void* data, std::size_t bytes,
                                                         std::uint64_t seed) {
  return checksumBody(data, bytes, seed);
}
#endif

using Kernel = std::uint64_t (*)(const void*, std::size_t, std::uint64_t);

Kernel kernelOf(ChecksumKernel k) {
  switch (k) {
    case ChecksumKernel::Portable: return portableKernel;
#ifdef KDET_FCL_X86_CHECKSUM
    case ChecksumKernel::Sse41: return sse41Kernel;
    case ChecksumKernel::Avx2: return avx2Kernel;
#else
    default: break;
#endif
  }
  return nullptr;
}

}  // namespace

bool checksumKernelAvailable(ChecksumKernel k) {
#ifdef KDET_FCL_X86_CHECKSUM
  __builtin_cpu_init();  // may run before libgcc's own constructor (a static initializer's call)
  switch (k) {
    case ChecksumKernel::Portable: return true;
    case ChecksumKernel::Sse41: return __builtin_cpu_supports("sse4.1");
    case ChecksumKernel::Avx2: return __builtin_cpu_supports("avx2");
  }
  return false;
#else
  return k == ChecksumKernel::Portable;
#endif
}

ChecksumKernel bestChecksumKernel() {
  static const ChecksumKernel best = [] {
    for (ChecksumKernel k : {ChecksumKernel::Avx2, ChecksumKernel::Sse41})
      if (checksumKernelAvailable(k)) return k;
    return ChecksumKernel::Portable;
  }();
  return best;
}

namespace {

// The pages' checksums folded with the length; page k's bytes are hashed with its own seed.
std::uint64_t pagedChecksum(Kernel kernel, const void* data, std::size_t bytes, std::uint64_t seed,
                            int threads) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  const std::size_t pages = std::max<std::size_t>(1, (bytes + kPage - 1) / kPage);
  auto pageSum = [&](std::size_t k) {
    const std::size_t lo = k * kPage, len = std::min(bytes - std::min(bytes, lo), kPage);
    return kernel(len ? p + lo : p, len, mix64(seed + kFoldFactor * (k + 1)));
  };
  std::uint64_t r = mix64(std::uint64_t(bytes) ^ mix64(seed));
  auto fold = [&r](std::uint64_t h) {
    r = (r ^ h) * kFoldFactor;
    r ^= r >> 31;
  };
  if (pages == 1 || threads <= 1) {
    for (std::size_t k = 0; k < pages; ++k) fold(pageSum(k));
  } else {
    std::vector<std::uint64_t> sums(pages);
    cpu::parallelFor(pages, cpu::shareOf(pages, threads), threads,
                     [&](std::size_t lo, std::size_t hi) {
                       for (std::size_t k = lo; k < hi; ++k) sums[k] = pageSum(k);
                     });
    for (std::uint64_t h : sums) fold(h);
  }
  return mix64(r);
}

}  // namespace

std::uint64_t checksumBytes(const void* data, std::size_t bytes, std::uint64_t seed,
                            int threads) {
  static const Kernel best = kernelOf(bestChecksumKernel());
  return pagedChecksum(best, data, bytes, seed, threads);
}

std::uint64_t checksumBytes(const void* data, std::size_t bytes, std::uint64_t seed,
                            ChecksumKernel k, int threads) {
  if (!checksumKernelAvailable(k))
    throw BackendUnavailableError("kdet_fcl: this CPU cannot run the checksum kernel asked for");
  return pagedChecksum(kernelOf(k), data, bytes, seed, threads);
}

}  // namespace kdet_fcl::detail
