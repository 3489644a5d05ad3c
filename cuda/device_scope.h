#pragma once
// cuda::DeviceScope: runs a stretch of a thread's CUDA calls on one device and then gives the
// thread back exactly the CUDA context it had (none included). The CUDA backend wraps every call
// in one (a library must not move its caller's CUDA work to another GPU: the current device is
// per host thread, and cudaMalloc, kernel launches and events follow it), and so do the
// library's worker threads where they copy or wait for the backend (a fresh thread's first CUDA
// call would otherwise create a context on device 0, about 500 MiB there, whichever device the
// backend runs on).
//
// The context is saved and restored through the driver's cuCtxGetCurrent/cuCtxSetCurrent, taken
// from the runtime (cudaGetDriverEntryPointByVersion; the library does not link libcuda), so
// that a thread with no context keeps none and a thread with a context of its own (a framework's
// cuCtxCreate) gets that one back, not a device's primary context. Where the entry points are
// not to be had, the runtime's cudaGetDevice/cudaSetDevice stand in.

#include <cuda.h>
#include <cuda_runtime_api.h>

#include "cuda_error.cuh"

namespace kdet_fcl {
namespace cuda {

namespace detail_scope {

struct DriverContextCalls {
  CUresult (*get)(CUcontext*) = nullptr;
  CUresult (*set)(CUcontext) = nullptr;
};

/// The driver's context calls, asked of the runtime once (nullptr each where it has none).
inline const DriverContextCalls& driverContextCalls() {
  static const DriverContextCalls calls = [] {
    DriverContextCalls c;
    void* get = nullptr;
    void* set = nullptr;
    cudaDriverEntryPointQueryResult got = cudaDriverEntryPointSymbolNotFound;
    cudaDriverEntryPointQueryResult put = cudaDriverEntryPointSymbolNotFound;
    if (cudaGetDriverEntryPointByVersion("cuCtxGetCurrent", &get, 4000, cudaEnableDefault, &got) ==
            cudaSuccess &&
        cudaGetDriverEntryPointByVersion("cuCtxSetCurrent", &set, 4000, cudaEnableDefault, &put) ==
            cudaSuccess &&
        got == cudaDriverEntryPointSuccess && put == cudaDriverEntryPointSuccess && get && set) {
      c.get = reinterpret_cast<CUresult (*)(CUcontext*)>(get);
      c.set = reinterpret_cast<CUresult (*)(CUcontext)>(set);
    }
    (void)cudaGetLastError();  // (a refusal is not sticky)
    return c;
  }();
  return calls;
}

}  // namespace detail_scope

/// Makes `device` the calling thread's current CUDA device for the scope's lifetime, then gives the
/// thread back the context it had (see the file's comment). Throws CudaError when the device cannot
/// be made current; the restoring never throws (a failure there is cleared).
class DeviceScope {
 public:
  explicit DeviceScope(int device) {
    const cudaError_t e = enter(device);
    if (e != cudaSuccess) throwCudaError(e, "cudaSetDevice(device)", __FILE__, __LINE__);
  }
  /// The same without throwing, for worker threads: `*error` receives the failure (cudaSuccess
  /// otherwise), and the thread is left as it was.
  DeviceScope(int device, cudaError_t* error) { *error = enter(device); }
  DeviceScope(const DeviceScope&) = delete;
  DeviceScope& operator=(const DeviceScope&) = delete;
  ~DeviceScope() {
    if (!changed_) return;
    if (driver_) {
      if (detail_scope::driverContextCalls().set(saved_) != CUDA_SUCCESS) (void)cudaGetLastError();
    } else if (previous_ >= 0 && cudaSetDevice(previous_) != cudaSuccess) {
      (void)cudaGetLastError();
    }
  }

 private:
  cudaError_t enter(int device) {
    const detail_scope::DriverContextCalls& d = detail_scope::driverContextCalls();
    CUcontext saved = nullptr;
    if (d.get != nullptr && d.get(&saved) == CUDA_SUCCESS) {
      // With a context current, the runtime's device is that context's: nothing to do when it
      // is the device's. Without one, the runtime would make one on device 0 at the next call.
      int current = -1;
      if (saved != nullptr && cudaGetDevice(&current) == cudaSuccess && current == device)
        return cudaSuccess;
      (void)cudaGetLastError();
      const cudaError_t e = cudaSetDevice(device);
      if (e != cudaSuccess) {
        (void)cudaGetLastError();
        (void)d.set(saved);
        return e;
      }
      driver_ = true;
      saved_ = saved;
      changed_ = true;
      return cudaSuccess;
    }
    int previous = -1;
    if (cudaGetDevice(&previous) != cudaSuccess) {
      (void)cudaGetLastError();
      previous = -1;
    }
    if (previous == device) return cudaSuccess;
    const cudaError_t e = cudaSetDevice(device);
    if (e != cudaSuccess) {
      (void)cudaGetLastError();
      return e;
    }
    previous_ = previous;
    changed_ = true;
    return cudaSuccess;
  }

  bool changed_ = false;
  bool driver_ = false;   ///< saved_ holds the context to restore (nullptr: none)
  CUcontext saved_ = nullptr;
  int previous_ = -1;     ///< without the driver's calls: the runtime's device to restore
};

/// The calling thread's current CUDA device as the runtime sees it (0 where it has none yet), for
/// worker threads' DeviceScopes: call it on the thread that is inside the backend's DeviceScope.
inline int threadDevice() {
  int d = 0;
  if (cudaGetDevice(&d) != cudaSuccess) {
    (void)cudaGetLastError();
    d = 0;
  }
  return d;
}

}  // namespace cuda
}  // namespace kdet_fcl
