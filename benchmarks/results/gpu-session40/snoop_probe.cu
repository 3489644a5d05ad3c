// Probe (session 40, device call 1): session 39 found that after commitVertices checked a 1M
// cloth's 13.5 MB of positions on 16 threads, the next query's uploads and re-hash took
// 0.35-0.42 ms longer than after a check on 1 thread (benchmarks/RESULTS-gpu.md). The guess left
// open: the DMA read of the page-locked array is slower while its lines sit in many cores' private
// caches. This probe takes the library out: one array of page-locked (registered) host memory,
// filled by the main thread or by T threads (plain or non-temporal stores), then read by T
// threads (the commit's check) or not, optionally flushed (clflushopt) by T threads; then one
// cudaMemcpyAsync to the device (call 2 added: reads that demote each line (CLDEMOTE) or
// prefetch it non-temporally, and a demote pass), timed by events (the DMA alone) and by the host clock (enqueue
// to sync). The scenarios run in turn, 40 rounds; medians and the 10th/90th percentiles.
// Build: nvcc -O3 -std=c++17 -arch=sm_90 -Xcompiler -O3,-march=native snoop_probe.cu -o probe
#include <cuda_runtime.h>
#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#define CK(x)                                                                   \
  do {                                                                          \
    cudaError_t e_ = (x);                                                       \
    if (e_ != cudaSuccess) {                                                    \
      std::fprintf(stderr, "%s: %s\n", #x, cudaGetErrorString(e_));             \
      std::exit(1);                                                             \
    }                                                                           \
  } while (0)

static double nowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Runs f(share_begin, share_end) on T threads (std::thread each time; the start is untimed).
static void onThreads(int T, std::size_t n, const std::function<void(std::size_t, std::size_t)>& f) {
  if (T <= 1) {
    f(0, n);
    return;
  }
  std::vector<std::thread> th;
  const std::size_t per = (n + T - 1) / T;
  for (int k = 0; k < T; ++k) {
    const std::size_t b = std::min(n, k * per), e = std::min(n, b + per);
    th.emplace_back([&, b, e] { f(b, e); });
  }
  for (auto& t : th) t.join();
}

static std::atomic<double> g_sink{0};

static void fillPlain(double* p, std::size_t b, std::size_t e, double base) {
  for (std::size_t i = b; i < e; ++i) p[i] = base + double(i & 1023);
}
static void fillStream(double* p, std::size_t b, std::size_t e, double base) {
  std::size_t i = b;
  for (; i < e && (reinterpret_cast<std::uintptr_t>(p + i) & 31); ++i) p[i] = base + double(i & 1023);
  for (; i + 4 <= e; i += 4) {
    const __m256d v = _mm256_set_pd(base + double((i + 3) & 1023), base + double((i + 2) & 1023),
                                    base + double((i + 1) & 1023), base + double(i & 1023));
    _mm256_stream_pd(p + i, v);
  }
  for (; i < e; ++i) p[i] = base + double(i & 1023);
  _mm_sfence();
}
static void readSum(const double* p, std::size_t b, std::size_t e) {
  double s = 0;
  for (std::size_t i = b; i < e; ++i) s += p[i];
  g_sink.store(s, std::memory_order_relaxed);
}
// The same read, each 64-byte line demoted (CLDEMOTE: a hint that moves the line from the core's
// private caches to the shared L3; a NOP where unsupported) once its 8 doubles are read.
static void readSumDemote(const double* p, std::size_t b, std::size_t e) {
  double s = 0;
  std::size_t i = b;
  for (; i < e && (reinterpret_cast<std::uintptr_t>(p + i) & 63); ++i) s += p[i];
  for (; i + 8 <= e; i += 8) {
    s += p[i] + p[i + 1] + p[i + 2] + p[i + 3] + p[i + 4] + p[i + 5] + p[i + 6] + p[i + 7];
    asm volatile("cldemote %0" ::"m"(*reinterpret_cast<const char*>(p + i)));
  }
  for (; i < e; ++i) s += p[i];
  g_sink.store(s, std::memory_order_relaxed);
}
// The same read, each line prefetched with the non-temporal hint 8 lines ahead.
static void readSumNta(const double* p, std::size_t b, std::size_t e) {
  double s = 0;
  for (std::size_t i = b; i < e; ++i) {
    if ((i & 7) == 0 && i + 64 < e) _mm_prefetch(reinterpret_cast<const char*>(p + i + 64), _MM_HINT_NTA);
    s += p[i];
  }
  g_sink.store(s, std::memory_order_relaxed);
}
static void demoteLines(const double* p, std::size_t b, std::size_t e) {
  const char* c = reinterpret_cast<const char*>(p + b);
  const char* end = reinterpret_cast<const char*>(p + e);
  for (c = reinterpret_cast<const char*>(reinterpret_cast<std::uintptr_t>(c) & ~std::uintptr_t(63));
       c < end; c += 64)
    asm volatile("cldemote %0" ::"m"(*c));
}
static void flushLines(const double* p, std::size_t b, std::size_t e) {
  const char* c = reinterpret_cast<const char*>(p + b);
  const char* end = reinterpret_cast<const char*>(p + e);
  for (c = reinterpret_cast<const char*>(reinterpret_cast<std::uintptr_t>(c) & ~std::uintptr_t(63));
       c < end; c += 64)
#ifdef __CLFLUSHOPT__
    _mm_clflushopt(const_cast<char*>(c));
#else
    _mm_clflush(c);
#endif
  _mm_sfence();
}

struct Scenario {
  std::string name;
  int writers;   // threads that write the array (0: main thread)
  bool stream;   // non-temporal stores
  int readers;   // threads that read it after (0: none; 1: main)
  int flushers;  // threads that flush its lines after (0: none)
  int read_kind = 0;   // 0 plain, 1 each line demoted after its read, 2 prefetchnta ahead
  int demoters = 0;    // threads that demote its lines after (0: none)
};

static void pct(std::vector<double> v, double* p10, double* p50, double* p90) {
  std::sort(v.begin(), v.end());
  *p10 = v[v.size() / 10];
  *p50 = v[v.size() / 2];
  *p90 = v[(v.size() * 9) / 10];
}

int main(int argc, char** argv) {
  const double mb = argc > 1 ? std::atof(argv[1]) : 13.5;
  const int rounds = argc > 2 ? std::atoi(argv[2]) : 40;
  const std::size_t n = static_cast<std::size_t>(mb * 1e6 / 8) & ~std::size_t(7);
  const std::size_t bytes = n * 8;
  double* h = static_cast<double*>(std::aligned_alloc(4096, (bytes + 4095) & ~std::size_t(4095)));
  std::memset(h, 0, bytes);
  CK(cudaHostRegister(h, bytes, cudaHostRegisterDefault));
  double* d = nullptr;
  CK(cudaMalloc(&d, bytes));
  cudaStream_t s;
  CK(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking));
  cudaEvent_t e0, e1;
  CK(cudaEventCreate(&e0));
  CK(cudaEventCreate(&e1));
  const int hw = static_cast<int>(std::thread::hardware_concurrency());
  const int T = std::min(16, hw);
  const std::vector<Scenario> sc = {
      {"main writes", 0, false, 0, 0},
      {"main writes, main reads", 0, false, 1, 0},
      {"main writes, 6 read", 0, false, 6, 0},
      {"main writes, T read", 0, false, T, 0},
      {"main writes, T read, T flush", 0, false, T, T},
      {"main writes, main flushes", 0, false, 0, 1},
      {"T write", T, false, 0, 0},
      {"T write, T flush", T, false, 0, T},
      {"T write non-temporal", T, true, 0, 0},
      {"main writes non-temporal", 0, true, 0, 0},
      {"main writes non-temporal, T read", 0, true, T, 0},
      {"main writes, T read + demote", 0, false, T, 0, 1},
      {"main writes, T read prefetchnta", 0, false, T, 0, 2},
      {"main writes, main reads + demote", 0, false, 1, 0, 1},
      {"T write, T read", T, false, T, 0},
      {"T write, T read + demote", T, false, T, 0, 1},
      {"T write, T demote", T, false, 0, 0, 0, T},
      {"main writes non-temporal, T read + demote", 0, true, T, 0, 1},
  };
  std::vector<std::vector<double>> dma(sc.size()), wall(sc.size()), prep(sc.size()),
      flush(sc.size());
  for (int r = 0; r < rounds; ++r)
    for (std::size_t k = 0; k < sc.size(); ++k) {
      const Scenario& c = sc[k];
      const double base = r * 7.0 + k;
      const double p0 = nowMs();
      onThreads(std::max(1, c.writers), n, [&](std::size_t b, std::size_t e) {
        if (c.stream) fillStream(h, b, e, base);
        else fillPlain(h, b, e, base);
      });
      if (c.readers > 0)
        onThreads(c.readers, n, [&](std::size_t b, std::size_t e) {
          if (c.read_kind == 1) readSumDemote(h, b, e);
          else if (c.read_kind == 2) readSumNta(h, b, e);
          else readSum(h, b, e);
        });
      if (c.demoters > 0)
        onThreads(c.demoters, n, [&](std::size_t b, std::size_t e) { demoteLines(h, b, e); });
      const double p1 = nowMs();
      if (c.flushers > 0)
        onThreads(c.flushers, n, [&](std::size_t b, std::size_t e) { flushLines(h, b, e); });
      const double p2 = nowMs();
      const double t0 = nowMs();
      CK(cudaEventRecord(e0, s));
      CK(cudaMemcpyAsync(d, h, bytes, cudaMemcpyHostToDevice, s));
      CK(cudaEventRecord(e1, s));
      CK(cudaStreamSynchronize(s));
      const double t1 = nowMs();
      float ms = 0;
      CK(cudaEventElapsedTime(&ms, e0, e1));
      if (r < 3) continue;  // warm-up
      dma[k].push_back(ms);
      wall[k].push_back(t1 - t0);
      prep[k].push_back(p1 - p0);
      flush[k].push_back(p2 - p1);
    }
  int dev = 0;
  cudaDeviceProp prop;
  CK(cudaGetDevice(&dev));
  CK(cudaGetDeviceProperties(&prop, dev));
  std::printf("%s, %.1f MB registered host array, %d host threads (T = %d), %d rounds\n",
              prop.name, bytes / 1e6, hw, T, rounds);
  std::printf("| scenario | DMA (events) ms p10/p50/p90 | GB/s (p50) | host wall ms p50 | "
              "fill+read ms p50 | flush ms p50 |\n|---|---|---:|---:|---:|---:|\n");
  for (std::size_t k = 0; k < sc.size(); ++k) {
    double a, b, c, w10, w50, w90, f10, f50, f90, x10, x50, x90;
    pct(dma[k], &a, &b, &c);
    pct(wall[k], &w10, &w50, &w90);
    pct(prep[k], &f10, &f50, &f90);
    pct(flush[k], &x10, &x50, &x90);
    std::printf("| %s | %.3f / %.3f / %.3f | %.1f | %.3f | %.3f | %.3f |\n", sc[k].name.c_str(), a,
                b, c, bytes / 1e6 / b, w50, f50, x50);
  }
  return 0;
}
