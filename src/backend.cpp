// Backend selection and CUDA device discovery (include/kdet_fcl/backend.h).

#include "kdet_fcl/backend.h"

#include <string>

#include "kdet_fcl/errors.h"

#ifndef KDET_FCL_HAVE_CUDA
#define KDET_FCL_HAVE_CUDA 0
#endif

#if KDET_FCL_HAVE_CUDA
#include "../cuda/cuda_backend.h"
#include "../cuda/device_info.h"
#endif

namespace kdet_fcl {
namespace {

/// Backend::Auto sends queries of at least this many triangles (both meshes together) to the GPU.
constexpr std::size_t kAutoCudaMinTriangles = 20000;

#if KDET_FCL_HAVE_CUDA
/// The device count and, when it is 0, the reason. Queried once per process: initialising the
/// CUDA runtime is not free, and the answer does not change while the process runs.
struct DeviceProbe {
  int count = 0;
  std::string error;
};

const DeviceProbe& probe() {
  static const DeviceProbe result = [] {
    DeviceProbe p;
    try {
      p.count = cuda_detail::deviceCount(&p.error);
    } catch (...) {
      p.count = 0;
      p.error = "unexpected failure while querying CUDA devices";
    }
    if (p.count == 0 && p.error.empty()) p.error = "no CUDA-capable device is detected";
    return p;
  }();
  return result;
}
#endif

}  // namespace

bool builtWithCuda() { return KDET_FCL_HAVE_CUDA != 0; }

int cudaDeviceCount() {
#if KDET_FCL_HAVE_CUDA
  try {
    return probe().count;
  } catch (...) {
    return 0;
  }
#else
  return 0;
#endif
}

std::string cudaDeviceDescription(int device) {
#if KDET_FCL_HAVE_CUDA
  try {
    if (device < 0 || device >= cudaDeviceCount()) return "none";
    cuda_detail::DeviceInfo info;
    if (!cuda_detail::deviceInfo(device, &info, nullptr)) return "none";
    const unsigned long long mib = info.total_memory / (1024ull * 1024ull);
    return info.name + ", compute capability " + std::to_string(info.major) + "." +
           std::to_string(info.minor) + ", " + std::to_string(mib) + " MiB";
  } catch (...) {
    return "none";
  }
#else
  (void)device;
  return "none";
#endif
}

std::size_t autoCudaMinTriangles() { return kAutoCudaMinTriangles; }

void setCudaDevice(int device) {
  if (device < 0)
    throw InvalidInputError("setCudaDevice(" + std::to_string(device) +
                            "): a CUDA device ordinal is 0 or more");
#if KDET_FCL_HAVE_CUDA
  if (cudaDeviceCount() == 0)
    throw BackendUnavailableError("setCudaDevice(" + std::to_string(device) +
                                  "): there is no CUDA device: " + probe().error);
  cuda::setDevice(device);
#else
  throw BackendUnavailableError("setCudaDevice(" + std::to_string(device) +
                                "): kdet_fcl was built without CUDA");
#endif
}

int cudaDevice() {
#if KDET_FCL_HAVE_CUDA
  if (cudaDeviceCount() == 0) return -1;
  return cuda::currentDevice();
#else
  return -1;
#endif
}

std::size_t cudaDeviceBytesInUse() {
#if KDET_FCL_HAVE_CUDA
  try {
    return cudaDeviceCount() > 0 ? cuda::deviceBytesInUse() : 0;
  } catch (...) {
    return 0;
  }
#else
  return 0;
#endif
}

Backend resolveBackend(Backend requested, std::size_t work_triangles) {
  switch (requested) {
    case Backend::Cpu:
      return Backend::Cpu;
    case Backend::Auto:
      // The GPU pays once the query is large enough to hide its launches and read-backs
      // (benchmarks/RESULTS-gpu.md has the measured break-even).
      return (cudaDeviceCount() > 0 && work_triangles >= kAutoCudaMinTriangles) ? Backend::Cuda
                                                                                 : Backend::Cpu;
    case Backend::Cuda: {
#if KDET_FCL_HAVE_CUDA
      if (cudaDeviceCount() == 0) {
        throw BackendUnavailableError("Backend::Cuda requested but there is no CUDA device: " +
                                      probe().error);
      }
      return Backend::Cuda;
#else
      throw BackendUnavailableError(
          "Backend::Cuda requested but kdet_fcl was built without CUDA (no nvcc at build time; "
          "reconfigure with -DKDET_FCL_CUDA=ON and a CUDA toolkit); use Backend::Cpu or "
          "Backend::Auto");
#endif
    }
  }
  throw InvalidInputError("resolveBackend: unknown Backend value " +
                          std::to_string(static_cast<int>(requested)));
}

}  // namespace kdet_fcl
