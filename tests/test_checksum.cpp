// The checksum behind CacheValidation::Checksum (src/fcl/checksum.h): every kernel gives the same
// value, and the changes a program makes to a model in place are all seen.

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <random>
#include <set>
#include <vector>

#include "fcl/checksum.h"
#include "kdet_fcl/errors.h"

namespace {

using kdet_fcl::detail::bestChecksumKernel;
using kdet_fcl::detail::checksumBytes;
using kdet_fcl::detail::checksumKernelAvailable;
using kdet_fcl::detail::ChecksumKernel;

constexpr ChecksumKernel kKernels[] = {ChecksumKernel::Portable, ChecksumKernel::Sse41,
                                       ChecksumKernel::Avx2};

std::vector<unsigned char> randomBytes(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<unsigned char> b(n);
  for (auto& c : b) c = static_cast<unsigned char>(rng());
  return b;
}

TEST(Checksum, EveryKernelGivesThePortableValueAtAnySizeAndAlignment) {
  int run = 0;
  for (ChecksumKernel k : kKernels) {
    if (!checksumKernelAvailable(k)) {
      EXPECT_THROW(checksumBytes("", 0, 1, k), kdet_fcl::BackendUnavailableError);
      continue;
    }
    ++run;
  }
  std::printf("[          ] %d kernel(s) on this CPU; the library uses kernel %d\n", run,
              static_cast<int>(bestChecksumKernel()));
  const auto buf = randomBytes(300001 + 8, 7);
  std::vector<std::size_t> sizes;
  for (std::size_t n = 0; n <= 800; ++n) sizes.push_back(n);
  for (std::size_t n : {1151u, 1152u, 1153u, 4096u, 100003u, 300001u}) sizes.push_back(n);
  for (std::size_t n : sizes)
    for (std::size_t offset : {0u, 1u, 4u, 7u})
      for (std::uint64_t seed : {1u, 2u}) {
        const std::uint64_t portable =
            checksumBytes(buf.data() + offset, n, seed, ChecksumKernel::Portable);
        EXPECT_EQ(checksumBytes(buf.data() + offset, n, seed), portable) << n << " " << offset;
        for (ChecksumKernel k : kKernels)
          if (checksumKernelAvailable(k))
            ASSERT_EQ(checksumBytes(buf.data() + offset, n, seed, k), portable)
                << "kernel " << static_cast<int>(k) << ", " << n << " bytes at offset " << offset;
      }
  EXPECT_EQ(checksumBytes(nullptr, 0, 1), checksumBytes(buf.data(), 0, 1));
}

// Pages of 96 KiB are hashed apart, by threads where asked: the value is the same for any count.
TEST(Checksum, TheValueDoesNotDependOnTheThreads) {
  constexpr std::size_t kPage = 96 * 1024;
  const auto buf = randomBytes(5 * kPage + 17, 11);
  for (std::size_t n : {std::size_t(0), kPage - 1, kPage, kPage + 1, 3 * kPage, 5 * kPage + 17}) {
    const std::uint64_t one = checksumBytes(buf.data(), n, 1, 1);
    for (int threads : {0, 2, 3, 7}) EXPECT_EQ(checksumBytes(buf.data(), n, 1, threads), one) << n;
    for (ChecksumKernel k : kKernels)
      if (checksumKernelAvailable(k))
        ASSERT_EQ(checksumBytes(buf.data(), n, 1, k, 4), one) << n << " " << static_cast<int>(k);
  }
  // A change in a later page is seen, whichever thread hashes it.
  auto b = buf;
  const std::uint64_t before = checksumBytes(b.data(), b.size(), 1, 3);
  for (std::size_t i : {std::size_t(0), kPage - 1, kPage, 4 * kPage + 5, b.size() - 1}) {
    b[i] ^= 0x10;
    EXPECT_NE(checksumBytes(b.data(), b.size(), 1, 3), before) << i;
    b[i] ^= 0x10;
  }
}

TEST(Checksum, EveryOneByteChangeIsSeen) {
  for (std::size_t n : {1u, 5u, 383u, 384u, 385u, 2000u}) {
    auto buf = randomBytes(n, n);
    for (ChecksumKernel k : kKernels) {
      if (!checksumKernelAvailable(k)) continue;
      const std::uint64_t before = checksumBytes(buf.data(), n, 1, k);
      for (std::size_t i = 0; i < n; ++i)
        for (unsigned char flip : {0x01, 0x80, 0xFF}) {
          buf[i] ^= flip;
          ASSERT_NE(checksumBytes(buf.data(), n, 1, k), before) << n << " bytes, byte " << i;
          buf[i] ^= flip;
        }
      ASSERT_EQ(checksumBytes(buf.data(), n, 1, k), before);
    }
  }
}

// Changes a sum, an xor or lanes hashed apart would miss: two vertices swapped, a word moved, equal
// and opposite changes in words that share a lane (96 words apart), zeros of other lengths.
TEST(Checksum, SwapsOffsettingChangesAndZeroPaddingAreSeen) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> v(3 * 1000);
  for (double& x : v) x = u(rng);
  const std::size_t bytes = v.size() * sizeof(double);
  const std::uint64_t before = checksumBytes(v.data(), bytes, 1);
  for (std::size_t i = 0; i < 1000; i += 7)
    for (std::size_t j = i + 1; j < 1000; j += 97) {
      for (int c = 0; c < 3; ++c) std::swap(v[3 * i + c], v[3 * j + c]);
      ASSERT_NE(checksumBytes(v.data(), bytes, 1), before) << "vertices " << i << " and " << j;
      for (int c = 0; c < 3; ++c) std::swap(v[3 * i + c], v[3 * j + c]);
    }
  std::vector<std::uint32_t> w(96 * 40);
  for (auto& x : w) x = static_cast<std::uint32_t>(rng());
  const std::uint64_t w_before = checksumBytes(w.data(), w.size() * 4, 1);
  for (std::size_t i = 0; i + 96 < w.size(); i += 13)
    for (std::uint32_t d : {1u, 0x10000u, 0x80000000u}) {
      w[i] += d;
      w[i + 96] -= d;
      ASSERT_NE(checksumBytes(w.data(), w.size() * 4, 1), w_before) << i;
      std::swap(w[i], w[i + 96]);  // the lane's words in another order
      ASSERT_NE(checksumBytes(w.data(), w.size() * 4, 1), w_before) << i;
      std::swap(w[i], w[i + 96]);
      w[i] -= d;
      w[i + 96] += d;
    }
  ASSERT_EQ(checksumBytes(w.data(), w.size() * 4, 1), w_before);
  std::set<std::uint64_t> zeros;
  const std::vector<unsigned char> z(1000, 0);
  for (std::size_t n = 0; n <= 1000; ++n) zeros.insert(checksumBytes(z.data(), n, 1));
  EXPECT_EQ(zeros.size(), 1001u);
  EXPECT_NE(checksumBytes(z.data(), 100, 1), checksumBytes(z.data(), 100, 2));
}

}  // namespace
