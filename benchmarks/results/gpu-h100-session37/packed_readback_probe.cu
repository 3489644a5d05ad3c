// Packed read-back probe (session 37, device call 1): does reading the pairs back as 5-byte keys
// (the key (a << b_bits) | b split into its low 32 bits and its high byte, in blocks of 32,768
// pairs: [low words][high bytes]) instead of 8-byte (a, b) pairs shorten the host read-back?
// The host's copy of freshly DMA'd data, not the bus, bounds the 8-byte read-back (session 36).
// For n = 445,614 (the two cloth-ball frames) and 61,530 (the cloth ball), medians of 60 after 10
// of warm-up, ms, into a kept (faulted-in) std::vector of 8-byte pairs:
//   p8-T    the library's form: 256 KiB chunks of 8-byte pairs queued at once, an event each, T
//           OpenMP threads each waiting for its chunks' events and copying them out (T = 1: one
//           thread, the form below 4 chunks)
//   p5-T    blocks of 32,768 5-byte keys (160 KiB) queued at once, an event each, T threads each
//           decoding its blocks into the pairs (a = key >> b_bits, b = key & mask)
//   p4-T    the same with 4-byte keys (meshes whose key fits in 32 bits)
//   k8/k5   the device-side delivery alone: a kernel writing n 8-byte pairs, or n 5-byte keys in
//           blocks, from n 64-bit keys (the order's last step)
// Build: nvcc -O3 -arch=sm_90 -Xcompiler -fopenmp packed_readback_probe.cu -o probe
#include <cuda_runtime.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#define CK(x)                                                   \
  do {                                                          \
    cudaError_t err = (x);                                      \
    if (err != cudaSuccess) {                                   \
      std::printf("%s: %s\n", #x, cudaGetErrorString(err));     \
      std::exit(1);                                             \
    }                                                           \
  } while (0)

struct Pair {
  std::uint32_t a, b;
};
constexpr std::size_t kBlock = 32768;
constexpr int kBBits = 18;

__global__ void deliver8(std::size_t n, const unsigned long long* keys, uint2* out) {
  for (std::size_t k = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; k < n;
       k += std::size_t(gridDim.x) * blockDim.x) {
    const unsigned long long u = keys[k];
    out[k] = make_uint2(static_cast<unsigned>(u >> kBBits),
                        static_cast<unsigned>(u & ((1ull << kBBits) - 1)));
  }
}
__global__ void deliver5(std::size_t n, const unsigned long long* keys, unsigned char* out) {
  for (std::size_t k = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; k < n;
       k += std::size_t(gridDim.x) * blockDim.x) {
    const unsigned long long u = keys[k];
    unsigned char* blk = out + (k / kBlock) * kBlock * 5;
    reinterpret_cast<std::uint32_t*>(blk)[k % kBlock] = static_cast<std::uint32_t>(u);
    blk[4 * kBlock + k % kBlock] = static_cast<unsigned char>(u >> 32);
  }
}

static double now() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int main() {
  for (const std::size_t n : {std::size_t(445614), std::size_t(61530)}) {
    std::printf("== n %zu\n", n);
    std::vector<unsigned long long> keys(n);
    std::mt19937 rng(7);
    std::uint32_t a = 0;
    for (std::size_t k = 0; k < n; ++k) {
      a += (rng() % 3 == 0) ? 1 : 0;
      keys[k] = (static_cast<unsigned long long>(a) << kBBits) | (rng() % 184460u);
    }
    std::sort(keys.begin(), keys.end());
    unsigned long long* dkeys = nullptr;
    uint2* d8 = nullptr;
    unsigned char* d5 = nullptr;
    const std::size_t blocks = (n + kBlock - 1) / kBlock;
    CK(cudaMalloc(&dkeys, n * 8));
    CK(cudaMalloc(&d8, n * 8));
    CK(cudaMalloc(&d5, blocks * kBlock * 5));
    CK(cudaMemcpy(dkeys, keys.data(), n * 8, cudaMemcpyHostToDevice));
    unsigned char* stage = nullptr;
    CK(cudaMallocHost(&stage, n * 8 + kBlock * 8));
    std::vector<Pair> dst(n, Pair{1, 1});
    cudaStream_t s;
    CK(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking));
    std::vector<cudaEvent_t> ev(64);
    for (auto& e : ev) CK(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
    deliver8<<<264, 256, 0, s>>>(n, dkeys, d8);
    deliver5<<<264, 256, 0, s>>>(n, dkeys, d5);
    CK(cudaStreamSynchronize(s));
    auto run = [&](const char* name, auto&& body) {
      std::vector<double> t;
      for (int r = 0; r < 70; ++r) {
        CK(cudaStreamSynchronize(s));
        std::fill(dst.begin(), dst.end(), Pair{1, 1});  // (kept storage, touched)
        const double t0 = now();
        body();
        const double t1 = now();
        if (r >= 10) t.push_back(t1 - t0);
      }
      std::printf("%-8s median %.4f ms  min %.4f\n", name, median(t),
                  *std::min_element(t.begin(), t.end()));
    };
    auto check = [&](const char* name) {
      for (std::size_t k = 0; k < n; ++k)
        if (dst[k].a != (keys[k] >> kBBits) || dst[k].b != (keys[k] & ((1ull << kBBits) - 1))) {
          std::printf("%s: MISMATCH at %zu\n", name, k);
          return;
        }
    };
    // 8-byte pairs, 256 KiB chunks.
    const std::size_t c8 = 32768, chunks8 = (n + c8 - 1) / c8;
    for (int T : {1, 4, 8}) {
      char name[16];
      std::snprintf(name, sizeof name, "p8-%d", T);
      run(name, [&] {
        for (std::size_t c = 0; c < chunks8; ++c) {
          const std::size_t off = c * c8, len = std::min(c8, n - off);
          cudaMemcpyAsync(stage + off * 8, d8 + off, len * 8, cudaMemcpyDeviceToHost, s);
          cudaEventRecord(ev[c], s);
        }
#pragma omp parallel for num_threads(T) schedule(dynamic, 1)
        for (long c = 0; c < long(chunks8); ++c) {
          cudaEventSynchronize(ev[c]);
          const std::size_t off = c * c8, len = std::min(c8, n - off);
          std::memcpy(dst.data() + off, stage + off * 8, len * 8);
        }
      });
      check(name);
    }
    // 5-byte keys in blocks.
    for (int T : {1, 4, 8}) {
      char name[16];
      std::snprintf(name, sizeof name, "p5-%d", T);
      run(name, [&] {
        for (std::size_t c = 0; c < blocks; ++c) {
          const std::size_t len = std::min(kBlock, n - c * kBlock);
          unsigned char* src = d5 + c * kBlock * 5;
          unsigned char* to = stage + c * kBlock * 5;
          if (len == kBlock) {
            cudaMemcpyAsync(to, src, kBlock * 5, cudaMemcpyDeviceToHost, s);
          } else {
            cudaMemcpyAsync(to, src, len * 4, cudaMemcpyDeviceToHost, s);
            cudaMemcpyAsync(to + 4 * kBlock, src + 4 * kBlock, len, cudaMemcpyDeviceToHost, s);
          }
          cudaEventRecord(ev[c], s);
        }
#pragma omp parallel for num_threads(T) schedule(dynamic, 1)
        for (long c = 0; c < long(blocks); ++c) {
          cudaEventSynchronize(ev[c]);
          const std::size_t off = c * kBlock, len = std::min(kBlock, n - off);
          const std::uint32_t* lo = reinterpret_cast<const std::uint32_t*>(stage + c * kBlock * 5);
          const unsigned char* hi = stage + c * kBlock * 5 + 4 * kBlock;
          Pair* out = dst.data() + off;
          for (std::size_t k = 0; k < len; ++k) {
            const unsigned long long u = (static_cast<unsigned long long>(hi[k]) << 32) | lo[k];
            out[k].a = static_cast<std::uint32_t>(u >> kBBits);
            out[k].b = static_cast<std::uint32_t>(u & ((1u << kBBits) - 1));
          }
        }
      });
      check(name);
    }
    // 4-byte keys (the low words alone; decoded as if the high byte were 0: timing only).
    for (int T : {1, 4}) {
      char name[16];
      std::snprintf(name, sizeof name, "p4-%d", T);
      run(name, [&] {
        for (std::size_t c = 0; c < blocks; ++c) {
          const std::size_t len = std::min(kBlock, n - c * kBlock);
          cudaMemcpyAsync(stage + c * kBlock * 4, d5 + c * kBlock * 5, len * 4,
                          cudaMemcpyDeviceToHost, s);
          cudaEventRecord(ev[c], s);
        }
#pragma omp parallel for num_threads(T) schedule(dynamic, 1)
        for (long c = 0; c < long(blocks); ++c) {
          cudaEventSynchronize(ev[c]);
          const std::size_t off = c * kBlock, len = std::min(kBlock, n - off);
          const std::uint32_t* lo = reinterpret_cast<const std::uint32_t*>(stage + c * kBlock * 4);
          Pair* out = dst.data() + off;
          for (std::size_t k = 0; k < len; ++k) {
            out[k].a = lo[k] >> kBBits;
            out[k].b = lo[k] & ((1u << kBBits) - 1);
          }
        }
      });
    }
    // The device-side delivery alone.
    cudaEvent_t e0, e1;
    CK(cudaEventCreate(&e0));
    CK(cudaEventCreate(&e1));
    for (int form : {8, 5}) {
      std::vector<double> t;
      for (int r = 0; r < 70; ++r) {
        cudaEventRecord(e0, s);
        if (form == 8)
          deliver8<<<264, 256, 0, s>>>(n, dkeys, d8);
        else
          deliver5<<<264, 256, 0, s>>>(n, dkeys, d5);
        cudaEventRecord(e1, s);
        CK(cudaEventSynchronize(e1));
        float ms = 0;
        cudaEventElapsedTime(&ms, e0, e1);
        if (r >= 10) t.push_back(ms);
      }
      std::printf("k%d      median %.4f ms (device events)\n", form, median(t));
    }
    cudaFree(dkeys);
    cudaFree(d8);
    cudaFree(d5);
    cudaFreeHost(stage);
  }
  return 0;
}
