// The staged host-to-device upload (cuda/staged_upload.h) that the CUDA backend and the GPU BVH
// baseline share: every byte arrives, nothing beyond the range is written, whatever the number
// of host threads and the chunk size; the knobs are parsed and bounded. The copy test skips
// without a device; the knob and empty-range tests need none.

#include <cuda_runtime.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "cuda/staged_upload.h"
#include "scoped_env.h"

namespace {

bool haveDevice() {
  int n = 0;
  return cudaGetDeviceCount(&n) == cudaSuccess && n > 0;
}

using kdet_test::ScopedEnv;
using kdet_fcl::staging::stagedUpload;
using kdet_fcl::staging::uploadChunk;
using kdet_fcl::staging::uploadThreads;

TEST(StagedUpload, EveryByteArrivesAndNothingBeyondForAnyThreadsAndChunks) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  constexpr std::size_t kGuard = 256;
  const std::size_t max_bytes = (std::size_t(3) << 20) + 7;
  unsigned char* dev = nullptr;
  ASSERT_EQ(cudaMalloc(&dev, max_bytes + kGuard), cudaSuccess);
  void* stage = nullptr;
  ASSERT_EQ(cudaMallocHost(&stage, max_bytes), cudaSuccess);
  cudaStream_t s = nullptr;
  ASSERT_EQ(cudaStreamCreate(&s), cudaSuccess);
  std::mt19937 rng(7);
  std::vector<unsigned char> src(max_bytes + 128), back(max_bytes + kGuard);
  for (auto& b : src) b = static_cast<unsigned char>(rng());
  int cases = 0;
  for (const char* threads : {"1", "2", "3", "8"}) {
    for (const char* chunk : {"4096", "5000", static_cast<const char*>(nullptr)}) {
      ScopedEnv t("KDET_FCL_CUDA_UPLOAD_THREADS", threads);
      ScopedEnv c("KDET_FCL_CUDA_UPLOAD_CHUNK", chunk);
      for (std::size_t bytes : {std::size_t(1), std::size_t(4095), std::size_t(4096),
                                std::size_t(4097), std::size_t(3 * 4096 + 5),
                                std::size_t(1) << 20, max_bytes}) {
        SCOPED_TRACE("threads " + std::string(threads) + ", chunk " +
                     (chunk ? chunk : "default") + ", bytes " + std::to_string(bytes));
        // The source differs per case (an offset view), so a stale copy would be seen.
        const std::size_t shift = std::size_t(cases++) % 97;
        ASSERT_EQ(cudaMemset(dev, 0xAB, max_bytes + kGuard), cudaSuccess);
        const std::size_t n = bytes;  // each case's range
        ASSERT_EQ(stagedUpload(dev, src.data() + shift, n, stage, s), cudaSuccess);
        ASSERT_EQ(cudaStreamSynchronize(s), cudaSuccess);
        ASSERT_EQ(cudaMemcpy(back.data(), dev, n + kGuard, cudaMemcpyDeviceToHost), cudaSuccess);
        std::size_t wrong = 0;
        for (std::size_t i = 0; i < n; ++i) wrong += back[i] != src[shift + i];
        EXPECT_EQ(wrong, 0u);
        std::size_t beyond = 0;
        for (std::size_t i = n; i < n + kGuard; ++i) beyond += back[i] != 0xAB;
        EXPECT_EQ(beyond, 0u);
      }
    }
  }
  EXPECT_EQ(cudaStreamDestroy(s), cudaSuccess);
  EXPECT_EQ(cudaFreeHost(stage), cudaSuccess);
  EXPECT_EQ(cudaFree(dev), cudaSuccess);
}

TEST(StagedUpload, ZeroBytesTouchNothing) {
  // No CUDA call is made for an empty range, so this holds with or without a device.
  EXPECT_EQ(stagedUpload(nullptr, nullptr, 0, nullptr, nullptr), cudaSuccess);
}

TEST(StagedUpload, KnobsAreParsedAndBounded) {
  {
    ScopedEnv c("KDET_FCL_CUDA_UPLOAD_CHUNK", nullptr);
    EXPECT_EQ(uploadChunk(), kdet_fcl::staging::kUploadChunk);
  }
  for (const char* bad : {"", "abc", "100", "4095", "-8192", "8192x"}) {
    ScopedEnv c("KDET_FCL_CUDA_UPLOAD_CHUNK", bad);
    EXPECT_EQ(uploadChunk(), kdet_fcl::staging::kUploadChunk) << "'" << bad << "'";
  }
  {
    ScopedEnv c("KDET_FCL_CUDA_UPLOAD_CHUNK", "8192");
    EXPECT_EQ(uploadChunk(), 8192u);
  }
  {
    ScopedEnv t("KDET_FCL_CUDA_UPLOAD_THREADS", "3");
    EXPECT_EQ(uploadThreads(100), 3);
    EXPECT_EQ(uploadThreads(2), 2);  // never more threads than chunks
    EXPECT_EQ(uploadThreads(1), 1);
    EXPECT_EQ(uploadThreads(0), 1);
  }
  for (const char* bad : {"0", "65", "x", "-1"}) {
    ScopedEnv t("KDET_FCL_CUDA_UPLOAD_THREADS", bad);
    const int n = uploadThreads(1000);
    EXPECT_GE(n, 1) << "'" << bad << "'";
    EXPECT_LE(n, kdet_fcl::staging::kMaxUploadThreads) << "'" << bad << "'";
  }
  {
    ScopedEnv t("KDET_FCL_CUDA_UPLOAD_THREADS", nullptr);
    EXPECT_EQ(uploadThreads(1), 1);
    EXPECT_LE(uploadThreads(1000), kdet_fcl::staging::kMaxUploadThreads);
  }
}

}  // namespace
