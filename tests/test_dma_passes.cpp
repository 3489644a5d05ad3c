// The vertex passes over a buffer that the GPU reads by DMA next (src/cpu/dma_passes.h): the
// non-temporal copy gives memcpy's bytes for every alignment of both ends and every length, and
// writes nothing outside the destination; the line demotion changes no byte, for ranges of any
// alignment and length; the knob that forces the rule takes 0, 1 or nothing. HashedMesh's passes
// in that form are in test_hierarchy (UpdateAndCommitLeavingTheCachesCheckAndBoundTheSame).

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "cpu/dma_passes.h"
#include "kdet_fcl/errors.h"
#include "scoped_env.h"

namespace {

using kdet_fcl::cpu::demoteLines;
using kdet_fcl::cpu::dmaPasses;
using kdet_fcl::cpu::streamCopy;

/// n bytes that differ from position to position and from seed to seed.
std::vector<unsigned char> pattern(std::size_t n, unsigned seed) {
  std::vector<unsigned char> v(n);
  std::uint32_t x = 2463534242u ^ (seed * 2654435761u);
  for (auto& b : v) {
    x ^= x << 13, x ^= x >> 17, x ^= x << 5;
    b = static_cast<unsigned char>(x);
  }
  return v;
}

/// The first address at or after p aligned to 64 bytes.
unsigned char* aligned64(unsigned char* p) {
  const auto a = reinterpret_cast<std::uintptr_t>(p);
  return p + ((64 - (a & 63)) & 63);
}

TEST(DmaPasses, StreamCopyGivesMemcpysBytesForEveryAlignmentAndLength) {
  constexpr std::size_t kGuard = 64;  // bytes before and after the destination, left as they were
  std::vector<std::size_t> lengths;
  for (std::size_t n = 0; n <= 200; ++n) lengths.push_back(n);
  for (std::size_t n : {255, 256, 257, 4095, 4096, 65537}) lengths.push_back(n);
  for (const std::size_t n : lengths) {
    const std::size_t step = n > 300 ? 5 : 1;  // (fewer offsets for the long copies)
    for (std::size_t so = 0; so < 16; so += step)
      for (std::size_t dof = 0; dof < 16; dof += step) {
        const std::vector<unsigned char> src = pattern(n + 16, unsigned(n * 17 + so));
        std::vector<unsigned char> room = pattern(n + 2 * kGuard + 16 + 64, unsigned(dof) + 99);
        unsigned char* base = aligned64(room.data());
        const std::vector<unsigned char> before = room;
        unsigned char* dst = base + kGuard + dof;
        streamCopy(dst, src.data() + so, n);
        ASSERT_EQ(std::memcmp(dst, src.data() + so, n), 0)
            << n << " bytes, source offset " << so << ", destination offset " << dof;
        const std::size_t at = static_cast<std::size_t>(dst - room.data());
        for (std::size_t i = 0; i < room.size(); ++i)
          if (i < at || i >= at + n)
            ASSERT_EQ(room[i], before[i]) << "byte " << i << " outside the destination (" << n
                                          << " bytes at offset " << dof << ")";
      }
  }
}

TEST(DmaPasses, DemotingLinesChangesNoByte) {
  const std::vector<unsigned char> want = pattern(3 * 4096 + 200, 5u);
  std::vector<unsigned char> data = want;
  for (std::size_t off : {0, 1, 31, 63, 64, 65, 4095})
    for (std::size_t n : {0, 1, 2, 63, 64, 65, 127, 4096, 8000}) {
      demoteLines(data.data() + off, n);
      ASSERT_EQ(data, want) << off << " " << n;
    }
  // Written after a demotion, read after another: the values written.
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<unsigned char>(want[i] ^ 0x5A);
  demoteLines(data.data(), data.size());
  for (std::size_t i = 0; i < data.size(); ++i)
    ASSERT_EQ(data[i], static_cast<unsigned char>(want[i] ^ 0x5A)) << i;
}

TEST(DmaPasses, TheKnobForcesTheRuleEitherWayAndRefusesOtherValues) {
  {
    kdet_test::ScopedEnv unset("KDET_FCL_DMA_PASSES", nullptr);
    EXPECT_TRUE(dmaPasses(true));
    EXPECT_FALSE(dmaPasses(false));
  }
  {
    kdet_test::ScopedEnv on("KDET_FCL_DMA_PASSES", "1");
    EXPECT_TRUE(dmaPasses(false));
  }
  {
    kdet_test::ScopedEnv off("KDET_FCL_DMA_PASSES", "0");
    EXPECT_FALSE(dmaPasses(true));
  }
  for (const char* bad : {"yes", "2", "-1", "on"}) {
    kdet_test::ScopedEnv b("KDET_FCL_DMA_PASSES", bad);
    try {
      dmaPasses(true);
      ADD_FAILURE() << "accepted KDET_FCL_DMA_PASSES=" << bad;
    } catch (const kdet_fcl::InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find("KDET_FCL_DMA_PASSES"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
