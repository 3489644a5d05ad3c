#include "cpu/worker_pool.h"
#include <chrono>
#include <cstdio>
#include <thread>
#include <vector>
#include <algorithm>
#include <atomic>
using Clock = std::chrono::steady_clock;
int main() {
  auto& pool = kdet_fcl::cpu::WorkerPool::shared();
  for (int threads : {2, 3, 4}) {
    std::vector<double> p, s;
    for (int r = 0; r < 300; ++r) {
      std::atomic<int> x{0};
      std::function<void()> w = [&] { x.fetch_add(1); };
      auto a = Clock::now();
      pool.run(threads, w);
      auto b = Clock::now();
      std::vector<std::thread> th;
      for (int i = 1; i < threads; ++i) th.emplace_back(w);
      w();
      for (auto& t : th) t.join();
      auto c = Clock::now();
      p.push_back(std::chrono::duration<double, std::micro>(b - a).count());
      s.push_back(std::chrono::duration<double, std::micro>(c - b).count());
      std::this_thread::sleep_for(std::chrono::microseconds(r % 2 ? 1000 : 0));
    }
    std::sort(p.begin(), p.end()); std::sort(s.begin(), s.end());
    std::printf("threads %d: pool median %.1f us (p90 %.1f), spawn median %.1f us (p90 %.1f)\n", threads, p[150], p[270], s[150], s[270]);
  }
}
