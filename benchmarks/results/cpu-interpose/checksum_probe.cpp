// Session 53: the cost of CacheValidation::Checksum's pass over a model's arrays, by size and
// threads: the vector checksum (src/fcl/checksum.h, the kernel the library picks) against the
// 64-bit scalar chain it replaced (four multiply-xorshift lanes, copied here as it was in
// src/fcl/fcl_collide.cpp up to 4686231). Medians of repeated passes over one buffer, in µs.
// Build (from the checkout; the library's two sources it needs, no FCL), on one line:
//   g++ -O3 -std=c++17 -Isrc -Iinclude benchmarks/results/cpu-interpose/checksum_probe.cpp
//     src/fcl/checksum.cpp src/cpu/worker_pool.cpp -pthread -o /tmp/checksum_probe
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <thread>
#include <vector>

#include "fcl/checksum.h"

namespace {

// The checksum before session 53 (scalar, four independent 64-bit chains).
std::uint64_t scalarChecksum(const void* data, std::size_t bytes, std::uint64_t seed) {
  constexpr std::uint64_t K = 0x9E3779B97F4A7C15ull;
  std::uint64_t h[4] = {seed ^ 0x243F6A8885A308D3ull, seed ^ 0x13198A2E03707344ull,
                        seed ^ 0xA4093822299F31D0ull, seed ^ 0x082EFA98EC4E6C89ull};
  const unsigned char* p = static_cast<const unsigned char*>(data);
  const std::size_t words = bytes / 8;
  std::size_t i = 0;
  for (; i + 4 <= words; i += 4) {
    std::uint64_t w[4];
    std::memcpy(w, p + 8 * i, 32);
    for (int k = 0; k < 4; ++k) {
      h[k] = (h[k] ^ w[k]) * K;
      h[k] ^= h[k] >> 29;
    }
  }
  for (; i < words; ++i) {
    std::uint64_t w;
    std::memcpy(&w, p + 8 * i, 8);
    h[0] = (h[0] ^ w) * K;
    h[0] ^= h[0] >> 29;
  }
  std::uint64_t tail = 0;
  std::memcpy(&tail, p + 8 * words, bytes - 8 * words);
  std::uint64_t r = (tail ^ bytes) * K;
  for (int k = 0; k < 4; ++k) {
    r = (r ^ h[k]) * K;
    r ^= r >> 31;
  }
  return r;
}

// Spins for `micros` µs with scalar work only (no vector instructions): the time a program spends
// elsewhere between two queries.
void spin(double micros) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double, std::micro>(micros);
  while (std::chrono::steady_clock::now() < end) {
  }
}

// Reads `bytes` of another buffer: the other data a program's query touches between two
// checksums, which pushes the model's arrays out of the nearer caches.
std::uint64_t readElsewhere(std::size_t bytes) {
  static std::vector<std::uint64_t> other;
  if (other.size() < bytes / 8) other.assign(bytes / 8, 1);
  std::uint64_t s = 0;
  for (std::size_t i = 0; i < bytes / 8; i += 8) s += other[i];  // a line at a time
  return s;
}

template <class F>
double medianMicros(F&& f, std::size_t bytes, double gap_micros = 0, std::size_t evict = 0) {
  const int reps = bytes > (64u << 20) ? 7 : bytes > (8u << 20) ? 21 : 101;
  std::vector<double> t;
  volatile std::uint64_t sink = 0;
  for (int r = 0; r < reps + 2; ++r) {
    if (gap_micros > 0) spin(gap_micros);
    if (evict > 0) sink = sink + readElsewhere(evict);
    const auto a = std::chrono::steady_clock::now();
    sink = sink + f();
    const auto b = std::chrono::steady_clock::now();
    if (r >= 2) t.push_back(std::chrono::duration<double, std::micro>(b - a).count());
  }
  std::nth_element(t.begin(), t.begin() + t.size() / 2, t.end());
  return t[t.size() / 2];
}

}  // namespace

int main() {
  using namespace kdet_fcl::detail;
  const int hw = int(std::max(1u, std::thread::hardware_concurrency()));
  std::printf("kernel %d (0 portable, 1 SSE4.1, 2 AVX2), %d hardware threads; the scalar column is the checksum before\n",
              int(bestChecksumKernel()), hw);
  std::printf("%12s %10s %10s", "bytes", "scalar", "1 thread");
  std::vector<int> threads;
  for (int t = 2; t <= hw; t *= 2) threads.push_back(t);
  for (int t : threads) std::printf(" %8d th", t);
  std::printf("   (µs; GB/s of the best)\n");
  // The interposer bench's small meshes (193.5 KB), its sheet and sphere (3.6 MB), a 1M-triangle
  // model's arrays (36 MB: 24 B a triangle, 24 B a vertex, half as many vertices) and 4M's.
  for (std::size_t bytes : {std::size_t(193536), std::size_t(1) << 20, std::size_t(3600000),
                            std::size_t(8) << 20, std::size_t(16) << 20, std::size_t(36000000),
                            std::size_t(144000000)}) {
    std::vector<unsigned char> buf(bytes);
    for (std::size_t i = 0; i < bytes; ++i) buf[i] = static_cast<unsigned char>(i * 131 + 7);
    const double scalar =
        medianMicros([&] { return scalarChecksum(buf.data(), bytes, 1); }, bytes);
    double best = 1e30;
    std::printf("%12zu %10.1f", bytes, scalar);
    for (int t : std::vector<int>{1}) {
      const double us = medianMicros([&] { return checksumBytes(buf.data(), bytes, 1, t); }, bytes);
      best = std::min(best, us);
      std::printf(" %10.1f", us);
    }
    for (int t : threads) {
      const double us = medianMicros([&] { return checksumBytes(buf.data(), bytes, 1, t); }, bytes);
      best = std::min(best, us);
      std::printf(" %11.1f", us);
    }
    std::printf("   (%.1f GB/s)\n", double(bytes) / best / 1e3);
  }
  // Each kernel on one thread, back to back and after a gap of scalar work (a program's other
  // work between queries; Intel cores slow their 256-bit units down after they idle).
  std::printf("\nby kernel, one thread (µs): back to back / after 20 µs / after 200 µs / after 2 ms "
              "of scalar work / after reading 4 MB / 64 MB elsewhere\n");
  for (std::size_t bytes : {std::size_t(193536), std::size_t(1) << 20, std::size_t(3600000)}) {
    std::vector<unsigned char> buf(bytes);
    for (std::size_t i = 0; i < bytes; ++i) buf[i] = static_cast<unsigned char>(i * 131 + 7);
    std::printf("%12zu  scalar", bytes);
    for (double gap : {0.0, 20.0, 200.0, 2000.0})
      std::printf(" %7.1f", medianMicros([&] { return scalarChecksum(buf.data(), bytes, 1); }, bytes, gap));
    for (std::size_t evict : {std::size_t(4) << 20, std::size_t(64) << 20})
      std::printf(" %7.1f", medianMicros([&] { return scalarChecksum(buf.data(), bytes, 1); }, bytes, 0, evict));
    for (ChecksumKernel k : {ChecksumKernel::Portable, ChecksumKernel::Sse41, ChecksumKernel::Avx2}) {
      if (!checksumKernelAvailable(k)) continue;
      std::printf("  kernel %d", int(k));
      for (double gap : {0.0, 20.0, 200.0, 2000.0})
        std::printf(" %7.1f", medianMicros([&] { return checksumBytes(buf.data(), bytes, 1, k); }, bytes, gap));
      for (std::size_t evict : {std::size_t(4) << 20, std::size_t(64) << 20})
        std::printf(" %7.1f", medianMicros([&] { return checksumBytes(buf.data(), bytes, 1, k); }, bytes, 0, evict));
    }
    std::printf("\n");
  }
}
