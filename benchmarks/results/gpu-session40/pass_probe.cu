// Probe (session 40, device call 3): calls 1 and 2 (snoop_probe.cu) found the DMA of a registered
// host array up to twice as slow when many threads have just read or written it (its lines sit in
// their private caches), and at full speed after non-temporal stores or after each line was
// demoted (CLDEMOTE) to the shared L3. What do the library's passes cost in each form, phase by
// phase, with the threads of a kept pool (as cpu::WorkerPool: woken, not started) and the
// library's split (cpu::vertexPassThreads: 512 KB a thread from 1.5 MB, at most 16)?
//   commit:  the simulation (main thread) writes the array; the check reads it: plain / demoting
//            each line after its read;
//   update:  the simulation writes its own array; updateVertices copies it into the registered
//            one: memcpy / non-temporal stores (the check of the source is left out: unchanged);
//   fcl:     threads convert into the array (plain / non-temporal stores), then the check reads
//            it (plain / demoting).
// Each phase timed by the host clock, the DMA by events; medians over 40 rounds after 3.
// Build: nvcc -O3 -std=c++17 -arch=sm_90 -Xcompiler -O3 pass_probe.cu -o probe  (SSE2 only, as
// the library is built: no -march)
#include <cuda_runtime.h>
#include <emmintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <mutex>
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

// A kept pool: job(k) for k in 0..T-1, k = 0 on the caller; workers sleep between jobs.
class Pool {
 public:
  explicit Pool(int workers) {
    for (int i = 0; i < workers; ++i) th_.emplace_back([this, i] { loop(i + 1); });
  }
  ~Pool() {
    {
      std::lock_guard<std::mutex> l(m_);
      quit_ = true;
    }
    cv_.notify_all();
    for (auto& t : th_) t.join();
  }
  void run(int T, const std::function<void(int)>& f) {
    {
      std::lock_guard<std::mutex> l(m_);
      f_ = &f;
      T_ = T;
      left_ = T - 1;
      ++gen_;
    }
    cv_.notify_all();
    f(0);
    std::unique_lock<std::mutex> l(m_);
    done_.wait(l, [&] { return left_ == 0; });
  }

 private:
  void loop(int id) {
    unsigned long long seen = 0;
    while (true) {
      const std::function<void(int)>* f;
      {
        std::unique_lock<std::mutex> l(m_);
        cv_.wait(l, [&] { return quit_ || gen_ != seen; });
        if (quit_) return;
        seen = gen_;
        if (id >= T_) continue;
        f = f_;
      }
      (*f)(id);
      std::lock_guard<std::mutex> l(m_);
      if (--left_ == 0) done_.notify_one();
    }
  }
  std::vector<std::thread> th_;
  std::mutex m_;
  std::condition_variable cv_, done_;
  const std::function<void(int)>* f_ = nullptr;
  int T_ = 0, left_ = 0;
  unsigned long long gen_ = 0;
  bool quit_ = false;
};

static std::atomic<double> g_sink{0};

static void writePlain(double* p, std::size_t b, std::size_t e, double base) {
  for (std::size_t i = b; i < e; ++i) p[i] = base + double(i & 1023);
}
static void writeStream(double* p, std::size_t b, std::size_t e, double base) {
  std::size_t i = b;
  for (; i < e && (reinterpret_cast<std::uintptr_t>(p + i) & 15); ++i) p[i] = base + double(i & 1023);
  for (; i + 2 <= e; i += 2)
    _mm_stream_pd(p + i, _mm_set_pd(base + double((i + 1) & 1023), base + double(i & 1023)));
  for (; i < e; ++i) p[i] = base + double(i & 1023);
  _mm_sfence();
}
static void copyStream(double* d, const double* s, std::size_t b, std::size_t e) {
  std::size_t i = b;
  for (; i < e && (reinterpret_cast<std::uintptr_t>(d + i) & 15); ++i) d[i] = s[i];
  for (; i + 8 <= e; i += 8) {
    const __m128d a = _mm_loadu_pd(s + i), c = _mm_loadu_pd(s + i + 2),
                  x = _mm_loadu_pd(s + i + 4), y = _mm_loadu_pd(s + i + 6);
    _mm_stream_pd(d + i, a);
    _mm_stream_pd(d + i + 2, c);
    _mm_stream_pd(d + i + 4, x);
    _mm_stream_pd(d + i + 6, y);
  }
  for (; i < e; ++i) d[i] = s[i];
  _mm_sfence();
}
// The check's read: min, max and sum per coordinate slot (as takeRange, vectorised by SSE2).
static void check(const double* p, std::size_t b, std::size_t e, bool demote) {
  __m128d lo = _mm_set1_pd(1e300), hi = _mm_set1_pd(-1e300), sm = _mm_setzero_pd();
  std::size_t i = b;
  double tail = 0;
  for (; i < e && (reinterpret_cast<std::uintptr_t>(p + i) & 63); ++i) tail += p[i];
  for (; i + 8 <= e; i += 8) {
    for (int k = 0; k < 8; k += 2) {
      const __m128d v = _mm_load_pd(p + i + k);
      lo = _mm_min_pd(lo, v);
      hi = _mm_max_pd(hi, v);
      sm = _mm_add_pd(sm, _mm_sub_pd(v, v));
    }
    if (demote) asm volatile("cldemote %0" ::"m"(*reinterpret_cast<const char*>(p + i)));
  }
  for (; i < e; ++i) tail += p[i];
  double o[2], q[2], r[2];
  _mm_storeu_pd(o, lo);
  _mm_storeu_pd(q, hi);
  _mm_storeu_pd(r, sm);
  g_sink.store(o[0] + o[1] + q[0] + q[1] + r[0] + r[1] + tail, std::memory_order_relaxed);
}

static double med(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
static double p90(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[(v.size() * 9) / 10];
}

int main(int argc, char** argv) {
  const int rounds = 43;
  Pool pool(15);
  cudaStream_t s;
  CK(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking));
  cudaEvent_t e0, e1;
  CK(cudaEventCreate(&e0));
  CK(cudaEventCreate(&e1));
  cudaDeviceProp prop;
  CK(cudaGetDeviceProperties(&prop, 0));
  std::vector<double> sizes = {13.5, 3.0, 1.1};
  for (int a = 1; a < argc; ++a) sizes.push_back(std::atof(argv[a]));
  for (double mb : sizes) {
    const std::size_t n = static_cast<std::size_t>(mb * 1e6 / 8) & ~std::size_t(7);
    const std::size_t bytes = n * 8;
    std::size_t t = bytes < (1536u << 10) ? 1 : std::min<std::size_t>(16, bytes / (512u << 10));
    const int T = t < 3 ? 1 : int(t);
    double* h = static_cast<double*>(std::aligned_alloc(4096, (bytes + 4095) & ~std::size_t(4095)));
    double* src = static_cast<double*>(std::aligned_alloc(4096, (bytes + 4095) & ~std::size_t(4095)));
    std::memset(h, 0, bytes);
    std::memset(src, 0, bytes);
    CK(cudaHostRegister(h, bytes, cudaHostRegisterDefault));
    double* d = nullptr;
    CK(cudaMalloc(&d, bytes));
    const std::size_t per = (n + T - 1) / T;
    auto share = [&](int k, std::size_t* b, std::size_t* e) {
      *b = std::min(n, k * per);
      *e = std::min(n, *b + per);
    };
    struct Form {
      std::string name;
      int kind;  // 0 commit, 1 update, 2 fcl
      bool stream, demote;
    };
    const std::vector<Form> forms = {
        {"commit: check plain", 0, false, false},
        {"commit: check demoting", 0, false, true},
        {"update: memcpy", 1, false, false},
        {"update: non-temporal copy", 1, true, false},
        {"fcl: write plain, check plain", 2, false, false},
        {"fcl: write plain, check demoting", 2, false, true},
        {"fcl: write non-temporal, check plain", 2, true, false},
        {"fcl: write non-temporal, check demoting", 2, true, true},
    };
    std::vector<std::vector<double>> pass(forms.size()), dma(forms.size()), sum(forms.size());
    for (int r = 0; r < rounds; ++r)
      for (std::size_t k = 0; k < forms.size(); ++k) {
        const Form& f = forms[k];
        const double base = r * 3.0 + k;
        double p0 = 0, p1 = 0;
        if (f.kind == 0) {
          writePlain(h, 0, n, base);  // the simulation, untimed
          p0 = nowMs();
          pool.run(T, [&](int id) {
            std::size_t b, e;
            share(id, &b, &e);
            check(h, b, e, f.demote);
          });
          p1 = nowMs();
        } else if (f.kind == 1) {
          writePlain(src, 0, n, base);  // the simulation's own array, untimed
          p0 = nowMs();
          pool.run(T, [&](int id) {
            std::size_t b, e;
            share(id, &b, &e);
            if (f.stream) copyStream(h, src, b, e);
            else std::memcpy(h + b, src + b, (e - b) * 8);
          });
          p1 = nowMs();
        } else {
          p0 = nowMs();
          pool.run(T, [&](int id) {
            std::size_t b, e;
            share(id, &b, &e);
            if (f.stream) writeStream(h, b, e, base);
            else writePlain(h, b, e, base);
          });
          pool.run(T, [&](int id) {
            std::size_t b, e;
            share(id, &b, &e);
            check(h, b, e, f.demote);
          });
          p1 = nowMs();
        }
        CK(cudaEventRecord(e0, s));
        CK(cudaMemcpyAsync(d, h, bytes, cudaMemcpyHostToDevice, s));
        CK(cudaEventRecord(e1, s));
        CK(cudaStreamSynchronize(s));
        const double p2 = nowMs();
        float ms = 0;
        CK(cudaEventElapsedTime(&ms, e0, e1));
        if (r < 3) continue;
        pass[k].push_back(p1 - p0);
        dma[k].push_back(ms);
        sum[k].push_back(p2 - p0);
      }
    std::printf("\n%s, %.1f MB registered array, %d threads for the passes, %d rounds\n",
                prop.name, bytes / 1e6, T, rounds - 3);
    std::printf("| form | passes ms p50 (p90) | DMA ms p50 (p90) | passes + DMA, host wall ms p50 (p90) |\n|---|---|---|---|\n");
    for (std::size_t k = 0; k < forms.size(); ++k)
      std::printf("| %s | %.3f (%.3f) | %.3f (%.3f) | %.3f (%.3f) |\n", forms[k].name.c_str(),
                  med(pass[k]), p90(pass[k]), med(dma[k]), p90(dma[k]), med(sum[k]), p90(sum[k]));
    std::fflush(stdout);
    CK(cudaHostUnregister(h));
    CK(cudaFree(d));
    std::free(h);
    std::free(src);
  }
  return 0;
}
