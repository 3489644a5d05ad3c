// CUDA device discovery for the backend seam (see include/kdet_fcl/backend.h). Every CUDA error
// becomes a return value: nothing here throws across the C++/CUDA boundary or exits.

#include <cuda_runtime_api.h>

#include <new>
#include <string>

#include "device_info.h"

namespace kdet_fcl {
namespace cuda_detail {
namespace {

std::string errorText(cudaError_t err) {
  std::string text = cudaGetErrorName(err);
  text += ": ";
  text += cudaGetErrorString(err);
  return text;
}

void setError(std::string* error, cudaError_t err) {
  // Clear the runtime's last-error slot so a later, unrelated call does not report this one.
  (void)cudaGetLastError();
  if (error == nullptr) return;
  try {
    *error = errorText(err);
  } catch (const std::bad_alloc&) {
    // Leave `error` as it was: still no throw.
  }
}

}  // namespace

int deviceCount(std::string* error) {
  int count = 0;
  const cudaError_t err = cudaGetDeviceCount(&count);
  if (err != cudaSuccess) {
    setError(error, err);
    return 0;
  }
  if (count <= 0) {
    setError(error, cudaErrorNoDevice);
    return 0;
  }
  return count;
}

bool deviceInfo(int device, DeviceInfo* info, std::string* error) {
  if (device < 0) {
    setError(error, cudaErrorInvalidDevice);
    return false;
  }
  cudaDeviceProp prop{};
  const cudaError_t err = cudaGetDeviceProperties(&prop, device);
  if (err != cudaSuccess) {
    setError(error, err);
    return false;
  }
  if (info != nullptr) {
    try {
      info->name = prop.name;
    } catch (const std::bad_alloc&) {
      return false;
    }
    info->major = prop.major;
    info->minor = prop.minor;
    info->total_memory = static_cast<unsigned long long>(prop.totalGlobalMem);
  }
  return true;
}

std::string runtimeVersion() {
  int v = 0;
  if (cudaRuntimeGetVersion(&v) != cudaSuccess) return "unknown";
  return std::to_string(v / 1000) + "." + std::to_string((v % 1000) / 10);
}

}  // namespace cuda_detail
}  // namespace kdet_fcl
