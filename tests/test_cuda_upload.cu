// The staged copies (cuda/staged_upload.h) that the CUDA backend and the GPU BVH baseline share.
// Upload: every byte arrives, nothing beyond the range is written, whatever the number of host
// threads and the chunk size. Download: every element arrives, in order, in whole-element chunks,
// and a throwing consumer leaves cleanly; into a kept vector (downloadInto) by several threads of
// a persistent pool (pooledDownload, CopyPool), the same elements, old contents replaced; and
// from chunks queued ahead of the count, any count they cover. The
// knobs are parsed and bounded, and a value out of bounds throws. Pinned uploads (a registered
// range's whole pages by DMA, its ends staged) bring every byte too. The copy tests skip without a device; the knob, page and empty-range tests need
// none.

#include <cuda_runtime.h>
#include <unistd.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cuda/staged_upload.h"
#include "cuda_device.h"
#include "scoped_env.h"

namespace {

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
using kdet_fcl::staging::downloadThreads;
using kdet_fcl::staging::stagedDownload;
using kdet_fcl::staging::stagedUpload;
using kdet_fcl::staging::uploadChunk;
using kdet_fcl::staging::uploadThreads;

TEST(StagedUpload, EveryByteArrivesAndNothingBeyondForAnyThreadsAndChunks) {
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
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
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
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

/// `count` pairs made by `make(i)`, copied to the device (`dev`), and a page-locked stage of as
/// many (`stage`), for the download tests; freed with the rig.
struct PairRig {
  std::vector<Pair8> src;
  Pair8* dev = nullptr;
  Pair8* stage = nullptr;
  template <class Make>
  PairRig(std::size_t count, Make&& make) : src(count) {
    for (std::size_t i = 0; i < count; ++i) src[i] = make(i);
    EXPECT_EQ(cudaMalloc(&dev, count * sizeof(Pair8)), cudaSuccess);
    EXPECT_EQ(cudaMemcpy(dev, src.data(), count * sizeof(Pair8), cudaMemcpyHostToDevice),
              cudaSuccess);
    EXPECT_EQ(cudaMallocHost(&stage, count * sizeof(Pair8)), cudaSuccess);
  }
  PairRig(const PairRig&) = delete;
  PairRig& operator=(const PairRig&) = delete;
  ~PairRig() {
    EXPECT_EQ(cudaFreeHost(stage), cudaSuccess);
    EXPECT_EQ(cudaFree(dev), cudaSuccess);
  }
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
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
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
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
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

// (CopyPool is the library's worker pool, cpu::WorkerPool: test_worker_pool.cpp tests that the
// threads asked for join a job, each once, and that its workers are kept.)

TEST(PooledDownload, EveryElementArrivesIntoAKeptVectorWhateverItHeld) {
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
  const std::size_t most = (std::size_t(1) << 18) + 3;  // pairs: 2 MiB
  const PairRig rig(most, [](std::size_t i) {
    return Pair8{static_cast<std::uint32_t>(i * 2654435761u), static_cast<std::uint32_t>(~i)};
  });
  const std::vector<Pair8>& src = rig.src;
  Pair8* const dev = rig.dev;
  Pair8* const stage = rig.stage;
  ASSERT_TRUE(dev != nullptr && stage != nullptr);
  kdet_fcl::staging::CopyPool pool;
  std::vector<Pair8> kept;  // kept across the cases: larger, smaller and empty in turn
  int pooled = 0;
  for (const char* threads : {"4", "1", static_cast<const char*>(nullptr)}) {
    ScopedEnv t("KDET_FCL_CUDA_DOWNLOAD_THREADS", threads);
    for (const char* chunk : {"4096", "5001", static_cast<const char*>(nullptr)}) {
      ScopedEnv c("KDET_FCL_CUDA_DOWNLOAD_CHUNK", chunk);
      for (std::size_t n : {most, std::size_t(7), std::size_t(0), most - 1000, std::size_t(513),
                            std::size_t(5000), std::size_t(4999), most}) {
        const std::size_t shift = (n * 7 + 3) % 11;
        if (n + shift > most) n = most - shift;
        SCOPED_TRACE(std::string("threads ") + (threads ? threads : "default") + ", chunk " +
                     (chunk ? chunk : "default") + ", pairs " + std::to_string(n) +
                     " after " + std::to_string(kept.size()));
        pooled += kdet_fcl::staging::pooledThreads(n, kept.size()) > 0;
        ASSERT_EQ(kdet_fcl::staging::downloadInto(dev + shift, n, stage, nullptr, pool, kept),
                  cudaSuccess);
        ASSERT_EQ(kept.size(), n);
        EXPECT_EQ(std::memcmp(kept.data(), src.data() + shift, n * sizeof(Pair8)), 0);
      }
    }
  }
  EXPECT_GT(pooled, 6) << "the pooled path ran";
  EXPECT_GT(pool.workers(), 0);
  EXPECT_EQ(cudaGetLastError(), cudaSuccess);
}

TEST(PooledDownload, ReadyRunsAfterTheFirstChunkAndAThrowLeavesCleanly) {
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
  const std::size_t n = 100000;
  const PairRig rig(n, [](std::size_t i) { return Pair8{static_cast<std::uint32_t>(i), 7u}; });
  const std::vector<Pair8>& src = rig.src;
  Pair8* const dev = rig.dev;
  Pair8* const stage = rig.stage;
  ASSERT_TRUE(dev != nullptr && stage != nullptr);
  ScopedEnv c("KDET_FCL_CUDA_DOWNLOAD_CHUNK", "4096");
  kdet_fcl::staging::CopyPool pool;
  // ready() sees the first chunk in the stage; every element is placed once, where it belongs.
  std::vector<Pair8> back(n, Pair8{0, 0});
  std::vector<std::atomic<int>> placed(n);
  bool first_there = false;
  ASSERT_EQ(kdet_fcl::staging::pooledDownload(
                dev, n, stage, nullptr, pool, 4,
                [&] { first_there = std::memcmp(stage, src.data(), 4096) == 0; },
                [&](std::size_t off, const Pair8* first, std::size_t k) {
                  std::memcpy(back.data() + off, first, k * sizeof(Pair8));
                  for (std::size_t i = off; i < off + k; ++i) placed[i].fetch_add(1);
                }),
            cudaSuccess);
  EXPECT_TRUE(first_there);
  EXPECT_EQ(std::memcmp(back.data(), src.data(), n * sizeof(Pair8)), 0);
  std::size_t wrong = 0;
  for (auto& p : placed) wrong += p.load() != 1;
  EXPECT_EQ(wrong, 0u);
  // A throwing ready() (a destination that cannot grow): it comes out after every transfer, and
  // nothing is placed.
  std::size_t calls = 0;
  EXPECT_THROW(kdet_fcl::staging::pooledDownload(
                   dev, n, stage, nullptr, pool, 4, [] { throw std::runtime_error("no memory"); },
                   [&](std::size_t, const Pair8*, std::size_t) { ++calls; }),
               std::runtime_error);
  EXPECT_EQ(calls, 0u);
  EXPECT_EQ(cudaStreamQuery(nullptr), cudaSuccess);
}

TEST(PooledDownload, ChunksQueuedAheadServeEveryCountTheyCover) {
  // The CUDA backend queues a read-back before it knows the count (a forecast's, runQuery):
  // downloadChunks of `ahead` elements, then downloadInto / stagedDownload of any n <= ahead
  // with those chunks. The n elements arrive, in order, by one thread and by the pool, from
  // the chunks queued, none enqueued again; the chunks past n are left to their owner's drain.
  if (!kdet_test::haveCudaDevice()) GTEST_SKIP() << "no CUDA device";
  const std::size_t most = 20000;
  const PairRig rig(most, [](std::size_t i) {
    return Pair8{static_cast<std::uint32_t>(i * 40503u + 1),
                 static_cast<std::uint32_t>(i ^ 0x5a5a)};
  });
  const std::vector<Pair8>& src = rig.src;
  Pair8* const dev = rig.dev;
  Pair8* const stage = rig.stage;
  ASSERT_TRUE(dev != nullptr && stage != nullptr);
  cudaStream_t s = nullptr;
  ASSERT_EQ(cudaStreamCreate(&s), cudaSuccess);
  ScopedEnv c("KDET_FCL_CUDA_DOWNLOAD_CHUNK", "4096");  // 512 pairs per chunk
  ScopedEnv t("KDET_FCL_CUDA_DOWNLOAD_THREADS", "4");
  kdet_fcl::staging::CopyPool pool;
  std::vector<Pair8> kept(most);  // held: the pool may take the larger counts
  int pooled = 0, cases = 0;
  for (std::size_t ahead : {std::size_t(512), std::size_t(3000), most}) {
    for (std::size_t n : {std::size_t(1), std::size_t(511), std::size_t(512), std::size_t(513),
                          std::size_t(2999), std::size_t(3000), most - 1, most}) {
      if (n > ahead) continue;
      const std::size_t shift = std::size_t(cases++) % 5;  // a stale stage would be seen
      const std::size_t cover = std::min(ahead, most - shift), k = std::min(n, cover);
      SCOPED_TRACE("ahead " + std::to_string(cover) + ", pairs " + std::to_string(k));
      std::memset(static_cast<void*>(stage), 0xEE, most * sizeof(Pair8));
      {
        kdet_fcl::staging::ChunkEvents queued;
        ASSERT_EQ(kdet_fcl::staging::downloadChunks(dev + shift, cover, stage, s, queued),
                  cudaSuccess);
        ASSERT_EQ(queued.ev.size(), (cover + 511) / 512);
        const std::size_t events = queued.ev.size();
        pooled += kdet_fcl::staging::pooledThreads(k, kept.size()) > 0;
        ASSERT_EQ(kdet_fcl::staging::downloadInto(dev + shift, k, stage, s, pool, kept, &queued),
                  cudaSuccess);
        EXPECT_EQ(queued.ev.size(), events) << "nothing enqueued again";
        ASSERT_EQ(kept.size(), k);
        EXPECT_EQ(std::memcmp(kept.data(), src.data() + shift, k * sizeof(Pair8)), 0);
      }  // (drained: its chunks past k have run)
      {
        kdet_fcl::staging::ChunkEvents queued;
        std::memset(static_cast<void*>(stage), 0xEE, most * sizeof(Pair8));
        ASSERT_EQ(kdet_fcl::staging::downloadChunks(dev + shift, cover, stage, s, queued),
                  cudaSuccess);
        std::vector<Pair8> got;
        std::size_t calls = 0;
        ASSERT_EQ(stagedDownload(
                      dev + shift, k, stage, s,
                      [&](const Pair8* first, std::size_t m) {
                        got.insert(got.end(), first, first + m);
                        ++calls;
                      },
                      &queued),
                  cudaSuccess);
        EXPECT_EQ(calls, (k + 511) / 512) << "one call per chunk of the k, none past them";
        ASSERT_EQ(got.size(), k);
        EXPECT_EQ(std::memcmp(got.data(), src.data() + shift, k * sizeof(Pair8)), 0);
      }
      kept.resize(most);  // (held again for the next case)
    }
  }
  EXPECT_GT(pooled, 3) << "the pooled path ran";
  EXPECT_EQ(cudaStreamDestroy(s), cudaSuccess);
}

TEST(PooledDownload, ThreadsKnobAndWhenThePoolRuns) {
  {
    ScopedEnv t("KDET_FCL_CUDA_DOWNLOAD_THREADS", "6");
    EXPECT_EQ(downloadThreads(100), 6);
    EXPECT_EQ(downloadThreads(2), 2);  // never more threads than chunks
    EXPECT_EQ(downloadThreads(0), 1);
  }
  for (const char* bad : {"0", "65", "x", "-1", "4 "}) {
    ScopedEnv t("KDET_FCL_CUDA_DOWNLOAD_THREADS", bad);
    EXPECT_THROW(downloadThreads(1000), kdet_fcl::InvalidInputError) << "'" << bad << "'";
  }
  ScopedEnv t("KDET_FCL_CUDA_DOWNLOAD_THREADS", nullptr);
  ScopedEnv c("KDET_FCL_CUDA_DOWNLOAD_CHUNK", nullptr);
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  EXPECT_EQ(downloadThreads(1000),
            int(std::min<unsigned>(kdet_fcl::staging::kDownloadThreads, hw)));
  // 256 KiB chunks of 8-byte pairs: from 4 chunks (131,072 pairs), into a destination that held
  // at least half as many.
  using kdet_fcl::staging::pooledThreads;
  const std::size_t four = 4 * 32768;
  EXPECT_EQ(pooledThreads(four - 32768, four), 0) << "three chunks: one thread";
  EXPECT_EQ(pooledThreads(four, 0), 0) << "a new result: one thread (no zero-fill first)";
  EXPECT_EQ(pooledThreads(four, four / 2 - 1), 0);
  EXPECT_EQ(pooledThreads(four, four / 2), hw > 1 ? downloadThreads(4) : 0);
  ScopedEnv one("KDET_FCL_CUDA_DOWNLOAD_THREADS", "1");
  EXPECT_EQ(pooledThreads(100 * four, 100 * four), 0) << "one thread asked for";
}

}  // namespace
