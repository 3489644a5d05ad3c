// Device->host read-back strategies into a fresh std::vector (probe, not project code).
#include <cuda_runtime.h>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>
#define CK(x) do { cudaError_t e = (x); if (e != cudaSuccess) { printf("CUDA %s line %d\n", cudaGetErrorString(e), __LINE__); exit(1); } } while (0)
using clk = std::chrono::steady_clock;
static double ms(clk::time_point a, clk::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }
struct P { unsigned a, b; };
__global__ void busy(unsigned long long* d, size_t n, long long cycles) {
  long long t0 = clock64(); while (clock64() - t0 < cycles) {}
  for (size_t i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x) d[i] = i * 2654435761ull;
}
struct Pool {  // persistent workers, woken by a condition variable
  std::vector<std::thread> th; std::mutex m; std::condition_variable cv, done_cv; std::function<void()> job; unsigned gen = 0; int running = 0; bool stop = false;
  explicit Pool(int n) { for (int i = 0; i < n; ++i) th.emplace_back([this] { unsigned seen = 0; for (;;) { std::function<void()> j; { std::unique_lock<std::mutex> l(m); cv.wait(l, [&] { return stop || gen != seen; }); if (stop) return; seen = gen; j = job; } j(); { std::lock_guard<std::mutex> l(m); if (--running == 0) done_cv.notify_all(); } } }); }
  void start(std::function<void()> j) { std::lock_guard<std::mutex> l(m); job = std::move(j); running = int(th.size()); ++gen; cv.notify_all(); }
  void wait() { std::unique_lock<std::mutex> l(m); done_cv.wait(l, [&] { return running == 0; }); }
  ~Pool() { { std::lock_guard<std::mutex> l(m); stop = true; } cv.notify_all(); for (auto& t : th) t.join(); }
};
int main() {
  cudaStream_t s; CK(cudaStreamCreate(&s)); CK(cudaFree(0));
  int clk_khz = 0; cudaDeviceGetAttribute(&clk_khz, cudaDevAttrClockRate, 0);
  const long long cycles = (long long)clk_khz * 100 / 1000;  // ~0.1 ms of GPU work before the read-back
  for (size_t npairs : {size_t(61530), size_t(445614), size_t(1000000)}) {
    const size_t bytes = npairs * 8;
    unsigned long long* dev; CK(cudaMalloc(&dev, bytes));
    char* stage; CK(cudaMallocHost(&stage, bytes + 4096));
    std::vector<P> ref(npairs); busy<<<264, 256, 0, s>>>(dev, npairs, 0); CK(cudaMemcpy(ref.data(), dev, bytes, cudaMemcpyDeviceToHost));
    auto run = [&](const char* name, auto&& f) {
      std::vector<double> t; bool ok = true;
      for (int r = 0; r < 40; ++r) {
        auto a = clk::now(); busy<<<264, 256, 0, s>>>(dev, npairs, cycles);
        std::vector<P> out = f(); auto b = clk::now();
        if (r >= 8) t.push_back(ms(a, b));
        ok = ok && out.size() == npairs && std::memcmp(out.data(), ref.data(), bytes) == 0;
      }
      std::sort(t.begin(), t.end());
      printf("%8zu pairs  %-34s median %.3f ms  min %.3f  %s\n", npairs, name, t[t.size() / 2], t[0], ok ? "ok" : "WRONG");
    };
    run("A whole DMA, sync, assign", [&] { std::vector<P> v; cudaMemcpyAsync(stage, dev, bytes, cudaMemcpyDeviceToHost, s); cudaStreamSynchronize(s); auto* p = (const P*)stage; v.assign(p, p + npairs); return v; });
    run("B whole DMA, resize, sync, memcpy", [&] { std::vector<P> v; cudaMemcpyAsync(stage, dev, bytes, cudaMemcpyDeviceToHost, s); v.resize(npairs); cudaStreamSynchronize(s); std::memcpy(v.data(), stage, bytes); return v; });
    run("K kernel only (sync)", [&] { cudaStreamSynchronize(s); return ref; });
    for (size_t chunk : {size_t(64) << 10, size_t(256) << 10, size_t(1) << 20}) {
      char nm[80];
      const size_t nc = (bytes + chunk - 1) / chunk;
      std::vector<cudaEvent_t> ev(nc); for (auto& e : ev) cudaEventCreateWithFlags(&e, cudaEventDisableTiming);
      auto enqueue = [&] { for (size_t c = 0; c < nc; ++c) { size_t o = c * chunk, n = std::min(chunk, bytes - o); cudaMemcpyAsync(stage + o, (char*)dev + o, n, cudaMemcpyDeviceToHost, s); cudaEventRecord(ev[c], s); } };
      snprintf(nm, 80, "C chunk %zuK 1T insert", chunk >> 10);
      run(nm, [&] { std::vector<P> v; enqueue(); v.reserve(npairs); for (size_t c = 0; c < nc; ++c) { cudaEventSynchronize(ev[c]); size_t o = c * chunk, n = std::min(chunk, bytes - o); auto* p = (const P*)(stage + o); v.insert(v.end(), p, p + n / 8); } cudaStreamSynchronize(s); return v; });
      for (int T : {2, 4, 8}) {
        Pool pool(T - 1);
        snprintf(nm, 80, "D chunk %zuK pool %dT resize", chunk >> 10, T);
        run(nm, [&] { std::vector<P> v; enqueue(); v.resize(npairs); std::atomic<size_t> next{0}; char* d = (char*)v.data();
          auto w = [&] { for (;;) { size_t c = next.fetch_add(1); if (c >= nc) return; cudaEventSynchronize(ev[c]); size_t o = c * chunk, n = std::min(chunk, bytes - o); std::memcpy(d + o, stage + o, n); } };
          if (T > 1) pool.start(w); w(); if (T > 1) pool.wait(); cudaStreamSynchronize(s); return v; });
        snprintf(nm, 80, "E chunk %zuK spawn %dT resize", chunk >> 10, T);
        run(nm, [&] { std::vector<P> v; enqueue(); std::atomic<char*> dd{nullptr}; std::atomic<size_t> next{0};
          auto w = [&] { char* d; while (!(d = dd.load())) std::this_thread::yield(); for (;;) { size_t c = next.fetch_add(1); if (c >= nc) return; cudaEventSynchronize(ev[c]); size_t o = c * chunk, n = std::min(chunk, bytes - o); std::memcpy(d + o, stage + o, n); } };
          std::vector<std::thread> th; for (int i = 1; i < T; ++i) th.emplace_back(w); v.resize(npairs); dd = (char*)v.data(); w(); for (auto& x : th) x.join(); cudaStreamSynchronize(s); return v; });
      }
      for (auto& e : ev) cudaEventDestroy(e);
    }
    // the cost parts alone
    run("R resize only (fresh) + sync", [&] { std::vector<P> v(npairs); cudaStreamSynchronize(s); std::memcpy(v.data(), ref.data(), 8); std::memcpy(v.data(), ref.data(), bytes); return v; });
    cudaFreeHost(stage); cudaFree(dev);
  }
  return 0;
}
