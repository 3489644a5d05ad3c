// Probe (device call 7): what a query pass's small stream operations cost around its kernels, by
// host wall time per pass (median of 400): (1) a kernel, then the 104-byte counters' copy to
// pinned memory, then cudaStreamSynchronize (the pass's end today); (2) the same kernel writing
// the counters into mapped pinned memory itself, then the sync (no copy); (3) two memsets (104 B
// and 256 KiB) before a kernel against (4) one kernel clearing both. Each variant checks what the
// host reads back. nvcc -O3 -arch=sm_90 trip_probe.cu -o trip_probe
#include <cuda_runtime.h>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

__global__ void work(unsigned long long* w, unsigned long long* mapped, int iters, unsigned long long tag) {
  // A small kernel (about the fused order's size) that leaves 13 counters in w.
  float v = threadIdx.x;
  for (int k = 0; k < iters; ++k) v = v * 0.999f + 1.0f;
  if (blockIdx.x == 0 && threadIdx.x < 13) {
    w[threadIdx.x] = tag + threadIdx.x + (v < 0 ? 1 : 0);
    if (mapped != nullptr) {
      mapped[threadIdx.x] = tag + threadIdx.x + (v < 0 ? 1 : 0);
    }
  }
}
__global__ void clearBoth(unsigned long long* w, int nw, unsigned int* seg, int ns) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < nw) w[i] = 0;
  for (int k = i; k < ns; k += gridDim.x * blockDim.x) seg[k] = 0;
}

int main() {
  cudaSetDeviceFlags(cudaDeviceMapHost);
  cudaStream_t s;
  cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking);
  unsigned long long *w, *h, *hd;
  unsigned int* seg;
  cudaMalloc(&w, 13 * 8);
  cudaMalloc(&seg, 65536 * 4);
  cudaHostAlloc(&h, 13 * 8, cudaHostAllocMapped);
  cudaHostGetDevicePointer(&hd, h, 0);
  const int reps = 400;
  for (int iters : {0, 2000}) {
    for (int mode = 0; mode < 4; ++mode) {
      std::vector<double> us;
      int bad = 0;
      for (int r = 0; r < reps + 50; ++r) {
        const unsigned long long tag = 1000ull * r;
        h[0] = 0;
        const auto t0 = std::chrono::steady_clock::now();
        if (mode == 2) {
          cudaMemsetAsync(w, 0, 13 * 8, s);
          cudaMemsetAsync(seg, 0, 65536 * 4, s);
        } else if (mode == 3) {
          clearBoth<<<64, 256, 0, s>>>(w, 13, seg, 65536);
        }
        work<<<132, 256, 0, s>>>(w, mode == 1 ? hd : nullptr, iters, tag);
        if (mode != 1) cudaMemcpyAsync(h, w, 13 * 8, cudaMemcpyDeviceToHost, s);
        cudaStreamSynchronize(s);
        const auto t1 = std::chrono::steady_clock::now();
        bad += h[0] != tag || h[12] != tag + 12;
        if (r >= 50) us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
      }
      std::sort(us.begin(), us.end());
      const char* names[] = {"kernel + counters' copy + sync", "kernel writes mapped counters + sync",
                             "2 memsets + kernel + copy + sync", "clear kernel + kernel + copy + sync"};
      printf("iters=%4d %-40s median %6.2f us  p10 %6.2f  p90 %6.2f  bad=%d  err=%s\n", iters,
             names[mode], us[us.size() / 2], us[us.size() / 10], us[us.size() * 9 / 10], bad,
             cudaGetErrorString(cudaGetLastError()));
    }
  }
  return 0;
}
