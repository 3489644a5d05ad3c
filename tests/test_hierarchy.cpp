// The hierarchical hash itself, and HashedMesh's life cycle (poses, deformation, topology
// changes, bad input).

#include <gtest/gtest.h>

#if defined(__linux__)
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <functional>
#include <new>
#endif

#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <random>
#include <thread>
#include <utility>
#include <vector>

#include "cpu/hierarchical_hash.h"
#include "oom_util.h"
#include "scoped_env.h"
#include "test_util.h"

using namespace kdet_fcl;

namespace {

/// f moved by |n| float steps, up for n > 0, down for n < 0.
float stepsUp(float f, int n) {
  for (int k = 0; k < (n > 0 ? n : -n); ++k) f = std::nextafter(f, n > 0 ? HUGE_VALF : -HUGE_VALF);
  return f;
}

template <class S>
void expectEveryTriangleInItsCells(const HashedMesh<S>& hm) {
  const auto& h = hm.hash();
  for (std::size_t i = 0; i < hm.numTriangles(); ++i) {
    const detail::CellRange r = detail::cellRange(h.boxes[i], h.level[i], h.grid);
    EXPECT_LE(r.count(), 27);
    for (auto x = r.lo[0]; x <= r.hi[0]; ++x)
      for (auto y = r.lo[1]; y <= r.hi[1]; ++y)
        for (auto z = r.lo[2]; z <= r.hi[2]; ++z) {
          const auto* s = h.find(detail::makeCellKey(h.level[i], x, y, z));
          ASSERT_NE(s, nullptr);
          int found = 0;
          const detail::EntryBox expectBox = detail::entryBox(h.boxes[i], h.grid.origin);
          for (std::uint32_t k = 0; k < s->count; ++k) {
            const auto& e = h.entriesOf(h.level[i])[s->begin + k];
            if (e.id != i) continue;
            ++found;
            EXPECT_EQ(e.diameter, h.diameter[i]);
            // The compact box holds the triangle's box (offsets from the grid origin, rounded
            // outward) and is at most two float steps looser on each side.
            EXPECT_EQ(std::memcmp(&e.box, &expectBox, sizeof e.box), 0);
            for (int a = 0; a < 3; ++a) {
              const double lo = h.boxes[i].lo[a] - h.grid.origin[a];
              const double hi = h.boxes[i].hi[a] - h.grid.origin[a];
              EXPECT_LE(double(e.box.lo[a]), lo);
              EXPECT_GE(double(e.box.hi[a]), hi);
              EXPECT_GT(double(stepsUp(e.box.lo[a], 2)), lo);
              EXPECT_LT(double(stepsUp(e.box.hi[a], -2)), hi);
            }
            EXPECT_EQ(e.lo_mask, (x == r.lo[0] ? 1 : 0) | (y == r.lo[1] ? 2 : 0) |
                                     (z == r.lo[2] ? 4 : 0));
          }
          EXPECT_EQ(found, 1) << "triangle " << i;
          // Largest first, ties by increasing id: a lookup stops at the first too-small triangle.
          for (std::uint32_t k = 1; k < s->count; ++k) {
            const auto& p = h.entriesOf(h.level[i])[s->begin + k - 1];
            const auto& e = h.entriesOf(h.level[i])[s->begin + k];
            EXPECT_TRUE(p.diameter > e.diameter || (p.diameter == e.diameter && p.id < e.id));
          }
        }
  }
  std::size_t expected_entries = 0;
  for (std::size_t i = 0; i < hm.numTriangles(); ++i)
    expected_entries += std::size_t(detail::cellRange(h.boxes[i], h.level[i], h.grid).count());
  EXPECT_EQ(h.numEntries(), expected_entries);  // and nothing else
}

}  // namespace

TEST(Hierarchy, EveryTriangleIsInExactlyTheCellsItsBoxCovers) {
  HashedMesh<double> cloth(makeDrapedCloth<double>(30, 4.0, 1.0, 0.02, 1.0));
  expectEveryTriangleInItsCells(cloth);
  HashedMesh<float> soup(makeRandomSoup<float>(3000, 10.f, 0.001f, 3.f, 9));
  expectEveryTriangleInItsCells(soup);
}

// The compact entry boxes: rounding outward stays within two float steps, handles zero, tiny
// values and doubles beyond float's range, and never turns an overlap (even a touch) of two
// double boxes into a miss.
TEST(Hierarchy, CompactEntryBoxesNeverDropAnOverlap) {
  // floatDown / floatUp take offsets >= 0 (boxes inside the hash's bounds, from its low corner).
  const float fmax = std::numeric_limits<float>::max();
  EXPECT_EQ(detail::floatDown(0.0), 0.0f);
  EXPECT_EQ(detail::floatUp(0.0), std::numeric_limits<float>::denorm_min());
  EXPECT_EQ(detail::floatDown(1e300), stepsUp(fmax, -1));
  EXPECT_EQ(detail::floatUp(1e300), HUGE_VALF);
  EXPECT_EQ(detail::floatDown(double(fmax)), stepsUp(fmax, -1));
  EXPECT_EQ(detail::floatUp(double(fmax)), HUGE_VALF);
  EXPECT_EQ(detail::floatDown(1e-300), 0.0f);  // rounds to 0, which is below
  EXPECT_EQ(detail::floatUp(1e-300), std::numeric_limits<float>::denorm_min());
  EXPECT_EQ(detail::floatDown(1.0), stepsUp(1.0f, -1));  // always one step from the nearest
  EXPECT_EQ(detail::floatUp(1.0), stepsUp(1.0f, 1));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mant(0, 1);
  std::uniform_int_distribution<int> expo(-140, 125);
  for (int k = 0; k < 200000; ++k) {
    const double x = std::ldexp(mant(rng), expo(rng));
    const float d = detail::floatDown(x), u = detail::floatUp(x);
    ASSERT_LE(double(d), x) << x;
    ASSERT_GE(double(u), x) << x;
    ASSERT_GT(double(stepsUp(d, 2)), x) << x;  // at most two steps away
    ASSERT_LT(double(stepsUp(u, -2)), x) << x;
  }
  // Boxes that touch or nearly touch in double, at several scales and origins: the compact
  // boxes must overlap whenever the double boxes do.
  std::uniform_real_distribution<double> unit(0, 1);
  int touching = 0;
  for (int k = 0; k < 200000; ++k) {
    const double scale = std::ldexp(1.0, expo(rng) / 4);
    const double origin[3] = {-scale * unit(rng), -scale * unit(rng), -scale * unit(rng)};
    detail::Aabb<double> p, q;
    for (int a = 0; a < 3; ++a) {
      p.lo[a] = origin[a] + scale * unit(rng);
      p.hi[a] = p.lo[a] + scale * unit(rng) * 1e-3;
      // q starts at p's end, one double step either side of it, or exactly there.
      const int step = int(rng() % 3) - 1;
      q.lo[a] = step == 0 ? p.hi[a] : std::nextafter(p.hi[a], step * HUGE_VAL);
      q.hi[a] = q.lo[a] + scale * unit(rng) * 1e-3;
      if (rng() & 1) {  // q on the low side on this axis
        std::swap(p.lo[a], q.lo[a]);
        std::swap(p.hi[a], q.hi[a]);
      }
    }
    const bool exact = detail::boxesOverlap(p, q);
    touching += exact;
    if (exact)
      ASSERT_TRUE(detail::entryBoxesOverlap(detail::entryBox(p, origin), detail::entryBox(q, origin)))
          << k;
  }
  EXPECT_GT(touching, 1000);  // the touching case was exercised
}

TEST(Hierarchy, LevelsFollowTheSizeRule) {
  HashedMesh<double> soup(makeRandomSoup<double>(2000, 10.0, 0.01, 5.0, 4));
  const auto& h = soup.hash();
  for (std::size_t i = 0; i < soup.numTriangles(); ++i) {
    const double cell = h.grid.cell0 * std::ldexp(1.0, h.level[i]);
    EXPECT_GE(cell, h.diameter[i]);
    if (h.level[i] > 0) EXPECT_LT(cell / 2, h.diameter[i]);
  }
  const HierarchyStats st = soup.stats();
  EXPECT_EQ(st.height, int(std::ceil(std::log2(st.d_max / st.d_min))) + 1);
  EXPECT_DOUBLE_EQ(st.cell_size0, st.d_min);
}

TEST(Hierarchy, MemoryIsLinearInTheTriangleCount) {
  // Same shape at 8k and 200k triangles: bytes per triangle stay put (no grid volume term).
  HashedMesh<float> small(makeDrapedCloth<float>(64, 4.f, 1.f, 0.02f, 1.f));
  HashedMesh<float> large(makeDrapedCloth<float>(316, 4.f, 1.f, 0.02f, 1.f));
  const double bs = double(small.stats().memory_bytes) / small.numTriangles();
  const double bl = double(large.stats().memory_bytes) / large.numTriangles();
  EXPECT_LT(bl, 1.5 * bs);
  // The hash and the build scratch (kept so a deforming mesh rebuilds without allocating): a few
  // hundred bytes per triangle, independent of n.
  EXPECT_LT(bl, 512.0);
  EXPECT_LE(large.stats().entries, 8 * large.numTriangles());
}

TEST(Hierarchy, HugeSizeRatioHasTallHierarchyWithoutOverflow) {
  TriangleMesh<double> m;
  m.addTriangle({0, 0, 0}, {1e7, 0, 0}, {0, 1e7, 0});  // one huge triangle
  for (int i = 0; i < 50; ++i) {
    const double x = 10.0 * i;
    m.addTriangle({x, 1, -0.5}, {x + 1, 1, 0.5}, {x, 2, 0.5});  // crosses z = 0
    m.addTriangle({x, 5, 1}, {x + 1, 5, 1}, {x, 6, 1});         // above the plane
  }
  HashedMesh<double> hm(m);
  EXPECT_GE(hm.stats().height, 24);
  const auto self = kdet_test::sorted(intersectSelf(hm).pairs);
  EXPECT_EQ(self, bruteForceIntersectSelf(m));
  EXPECT_EQ(self.size(), 50u);
}

// Size ratios beyond 2^38 (docs/numerics.md section 1): the finest cell is the extent / 2^38, and
// the triangles smaller than it are counted (HierarchyStats::below_cell0); within the range none
// are, and a point-like triangle (size 0) never is. The pairs are the brute force's either way.
TEST(Hierarchy, TrianglesBelowTheFinestCellAreCountedBeyondARatioOf2To38) {
  auto scene = [](double big) {
    TriangleMesh<double> m;
    m.addTriangle({-big, -big, 0}, {big, -big, 0}, {0, big, 0});
    for (int i = 0; i < 12; ++i) {  // tiny triangles of size ~1e-3 near the origin, crossing z = 0
      const double x = 2e-3 * (i % 4), y = 2e-3 * (i / 4);
      m.addTriangle({x, y, -5e-4}, {x + 1e-3, y, 5e-4}, {x, y + 1e-3, 5e-4});
    }
    m.addTriangle({5e-2, 5e-2, 1}, {5e-2, 5e-2, 1}, {5e-2, 5e-2, 1});  // a point
    return m;
  };
  for (const double big : {1e3, 1e7}) {  // ratios about 1e6 and 1e10: within 2^38
    HashedMesh<double> hm(scene(big));
    EXPECT_EQ(hm.stats().below_cell0, 0u) << big;
    EXPECT_EQ(kdet_test::sorted(intersectSelf(hm).pairs), bruteForceIntersectSelf(hm.mesh()));
  }
  for (const double big : {1e9, 1e12}) {  // ratios about 1e12 and 1e15: beyond 2^38 (2.7e11)
    HashedMesh<double> hm(scene(big));
    const HierarchyStats s = hm.stats();
    EXPECT_EQ(s.below_cell0, 12u) << big;
    EXPECT_GT(s.cell_size0, s.d_min) << big;
    const auto self = kdet_test::sorted(intersectSelf(hm).pairs);
    EXPECT_EQ(self, bruteForceIntersectSelf(hm.mesh())) << big;
    EXPECT_EQ(self.size(), 12u) << big;  // each tiny triangle crosses the huge one
  }
}

TEST(Hierarchy, PointLikeAndEmptyMeshes) {
  TriangleMesh<double> pts;
  pts.addTriangle({1, 1, 1}, {1, 1, 1}, {1, 1, 1});
  pts.addTriangle({1, 1, 1}, {1, 1, 1}, {1, 1, 1});
  HashedMesh<double> hp(pts);
  EXPECT_EQ(hp.stats().height, 1);
  // Coincident point triangles share equal coordinates: adjacent, so not a self-collision.
  EXPECT_TRUE(intersectSelf(hp).pairs.empty());
  HashedMesh<double> other(pts, makeTransform<double>({0, 0, 1}, 0.0, {0, 0, 0}));
  EXPECT_EQ(intersectMeshes(hp, other).pairs.size(), 4u);

  HashedMesh<double> empty(TriangleMesh<double>{});
  EXPECT_EQ(empty.stats().triangles, 0u);
  EXPECT_TRUE(intersectMeshes(empty, hp).pairs.empty());
  EXPECT_TRUE(intersectSelf(empty).pairs.empty());
}

TEST(HashedMesh, RejectsBadInputAndKeepsState) {
  TriangleMesh<double> m;
  m.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  TriangleMesh<double> nan = m;
  nan.vertices[1].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(HashedMesh<double>{nan}, InvalidInputError);
  TriangleMesh<double> inf = m;
  inf.vertices[2].z = std::numeric_limits<double>::infinity();
  EXPECT_THROW(HashedMesh<double>{inf}, InvalidInputError);
  TriangleMesh<double> bad = m;
  bad.triangles[0][2] = 3;
  try {
    HashedMesh<double> h(bad);
    FAIL() << "no exception";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 0"), std::string::npos) << e.what();
  }

  HashedMesh<double> hm(m);
  const auto v0 = hm.version();
  Transform<double> scaled;
  scaled.R[0][0] = 2;
  EXPECT_THROW(hm.setPose(scaled), InvalidInputError);
  Transform<double> reflect;
  reflect.R[2][2] = -1;
  EXPECT_THROW(hm.setPose(reflect), InvalidInputError);
  Transform<double> nanpose;
  nanpose.t.x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(hm.setPose(nanpose), InvalidInputError);
  EXPECT_TRUE(hm.pose().isIdentity());

  EXPECT_THROW(hm.updateVertices({{0, 0, 0}}), InvalidInputError);  // wrong count
  EXPECT_THROW(hm.updateVertices({{0, 0, 0}, {std::nan(""), 0, 0}, {0, 1, 0}}), InvalidInputError);
  EXPECT_THROW(hm.setMesh(bad), InvalidInputError);
  EXPECT_EQ(hm.version(), v0);
  EXPECT_EQ(hm.mesh().vertices[1].x, 1.0);
  EXPECT_EQ(hm.numTriangles(), 1u);
}

// updateVertices checks and bounds the new positions in one pass and copies them into the mesh's
// own buffer: the buffer keeps its address, the bounds equal those of the positions, and any
// non-finite coordinate anywhere (NaN, +inf, -inf, each axis, first and last vertex) is refused
// with the vertex named and the mesh left as it was.
template <class S>
void checkUpdateVerticesInPlace() {
  HashedMesh<S> hm(makeSphere<S>({0, 0, 0}, 1, 12, 6));
  const Vec3<S>* buffer = hm.mesh().vertices.data();
  const std::size_t nv = hm.mesh().vertices.size();
  std::vector<Vec3<S>> moved = hm.mesh().vertices;
  for (std::size_t i = 0; i < nv; ++i)
    moved[i] = {moved[i].x * S(3) - S(7), moved[i].y * S(0.5), -moved[i].z + S(1e3)};
  const auto v0 = hm.version();
  hm.updateVertices(moved);
  EXPECT_EQ(hm.mesh().vertices.data(), buffer) << "the vertex buffer was reallocated";
  EXPECT_EQ(hm.mesh().vertices, moved);
  EXPECT_GT(hm.version(), v0);
  detail::Aabb<double> want{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (const Vec3<S>& p : moved)
    for (int a = 0; a < 3; ++a) {
      want.lo[a] = std::min(want.lo[a], double(p[a]));
      want.hi[a] = std::max(want.hi[a], double(p[a]));
    }
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(hm.localBounds().lo[a], want.lo[a]) << a;
    EXPECT_EQ(hm.localBounds().hi[a], want.hi[a]) << a;
  }
  EXPECT_EQ(kdet_test::sorted(intersectSelf(hm).pairs), bruteForceIntersectSelf(hm.mesh()));
  const S bad[] = {std::numeric_limits<S>::quiet_NaN(), std::numeric_limits<S>::infinity(),
                   -std::numeric_limits<S>::infinity()};
  for (const S x : bad)
    for (const std::size_t i : {std::size_t(0), std::size_t(1), std::size_t(2), std::size_t(3),
                                std::size_t(4), std::size_t(5), nv / 2, nv - 2, nv - 1})
      for (int a = 0; a < 3; ++a) {
        std::vector<Vec3<S>> v = moved;
        v[i][a] = x;
        const auto before = hm.version();
        try {
          hm.updateVertices(v);
          ADD_FAILURE() << "accepted " << x << " at vertex " << i << " axis " << a;
        } catch (const InvalidInputError& e) {
          EXPECT_NE(std::string(e.what()).find("vertex " + std::to_string(i) + " "),
                    std::string::npos)
              << e.what();
        }
        EXPECT_EQ(hm.version(), before);
        EXPECT_EQ(hm.mesh().vertices, moved);
      }
  EXPECT_EQ(hm.mesh().vertices.data(), buffer);
  // The bounds see an extreme coordinate at any vertex and axis (every lane of the vector pass
  // and the scalar tail), low and high, for vertex counts around the vector step.
  for (std::size_t count : {std::size_t(1), std::size_t(2), std::size_t(3), std::size_t(5),
                            std::size_t(8), std::size_t(11)}) {
    TriangleMesh<S> small;
    for (std::size_t i = 0; i < count; ++i)
      small.vertices.push_back({S(i % 3), S(i % 5) - S(2), S(i) * S(0.25)});
    small.triangles.push_back({0, 0, 0});
    HashedMesh<S> sm(small);
    for (std::size_t i = 0; i < count; ++i)
      for (int a = 0; a < 3; ++a)
        for (const S x : {S(-1e6), S(1e6)}) {
          std::vector<Vec3<S>> v = small.vertices;
          v[i][a] = x;
          sm.updateVertices(v);
          const detail::Aabb<double>& b = sm.localBounds();
          EXPECT_EQ(x < 0 ? b.lo[a] : b.hi[a], double(x)) << count << " " << i << " " << a;
          for (int o = 0; o < 3; ++o) {
            double lo = 1e300, hi = -1e300;
            for (const Vec3<S>& p : v) {
              lo = std::min(lo, double(p[o]));
              hi = std::max(hi, double(p[o]));
            }
            EXPECT_EQ(b.lo[o], lo);
            EXPECT_EQ(b.hi[o], hi);
          }
        }
  }
}

TEST(HashedMesh, UpdateVerticesKeepsTheBufferAndBoundsInOnePass) {
  checkUpdateVerticesInPlace<float>();
  checkUpdateVerticesInPlace<double>();
}

// From 1.5 MB of positions on, updateVertices checks and copies them in several threads (one per
// 512 KB, at most the mesh's, where that makes at least 3: here 3, 4 and the hardware's count of
// the counts below; the threads are the library's kept workers, cpu/worker_pool.h): the
// same bounds, the same positions, the same refusal of a non-finite coordinate in any thread's
// share (first and last vertex of each share and their neighbours) with the vertex named and the
// mesh left as it was, for every thread count. commitVertices checks its write buffer in place
// by the same rule: the same bounds and refusals (the refused positions left in the write buffer
// as written, the mesh unchanged), and a mended buffer commits.
template <class S>
void checkUpdateVerticesInThreads() {
  // 9 MB: up to 18 threads; an odd count, so that the shares' ends fall between 16-byte
  // boundaries (the non-temporal copy's tails).
  const std::size_t nv = (std::size_t(9) << 20) / sizeof(Vec3<S>) + 7;
  TriangleMesh<S> m;
  for (std::size_t i = 0; i < nv; ++i)
    m.vertices.push_back({S(i % 1000), S((i / 1000) % 1000), S(i % 7) - S(3)});
  m.triangles.push_back({0, 1, 2});
  std::vector<Vec3<S>> moved = m.vertices;
  for (std::size_t i = 0; i < nv; ++i)
    moved[i] = {moved[i].x * S(0.5) - S(11), -moved[i].y, moved[i].z + S(i % 13)};
  moved[nv / 3] = {S(-1e6), S(2e6), S(-3e6)};  // extremes inside the second share
  moved[nv - 1] = {S(4e6), S(-5e6), S(6e6)};   // and at the end
  detail::Aabb<double> want{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (const Vec3<S>& p : moved)
    for (int a = 0; a < 3; ++a) {
      want.lo[a] = std::min(want.lo[a], double(p[a]));
      want.hi[a] = std::max(want.hi[a], double(p[a]));
    }
  for (int threads : {1, 2, 3, 4, 0}) {
    HashedMesh<S> hm(m, Transform<S>::identity(), threads);
    const Vec3<S>* buffer = hm.mesh().vertices.data();
    hm.updateVertices(moved);
    EXPECT_EQ(hm.mesh().vertices.data(), buffer) << threads;
    EXPECT_TRUE(hm.mesh().vertices == moved) << threads;
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(hm.localBounds().lo[a], want.lo[a]) << threads << " " << a;
      EXPECT_EQ(hm.localBounds().hi[a], want.hi[a]) << threads << " " << a;
    }
    std::vector<std::size_t> at = {0, 1, nv - 2, nv - 1};
    for (int t = 2; t <= 4; ++t)
      for (int k = 1; k < t; ++k) {
        const std::size_t edge = k * ((nv + t - 1) / t);  // where a share of t threads starts
        at.insert(at.end(), {edge - 1, edge, edge + 1});
      }
    for (const std::size_t i : at) {
      std::vector<Vec3<S>> v = moved;
      v[i][int(i % 3)] = i % 2 ? std::numeric_limits<S>::infinity()
                               : std::numeric_limits<S>::quiet_NaN();
      const auto before = hm.version();
      try {
        hm.updateVertices(v);
        ADD_FAILURE() << "accepted a non-finite coordinate at vertex " << i << ", " << threads
                      << " threads";
      } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("vertex " + std::to_string(i) + " "),
                  std::string::npos)
            << e.what();
      }
      EXPECT_EQ(hm.version(), before);
      EXPECT_TRUE(hm.mesh().vertices == moved) << "changed by a refused update at " << i;
      Vec3<S>* w = hm.vertexWriteBuffer();
      std::copy(v.begin(), v.end(), w);
      try {
        hm.commitVertices();
        ADD_FAILURE() << "committed a non-finite coordinate at vertex " << i << ", " << threads
                      << " threads";
      } catch (const InvalidInputError& e) {
        EXPECT_NE(std::string(e.what()).find("vertex " + std::to_string(i) + " "),
                  std::string::npos)
            << e.what();
      }
      EXPECT_EQ(hm.version(), before);
      EXPECT_TRUE(hm.mesh().vertices == moved) << "changed by a refused commit at " << i;
      EXPECT_EQ(std::memcmp(w, v.data(), nv * sizeof(Vec3<S>)), 0) << "write buffer at " << i;
    }
    // The mended write buffer commits, with the bounds of what it holds (moved, reflected).
    Vec3<S>* w = hm.vertexWriteBuffer();
    for (std::size_t i = 0; i < nv; ++i) w[i] = {-moved[i].x, moved[i].y, moved[i].z};
    hm.commitVertices();
    EXPECT_EQ(hm.mesh().vertices.data(), w) << threads;
    EXPECT_EQ(hm.localBounds().lo.x, -want.hi.x) << threads;
    EXPECT_EQ(hm.localBounds().hi.x, -want.lo.x) << threads;
    EXPECT_EQ(hm.localBounds().lo.y, want.lo.y) << threads;
    EXPECT_EQ(hm.localBounds().hi.z, want.hi.z) << threads;
  }
}

TEST(HashedMesh, UpdateVerticesOfLargeArraysInSeveralThreadsChecksAndBoundsTheSame) {
  checkUpdateVerticesInThreads<float>();
  checkUpdateVerticesInThreads<double>();
}

// The same passes in the form they take over a buffer the GPU reads by DMA next (src/cpu/
// dma_passes.h; by default only where the CUDA backend registered it, here forced by the knob):
// updateVertices copies by non-temporal stores, commitVertices demotes each line it has checked.
// The same positions, bounds and refusals for every thread count; and a knob value the rule does
// not accept fails the update and the commit before the mesh changes.
TEST(HashedMesh, UpdateAndCommitLeavingTheCachesCheckAndBoundTheSame) {
  {
    kdet_test::ScopedEnv on("KDET_FCL_DMA_PASSES", "1");
    checkUpdateVerticesInThreads<float>();
    checkUpdateVerticesInThreads<double>();
  }
  const TriangleMesh<double> sphere = makeSphere<double>({0, 0, 0}, 1, 12, 6);
  HashedMesh<double> hm(sphere);
  std::vector<Vec3<double>> moved = sphere.vertices;
  for (auto& p : moved) p.x += 0.5;
  kdet_test::ScopedEnv bad("KDET_FCL_DMA_PASSES", "yes");
  const auto v0 = hm.version();
  EXPECT_THROW(hm.updateVertices(moved), InvalidInputError);
  std::copy(moved.begin(), moved.end(), hm.vertexWriteBuffer());
  EXPECT_THROW(hm.commitVertices(), InvalidInputError);
  EXPECT_EQ(hm.version(), v0);
  EXPECT_TRUE(hm.mesh().vertices == sphere.vertices);
}

// The topology version changes with the triangles only (construction, setMesh), not with
// updateVertices or setPose; it is unique in the process and goes along with a move. The CUDA
// backend keys its copy of the triangles by it (test_cuda_query checks that side).
TEST(HashedMesh, TopologyVersionChangesWithTheTrianglesOnly) {
  const TriangleMesh<double> sphere = makeSphere<double>({0, 0, 0}, 1, 12, 6);
  HashedMesh<double> a(sphere), b(sphere);
  EXPECT_NE(a.topologyVersion(), b.topologyVersion());
  const auto t0 = a.topologyVersion(), v0 = a.version();
  std::vector<Vec3<double>> moved = sphere.vertices;
  for (auto& p : moved) p.x += 0.5;
  a.updateVertices(moved);
  Transform<double> shifted;
  shifted.t = {1, 2, 3};
  a.setPose(shifted);
  EXPECT_GT(a.version(), v0);
  EXPECT_EQ(a.topologyVersion(), t0);
  TriangleMesh<double> bad;  // a vertex index out of range
  bad.vertices = {{0, 0, 0}};
  bad.triangles = {{0, 0, 5}};
  EXPECT_THROW(a.setMesh(bad), InvalidInputError);
  EXPECT_EQ(a.topologyVersion(), t0);  // a refused setMesh changes nothing
  a.setMesh(sphere);  // the same triangles, but set anew
  const auto t1 = a.topologyVersion();
  EXPECT_NE(t1, t0);
  EXPECT_NE(t1, b.topologyVersion());
  HashedMesh<double> c(std::move(a));
  EXPECT_EQ(c.topologyVersion(), t1);
  b = std::move(c);
  EXPECT_EQ(b.topologyVersion(), t1);
}

TEST(HashedMesh, IdentityIsTheObjectsFromConstructionAndMovesWithTheMesh) {
  const TriangleMesh<double> sphere = makeSphere<double>({0, 0, 0}, 1, 12, 6);
  std::optional<HashedMesh<double>> a;
  a.emplace(sphere);
  HashedMesh<double> b(sphere);
  const auto id = a->identity();
  EXPECT_NE(id, 0u);
  EXPECT_NE(id, b.identity());
  std::vector<Vec3<double>> moved = sphere.vertices;
  for (auto& p : moved) p.x += 0.5;
  a->updateVertices(moved);
  Transform<double> shifted;
  shifted.t = {1, 2, 3};
  a->setPose(shifted);
  a->setMesh(makeSphere<double>({0, 0, 0}, 1, 8, 4));
  Vec3<double>* w = a->vertexWriteBuffer();
  for (std::size_t k = 0; k < a->numVertices(); ++k) w[k] = a->mesh().vertices[k];
  a->commitVertices();
  EXPECT_EQ(a->identity(), id) << "every change of the mesh keeps its identity";
  const void* at = &*a;
  a.emplace(sphere);  // a new mesh at the freed mesh's address
  ASSERT_EQ(static_cast<const void*>(&*a), at);
  EXPECT_NE(a->identity(), id);
  EXPECT_NE(a->identity(), b.identity());
  const auto id_a = a->identity(), id_b = b.identity();
  HashedMesh<double> c(std::move(*a));
  EXPECT_EQ(c.identity(), id_a) << "moved with the mesh";
  b = std::move(c);
  EXPECT_EQ(b.identity(), id_a) << "moved with the mesh into another object";
  EXPECT_NE(b.identity(), id_b);
}

// commitVertices: the positions written into vertexWriteBuffer() become the mesh's without a copy
// (the two buffers trade places, so the mesh's buffer alternates between two addresses), with
// the same version rules and bounds as updateVertices, and every query answers for them as for
// a mesh built from those positions (frames of a cloth over a sphere, self and inter, brute force
// as the reference). updateVertices after a commit copies into the current buffer, as always.
TEST(HashedMesh, CommittedVerticesBecomeTheMeshsWithoutACopy) {
  auto frame = [](double t) { return makeDrapedCloth<double>(24, 4.0, 1.0, 0.03, t); };
  const TriangleMesh<double> ball = makeSphere<double>({0, 0, 0}, 1.0, 16, 8);
  HashedMesh<double> cloth(frame(0.2)), sphere(ball);
  const auto t0 = cloth.topologyVersion();
  EXPECT_EQ(cloth.numVertices(), frame(0.2).vertices.size());
  const Vec3<double>* first = cloth.mesh().vertices.data();
  const Vec3<double>* second = nullptr;
  int frames_with_pairs = 0;
  for (int f = 1; f <= 5; ++f) {
    const TriangleMesh<double> want = frame(0.2 + 0.15 * f);
    Vec3<double>* w = cloth.vertexWriteBuffer();
    ASSERT_NE(w, cloth.mesh().vertices.data());
    if (f == 1) second = w;
    EXPECT_EQ(w, f % 2 ? second : first) << f;  // the two buffers alternate
    std::copy(want.vertices.begin(), want.vertices.end(), w);
    const auto v0 = cloth.version();
    cloth.commitVertices();
    EXPECT_EQ(cloth.mesh().vertices.data(), w) << f;  // no copy: the written buffer is the mesh's
    EXPECT_EQ(cloth.mesh().vertices, want.vertices) << f;
    EXPECT_GT(cloth.version(), v0);
    EXPECT_EQ(cloth.topologyVersion(), t0);
    EXPECT_FALSE(cloth.cpuHashFresh());
    const detail::Aabb<double> b = cloth.localBounds();
    const detail::Aabb<double> fresh = HashedMesh<double>(want).localBounds();
    EXPECT_EQ(b.lo.x, fresh.lo.x);
    EXPECT_EQ(b.hi.z, fresh.hi.z);
    const auto self = kdet_test::sorted(intersectSelf(cloth).pairs);
    const auto inter = kdet_test::sorted(intersectMeshes(cloth, sphere).pairs);
    EXPECT_EQ(self, kdet_test::sorted(bruteForceIntersectSelf(want))) << f;
    EXPECT_EQ(inter, kdet_test::sorted(bruteForceIntersectMeshes(want, {}, ball, {}))) << f;
    frames_with_pairs += !self.empty() && !inter.empty();
  }
  EXPECT_GT(frames_with_pairs, 0);  // the frames test something
  // updateVertices copies into the current buffer and keeps it; the next write buffer is the other.
  const Vec3<double>* current = cloth.mesh().vertices.data();
  cloth.updateVertices(frame(0.3).vertices);
  EXPECT_EQ(cloth.mesh().vertices.data(), current);
  EXPECT_EQ(cloth.mesh().vertices, frame(0.3).vertices);
  EXPECT_NE(cloth.vertexWriteBuffer(), current);
  // A move takes both buffers along.
  HashedMesh<double> moved(std::move(cloth));
  EXPECT_EQ(moved.mesh().vertices.data(), current);
  const TriangleMesh<double> last = frame(0.4);
  Vec3<double>* w = moved.vertexWriteBuffer();
  std::copy(last.vertices.begin(), last.vertices.end(), w);
  moved.commitVertices();
  EXPECT_EQ(moved.mesh().vertices, last.vertices);
  EXPECT_EQ(kdet_test::sorted(intersectSelf(moved).pairs),
            kdet_test::sorted(bruteForceIntersectSelf(last)));
}

// The registration of the vertex buffer (detail::HostPin, made by the CUDA backend for direct
// device copies) lives exactly as long as that buffer: updateVertices keeps it (same buffer),
// setMesh, move assignment and the destructor drop it before the buffer goes, and a move takes
// it along with the buffer. Each fake registration's release reads the first vertex through the
// registered address: under AddressSanitizer (the sanitize step of CI) a release after the
// buffer was freed is a use-after-free.
TEST(HashedMesh, AVertexBufferRegistrationLivesExactlyAsLongAsTheBuffer) {
  int released = 0;
  auto pin = [&](const HashedMesh<double>& h) {
    const Vec3<double>* at = h.mesh().vertices.data();
    const Vec3<double> first = at[0];
    auto release = [&released, first](void* p) {
      EXPECT_EQ(*static_cast<const Vec3<double>*>(p), first) << "released after a change";
      ++released;
    };
    h.hostPin().set(at, std::shared_ptr<void>(const_cast<Vec3<double>*>(at), release));
  };
  const TriangleMesh<double> sphere = makeSphere<double>({0, 0, 0}, 1.0, 16, 8);
  {
    HashedMesh<double> h(sphere);
    EXPECT_EQ(h.hostPin().at(), nullptr);
    pin(h);
    EXPECT_TRUE(h.hostPin().pinned());
    std::vector<Vec3<double>> moved = sphere.vertices;
    for (auto& p : moved) p.x += 0.5;
    moved[0] = sphere.vertices[0];  // the release checks the first vertex
    h.updateVertices(moved);  // same buffer: kept
    EXPECT_EQ(released, 0);
    EXPECT_EQ(h.hostPin().at(), h.mesh().vertices.data());
    EXPECT_THROW(h.updateVertices({{0, 0, 0}}), InvalidInputError);  // refused: kept
    EXPECT_EQ(released, 0);
    h.setMesh(makeSphere<double>({0, 0, 0}, 2.0, 8, 4));  // new buffer: dropped first
    EXPECT_EQ(released, 1);
    EXPECT_EQ(h.hostPin().at(), nullptr);
    EXPECT_FALSE(h.hostPin().pinned());
    pin(h);
    HashedMesh<double> g(std::move(h));  // the buffer and its registration move together
    EXPECT_EQ(released, 1);
    EXPECT_EQ(g.hostPin().at(), g.mesh().vertices.data());
    EXPECT_EQ(h.hostPin().at(), nullptr);
    HashedMesh<double> k(sphere);
    pin(k);
    k = std::move(g);  // k's own buffer is freed: its registration goes first
    EXPECT_EQ(released, 2);
    EXPECT_EQ(k.hostPin().at(), k.mesh().vertices.data());
    EXPECT_TRUE(k.hostPin().pinned());
    // A first upload is a record without a registration; a failed registration is a tried
    // record without a handle: nothing to release for either.
    HashedMesh<double> f(sphere);
    f.hostPin().see(f.mesh().vertices.data());
    EXPECT_EQ(f.hostPin().at(), f.mesh().vertices.data());
    EXPECT_FALSE(f.hostPin().tried());
    EXPECT_FALSE(f.hostPin().pinned());
    f.hostPin().set(f.mesh().vertices.data(), nullptr);
    EXPECT_TRUE(f.hostPin().tried());
    EXPECT_FALSE(f.hostPin().pinned());
    EXPECT_EQ(f.hostPin().at(), f.mesh().vertices.data());
  }  // k's destructor drops the last registration before its buffer goes
  EXPECT_EQ(released, 3);
  // commitVertices: each buffer's registration moves with it, so the mesh's record is always its
  // current buffer's; setMesh and the destructor drop both before the buffers go.
  {
    std::vector<Vec3<double>> moved = sphere.vertices;
    for (auto& p : moved) p.y += 0.5;
    moved[0] = sphere.vertices[0];  // the release checks the first vertex
    HashedMesh<double> c(sphere);
    const Vec3<double>* a = c.mesh().vertices.data();
    pin(c);
    Vec3<double>* b = c.vertexWriteBuffer();
    std::copy(moved.begin(), moved.end(), b);
    c.commitVertices();  // now b is current, a the write buffer: a's record went with it
    EXPECT_EQ(released, 3);
    EXPECT_EQ(c.hostPin().at(), nullptr);  // b has none yet
    pin(c);
    EXPECT_EQ(c.hostPin().at(), b);
    std::copy(sphere.vertices.begin(), sphere.vertices.end(), c.vertexWriteBuffer());
    c.commitVertices();  // back to a, with its own record
    EXPECT_EQ(c.mesh().vertices.data(), a);
    EXPECT_EQ(c.hostPin().at(), a);
    EXPECT_TRUE(c.hostPin().pinned());
    EXPECT_EQ(released, 3);
    EXPECT_THROW(c.updateVertices({{0, 0, 0}}), InvalidInputError);  // refused: both kept
    EXPECT_EQ(released, 3);
    HashedMesh<double> d(std::move(c));  // both buffers and both records move together
    EXPECT_EQ(released, 3);
    d.setMesh(makeSphere<double>({0, 0, 0}, 2.0, 8, 4));  // both buffers go: both dropped first
    EXPECT_EQ(released, 5);
    EXPECT_EQ(d.hostPin().at(), nullptr);
    EXPECT_THROW(d.commitVertices(), InvalidInputError);  // the write buffer went too
    pin(d);
    std::copy(d.mesh().vertices.begin(), d.mesh().vertices.end(), d.vertexWriteBuffer());
    d.commitVertices();
    pin(d);
  }  // d's destructor drops both records before its buffers go
  EXPECT_EQ(released, 7);
}

TEST(HashedMesh, PoseChangesDoNotRehashDeformationsDo) {
  HashedMesh<double> hm(makeSphere<double>({0, 0, 0}, 1.0, 16, 8));
  const auto v0 = hm.version();
  const auto* entries = hm.hash().entriesOf(0);
  hm.setPose(makeTransform<double>({0, 1, 0}, 0.5, {1, 2, 3}));
  EXPECT_EQ(hm.version(), v0);
  EXPECT_EQ(hm.hash().entriesOf(0), entries);  // the same table, untouched
  auto v = hm.mesh().vertices;
  for (auto& p : v) p.x *= 2;
  hm.updateVertices(v);
  EXPECT_GT(hm.version(), v0);
  HashedMesh<double> other(hm.mesh());
  EXPECT_NE(other.version(), hm.version());  // versions are unique in the process
  EXPECT_DOUBLE_EQ(hm.hash().bounds.hi.x, 2.0);
}

namespace {

/// The whole layout of a hierarchy: every entry in table order, and every cell's slot.
template <class S>
void expectSameLayout(const detail::HierarchicalHash<S>& a, const detail::HierarchicalHash<S>& b) {
  ASSERT_EQ(a.numEntries(), b.numEntries());
  for (std::size_t i = 0; i < a.numTriangles(); ++i) {
    ASSERT_EQ(a.level[i], b.level[i]);
    const detail::CellRange r = detail::cellRange(a.boxes[i], a.level[i], a.grid);
    for (auto x = r.lo[0]; x <= r.hi[0]; ++x)
      for (auto y = r.lo[1]; y <= r.hi[1]; ++y)
        for (auto z = r.lo[2]; z <= r.hi[2]; ++z) {
          const detail::CellKey key = detail::makeCellKey(a.level[i], x, y, z);
          const auto *sa = a.find(key), *sb = b.find(key);
          ASSERT_TRUE(sa && sb);
          EXPECT_EQ(sa->begin, sb->begin);
          ASSERT_EQ(sa->count, sb->count);
          // The cell's entries, in table order.
          const auto* ea = a.entriesOf(a.level[i]) + sa->begin;
          const auto* eb = b.entriesOf(b.level[i]) + sb->begin;
          for (std::uint32_t k = 0; k < sa->count; ++k) {
            ASSERT_EQ(ea[k].id, eb[k].id) << k;
            ASSERT_EQ(ea[k].lo_mask, eb[k].lo_mask) << k;
            ASSERT_EQ(std::memcmp(&ea[k].box, &eb[k].box, sizeof ea[k].box), 0);
          }
        }
  }
  EXPECT_EQ(a.stats().cells, b.stats().cells);
  EXPECT_EQ(a.stats().max_cell_load, b.stats().max_cell_load);
}

}  // namespace

TEST(Hierarchy, LayoutDoesNotDependOnTheThreadCount) {
  const auto cloth = makeDrapedCloth<double>(120, 4.0, 1.0, 0.02, 1.0);
  const auto soup = makeRandomSoup<double>(20000, 10.0, 0.001, 3.0, 5);
  for (const auto* m : {&cloth, &soup}) {
    detail::HierarchicalHash<double> one, many;
    one.build(*m, 1);
    for (int threads : {2, 3, 7}) {
      many.build(*m, threads);  // rebuilt in place: also exercises the reused buffers
      expectSameLayout(one, many);
    }
  }
}

TEST(Hierarchy, CrowdedCellsStayOrderedAndFindable) {
  // Hundreds of triangles in the same few cells (a fan around one point, sizes repeating so that
  // diameter ties are decided by id), plus a few far away: long runs per cell and big buckets.
  TriangleMesh<double> m;
  for (int i = 0; i < 600; ++i) {
    const double a = 0.01 * i, s = 1.0 + 0.25 * (i % 4);
    m.addTriangle({0, 0, 0}, {s * std::cos(a), s * std::sin(a), 0.0},
                  {s * std::cos(a + 0.5), s * std::sin(a + 0.5), 0.1});
  }
  for (int i = 0; i < 20; ++i) m.addTriangle({50.0 + i, 0, 0}, {51.0 + i, 0, 0}, {50.0 + i, 1, 0});
  HashedMesh<double> hm(m, Transform<double>::identity(), 2);
  expectEveryTriangleInItsCells(hm);
  EXPECT_GE(hm.stats().max_cell_load, 100u);
  EXPECT_EQ(kdet_test::sorted(intersectSelf(hm).pairs), bruteForceIntersectSelf(m));
  // Cells that hold nothing are not found, wherever they hash.
  const auto& h = hm.hash();
  for (std::int64_t x = 0; x < 200; ++x)
    EXPECT_EQ(h.find(detail::makeCellKey(h.top_level, 1000 + x, 7, 3)), nullptr);
}

TEST(HashedMesh, RehashIsLazyAndCorrectAfterUpdates) {
  const auto m0 = makeDrapedCloth<double>(40, 4.0, 1.0, 0.05, 0.4);
  HashedMesh<double> cloth(m0, Transform<double>::identity(), 2);
  HashedMesh<double> sphere(makeSphere<double>({0, 0, 0}, 1.0, 24, 12));
  EXPECT_FALSE(cloth.cpuHashFresh());  // nothing built until a query needs it
  const auto b0 = cloth.localBounds();
  EXPECT_LE(b0.lo.z, b0.hi.z);
  for (double t : {0.6, 0.8, 1.0}) {
    const auto mt = makeDrapedCloth<double>(40, 4.0, 1.0, 0.05, t);
    const auto v0 = cloth.version();
    cloth.updateVertices(mt.vertices);
    EXPECT_GT(cloth.version(), v0);
    EXPECT_FALSE(cloth.cpuHashFresh());
    // The bounds are current without a re-hash.
    double lo_z = mt.vertices[0].z;
    for (const auto& p : mt.vertices) lo_z = std::min(lo_z, p.z);
    EXPECT_EQ(cloth.localBounds().lo.z, lo_z);
    EXPECT_FALSE(cloth.cpuHashFresh());
    const auto self = kdet_test::sorted(intersectSelf(cloth).pairs);
    EXPECT_TRUE(cloth.cpuHashFresh());
    EXPECT_EQ(self, bruteForceIntersectSelf(mt));
    EXPECT_EQ(kdet_test::sorted(intersectMeshes(cloth, sphere).pairs),
              bruteForceIntersectMeshes(mt, cloth.pose(), sphere.mesh(), sphere.pose()));
    expectEveryTriangleInItsCells(cloth);
    EXPECT_DOUBLE_EQ(cloth.hash().bounds.lo.z, lo_z);
  }
  // A topology change, then stats() (which builds what it describes).
  cloth.setMesh(makeRandomSoup<double>(500, 2.0, 0.01, 0.5, 3));
  EXPECT_FALSE(cloth.cpuHashFresh());
  const HierarchyStats st = cloth.stats();
  EXPECT_TRUE(cloth.cpuHashFresh());
  EXPECT_EQ(st.triangles, 500u);
  EXPECT_GE(st.entries, 500u);
  EXPECT_LE(st.entries, 8 * 500u);
  EXPECT_GE(st.cells, 1u);
  EXPECT_LE(st.cells, st.entries);
  EXPECT_GE(st.max_cell_load, 1u);
  EXPECT_GT(st.memory_bytes, st.entries * sizeof(detail::HierarchicalHash<double>::Entry));
  cloth.prepareCpuHash();  // fresh already: nothing to do
  EXPECT_TRUE(cloth.cpuHashFresh());
}

// An inter-object query builds only the cell tables of the levels its lookups visit: a fine
// cloth against a coarse sphere needs the cloth's cells from the level of the sphere's smallest
// triangle up. A later query that needs more (a self query) adds the missing levels as a second
// table. Every answer equals brute force, in either argument order, in every state.
TEST(HashedMesh, InterQueriesBuildOnlyTheLevelsTheirLookupsVisit) {
  using Hash = detail::HierarchicalHash<double>;
  const auto sphere_mesh = makeSphere<double>({0, 0, 0}, 1.0, 16, 8);  // coarse
  HashedMesh<double> sphere(sphere_mesh);
  const auto full = HashedMesh<double>(makeDrapedCloth<double>(60, 4.0, 1.0, 0.05, 1.0)).stats();
  HashedMesh<double> cloth(makeDrapedCloth<double>(60, 4.0, 1.0, 0.05, 0.3));
  for (int order = 0; order < 2; ++order) {
    const auto mt = makeDrapedCloth<double>(60, 4.0, 1.0, 0.05, 1.0);
    cloth.updateVertices(makeDrapedCloth<double>(60, 4.0, 1.0, 0.05, 0.5).vertices);
    cloth.updateVertices(mt.vertices);
    const auto want_inter = bruteForceIntersectMeshes(mt, cloth.pose(), sphere_mesh, sphere.pose());
    ASSERT_FALSE(want_inter.empty());
    std::vector<TrianglePair> inter;
    if (order == 0) {
      inter = kdet_test::sorted(intersectMeshes(cloth, sphere).pairs);
    } else {
      for (const TrianglePair& p : intersectMeshes(sphere, cloth).pairs)
        inter.push_back({p.b, p.a});
      inter = kdet_test::sorted(std::move(inter));
    }
    EXPECT_EQ(inter, want_inter) << "order " << order;
    // Only the upper levels of the cloth: its smallest triangles are below the sphere's.
    const Hash& h = cloth.hashFrom(Hash::kNoTable);  // (builds nothing more)
    EXPECT_FALSE(cloth.cpuHashFresh());
    EXPECT_GT(h.coveredFrom(), 0);
    EXPECT_LE(h.coveredFrom(), h.top_level);
    EXPECT_EQ(h.coveredFrom(), detail::levelFor(sphere.hash().d_smallest, h.grid));
    std::size_t upper_entries = 0;
    for (std::size_t i = 0; i < cloth.numTriangles(); ++i)
      if (h.level[i] >= h.coveredFrom())
        upper_entries += std::size_t(detail::cellRange(h.boxes[i], h.level[i], h.grid).count());
    EXPECT_EQ(h.numEntries(), upper_entries);
    EXPECT_LT(2 * h.numEntries(), full.entries) << "most of the cloth is finer than the sphere";
    // The same answer again (fast path), then a self query adds the lower levels.
    EXPECT_EQ(kdet_test::sorted(intersectMeshes(cloth, sphere).pairs), want_inter);
    EXPECT_EQ(kdet_test::sorted(intersectSelf(cloth).pairs), bruteForceIntersectSelf(mt));
    EXPECT_TRUE(cloth.cpuHashFresh());
    EXPECT_EQ(h.coveredFrom(), 0);
    expectEveryTriangleInItsCells(cloth);  // both tables: every cell complete, nothing else
    EXPECT_EQ(cloth.stats().entries, full.entries);
    EXPECT_EQ(cloth.stats().cells, full.cells);
    EXPECT_EQ(kdet_test::sorted(intersectMeshes(cloth, sphere).pairs), want_inter);
  }
  // No lookup at all into a mesh whose triangles are all smaller than the other's smallest: no
  // table is built for it (and the answer is still complete).
  HashedMesh<double> tiny(makeSphere<double>({0, 0, 1}, 0.05, 32, 16));  // on the sphere's top
  const auto want = bruteForceIntersectMeshes(tiny.mesh(), tiny.pose(), sphere_mesh, sphere.pose());
  ASSERT_FALSE(want.empty());
  EXPECT_EQ(kdet_test::sorted(intersectMeshes(tiny, sphere).pairs), want);
  const Hash& ht = tiny.hashFrom(Hash::kNoTable);
  ASSERT_LT(ht.d_max, sphere.hash().d_smallest);
  EXPECT_EQ(ht.coveredFrom(), Hash::kNoTable);
  EXPECT_EQ(ht.numEntries(), 0u);
}

TEST(HashedMesh, ConcurrentQueriesRightAfterAnUpdate) {
  // Two threads query the same stale mesh at once: one rebuilds, the other waits; both must see
  // the complete new hash. Repeated over several deformations.
  const auto sphere_mesh = makeSphere<double>({0, 0, 0}, 1.0, 24, 12);
  HashedMesh<double> sphere(sphere_mesh);
  HashedMesh<double> cloth(makeDrapedCloth<double>(36, 4.0, 1.0, 0.05, 0.3),
                           Transform<double>::identity(), 2);
  for (double t : {0.5, 0.7, 0.85, 1.0}) {
    const auto mt = makeDrapedCloth<double>(36, 4.0, 1.0, 0.05, t);
    const auto want_self = bruteForceIntersectSelf(mt);
    const auto want_inter =
        bruteForceIntersectMeshes(mt, cloth.pose(), sphere_mesh, sphere.pose());
    cloth.updateVertices(mt.vertices);
    std::vector<TrianglePair> self[2], inter[2];
    auto work = [&](int k) {
      QueryOptions q;
      q.threads = 1 + k;
      if (k == 0) {
        self[k] = kdet_test::sorted(intersectSelf(cloth, q).pairs);
        inter[k] = kdet_test::sorted(intersectMeshes(cloth, sphere, q).pairs);
      } else {
        inter[k] = kdet_test::sorted(intersectMeshes(sphere, cloth, q).pairs);
        self[k] = kdet_test::sorted(intersectSelf(cloth, q).pairs);
        for (auto& p : inter[k]) std::swap(p.a, p.b);
        inter[k] = kdet_test::sorted(std::move(inter[k]));
      }
    };
    std::thread other(work, 1);
    work(0);
    other.join();
    for (int k = 0; k < 2; ++k) {
      EXPECT_EQ(self[k], want_self) << "t " << t << " thread " << k;
      EXPECT_EQ(inter[k], want_inter) << "t " << t << " thread " << k;
    }
  }
}

#if defined(__linux__)
namespace {

// A forked child with a limited address space (as in test_bad_input.cpp): its exit code says how
// the allocation failure surfaced.
enum LazyOomResult : int {
  kFailedCleanly = 0,  // bad_alloc from the query, then the mesh answered correctly
  kSucceeded = 12,     // the limit was generous enough
  kWrong = 13,         // a wrong answer, before or after the failure
  kOther = 11,         // any other exception
};

/// Runs child(headroom) in a fresh forked child per run, under address-space limits growing in
/// 512 KiB steps (the child sets the limit where the allocations under test begin), until a run
/// succeeds or the headroom passes 64 MiB, so that the failure hits those allocations one after
/// another. Every run must end cleanly (kFailedCleanly or kSucceeded) and the last one succeed.
/// Skips when the limit never bit.
void expectCleanFailuresUnderGrowingLimits(const char* what,
                                           const std::function<int(std::size_t)>& child) {
  int failures = 0, successes = 0, wrong = 0, signals = 0;
  for (std::size_t headroom = 0; headroom <= (64u << 20) && successes == 0;
       headroom += 512u << 10) {
    ::malloc_trim(0);
    const int rc = kdet_test::runInChild([&] { return child(headroom); }, kOther);
    failures += rc == kFailedCleanly;
    successes += rc == kSucceeded;
    wrong += rc == kWrong || rc == kOther;
    signals += rc < 0;
  }
  std::printf("%s under growing memory limits: %d clean failures, %d wrong, %d killed by a "
              "signal, then success: %d\n",
              what, failures, wrong, signals, successes);
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(signals, 0);
  EXPECT_EQ(successes, 1);
  // Run alone (as ctest runs every test), the limit bites. After other tests in the same process,
  // free heap they left can serve the allocations without new address space.
  if (failures == 0) GTEST_SKIP() << "the limit never bit (free heap left by earlier tests?)";
}


}  // namespace

/// The CPU hash is rebuilt lazily, by the first query after a geometry change: an allocation
/// failure there (std::bad_alloc) propagates from the query, and the HashedMesh stays valid: it
/// holds the new geometry, its hash stays stale, and the next query (with memory) rebuilds and
/// answers correctly. Run under address-space limits growing in 512 KiB steps, each in a fresh
/// child, so that the failure hits the allocations of the rebuild one after another.
TEST(HashedMesh, AFailedLazyRebuildThrowsFromTheQueryAndKeepsTheMeshUsable) {
  if (kdet_test::kSanitized) GTEST_SKIP() << "RLIMIT_AS and AddressSanitizer do not mix";
  ::mallopt(M_MMAP_THRESHOLD, 64 * 1024);  // large blocks from mmap, so that the limit bites
  const TriangleMesh<double> small = makeDrapedCloth<double>(10, 4.0, 1.0, 0.03, 1.0);
  const TriangleMesh<double> big = makeRandomSoup<double>(40000, 6.0, 0.01, 0.3, 3);
  QueryOptions one;
  one.threads = 1;  // no thread stacks to allocate under the limit
  HashedMesh<double> reference(big, Transform<double>::identity(), 1);
  const auto want = kdet_test::sorted(intersectSelf(reference, one).pairs);
  ASSERT_FALSE(want.empty());
  HashedMesh<double> h(small, Transform<double>::identity(), 1);
  ASSERT_FALSE(intersectSelf(h, one).pairs.empty());  // built for the small mesh
  expectCleanFailuresUnderGrowingLimits("lazy rebuild", [&](std::size_t headroom) {
    h.setMesh(big);  // validates and stores: the re-hash waits for a query
    if (h.cpuHashFresh()) return int(kWrong);
    kdet_test::limitAddressSpace(headroom);
    try {
      const bool same = kdet_test::sorted(intersectSelf(h, one).pairs) == want;
      return int(same ? kSucceeded : kWrong);
    } catch (const std::bad_alloc&) {
      kdet_test::unlimitAddressSpace();
      // (The failure may also have come after the rebuild, from the query's own output.)
      const bool same = h.numTriangles() == big.triangles.size() &&
                        kdet_test::sorted(intersectSelf(h, one).pairs) == want &&
                        h.cpuHashFresh();
      return int(same ? kFailedCleanly : kWrong);
    }
  });
}

/// The same for the second table: an inter query built the upper levels of a mesh (before the
/// limit), then a self query must add the lower ones under the limit. A failure there propagates
/// from the self query and leaves the first table as it was: the inter query still answers from
/// it, and the next self query (with memory) completes the hash.
TEST(HashedMesh, AFailedTableExtensionThrowsFromTheQueryAndKeepsTheFirstTable) {
  if (kdet_test::kSanitized) GTEST_SKIP() << "RLIMIT_AS and AddressSanitizer do not mix";
  using Hash = detail::HierarchicalHash<double>;
  ::mallopt(M_MMAP_THRESHOLD, 64 * 1024);
  const TriangleMesh<double> big = makeRandomSoup<double>(40000, 6.0, 0.01, 0.3, 3);
  QueryOptions one;
  one.threads = 1;
  HashedMesh<double> probe(makeSphere<double>({3, 3, 3}, 1.5, 60, 30),
                           Transform<double>::identity(), 1);
  HashedMesh<double> reference(big, Transform<double>::identity(), 1);
  const auto want_self = kdet_test::sorted(intersectSelf(reference, one).pairs);
  const auto want_inter = kdet_test::sorted(intersectMeshes(reference, probe, one).pairs);
  ASSERT_FALSE(want_self.empty());
  ASSERT_FALSE(want_inter.empty());
  expectCleanFailuresUnderGrowingLimits("table extension", [&](std::size_t headroom) {
    HashedMesh<double> h(big, Transform<double>::identity(), 1);
    if (kdet_test::sorted(intersectMeshes(h, probe, one).pairs) != want_inter) return int(kWrong);
    const int from = h.hashFrom(Hash::kNoTable).coveredFrom();
    if (from <= 0 || from == Hash::kNoTable) return int(kWrong);  // not the case under test
    kdet_test::limitAddressSpace(headroom);
    try {
      const bool same = kdet_test::sorted(intersectSelf(h, one).pairs) == want_self;
      return int(same ? kSucceeded : kWrong);
    } catch (const std::bad_alloc&) {
      kdet_test::unlimitAddressSpace();
      // Either the extension failed (the first table is kept) or the query's own output did
      // (after a complete extension).
      const int after = h.hashFrom(Hash::kNoTable).coveredFrom();
      const bool kept = after == from || (after == 0 && h.cpuHashFresh());
      const bool same = kept &&
                        kdet_test::sorted(intersectMeshes(h, probe, one).pairs) == want_inter &&
                        kdet_test::sorted(intersectSelf(h, one).pairs) == want_self &&
                        h.cpuHashFresh();
      return int(same ? kFailedCleanly : kWrong);
    }
  });
}
#endif
