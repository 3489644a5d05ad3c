#pragma once
// Host-only declarations of the CUDA device queries in device_info.cu. Plain C++: no CUDA header,
// so src/backend.cpp (compiled by the host compiler) can include it. Only used when the library
// is built with CUDA (KDET_FCL_HAVE_CUDA=1).

#include <string>

namespace kdet_fcl {
namespace cuda_detail {

/// What the CUDA runtime knows about one device.
struct DeviceInfo {
  std::string name;
  int major = 0;                        ///< compute capability, major
  int minor = 0;                        ///< compute capability, minor
  unsigned long long total_memory = 0;  ///< bytes of global memory
};

/// Number of CUDA devices. On any CUDA error (no driver, driver too old, no device) returns 0
/// and, when `error` is not null, stores "<cudaErrorName>: <description>" there. Never throws
/// and never exits.
int deviceCount(std::string* error);

/// Properties of device `device`. Returns false (and the error text in `error`, when not null)
/// if the device does not exist or cannot be queried. Never throws and never exits.
bool deviceInfo(int device, DeviceInfo* info, std::string* error);

/// The CUDA runtime version this library was linked against, as "major.minor" (e.g. "13.0").
std::string runtimeVersion();

}  // namespace cuda_detail
}  // namespace kdet_fcl
