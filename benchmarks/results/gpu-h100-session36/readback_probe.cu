// Read-back probe (device call 3): where the two cloth-ball frames' 3.6 MB host read-back goes.
// 445,614 eight-byte pairs in device memory; medians of 60 after 10 of warm-up, ms:
//   dma      one cudaMemcpyAsync into page-locked memory, then cudaEventSynchronize
//   chunks   the same in 256 KiB chunks, an event after each, the host waiting for the last
//   copy1/4  the host's memcpy of 3.6 MB from the page-locked stage into a kept (faulted-in)
//            std::vector, by 1 or 4 OpenMP threads
//   pipedN   chunks queued at once, N OpenMP threads each waiting for its chunks' events and
//            copying them out as they land (the library's pooled read-back, in miniature)
//   dma+cpN  (call 4) the whole DMA, then the copy by N threads
//   piped4q  piped4 with each thread polling its chunk's event (cudaEventQuery)
//   piped4m  1 MiB chunks, each copied by the 4 threads in quarters
// Build: nvcc -O3 -arch=sm_90 -Xcompiler -fopenmp readback_probe.cu -o readback_probe
#include <cuda_runtime.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

#define CK(x)                                                              \
  do {                                                                     \
    cudaError_t err = (x);                                                 \
    if (err != cudaSuccess) {                                              \
      std::printf("%s: %s\n", #x, cudaGetErrorString(err));                \
      return 1;                                                            \
    }                                                                      \
  } while (0)

static double now() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

int main() {
  const std::size_t n = 445614, bytes = n * 8, chunk = 256 * 1024;
  const std::size_t chunks = (bytes + chunk - 1) / chunk;
  std::uint64_t *dev = nullptr, *stage = nullptr;
  CK(cudaMalloc(&dev, bytes));
  CK(cudaMemset(dev, 1, bytes));
  CK(cudaMallocHost(&stage, bytes));
  std::vector<std::uint64_t> dst(n, 0);
  cudaStream_t s;
  CK(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking));
  std::vector<cudaEvent_t> ev(chunks);
  for (auto& event : ev) CK(cudaEventCreateWithFlags(&event, cudaEventDisableTiming));
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  auto run = [&](const char* name, auto&& body) {
    std::vector<double> t;
    for (int r = 0; r < 70; ++r) {
      CK(cudaStreamSynchronize(s));
      const double a = now();
      body();
      const double b = now();
      if (r >= 10) t.push_back(b - a);
    }
    std::printf("%-8s median %.4f ms  min %.4f  (%.1f GB/s)\n", name, median(t),
                *std::min_element(t.begin(), t.end()), bytes / median(t) / 1e6);
    return 0;
  };
  auto enqueueChunks = [&] {
    for (std::size_t c = 0; c < chunks; ++c) {
      const std::size_t off = c * chunk, len = std::min(chunk, bytes - off);
      cudaMemcpyAsync(reinterpret_cast<char*>(stage) + off, reinterpret_cast<char*>(dev) + off,
                      len, cudaMemcpyDeviceToHost, s);
      cudaEventRecord(ev[c], s);
    }
  };
  auto copyOut = [&](int threads) {
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (long c = 0; c < long(chunks); ++c) {
      const std::size_t off = c * chunk, len = std::min(chunk, bytes - off);
      std::memcpy(reinterpret_cast<char*>(dst.data()) + off,
                  reinterpret_cast<char*>(stage) + off, len);
    }
  };
  run("dma", [&] {
    cudaMemcpyAsync(stage, dev, bytes, cudaMemcpyDeviceToHost, s);
    cudaEventRecord(ev[0], s);
    cudaEventSynchronize(ev[0]);
  });
  run("chunks", [&] {
    enqueueChunks();
    cudaEventSynchronize(ev[chunks - 1]);
  });
  run("copy1", [&] { copyOut(1); });
  run("copy4", [&] { copyOut(4); });
  run("copy8", [&] { copyOut(8); });
  for (int threads : {1, 4, 8}) {
    char name[16];
    std::snprintf(name, sizeof name, "piped%d", threads);
    run(name, [&] {
      enqueueChunks();
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
      for (long c = 0; c < long(chunks); ++c) {
        cudaEventSynchronize(ev[c]);
        const std::size_t off = c * chunk, len = std::min(chunk, bytes - off);
        std::memcpy(reinterpret_cast<char*>(dst.data()) + off,
                    reinterpret_cast<char*>(stage) + off, len);
      }
    });
  }
  // (call 4) The whole DMA first, then the copy by 4, 8 or 16 threads; and the pipelined form
  // with 1 MiB chunks, or with each thread polling its chunk's event (cudaEventQuery).
  for (int threads : {4, 8, 16}) {
    char name[16];
    std::snprintf(name, sizeof name, "dma+cp%d", threads);
    run(name, [&] {
      cudaMemcpyAsync(stage, dev, bytes, cudaMemcpyDeviceToHost, s);
      cudaEventRecord(ev[0], s);
      cudaEventSynchronize(ev[0]);
      copyOut(threads);
    });
  }
  run("piped4q", [&] {
    enqueueChunks();
#pragma omp parallel for num_threads(4) schedule(dynamic, 1)
    for (long c = 0; c < long(chunks); ++c) {
      while (cudaEventQuery(ev[c]) == cudaErrorNotReady) {
      }
      const std::size_t off = c * chunk, len = std::min(chunk, bytes - off);
      std::memcpy(reinterpret_cast<char*>(dst.data()) + off,
                  reinterpret_cast<char*>(stage) + off, len);
    }
  });
  const std::size_t big = 1024 * 1024, bigs = (bytes + big - 1) / big;
  run("piped4m", [&] {
    for (std::size_t c = 0; c < bigs; ++c) {
      const std::size_t off = c * big, len = std::min(big, bytes - off);
      cudaMemcpyAsync(reinterpret_cast<char*>(stage) + off, reinterpret_cast<char*>(dev) + off,
                      len, cudaMemcpyDeviceToHost, s);
      cudaEventRecord(ev[c], s);
    }
#pragma omp parallel for num_threads(4) schedule(static, 1)
    for (long t = 0; t < 4 * long(bigs); ++t) {  // each chunk's quarters by 4 threads
      const long c = t / 4, q = t % 4;
      cudaEventSynchronize(ev[c]);
      const std::size_t off = c * big, len = std::min(big, bytes - off);
      const std::size_t part = (len / 4 + 7) & ~std::size_t(7);
      const std::size_t a = std::min(len, q * part), b = std::min(len, a + part);
      std::memcpy(reinterpret_cast<char*>(dst.data()) + off + a,
                  reinterpret_cast<char*>(stage) + off + a, b - a);
    }
  });
  std::printf("check %llu\n", static_cast<unsigned long long>(dst[n / 2]));
  return 0;
}
