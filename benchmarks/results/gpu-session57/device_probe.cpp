// Session 57's probe of the CUDA backend on a machine with two GPUs: does a query leave the
// caller's current CUDA device as it was, and does it run when the calling thread's current
// device is not the one the backend initialised on? Uses only the public API (and the CUDA
// runtime for the caller's own device), so it builds against any tree of the library.
//   g++ -std=c++17 -O2 device_probe.cpp -I<repo>/include -L<build> -lkdet_fcl \
//       -I/usr/local/cuda/include -L/usr/local/cuda/lib64 -lcudart -pthread
#include <cuda_runtime_api.h>

#include <cstdio>
#include <exception>
#include <thread>

#include "kdet_fcl/hashed_mesh.h"
#include "kdet_fcl/query.h"
#include "kdet_fcl/scenes.h"

using namespace kdet_fcl;

static int current() {
  int d = -1;
  cudaGetDevice(&d);
  return d;
}

// Free memory of device d, in MiB (sets and restores the caller's device).
static long long freeMiB(int d) {
  const int was = current();
  cudaSetDevice(d);
  std::size_t f = 0, t = 0;
  cudaMemGetInfo(&f, &t);
  cudaSetDevice(was);
  return static_cast<long long>(f >> 20);
}

static void query(const char* what, const HashedMesh<float>& m, std::size_t want) {
  QueryOptions o;
  o.backend = Backend::Cuda;
  const int before = current();
  try {
    const QueryResult r = intersectSelf(m, o);
    std::printf("%s: caller's device %d before, %d after; %zu pairs (CPU %zu): %s\n", what, before,
                current(), r.pairs.size(), want, r.pairs.size() == want ? "equal" : "DIFFERENT");
  } catch (const std::exception& e) {
    std::printf("%s: caller's device %d before, %d after; threw: %s\n", what, before, current(),
                e.what());
  }
}

int main() {
  int n = 0;
  cudaGetDeviceCount(&n);
  std::printf("devices: %d\n", n);
  HashedMesh<float> cloth(makeDrapedCloth<float>(120, 2.0f, 0.6f, 0.05f, 0.4f));
  QueryOptions cpu;
  const std::size_t want = intersectSelf(cloth, cpu).pairs.size();
  if (n < 2) {
    std::printf("needs two devices\n");
    return 0;
  }
  // 1. The caller works on device 1 and asks for its first GPU query.
  cudaSetDevice(1);
  query("1. first query, caller on device 1", cloth, want);
  // 2. The caller goes back to device 1 (its own work) and queries again.
  cudaSetDevice(1);
  query("2. second query, caller on device 1", cloth, want);
  // 3. The caller on device 0.
  cudaSetDevice(0);
  query("3. caller on device 0", cloth, want);
  // 4. Another thread whose current device is 1.
  std::thread t([&] {
    cudaSetDevice(1);
    query("4. another thread on device 1", cloth, want);
  });
  t.join();
  // 5. Device 0 again after that.
  cudaSetDevice(0);
  query("5. caller on device 0 again", cloth, want);
  // 6. A new, larger mesh from a thread on device 1: its buffers are allocated in this query.
  HashedMesh<float> big(makeDrapedCloth<float>(400, 2.0f, 0.6f, 0.05f, 0.4f));
  const std::size_t want_big = intersectSelf(big, cpu).pairs.size();
  std::thread t2([&] {
    cudaSetDevice(1);
    const long long f0 = freeMiB(0), f1 = freeMiB(1);
    query("6. a new larger mesh, another thread on device 1", big, want_big);
    std::printf("   free MiB: device 0 %lld -> %lld, device 1 %lld -> %lld\n", f0, freeMiB(0), f1,
                freeMiB(1));
  });
  t2.join();
  cudaSetDevice(0);
  query("7. the larger mesh, caller on device 0", big, want_big);
  return 0;
}
