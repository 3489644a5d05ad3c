// Runs only where a CUDA device exists (LABELS cuda); skips everywhere else.

#include <gtest/gtest.h>

#include <iostream>
#include <regex>
#include <string>

#include "kdet_fcl/backend.h"

namespace kdet_fcl {
namespace {

TEST(CudaDevice, DescribesADeviceOfComputeCapability70OrNewer) {
  if (cudaDeviceCount() == 0) {
    GTEST_SKIP() << (builtWithCuda() ? "no CUDA device on this machine"
                                     : "kdet_fcl was built without CUDA");
  }
  ASSERT_TRUE(builtWithCuda());
  for (int d = 0; d < cudaDeviceCount(); ++d) {
    const std::string desc = cudaDeviceDescription(d);
    SCOPED_TRACE("device " + std::to_string(d) + ": " + desc);
    std::smatch m;
    ASSERT_TRUE(std::regex_match(
        desc, m, std::regex(R"((.+), compute capability ([0-9]+)\.([0-9]+), ([0-9]+) MiB)")));
    EXPECT_FALSE(m[1].str().empty());
    const int major = std::stoi(m[2].str()), minor = std::stoi(m[3].str());
    EXPECT_GE(major * 10 + minor, 70);
    EXPECT_GT(std::stoull(m[4].str()), 0u);
    std::cout << "[ device   ] " << d << ": " << desc << "\n";
  }
}

TEST(CudaDevice, CudaBackendResolvesWithADevice) {
  if (cudaDeviceCount() == 0) GTEST_SKIP() << "no CUDA device";
  EXPECT_EQ(resolveBackend(Backend::Cuda, 1000), Backend::Cuda);
}

}  // namespace
}  // namespace kdet_fcl
