// commitVertices' check and updateVertices' copy with a copy to the device (src/commit_copy.h,
// detail::checkedPieces and copiedPieces), against a copy that records what it is sent: the
// ranges follow each other from offset 0 and cover the buffer exactly once, each but the last at
// least the copy's batch; the check's bounds and verdict are the plain check's, and the copy
// writes every position and nothing beside; a buffer with a coordinate that is not finite is
// refused, and no range sent reaches the piece that holds it. For float and double, on one and
// several threads, with and without the lines' demotion or the non-temporal stores. The CUDA
// backend's copy is tested on a device (test_cuda_query: ACommitCopiesThePositionsWhileIt...,
// UpdateVerticesCopiesThePositionsWhileItWritesThem...).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "commit_copy.h"
#include "kdet_fcl/vec3.h"

namespace {

using kdet_fcl::Vec3;
using kdet_fcl::detail::Aabb;
using kdet_fcl::detail::CommitCopy;
using kdet_fcl::detail::checkedPieces;
using kdet_fcl::detail::copiedPieces;
using kdet_fcl::detail::kCommitBatchBytes;
using kdet_fcl::detail::kCommitPieceBytes;

/// Records every range it is sent (piece() is called by one thread at a time, but from any).
class RecordingCopy : public CommitCopy {
 public:
  explicit RecordingCopy(std::size_t batch = kCommitBatchBytes) : batch(batch) {}
  std::size_t batchBytes() const noexcept override { return batch; }
  void piece(std::size_t offset, std::size_t bytes) noexcept override {
    std::lock_guard<std::mutex> lock(mutex);
    ranges.emplace_back(offset, bytes);
  }
  void finish(bool, std::uint64_t) noexcept override { ++finishes; }
  std::mutex mutex;
  std::vector<std::pair<std::size_t, std::size_t>> ranges;
  int finishes = 0;
  std::size_t batch;
};

/// n vertices that differ from one another, spread over a box that depends on the seed.
template <class S>
std::vector<Vec3<S>> positions(std::size_t n, unsigned seed) {
  std::vector<Vec3<S>> v(n);
  std::uint32_t x = 2463534242u ^ (seed * 2654435761u);
  auto next = [&] {
    x ^= x << 13, x ^= x >> 17, x ^= x << 5;
    return S(double(x % 2000001) / 1000.0 - 1000.0 + seed);
  };
  for (auto& p : v) p = Vec3<S>{next(), next(), next()};
  return v;
}

/// The bounds of v, computed the plain way.
template <class S>
Aabb<double> plainBounds(const std::vector<Vec3<S>>& v) {
  Aabb<double> b{{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()},
                 {-std::numeric_limits<double>::infinity(),
                  -std::numeric_limits<double>::infinity(),
                  -std::numeric_limits<double>::infinity()}};
  for (const auto& p : v) {
    const double c[3] = {double(p.x), double(p.y), double(p.z)};
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::min(b.lo[a], c[a]);
      b.hi[a] = std::max(b.hi[a], c[a]);
    }
  }
  return b;
}

/// The vertices of a piece, and the pieces of a batch, of a copy whose batch is `batch` bytes
/// (checkedPieces' rule: pieces of kCommitPieceBytes at most, and no larger than the batch).
template <class S>
std::pair<std::size_t, std::size_t> pieceAndBatch(std::size_t batch) {
  const std::size_t per = std::max<std::size_t>(1, std::min(kCommitPieceBytes, batch) /
                                                       sizeof(Vec3<S>));
  const std::size_t bytes = per * sizeof(Vec3<S>);
  return {per, (batch + bytes - 1) / bytes};
}

/// The ranges sent for a buffer of n vertices follow each other from 0 and cover every byte
/// once, each starting on a piece (`per` vertices) and each but the last at least a batch of
/// whole pieces (the run grows by pieces); on one thread a buffer of more than two batches goes
/// in two ranges at least (sent while the pass went on).
template <class S>
void expectConsecutiveRanges(const RecordingCopy& copy, std::size_t n, std::size_t per,
                             std::size_t batch_pieces, int threads, const std::string& what) {
  std::size_t at = 0;
  for (std::size_t k = 0; k < copy.ranges.size(); ++k) {
    const auto [offset, bytes] = copy.ranges[k];
    EXPECT_EQ(offset, at) << what << ", range " << k;
    EXPECT_GT(bytes, 0u) << what << ", range " << k;
    EXPECT_EQ(offset % (per * sizeof(Vec3<S>)), 0u) << what << ", range " << k;
    if (k + 1 < copy.ranges.size())
      EXPECT_GE(bytes, batch_pieces * per * sizeof(Vec3<S>)) << what << ", range " << k;
    at = offset + bytes;
  }
  EXPECT_EQ(at, n * sizeof(Vec3<S>)) << what;
  if (n > 2 * batch_pieces * per && threads == 1) EXPECT_GE(copy.ranges.size(), 2u) << what;
}

template <class S>
void checkFiniteBuffers(std::size_t batch) {
  const auto [per, batch_pieces] = pieceAndBatch<S>(batch);
  // Sizes: none, one vertex, less than a piece, a piece exactly, a piece and one, a batch and
  // some, and about 5 MB (many batches).
  const std::size_t sizes[] = {0,       1,       per / 3, per, per + 1, batch_pieces * per + 7,
                               (std::size_t(5) << 20) / sizeof(Vec3<S>) + 5};
  for (std::size_t n : sizes)
    for (int threads : {1, 2, 4})
      for (bool demote : {false, true}) {
        const std::string what = "batch " + std::to_string(batch) + ", n " + std::to_string(n) +
                                 ", threads " + std::to_string(threads) +
                                 (demote ? ", demoting" : "");
        const std::vector<Vec3<S>> v = positions<S>(n, unsigned(n % 97 + threads));
        RecordingCopy copy(batch);
        Aabb<double> b;
        ASSERT_TRUE(checkedPieces(v, threads, demote, copy, &b)) << what;
        EXPECT_EQ(copy.finishes, 0) << what;  // the caller's to call
        const Aabb<double> want = plainBounds(v);
        for (int a = 0; a < 3; ++a) {
          EXPECT_EQ(b.lo[a], want.lo[a]) << what << ", axis " << a;
          EXPECT_EQ(b.hi[a], want.hi[a]) << what << ", axis " << a;
        }
        expectConsecutiveRanges<S>(copy, n, per, batch_pieces, threads, what);
      }
}

template <class S>
void checkCopiedBuffers(std::size_t batch) {
  const auto [per, batch_pieces] = pieceAndBatch<S>(batch);
  const std::size_t sizes[] = {0, 1, per - 1, per, batch_pieces * per + 3,
                               (std::size_t(5) << 20) / sizeof(Vec3<S>) + 2};
  for (std::size_t n : sizes)
    for (int threads : {1, 2, 4})
      for (bool stream : {false, true}) {
        const std::string what = "batch " + std::to_string(batch) + ", n " + std::to_string(n) +
                                 ", threads " + std::to_string(threads) +
                                 (stream ? ", non-temporal" : "");
        const std::vector<Vec3<S>> src = positions<S>(n, unsigned(n % 89 + threads));
        // One vertex of room on each side, which must stay as it was.
        std::vector<Vec3<S>> dst(n + 2, Vec3<S>{S(-7), S(-7), S(-7)});
        RecordingCopy copy(batch);
        copiedPieces(src, dst.data() + 1, threads, stream, copy);
        EXPECT_EQ(copy.finishes, 0) << what;
        EXPECT_TRUE(std::equal(src.begin(), src.end(), dst.begin() + 1,
                               [](const Vec3<S>& a, const Vec3<S>& b) {
                                 return a.x == b.x && a.y == b.y && a.z == b.z;
                               }))
            << what;
        for (std::size_t k : {std::size_t(0), n + 1})
          EXPECT_TRUE(dst[k].x == S(-7) && dst[k].y == S(-7) && dst[k].z == S(-7)) << what;
        expectConsecutiveRanges<S>(copy, n, per, batch_pieces, threads, what);
      }
}

template <class S>
void checkRefusedBuffers(std::size_t batch) {
  const std::size_t per = pieceAndBatch<S>(batch).first;
  const std::size_t n = (std::size_t(5) << 20) / sizeof(Vec3<S>) + 11;
  const S bad_values[] = {std::numeric_limits<S>::quiet_NaN(), std::numeric_limits<S>::infinity(),
                          -std::numeric_limits<S>::infinity()};
  for (std::size_t at : {std::size_t(0), per - 1, per, n / 2, n - 1})
    for (int axis = 0; axis < 3; ++axis)
      for (int threads : {1, 4}) {
        const S bad = bad_values[(at + std::size_t(axis)) % 3];
        const std::string what = "batch " + std::to_string(batch) + ", bad vertex " +
                                 std::to_string(at) + ", axis " + std::to_string(axis) +
                                 ", threads " + std::to_string(threads);
        std::vector<Vec3<S>> v = positions<S>(n, 5);
        (axis == 0 ? v[at].x : axis == 1 ? v[at].y : v[at].z) = bad;
        RecordingCopy copy(batch);
        Aabb<double> b;
        EXPECT_FALSE(checkedPieces(v, threads, false, copy, &b)) << what;
        EXPECT_EQ(copy.finishes, 0) << what;
        // Nothing sent reaches the bad vertex's piece (the pieces before it may have gone).
        const std::size_t piece_start = at / per * per * sizeof(Vec3<S>);
        for (const auto& [offset, bytes] : copy.ranges)
          EXPECT_LE(offset + bytes, piece_start) << what;
      }
}

// Batches: the default, one piece, a part of a piece that is no whole number of vertices, a
// batch of whole pieces and a part, and four pieces.
const std::size_t kBatches[] = {kCommitBatchBytes, kCommitPieceBytes, 100000,
                                3 * kCommitPieceBytes + 4096, 4 * kCommitPieceBytes};

TEST(CommitCopy, AFiniteBufferIsSentOnceInOrderWithThePlainChecksBounds) {
  for (std::size_t batch : kBatches) {
    checkFiniteBuffers<float>(batch);
    checkFiniteBuffers<double>(batch);
  }
}

TEST(CommitCopy, UpdateVerticesCopyWritesEveryPositionAndSendsTheRunWritten) {
  for (std::size_t batch : kBatches) {
    checkCopiedBuffers<float>(batch);
    checkCopiedBuffers<double>(batch);
  }
}

TEST(CommitCopy, ABufferWithANonFiniteCoordinateIsRefusedAndNothingSentReachesIt) {
  for (std::size_t batch : kBatches) {
    checkRefusedBuffers<float>(batch);
    checkRefusedBuffers<double>(batch);
  }
}

}  // namespace
