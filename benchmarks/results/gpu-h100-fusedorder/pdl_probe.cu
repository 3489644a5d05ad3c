// Probe (device call 2): what programmatic dependent launch (PDL: each kernel launched with
// cudaLaunchAttributeProgrammaticStreamSerialization, waiting for its predecessor at its top with
// cudaGridDependencySynchronize) saves per kernel in a chain of small dependent kernels, against
// plain launches, eagerly and as a captured graph. Each kernel reads the array the one before
// wrote (n floats), so every step depends on the last; the final sum checks that no step read
// early. nvcc -O3 -arch=sm_90 pdl_probe.cu -o pdl_probe
#include <cuda_runtime.h>
#include <algorithm>
#include <cstdio>
#include <vector>

__global__ void step(const float* __restrict__ in, float* __restrict__ out, int n, int iters) {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
  cudaGridDependencySynchronize();
#endif
  for (int i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x) {
    float v = in[i];
    for (int k = 0; k < iters; ++k) v = v * 0.999f + 1.0f;
    out[i] = v;
  }
}

static void launch(bool pdl, cudaStream_t s, const float* in, float* out, int n, int iters,
                   int blocks) {
  cudaLaunchConfig_t cfg = {};
  cfg.gridDim = dim3(blocks);
  cfg.blockDim = dim3(256);
  cfg.stream = s;
  cudaLaunchAttribute a = {};
  a.id = cudaLaunchAttributeProgrammaticStreamSerialization;
  a.val.programmaticStreamSerializationAllowed = 1;
  cfg.attrs = &a;
  cfg.numAttrs = pdl ? 1 : 0;
  cudaLaunchKernelEx(&cfg, step, in, out, n, iters);
}

int main() {
  cudaStream_t s;
  cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking);
  cudaEvent_t e0, e1;
  cudaEventCreate(&e0);
  cudaEventCreate(&e1);
  const int chain = 20;
  for (int n : {22400, 100000, 1000000}) {
    for (int iters : {0, 50}) {
      float *a, *b;
      cudaMalloc(&a, n * sizeof(float));
      cudaMalloc(&b, n * sizeof(float));
      const int blocks = std::min((n + 255) / 256, 132 * 8);
      for (int mode = 0; mode < 4; ++mode) {
        const bool pdl = mode & 1, graph = mode & 2;
        cudaGraphExec_t exec = nullptr;
        auto body = [&] {
          cudaMemsetAsync(a, 0, n * sizeof(float), s);
          for (int k = 0; k < chain; ++k)
            launch(pdl, s, k % 2 ? b : a, k % 2 ? a : b, n, iters, blocks);
        };
        if (graph) {
          cudaGraph_t g;
          cudaStreamBeginCapture(s, cudaStreamCaptureModeRelaxed);
          body();
          cudaStreamEndCapture(s, &g);
          if (cudaGraphInstantiate(&exec, g, 0) != cudaSuccess) {
            printf("instantiate failed: %s\n", cudaGetErrorString(cudaGetLastError()));
            continue;
          }
          cudaGraphDestroy(g);
        }
        std::vector<float> ms;
        for (int r = 0; r < 60; ++r) {
          cudaEventRecord(e0, s);
          if (graph) cudaGraphLaunch(exec, s);
          else body();
          cudaEventRecord(e1, s);
          cudaEventSynchronize(e1);
          float t = 0;
          cudaEventElapsedTime(&t, e0, e1);
          if (r >= 10) ms.push_back(t);
        }
        std::sort(ms.begin(), ms.end());
        std::vector<float> h(n);
        cudaMemcpy(h.data(), a, n * sizeof(float), cudaMemcpyDeviceToHost);  // chain even: in a
        // Expected: after `chain` steps from 0, each iters-fold map applied chain times.
        double want = 0;
        for (int k = 0; k < chain; ++k) {
          float v = float(want);
          for (int i = 0; i < iters; ++i) v = v * 0.999f + 1.0f;
          want = v;
        }
        int bad = 0;
        for (int i = 0; i < n; ++i) bad += h[i] != float(want);
        printf("n=%8d iters=%3d %-5s %-6s median %.1f us per chain of %d = %.2f us/kernel  bad=%d  err=%s\n",
               n, iters, pdl ? "PDL" : "plain", graph ? "graph" : "eager", 1000 * ms[ms.size() / 2],
               chain, 1000 * ms[ms.size() / 2] / chain, bad, cudaGetErrorString(cudaGetLastError()));
        if (exec) cudaGraphExecDestroy(exec);
      }
      cudaFree(a);
      cudaFree(b);
    }
  }
  return 0;
}
