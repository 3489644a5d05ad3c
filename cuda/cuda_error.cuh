#pragma once
// The one seam where CUDA runtime errors become C++ exceptions (kdet_fcl::CudaError). Host code
// only: device code never throws; kernels report through device flags and counters instead.

#include <cuda_runtime_api.h>

#include <string>

#include "kdet_fcl/errors.h"

namespace kdet_fcl {
namespace cuda {

/// "<where>: <call>: <cudaErrorName>: <description>". Clears the runtime's last-error slot so a
/// later, unrelated check does not report this error again (sticky errors stay sticky).
[[noreturn]] inline void throwCudaError(cudaError_t err, const char* call, const char* file,
                                        int line) {
  (void)cudaGetLastError();
  std::string text = std::string("CUDA error at ") + file + ":" + std::to_string(line) + ": " +
                     call + ": " + cudaGetErrorName(err) + ": " + cudaGetErrorString(err);
  throw CudaError(text);
}

}  // namespace cuda
}  // namespace kdet_fcl

/// Evaluates a CUDA runtime call and throws kdet_fcl::CudaError (with the CUDA error text) when it
/// does not return cudaSuccess.
#define CUDA_TRY(call)                                                            \
  do {                                                                            \
    const cudaError_t kdet_cuda_err_ = (call);                                    \
    if (kdet_cuda_err_ != cudaSuccess)                                            \
      ::kdet_fcl::cuda::throwCudaError(kdet_cuda_err_, #call, __FILE__, __LINE__); \
  } while (0)
