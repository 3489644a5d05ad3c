// The staged copies (cuda/staged_upload.h) that the CUDA backend and the GPU BVH baseline share.
// Upload: every byte arrives, nothing beyond the range is written, whatever the number of host
// threads and the chunk size. Download: every element arrives, in order, in whole-element chunks,
// and a throwing consumer leaves cleanly. The knobs are parsed and bounded, and a value out of
// bounds throws. Pinned uploads (a registered range's whole pages by DMA, its ends staged) bring
// every byte too. The copy tests skip without a device; the knob, page and empty-range tests need
// none.

#include <cuda_runtime.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "cuda/staged_upload.h"
#include "scoped_env.h"

namespace {

bool haveDevice() {
  int n = 0;
  return cudaGetDeviceCount(&n) == cudaSuccess && n > 0;
}

/// A device buffer of `bytes` + kGuard, a pinned stage of `bytes` and a stream, for the upload
/// tests; check() uploads a range with `upload` and compares what arrived, and the guard bytes
/// after it, which must be untouched.
struct UploadRig {
  static constexpr std::size_t kGuard = 256;
  unsigned char* dev = nullptr;
  void* stage = nullptr;
  cudaStream_t s = nullptr;
  std::vector<unsigned char> back;
  explicit UploadRig(std::size_t bytes) : back(bytes + kGuard) {
    EXPECT_EQ(cudaMalloc(&dev, bytes + kGuard), cudaSuccess);
    EXPECT_EQ(cudaMallocHost(&stage, bytes), cudaSuccess);
    EXPECT_EQ(cudaStreamCreate(&s), cudaSuccess);
  }
  ~UploadRig() {
    EXPECT_EQ(cudaStreamDestroy(s), cudaSuccess);
    EXPECT_EQ(cudaFreeHost(stage), cudaSuccess);
    EXPECT_EQ(cudaFree(dev), cudaSuccess);
  }
  template <class Upload>
  void check(const unsigned char* from, std::size_t n, Upload&& upload, const std::string& what) {
    ASSERT_EQ(cudaMemset(dev, 0xAB, n + kGuard), cudaSuccess);
    ASSERT_EQ(upload(dev, from, n, stage, s), cudaSuccess) << what;
    ASSERT_EQ(cudaStreamSynchronize(s), cudaSuccess);
    ASSERT_EQ(cudaMemcpy(back.data(), dev, n + kGuard, cudaMemcpyDeviceToHost), cudaSuccess);
    EXPECT_EQ(std::memcmp(back.data(), from, n), 0) << what;
    std::size_t beyond = 0;
    for (std::size_t i = n; i < n + kGuard; ++i) beyond += back[i] != 0xAB;
    EXPECT_EQ(beyond, 0u) << what;
  }
};

using kdet_test::ScopedEnv;
using kdet_fcl::staging::downloadChunk;
using kdet_fcl::staging::stagedDownload;
using kdet_fcl::staging::stagedUpload;
using kdet_fcl::staging::uploadChunk;
using kdet_fcl::staging::uploadThreads;

TEST(StagedUpload, EveryByteArrivesAndNothingBeyondForAnyThreadsAndChunks) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  const std::size_t max_bytes = (std::size_t(3) << 20) + 7;
  UploadRig rig(max_bytes);
  std::mt19937 rng(7);
  std::vector<unsigned char> src(max_bytes + 128);
  for (auto& b : src) b = static_cast<unsigned char>(rng());
  int cases = 0;
  for (const char* threads : {"1", "2", "3", "8"}) {
    for (const char* chunk : {"4096", "5000", static_cast<const char*>(nullptr)}) {
      ScopedEnv t("KDET_FCL_CUDA_UPLOAD_THREADS", threads);
      ScopedEnv c("KDET_FCL_CUDA_UPLOAD_CHUNK", chunk);
      for (std::size_t bytes : {std::size_t(1), std::size_t(4095), std::size_t(4096),
                                std::size_t(4097), std::size_t(3 * 4096 + 5),
                                std::size_t(1) << 20, max_bytes}) {
        // The source differs per case (an offset view), so a stale copy would be seen.
        const std::size_t shift = std::size_t(cases++) % 97;
        rig.check(src.data() + shift, bytes, stagedUpload,
                  "threads " + std::string(threads) + ", chunk " + (chunk ? chunk : "default") +
                      ", bytes " + std::to_string(bytes));
      }
    }
  }
}

TEST(StagedUpload, ZeroBytesTouchNothing) {
  // No CUDA call is made for an empty range, so this holds with or without a device.
  EXPECT_EQ(stagedUpload(nullptr, nullptr, 0, nullptr, nullptr), cudaSuccess);
}

// The whole pages inside a range (staging::pageInterior), which pinHostMemory registers: page
// aligned, inside the range, and every whole page of it. Needs no device.
TEST(PinnedUpload, ThePageInteriorIsEveryWholePageInside) {
  const std::uintptr_t page = std::uintptr_t(sysconf(_SC_PAGESIZE));
  ASSERT_GT(page, 0u);
  const std::uintptr_t base = 1000 * page;  // addresses only, never dereferenced
  std::size_t with_pages = 0;
  for (std::uintptr_t off : {std::uintptr_t(0), std::uintptr_t(1), page - 1, page, page + 3})
    for (std::size_t bytes : {std::size_t(0), std::size_t(1), std::size_t(page - 1),
                              std::size_t(page), std::size_t(page + 1), std::size_t(2 * page),
                              std::size_t(3 * page - 2), std::size_t(1) << 20}) {
      const std::uintptr_t a = base + off;
      const kdet_fcl::staging::PageInterior in =
          kdet_fcl::staging::pageInterior(reinterpret_cast<const void*>(a), bytes);
      const std::string what = "offset " + std::to_string(off) + ", bytes " + std::to_string(bytes);
      ASSERT_LE(in.begin, in.end) << what;
      ASSERT_LE(in.end, bytes) << what;
      // The first whole page starting at or after a, the last whole page ending at or before the
      // end: none when they do not meet.
      const std::uintptr_t lo = (a + page - 1) / page * page, hi = (a + bytes) / page * page;
      if (hi <= lo) {
        EXPECT_EQ(in.begin, in.end) << what;
      } else {
        ++with_pages;
        EXPECT_EQ(a + in.begin, lo) << what;
        EXPECT_EQ(a + in.end, hi) << what;
        EXPECT_EQ((in.end - in.begin) % page, 0u) << what;
      }
    }
  EXPECT_GT(with_pages, 10u);
}

// pinnedUpload: every byte arrives, nothing beyond, for ranges at every kind of offset from a
// page and of every size around a page; a range registered once cannot be registered again
// until its registration is dropped (so a leaked registration would show).
TEST(PinnedUpload, EveryByteArrivesFromARegisteredRange) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  const std::size_t page = std::size_t(sysconf(_SC_PAGESIZE));
  const std::size_t max_bytes = (std::size_t(3) << 20) + 7;
  UploadRig rig(max_bytes);
  std::vector<unsigned char> src(max_bytes + 2 * page);
  std::mt19937 rng(13);
  for (auto& b : src) b = static_cast<unsigned char>(rng());
  int registered = 0;
  for (std::size_t off : {std::size_t(0), std::size_t(1), page - 1, page, page + 5})
    for (std::size_t bytes : {std::size_t(1), page - 1, page, page + 1, 3 * page - 2,
                              std::size_t(1) << 20, max_bytes}) {
      const std::string what = "offset " + std::to_string(off) + ", bytes " + std::to_string(bytes);
      const unsigned char* from = src.data() + off;
      std::shared_ptr<void> pin = kdet_fcl::staging::pinHostMemory(from, bytes);
      const kdet_fcl::staging::PageInterior in = kdet_fcl::staging::pageInterior(from, bytes);
      EXPECT_EQ(pin != nullptr, in.end > in.begin) << what;
      if (pin) {
        ++registered;
        EXPECT_EQ(kdet_fcl::staging::pinHostMemory(from, bytes), nullptr) << what << ": twice";
      }
      rig.check(from, bytes, kdet_fcl::staging::pinnedUpload, what);
      pin.reset();  // unregistered: the same range registers again
      if (in.end > in.begin) {
        EXPECT_NE(kdet_fcl::staging::pinHostMemory(from, bytes), nullptr) << what << ": again";
      }
    }
  EXPECT_GT(registered, 10);
}

/// An 8-byte element, as a triangle pair.
struct Pair8 {
  std::uint32_t a, b;
};

/// Downloads `count` elements of `dev` (+ shift) through `stage` and checks that the chunks come
/// in order, each a whole number of elements at most `chunk_bytes` long, and the values.
template <class T>
void checkDownload(const T* dev, const std::vector<T>& src, std::size_t shift, std::size_t count,
                   T* stage, cudaStream_t s, std::size_t chunk_bytes) {
  std::vector<T> back;
  std::size_t calls = 0, out_of_order = 0, too_long = 0;
  const cudaError_t e =
      stagedDownload(dev + shift, count, stage, s, [&](const T* first, std::size_t n) {
        out_of_order += first != stage + back.size();  // chunk c sits at stage + c * chunk
        too_long += n * sizeof(T) > std::max(chunk_bytes, sizeof(T)) || n == 0;
        ++calls;
        back.insert(back.end(), first, first + n);
      });
  ASSERT_EQ(e, cudaSuccess);
  EXPECT_EQ(out_of_order, 0u);
  EXPECT_EQ(too_long, 0u);
  const std::size_t per = std::max<std::size_t>(1, chunk_bytes / sizeof(T));
  EXPECT_EQ(calls, (count + per - 1) / per);
  ASSERT_EQ(back.size(), count);
  EXPECT_EQ(std::memcmp(back.data(), src.data() + shift, count * sizeof(T)), 0);
}

TEST(StagedDownload, EveryElementArrivesInOrderForAnyChunk) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  const std::size_t max_bytes = (std::size_t(3) << 20) + 7;
  std::mt19937 rng(11);
  std::vector<unsigned char> bytes(max_bytes + 128);
  for (auto& b : bytes) b = static_cast<unsigned char>(rng());
  std::vector<Pair8> pairs(bytes.size() / sizeof(Pair8));
  std::memcpy(pairs.data(), bytes.data(), pairs.size() * sizeof(Pair8));
  unsigned char* dev = nullptr;
  ASSERT_EQ(cudaMalloc(&dev, bytes.size()), cudaSuccess);
  ASSERT_EQ(cudaMemcpy(dev, bytes.data(), bytes.size(), cudaMemcpyHostToDevice), cudaSuccess);
  void* stage = nullptr;
  ASSERT_EQ(cudaMallocHost(&stage, bytes.size()), cudaSuccess);
  cudaStream_t s = nullptr;
  ASSERT_EQ(cudaStreamCreate(&s), cudaSuccess);
  int cases = 0;
  for (const char* chunk : {"4096", "5001", static_cast<const char*>(nullptr)}) {
    ScopedEnv c("KDET_FCL_CUDA_DOWNLOAD_CHUNK", chunk);
    const std::size_t chunk_bytes = downloadChunk();
    for (std::size_t n : {std::size_t(1), std::size_t(4095), std::size_t(4096), std::size_t(4097),
                          std::size_t(3 * 4096 + 5), std::size_t(1) << 20, max_bytes}) {
      // The source differs per case (an offset into the device data), so a stale stage or a
      // chunk out of place would be seen.
      const std::size_t shift = std::size_t(cases++) % 97;
      SCOPED_TRACE("chunk " + std::string(chunk ? chunk : "default") + ", bytes " +
                   std::to_string(n) + ", shift " + std::to_string(shift));
      checkDownload(dev, bytes, shift, n, static_cast<unsigned char*>(stage), s, chunk_bytes);
      // 8-byte elements: a chunk of 5001 bytes carries 625 whole pairs, never a split one.
      const std::size_t np = n / sizeof(Pair8) + 1, ps = shift % 13;
      checkDownload(reinterpret_cast<const Pair8*>(dev), pairs, ps, np,
                    static_cast<Pair8*>(stage), s, chunk_bytes);
    }
  }
  EXPECT_EQ(cudaStreamDestroy(s), cudaSuccess);
  EXPECT_EQ(cudaFreeHost(stage), cudaSuccess);
  EXPECT_EQ(cudaFree(dev), cudaSuccess);
}

TEST(StagedDownload, AThrowingConsumerLeavesCleanlyAndTheNextCopyWorks) {
  if (!haveDevice()) GTEST_SKIP() << "no CUDA device";
  const std::size_t bytes = (std::size_t(1) << 20) + 3;
  std::vector<unsigned char> src(bytes);
  for (std::size_t i = 0; i < bytes; ++i) src[i] = static_cast<unsigned char>(i * 7 + 1);
  unsigned char* dev = nullptr;
  ASSERT_EQ(cudaMalloc(&dev, bytes), cudaSuccess);
  ASSERT_EQ(cudaMemcpy(dev, src.data(), bytes, cudaMemcpyHostToDevice), cudaSuccess);
  unsigned char* stage = nullptr;
  ASSERT_EQ(cudaMallocHost(&stage, bytes), cudaSuccess);
  ScopedEnv c("KDET_FCL_CUDA_DOWNLOAD_CHUNK", "4096");
  // The consumer throws in the second chunk (as a vector's growth may): the exception comes
  // out, after every transfer has run.
  int calls = 0;
  EXPECT_THROW(stagedDownload(dev, bytes, stage, nullptr,
                              [&](const unsigned char*, std::size_t) {
                                if (++calls == 2) throw std::runtime_error("no memory");
                              }),
               std::runtime_error);
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(cudaStreamQuery(nullptr), cudaSuccess);  // nothing left in flight
  // The stage and the stream still serve.
  std::vector<unsigned char> back;
  ASSERT_EQ(stagedDownload(dev, bytes, stage, nullptr,
                           [&](const unsigned char* first, std::size_t n) {
                             back.insert(back.end(), first, first + n);
                           }),
            cudaSuccess);
  EXPECT_TRUE(back == src);
  EXPECT_EQ(cudaGetLastError(), cudaSuccess);
  EXPECT_EQ(cudaFreeHost(stage), cudaSuccess);
  EXPECT_EQ(cudaFree(dev), cudaSuccess);
}

TEST(StagedDownload, ZeroElementsTouchNothing) {
  // No CUDA call is made for an empty range, so this holds with or without a device.
  int calls = 0;
  EXPECT_EQ(stagedDownload(static_cast<const Pair8*>(nullptr), 0, static_cast<Pair8*>(nullptr),
                           nullptr, [&](const Pair8*, std::size_t) { ++calls; }),
            cudaSuccess);
  EXPECT_EQ(calls, 0);
}

/// A chunk knob: unset or empty gives the default, "8192" gives 8192, and a value that is not a
/// whole number from 4096 to 2^32 throws InvalidInputError naming the variable.
void checkChunkKnob(const char* name, std::size_t (*chunk)(), std::size_t fallback) {
  for (const char* unset : {static_cast<const char*>(nullptr), ""}) {
    ScopedEnv c(name, unset);
    EXPECT_EQ(chunk(), fallback);
  }
  for (const char* bad : {"abc", "100", "4095", "-8192", "8192x", "4294967297"}) {
    ScopedEnv c(name, bad);
    EXPECT_THROW(chunk(), kdet_fcl::InvalidInputError) << name << "='" << bad << "'";
  }
  ScopedEnv c(name, "8192");
  EXPECT_EQ(chunk(), 8192u);
}

TEST(StagedUpload, KnobsAreParsedAndBounded) {
  checkChunkKnob("KDET_FCL_CUDA_UPLOAD_CHUNK", uploadChunk, kdet_fcl::staging::kUploadChunk);
  {
    ScopedEnv t("KDET_FCL_CUDA_UPLOAD_THREADS", "3");
    EXPECT_EQ(uploadThreads(100), 3);
    EXPECT_EQ(uploadThreads(2), 2);  // never more threads than chunks
    EXPECT_EQ(uploadThreads(1), 1);
    EXPECT_EQ(uploadThreads(0), 1);
  }
  for (const char* bad : {"0", "65", "x", "-1", "3 "}) {
    ScopedEnv t("KDET_FCL_CUDA_UPLOAD_THREADS", bad);
    EXPECT_THROW(uploadThreads(1000), kdet_fcl::InvalidInputError) << "'" << bad << "'";
  }
  {
    ScopedEnv t("KDET_FCL_CUDA_UPLOAD_THREADS", nullptr);
    EXPECT_EQ(uploadThreads(1), 1);
    EXPECT_LE(uploadThreads(1000), kdet_fcl::staging::kMaxUploadThreads);
  }
}

TEST(StagedDownload, TheChunkKnobIsParsedAndBoundedApartFromTheUploads) {
  checkChunkKnob("KDET_FCL_CUDA_DOWNLOAD_CHUNK", downloadChunk,
                 kdet_fcl::staging::kDownloadChunk);
  // Each direction reads its own knob.
  ScopedEnv uc("KDET_FCL_CUDA_UPLOAD_CHUNK", "8192");
  ScopedEnv dc("KDET_FCL_CUDA_DOWNLOAD_CHUNK", "12288");
  EXPECT_EQ(downloadChunk(), 12288u);
  EXPECT_EQ(uploadChunk(), 8192u);
}

}  // namespace
