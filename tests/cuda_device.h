// For the tests compiled as CUDA (tests/*.cu): whether the runtime sees a device, so that they
// skip cleanly without one.
#pragma once

#include <cuda_runtime.h>

namespace kdet_test {

/// Whether the CUDA runtime finds a device.
inline bool haveCudaDevice() {
  int n = 0;
  return cudaGetDeviceCount(&n) == cudaSuccess && n > 0;
}

}  // namespace kdet_test
