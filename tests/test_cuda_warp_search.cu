// The warp's search for the triangle of each entry (cuda/device_hash.cuh, warpEntryTriangle), the
// counting build's fill kernel's: for every entry, the last triangle whose first entry is at or
// before it, as a binary search of the exclusive scan of the triangles' entry counts finds it.
// Warps start where the kernel's start (every 32nd entry) and 1, 5, 17 or 31 entries later, over
// scans of 1 to 200,000 triangles with one to eight entries each, and with triangles of no
// entries (runs longer than a warp among them), where a lane searches past the warp's window.
// And the warp's queue of seen entries (EntryRing, the warp scans'): what comes off it, 32 at a
// time and the rest at the end, is what went on, in order, with its tags. And the exact kernels'
// spread of items over the warps (spreadIndex): every item once. Skips without a device.

#include <cuda_runtime.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "cuda/device_hash.cuh"
#include "cuda_device.h"

namespace {

/// Thread k of the grid takes entry shift + k (its warp's first: shift + k rounded down to the
/// warp), for the entries below offsets[n].
__global__ void entryTriangleKernel(const std::uint32_t* offsets, std::uint32_t n,
                                    std::uint32_t shift, std::uint32_t* out) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  const std::uint32_t e = shift + k, e0 = e - (threadIdx.x & 31u);
  const std::uint32_t total = offsets[n];
  if (e0 >= total) return;
  const std::uint32_t i = kdet_fcl::cuda::warpEntryTriangle(offsets, n, e0, e);
  if (e < total) out[e] = i;
}

/// Counts, per item below m, the threads of the grid-stride loop of spreadIndex that take it, and
/// per warp of the grid (hits[m + w]) the items it took below `first_round` (W items or fewer
/// take one lane of as many warps).
__global__ void spreadKernel(unsigned long long m, unsigned long long first_round,
                             unsigned int* hits) {
  const kdet_fcl::cuda::SpreadIndex at = kdet_fcl::cuda::spreadIndex();
  const unsigned long long warp = blockIdx.x * (blockDim.x >> 5) + (threadIdx.x >> 5);
  for (unsigned long long k = at.first; k < m; k += at.stride) {
    atomicAdd(hits + k, 1u);
    if (k < first_round) atomicAdd(hits + m + warp, 1u);
  }
}

/// One warp per block: `rounds` rounds of 32 lanes; lane l of round r keeps its value
/// r * 32 + l (tag r % 251) when bit l of keep[r] is set, pushes it on the warp's ring and, when
/// 32 or more are queued (or, with drain_every > 0, every drain_every rounds, whatever is
/// queued), pops them into out[] (value, tag) in the order they come off; then pops the rest.
/// out[0] ends as the number popped.
__global__ void ringKernel(const std::uint32_t* keep, std::uint32_t rounds,
                           std::uint32_t drain_every, std::uint32_t* out) {
  __shared__ std::uint32_t tri[64];
  __shared__ std::uint8_t tag[64];
  kdet_fcl::cuda::EntryRing ring{tri, tag, 0u, 0u};
  const unsigned int lane = threadIdx.x & 31u;
  std::uint32_t popped = 0;
  const auto take = [&](bool have, std::uint32_t value, std::uint8_t t) {
    if (have) {
      out[1 + 2 * (popped + lane)] = value;
      out[2 + 2 * (popped + lane)] = t;
    }
    popped += static_cast<std::uint32_t>(__popc(__ballot_sync(0xFFFFFFFFu, have)));
  };
  for (std::uint32_t r = 0; r < rounds; ++r) {
    const bool kept = (keep[r] >> lane) & 1u;
    kdet_fcl::cuda::pushRing(ring, kept, r * 32 + lane, static_cast<std::uint8_t>(r % 251));
    if (ring.count >= 32) kdet_fcl::cuda::popRing(ring, 32, take);
    if (drain_every > 0 && r % drain_every == drain_every - 1)
      kdet_fcl::cuda::popRing(ring, ring.count, take);
  }
  kdet_fcl::cuda::popRing(ring, ring.count, take);
  if (lane == 0) out[0] = popped;
}

/// The exclusive scan of `counts` (n + 1 words).
std::vector<std::uint32_t> scanOf(const std::vector<std::uint32_t>& counts) {
  std::vector<std::uint32_t> off(counts.size() + 1, 0);
  for (std::size_t i = 0; i < counts.size(); ++i) off[i + 1] = off[i] + counts[i];
  return off;
}

/// Every entry's triangle from the device (threads from entry `shift`), against the host's.
void check(const std::vector<std::uint32_t>& counts, std::uint32_t shift, const std::string& what) {
  const std::vector<std::uint32_t> off = scanOf(counts);
  const auto n = static_cast<std::uint32_t>(counts.size());
  const std::uint32_t total = off[n];
  ASSERT_GT(total, shift) << what;
  std::uint32_t *d_off = nullptr, *d_out = nullptr;
  ASSERT_EQ(cudaMalloc(&d_off, off.size() * sizeof(std::uint32_t)), cudaSuccess);
  ASSERT_EQ(cudaMalloc(&d_out, total * sizeof(std::uint32_t)), cudaSuccess);
  ASSERT_EQ(cudaMemcpy(d_off, off.data(), off.size() * sizeof(std::uint32_t),
                       cudaMemcpyHostToDevice),
            cudaSuccess);
  ASSERT_EQ(cudaMemset(d_out, 0xFF, total * sizeof(std::uint32_t)), cudaSuccess);
  const std::uint32_t threads = total - shift;
  entryTriangleKernel<<<(threads + 127) / 128, 128>>>(d_off, n, shift, d_out);
  ASSERT_EQ(cudaDeviceSynchronize(), cudaSuccess) << what;
  std::vector<std::uint32_t> got(total);
  ASSERT_EQ(cudaMemcpy(got.data(), d_out, total * sizeof(std::uint32_t), cudaMemcpyDeviceToHost),
            cudaSuccess);
  cudaFree(d_off);
  cudaFree(d_out);
  std::size_t wrong = 0;
  for (std::uint32_t e = shift; e < total; ++e) {
    // The last i with off[i] <= e.
    const auto want = static_cast<std::uint32_t>(
        std::upper_bound(off.begin(), off.begin() + n, e) - off.begin() - 1);
    if (got[e] != want && ++wrong <= 5)
      ADD_FAILURE() << what << ": entry " << e << " gave triangle " << got[e] << ", not " << want;
  }
  EXPECT_EQ(wrong, 0u) << what;
}

TEST(CudaWarpSearch, EachEntrysTriangleIsTheBinarySearchs) {
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::uint32_t> cells(1, 8);
  for (const std::uint32_t n : {1u, 2u, 31u, 32u, 33u, 1000u, 92230u, 200000u}) {
    std::vector<std::uint32_t> counts(n);
    for (auto& c : counts) c = cells(rng);
    const std::string what = std::to_string(n) + " triangles";
    check(counts, 0, what);
    for (const std::uint32_t shift : {1u, 17u, 31u})
      if (scanOf(counts).back() > shift)
        check(counts, shift, what + ", from entry " + std::to_string(shift));
  }
  // One entry each: every warp's 32 entries are its 32 triangles.
  check(std::vector<std::uint32_t>(5000, 1), 0, "one entry each");
}

TEST(CudaWarpSearch, EntriesPastTrianglesWithoutEntriesAreFound) {
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
  std::mt19937 rng(12);
  std::uniform_int_distribution<std::uint32_t> cells(0, 3);
  for (const std::uint32_t n : {40u, 3000u, 100000u}) {
    std::vector<std::uint32_t> counts(n);
    for (auto& c : counts) c = cells(rng);
    counts[0] = 0;  // the first triangles hold none
    counts[1] = 0;
    // A run of 100 triangles without entries, and one of exactly 32, inside the warps' windows.
    for (std::uint32_t i = n / 3; i < std::min(n, n / 3 + 100); ++i) counts[i] = 0;
    for (std::uint32_t i = 2 * n / 3; i < std::min(n, 2 * n / 3 + 32); ++i) counts[i] = 0;
    counts[n - 1] = 0;  // and the last
    const std::string what = std::to_string(n) + " triangles, some without entries";
    for (const std::uint32_t shift : {0u, 5u})
      if (scanOf(counts).back() > shift)
        check(counts, shift, what + ", from entry " + std::to_string(shift));
  }
}

TEST(CudaWarpSearch, TheRingOfSeenEntriesGivesBackWhatWentOnInOrder) {
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
  std::mt19937 rng(13);
  const std::uint32_t rounds = 2000;
  // Rounds of each kind: none kept, all 32, one, 31, and random densities.
  std::vector<std::uint32_t> keep(rounds);
  for (std::uint32_t r = 0; r < rounds; ++r) {
    switch (r % 7) {
      case 0: keep[r] = 0u; break;
      case 1: keep[r] = 0xFFFFFFFFu; break;
      case 2: keep[r] = 1u << (rng() % 32); break;
      case 3: keep[r] = ~(1u << (rng() % 32)); break;
      default: keep[r] = rng() & rng() & (r % 2 ? rng() : 0xFFFFFFFFu); break;
    }
  }
  std::vector<std::uint32_t> want;  // value, tag
  for (std::uint32_t r = 0; r < rounds; ++r)
    for (std::uint32_t l = 0; l < 32; ++l)
      if ((keep[r] >> l) & 1u) want.insert(want.end(), {r * 32 + l, r % 251});
  std::uint32_t *d_keep = nullptr, *d_out = nullptr;
  const std::size_t out_words = 1 + 2 * 32 * rounds;
  ASSERT_EQ(cudaMalloc(&d_keep, rounds * sizeof(std::uint32_t)), cudaSuccess);
  ASSERT_EQ(cudaMalloc(&d_out, out_words * sizeof(std::uint32_t)), cudaSuccess);
  ASSERT_EQ(cudaMemcpy(d_keep, keep.data(), rounds * sizeof(std::uint32_t),
                       cudaMemcpyHostToDevice),
            cudaSuccess);
  // Popped only when 32 are queued, and also drained every round, every 3rd and every 64th.
  for (const std::uint32_t drain : {0u, 1u, 3u, 64u}) {
    const std::string what = "drained every " + std::to_string(drain) + " rounds";
    ASSERT_EQ(cudaMemset(d_out, 0xFF, out_words * sizeof(std::uint32_t)), cudaSuccess);
    ringKernel<<<1, 32>>>(d_keep, rounds, drain, d_out);
    ASSERT_EQ(cudaDeviceSynchronize(), cudaSuccess) << what;
    std::vector<std::uint32_t> got(out_words);
    ASSERT_EQ(cudaMemcpy(got.data(), d_out, out_words * sizeof(std::uint32_t),
                         cudaMemcpyDeviceToHost),
              cudaSuccess);
    ASSERT_EQ(got[0], want.size() / 2) << what;
    const std::vector<std::uint32_t> items(got.begin() + 1, got.begin() + 1 + want.size());
    EXPECT_EQ(items, want) << what;
  }
  cudaFree(d_keep);
  cudaFree(d_out);
}

TEST(CudaWarpSearch, SpreadItemsAreEachTakenOnceAndFewItemsOnePerWarp) {
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
  for (const unsigned int blocks : {1u, 3u, 264u}) {
    const unsigned long long warps = blocks * 4ull;  // blocks of 128 threads
    for (const unsigned long long m :
         {0ull, 1ull, warps - 1, warps, warps + 1, 32 * warps - 1, 32 * warps, 32 * warps + 5,
          3 * 32 * warps + 77}) {
      const std::string what = std::to_string(blocks) + " blocks, " + std::to_string(m) + " items";
      unsigned int* d = nullptr;
      const std::size_t words = m + warps;
      ASSERT_EQ(cudaMalloc(&d, words * sizeof(unsigned int)), cudaSuccess);
      ASSERT_EQ(cudaMemset(d, 0, words * sizeof(unsigned int)), cudaSuccess);
      spreadKernel<<<blocks, 128>>>(m, warps, d);
      ASSERT_EQ(cudaDeviceSynchronize(), cudaSuccess) << what;
      std::vector<unsigned int> hits(words);
      ASSERT_EQ(cudaMemcpy(hits.data(), d, words * sizeof(unsigned int), cudaMemcpyDeviceToHost),
                cudaSuccess);
      cudaFree(d);
      EXPECT_EQ(std::count(hits.begin(), hits.begin() + m, 1u), static_cast<long>(m)) << what;
      // The first W items: one per warp, each warp one at most.
      const unsigned long long few = m < warps ? m : warps;
      EXPECT_EQ(std::count(hits.begin() + m, hits.end(), 1u), static_cast<long>(few)) << what;
      EXPECT_EQ(std::count(hits.begin() + m, hits.end(), 0u), static_cast<long>(warps - few))
          << what;
    }
  }
}

}  // namespace
