// The CUDA backend's device (kdet_fcl::setCudaDevice, KDET_FCL_CUDA_DEVICE) and its calls from
// threads whose current CUDA device is another one (LABELS cuda). The refusals run everywhere,
// the queries where a device is usable; the tests named CudaDevicesTwoGpus need two devices and
// skip with fewer (scripts/gpu_check.sh lets those skips pass on a one-GPU machine).
//
// Each test runs in a process of its own under ctest (gtest_discover_tests); run as one process,
// CudaDevicesKnob must come first (it reads the knob before anything chose a device), as it
// does in this file's order.

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "kdet_fcl/backend.h"
#include "kdet_fcl/errors.h"
#include "kdet_fcl/hashed_mesh.h"
#include "kdet_fcl/query.h"
#include "kdet_fcl/scenes.h"
#include "scoped_env.h"
#include "test_util.h"

#if KDET_FCL_TEST_HAVE_CUDA
#include <cuda.h>
#include <cuda_runtime_api.h>

#include "../cuda/cuda_backend.h"
#endif

using namespace kdet_fcl;
using kdet_test::sorted;

namespace {

QueryOptions gpu() {
  QueryOptions o;
  o.backend = Backend::Cuda;
  return o;
}

template <class S>
std::vector<TrianglePair> cpuSelf(const HashedMesh<S>& m) {
  return sorted(intersectSelf(m, QueryOptions{}).pairs);
}

/// A cloth over a sphere with self-intersections: n x n quads.
HashedMesh<float> cloth(int n) {
  return HashedMesh<float>(makeDrapedCloth<float>(n, 2.0f, 0.6f, 0.05f, 0.4f));
}

#if KDET_FCL_TEST_HAVE_CUDA
/// The calling thread's current CUDA device, as its own CUDA runtime sees it (the library has its
/// own copy of the runtime; both see the driver's current context).
int callerDevice() {
  int d = -1;
  EXPECT_EQ(cudaGetDevice(&d), cudaSuccess);
  return d;
}

/// Free memory of device d in bytes (the caller's device is given back).
std::size_t freeBytesOn(int d) {
  const int was = callerDevice();
  EXPECT_EQ(cudaSetDevice(d), cudaSuccess);
  std::size_t free_bytes = 0, total = 0;
  EXPECT_EQ(cudaMemGetInfo(&free_bytes, &total), cudaSuccess);
  EXPECT_EQ(cudaSetDevice(was), cudaSuccess);
  return free_bytes;
}

/// A pair buffer on device d (the caller's device is given back), freed at the end of its scope.
struct PairBuffer {
  TrianglePair* p = nullptr;
  std::size_t n = 0;
  PairBuffer(int d, std::size_t count) : n(count) {
    const int was = callerDevice();
    EXPECT_EQ(cudaSetDevice(d), cudaSuccess);
    EXPECT_EQ(cudaMalloc(reinterpret_cast<void**>(&p), n * sizeof(TrianglePair)), cudaSuccess);
    EXPECT_EQ(cudaSetDevice(was), cudaSuccess);
  }
  ~PairBuffer() { (void)cudaFree(p); }
  std::vector<TrianglePair> read(std::size_t count) const {
    std::vector<TrianglePair> out(count);
    EXPECT_EQ(cudaMemcpy(out.data(), p, count * sizeof(TrianglePair), cudaMemcpyDeviceToHost),
              cudaSuccess);
    return out;
  }
};

/// Whether device d's primary context is active (cuDevicePrimaryCtxGetState, through the runtime:
/// the test links no libcuda), or nullopt where the driver's call cannot be had. Creates no
/// context.
std::optional<bool> primaryContextActive(int d) {
  void* fn = nullptr;
  cudaDriverEntryPointQueryResult q = cudaDriverEntryPointSymbolNotFound;
  if (cudaGetDriverEntryPointByVersion("cuDevicePrimaryCtxGetState", &fn, 7000, cudaEnableDefault,
                                       &q) != cudaSuccess ||
      q != cudaDriverEntryPointSuccess || fn == nullptr)
    return std::nullopt;
  unsigned int flags = 0;
  int active = 0;
  if (reinterpret_cast<CUresult (*)(CUdevice, unsigned int*, int*)>(fn)(d, &flags, &active) !=
      CUDA_SUCCESS)
    return std::nullopt;
  return active != 0;
}
#endif

}  // namespace

// KDET_FCL_CUDA_DEVICE chooses the device until setCudaDevice does; one that does not exist fails
// the query (and cudaDevice) with InvalidInputError naming the variable, until it is mended.
TEST(CudaDevicesKnob, TheKnobChoosesTheDeviceAndOneThatDoesNotExistFailsTheQuery) {
#if KDET_FCL_TEST_HAVE_CUDA
  const int n = cudaDeviceCount();
  if (n == 0) GTEST_SKIP() << "no CUDA device";
  HashedMesh<float> m = cloth(40);
  const std::vector<TrianglePair> want = cpuSelf(m);
  ASSERT_FALSE(want.empty());
  {
    kdet_test::ScopedEnv knob("KDET_FCL_CUDA_DEVICE", std::to_string(n).c_str());
    try {
      (void)intersectSelf(m, gpu());
      ADD_FAILURE() << "a query ran with KDET_FCL_CUDA_DEVICE=" << n;
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find("KDET_FCL_CUDA_DEVICE=" + std::to_string(n)),
                std::string::npos)
          << e.what();
    }
    EXPECT_THROW((void)cudaDevice(), InvalidInputError);
    EXPECT_EQ(callerDevice(), 0);
  }
  // The last device, named by the knob (device 0 on a one-GPU machine), from a caller on 0.
  kdet_test::ScopedEnv knob("KDET_FCL_CUDA_DEVICE", std::to_string(n - 1).c_str());
  ASSERT_EQ(cudaSetDevice(0), cudaSuccess);
  EXPECT_EQ(cudaDevice(), n - 1);
  EXPECT_EQ(sorted(intersectSelf(m, gpu()).pairs), want);
  EXPECT_EQ(callerDevice(), 0);
  EXPECT_EQ(cudaDevice(), n - 1);
#else
  GTEST_SKIP() << "kdet_fcl was built without CUDA";
#endif
}

// setCudaDevice refuses a negative ordinal everywhere, one past the last device where there are
// devices, and any where there are none; a refusal leaves the backend's device as it was.
TEST(CudaDevices, SetCudaDeviceRefusesDevicesThatDoNotExist) {
  EXPECT_THROW(setCudaDevice(-1), InvalidInputError);
  const int n = cudaDeviceCount();
  if (n == 0) {
    EXPECT_THROW(setCudaDevice(0), BackendUnavailableError);
    EXPECT_EQ(cudaDevice(), -1);
    return;
  }
  const int before = cudaDevice();
  EXPECT_GE(before, 0);
  EXPECT_LT(before, n);
  try {
    setCudaDevice(n);
    ADD_FAILURE() << "setCudaDevice(" << n << ") was accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("this machine has " + std::to_string(n)),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(cudaDevice(), before);
  setCudaDevice(before);  // the same device again: nothing changes
  EXPECT_EQ(cudaDevice(), before);
}

#if KDET_FCL_TEST_HAVE_CUDA
// A query leaves the caller's current device as it found it, and runs right whatever that device
// is: on a machine of two GPUs the caller works on device 1 and the backend on device 0 (before
// session 57 the first query moved the caller to device 0, and a query from a thread on device 1
// that grew a buffer allocated it there and failed with an illegal address, which then failed
// every later query of the process). With one GPU both are device 0.
TEST(CudaDevices, AQueryLeavesTheCallersCurrentDeviceAsItFoundIt) {
  const int n = cudaDeviceCount();
  if (n == 0) GTEST_SKIP() << "no CUDA device";
  const int other = n > 1 ? 1 : 0;
  setCudaDevice(0);
  ASSERT_EQ(cudaSetDevice(other), cudaSuccess);
  HashedMesh<float> small = cloth(60);
  const std::vector<TrianglePair> want = cpuSelf(small);
  ASSERT_FALSE(want.empty());
  EXPECT_EQ(intersectSelf(small, gpu()).pairs, want);  // the backend's first call
  EXPECT_EQ(callerDevice(), other);
  EXPECT_GT(cudaDeviceBytesInUse(), 0u);

  // A new, larger mesh from another thread on that device: its query grows the backend's buffers.
  HashedMesh<float> big = cloth(220);
  const std::vector<TrianglePair> want_big = cpuSelf(big);
  std::vector<TrianglePair> got_self, got_inter;
  int after = -1;
  std::string error;
  std::thread t([&] {
    if (cudaSetDevice(other) != cudaSuccess) return;
    try {
      got_self = intersectSelf(big, gpu()).pairs;
      got_inter = intersectMeshes(big, small, gpu()).pairs;
    } catch (const std::exception& e) {
      error = e.what();
    }
    after = callerDevice();
  });
  t.join();
  EXPECT_EQ(error, "");
  EXPECT_EQ(got_self, want_big);
  EXPECT_EQ(got_inter, sorted(intersectMeshes(big, small, QueryOptions{}).pairs));
  EXPECT_EQ(after, other);
  EXPECT_EQ(sorted(intersectSelf(big, gpu()).pairs), want_big);  // the process's GPU still works
  EXPECT_EQ(callerDevice(), other);

  // The caller's own allocation still lands on its device.
  void* p = nullptr;
  ASSERT_EQ(cudaMalloc(&p, 4096), cudaSuccess);
  cudaPointerAttributes at{};
  ASSERT_EQ(cudaPointerGetAttributes(&at, p), cudaSuccess);
  EXPECT_EQ(at.device, other);
  (void)cudaFree(p);

  // Pairs into a buffer of the backend's device, from a caller on the other.
  PairBuffer buf(0, want.size() + 8);
  const DevicePairsResult r = intersectSelfOnDevice(small, buf.p, buf.n, gpu());
  EXPECT_EQ(r.count, want.size());
  EXPECT_EQ(buf.read(r.count), want);
  EXPECT_EQ(callerDevice(), other);
  ASSERT_EQ(cudaSetDevice(0), cudaSuccess);
}

// A simulation's thread working on another device than the backend's commits each frame's
// positions (commitVertices, whose check copies them to the backend's device once the buffers
// are registered: from the third or fourth frame) and queries: every answer is the CPU's, the
// copies do happen, and the thread keeps its device.
TEST(CudaDevices, ADeformingMeshCommittedFromAThreadOnAnotherDeviceStaysRight) {
  const int n = cudaDeviceCount();
  if (n == 0) GTEST_SKIP() << "no CUDA device";
  const int other = n > 1 ? 1 : 0;
  setCudaDevice(0);
  auto frame = [](double t) { return makeDrapedCloth<double>(300, 2.0, 0.6, 0.05, t); };
  HashedMesh<double> m(frame(0.2));
  ASSERT_GE(m.numVertices() * sizeof(Vec3<double>), cuda::kCommitCopyMinBytes);
  cuda::setProfiling(true);
  int copies = 0, after = -1;
  std::vector<std::string> wrong;
  std::string error;
  std::thread t([&] {
    if (cudaSetDevice(other) != cudaSuccess) return;
    try {
      for (int f = 0; f <= 6; ++f) {
        if (f > 0) {
          const TriangleMesh<double> next = frame(0.2 + 0.1 * f);
          std::copy(next.vertices.begin(), next.vertices.end(), m.vertexWriteBuffer());
          m.commitVertices();
        }
        const std::vector<TrianglePair> got = intersectSelf(m, gpu()).pairs;
        copies += cuda::lastQueryProfile().commit_uploads;
        if (got != cpuSelf(m) || got.empty()) wrong.push_back("frame " + std::to_string(f));
      }
    } catch (const std::exception& e) {
      error = e.what();
    }
    after = callerDevice();
  });
  t.join();
  cuda::setProfiling(false);
  EXPECT_EQ(error, "");
  EXPECT_TRUE(wrong.empty()) << "the GPU's pairs differ from the CPU's, or are none, in "
                             << wrong.front();
  if (!m.hostPin().tried() || m.hostPin().pinned())
    EXPECT_GE(copies, 2);  // frames 5 and 6 at least (where the machine registers host memory)
  EXPECT_EQ(after, other);
}

// With the backend on device 1, nothing of the library makes a context on device 0 (about 500 MiB
// there): not the calling thread, whose context the calls give back (here: none), and not the
// library's worker threads, which copy the staged uploads and the pooled read-backs (forced here
// by small chunks and four threads each) and whose first CUDA call would otherwise make one on
// their default device 0 (session 57: gpu_bench on device 1 held 527 MiB on device 0). Needs a
// process of its own, as ctest gives each test.
TEST(CudaDevicesTwoGpus, TheBackendOnDevice1MakesNoContextOnDevice0) {
  if (cudaDeviceCount() < 2) GTEST_SKIP() << "needs two CUDA devices";
  const std::optional<bool> before = primaryContextActive(0);
  if (!before) GTEST_SKIP() << "the driver's cuDevicePrimaryCtxGetState cannot be had";
  if (*before) GTEST_SKIP() << "device 0 has a context already (run in a process of its own)";
  setCudaDevice(1);
  kdet_test::ScopedEnv pin("KDET_FCL_CUDA_PIN_VERTICES", "0");
  kdet_test::ScopedEnv up("KDET_FCL_CUDA_UPLOAD_CHUNK", "4096");
  kdet_test::ScopedEnv up_threads("KDET_FCL_CUDA_UPLOAD_THREADS", "4");
  kdet_test::ScopedEnv down("KDET_FCL_CUDA_DOWNLOAD_CHUNK", "4096");
  kdet_test::ScopedEnv down_threads("KDET_FCL_CUDA_DOWNLOAD_THREADS", "4");
  HashedMesh<float> m = cloth(120);
  QueryResult kept;
  for (int frame = 0; frame < 3; ++frame) {
    if (frame > 0) {
      m.updateVertices(
          makeDrapedCloth<float>(120, 2.0f, 0.6f, 0.05f, 0.4f + 0.1f * frame).vertices);
    }
    intersectSelf(m, kept, gpu());  // into a result kept from frame to frame: a pooled read-back
    EXPECT_EQ(kept.pairs, cpuSelf(m)) << "frame " << frame;
    EXPECT_GE(kept.pairs.size(), 4u * 4096 / sizeof(TrianglePair)) << "fewer than four chunks";
  }
  EXPECT_EQ(primaryContextActive(1), std::optional<bool>(true));
  EXPECT_EQ(primaryContextActive(0), std::optional<bool>(false));
}

// setCudaDevice(1) moves the backend to device 1: what it held on device 0 is freed, each mesh is
// uploaded there again by its next query (the same pairs), the memory it takes is device 1's, a
// pair buffer must be device 1's, and the caller's device stays its own. Back on device 0, the
// same again.
TEST(CudaDevicesTwoGpus, TheBackendRunsOnTheChosenDevice) {
  if (cudaDeviceCount() < 2) GTEST_SKIP() << "needs two CUDA devices";
  ASSERT_EQ(cudaSetDevice(0), cudaSuccess);
  setCudaDevice(0);
  HashedMesh<float> m = cloth(160);
  HashedMesh<float> other = cloth(90);
  const std::vector<TrianglePair> want = cpuSelf(m);
  const std::vector<TrianglePair> want_inter = sorted(intersectMeshes(m, other, QueryOptions{}).pairs);
  EXPECT_EQ(intersectSelf(m, gpu()).pairs, want);
  EXPECT_GT(cudaDeviceBytesInUse(), 0u);

  const std::size_t free1 = freeBytesOn(1);
  setCudaDevice(1);
  EXPECT_EQ(cudaDevice(), 1);
  EXPECT_EQ(cudaDeviceBytesInUse(), 0u);  // device 0's buffers and meshes were dropped
  EXPECT_EQ(intersectSelf(m, gpu()).pairs, want);
  EXPECT_EQ(intersectMeshes(m, other, gpu()).pairs, want_inter);
  const std::size_t held = cudaDeviceBytesInUse();
  EXPECT_GT(held, 0u);
  EXPECT_LE(freeBytesOn(1) + held, free1);  // it is device 1's memory that the backend took
  EXPECT_EQ(callerDevice(), 0);

  {
    PairBuffer on1(1, want.size());
    const DevicePairsResult r = intersectSelfOnDevice(m, on1.p, on1.n, gpu());
    EXPECT_EQ(r.count, want.size());
    EXPECT_EQ(on1.read(r.count), want);
    PairBuffer on0(0, want.size());
    try {
      (void)intersectSelfOnDevice(m, on0.p, on0.n, gpu());
      ADD_FAILURE() << "a buffer of device 0 was taken by the backend on device 1";
    } catch (const InvalidInputError& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find("memory of CUDA device 0"), std::string::npos) << w;
      EXPECT_NE(w.find("runs on device 1"), std::string::npos) << w;
    }
  }
  EXPECT_EQ(callerDevice(), 0);

  // From a caller on device 1, back to device 0.
  ASSERT_EQ(cudaSetDevice(1), cudaSuccess);
  setCudaDevice(0);
  EXPECT_EQ(cudaDeviceBytesInUse(), 0u);
  EXPECT_EQ(intersectSelf(m, gpu()).pairs, want);
  EXPECT_EQ(intersectMeshes(m, other, gpu()).pairs, want_inter);
  EXPECT_EQ(callerDevice(), 1);
  ASSERT_EQ(cudaSetDevice(0), cudaSuccess);
}
#endif
