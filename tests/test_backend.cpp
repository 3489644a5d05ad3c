// The backend seam: builtWithCuda(), cudaDeviceCount(), cudaDeviceDescription() and
// resolveBackend() answer consistently with the build configuration and the machine.

#include <gtest/gtest.h>

#include <string>

#include "kdet_fcl/backend.h"
#include "kdet_fcl/errors.h"

#ifndef KDET_FCL_EXPECT_CUDA
#error "tests/CMakeLists.txt must define KDET_FCL_EXPECT_CUDA (0 or 1) for test_backend"
#endif

namespace kdet_fcl {
namespace {

TEST(Backend, BuiltWithCudaMatchesConfiguration) {
  EXPECT_EQ(builtWithCuda(), KDET_FCL_EXPECT_CUDA != 0);
}

TEST(Backend, DeviceCountIsConsistent) {
  const int count = cudaDeviceCount();
  EXPECT_GE(count, 0);
  if (!builtWithCuda()) {
    EXPECT_EQ(count, 0);
  }
  EXPECT_EQ(cudaDeviceCount(), count);  // stable within a process
}

TEST(Backend, NoDeviceMemoryWithoutADeviceOrBeforeAGpuQuery) {
  // This test program runs no GPU query: nothing is held on a device, whatever the machine.
  EXPECT_EQ(cudaDeviceBytesInUse(), 0u);
  EXPECT_EQ(cudaDeviceBytesInUse(), 0u);  // asking allocates nothing
}

TEST(Backend, DescriptionNoneWithoutDevice) {
  const int count = cudaDeviceCount();
  EXPECT_EQ(cudaDeviceDescription(count), "none");  // one past the last device
  EXPECT_EQ(cudaDeviceDescription(-1), "none");
  if (count == 0) {
    EXPECT_EQ(cudaDeviceDescription(), "none");
  } else {
    EXPECT_NE(cudaDeviceDescription(), "none");
  }
}

TEST(Backend, CpuIsAlwaysCpuAutoPicksTheGpuForLargeWork) {
  EXPECT_EQ(resolveBackend(Backend::Cpu, 0), Backend::Cpu);
  EXPECT_EQ(resolveBackend(Backend::Cpu, 10'000'000), Backend::Cpu);
  // Auto: the CPU for small work or without a device, the GPU for large work with one.
  EXPECT_EQ(resolveBackend(Backend::Auto, 0), Backend::Cpu);
  const Backend big = resolveBackend(Backend::Auto, 10'000'000);
  EXPECT_EQ(big, cudaDeviceCount() > 0 ? Backend::Cuda : Backend::Cpu);
  EXPECT_EQ(resolveBackend(Backend::Auto, autoCudaMinTriangles() - 1), Backend::Cpu);
}

TEST(Backend, CudaResolvesWithADeviceAndThrowsWithAReasonWithout) {
  if (cudaDeviceCount() > 0) {
    EXPECT_EQ(resolveBackend(Backend::Cuda, 1000), Backend::Cuda);
    return;
  }
  std::string message;
  try {
    resolveBackend(Backend::Cuda, 1000);
    FAIL() << "resolveBackend(Backend::Cuda) returned although there is no CUDA device";
  } catch (const BackendUnavailableError& e) {
    message = e.what();
  }
  EXPECT_FALSE(message.empty());
  if (!builtWithCuda())
    EXPECT_NE(message.find("built without CUDA"), std::string::npos) << message;
  else
    EXPECT_NE(message.find("no CUDA device: "), std::string::npos) << message;
}

TEST(Backend, CudaErrorIsAKdetError) {
  // Callers can catch every library failure as kdet_fcl::Error.
  if (cudaDeviceCount() > 0) GTEST_SKIP() << "a CUDA device is present";
  EXPECT_THROW(resolveBackend(Backend::Cuda), Error);
}

}  // namespace
}  // namespace kdet_fcl
