// Unit tests of the algorithm pieces: enclosing sphere, level rule, cell coverage, cell keys.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "kdet_fcl/detail/enclosing_sphere.h"
#include "kdet_fcl/detail/hierarchy.h"
#include "kdet_fcl/detail/pose.h"
#include "test_util.h"

using namespace kdet_fcl;
using namespace kdet_fcl::detail;

TEST(EnclosingSphere, EquilateralIsCircumdiameter) {
  const double s = 2.0;
  const Vec3<double> a{0, 0, 0}, b{s, 0, 0}, c{s / 2, s * std::sqrt(3.0) / 2, 0};
  EXPECT_NEAR(enclosingDiameter(a, b, c), 2 * s / std::sqrt(3.0), 1e-12);
}

TEST(EnclosingSphere, ObtuseIsLongestEdge) {
  const Vec3<double> a{0, 0, 0}, b{10, 0, 0}, c{5, 1, 0};  // angle at c is obtuse
  EXPECT_DOUBLE_EQ(enclosingDiameter(a, b, c), 10.0);
}

TEST(EnclosingSphere, RightTriangleIsHypotenuse) {
  const Vec3<double> a{0, 0, 0}, b{3, 0, 0}, c{0, 4, 0};
  EXPECT_DOUBLE_EQ(enclosingDiameter(a, b, c), 5.0);
}

TEST(EnclosingSphere, SliverStaysBounded) {
  // A sliver's circumcircle is huge; the enclosing sphere is its longest edge.
  const Vec3<double> a{0, 0, 0}, b{1, 0, 0}, c{0.5, 1e-9, 0};
  EXPECT_DOUBLE_EQ(enclosingDiameter(a, b, c), 1.0);
}

TEST(EnclosingSphere, DegenerateTriangles) {
  const Vec3<double> a{1, 1, 1};
  EXPECT_EQ(enclosingDiameter(a, a, a), 0.0);                              // a point
  EXPECT_DOUBLE_EQ(enclosingDiameter(a, a, Vec3<double>{1, 1, 4}), 3.0);   // repeated vertex
  EXPECT_DOUBLE_EQ(enclosingDiameter(Vec3<double>{0, 0, 0}, Vec3<double>{2, 0, 0},
                                     Vec3<double>{7, 0, 0}),
                   7.0);  // collinear
}

TEST(EnclosingSphere, ContainsTheTriangleAndIsMinimalOnRandomTriangles) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 2000; ++k) {
    const Vec3<double> p[3] = {{u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)},
                               {u(rng), u(rng), u(rng)}};
    const double d = enclosingDiameter(p[0], p[1], p[2]);
    double longest = 0;
    for (int i = 0; i < 3; ++i)
      longest = std::max(longest, std::sqrt(squaredNorm(p[i] - p[(i + 1) % 3])));
    EXPECT_GE(d, longest * (1 - 1e-12));               // never smaller than the longest edge
    EXPECT_LE(d, longest * 2 / std::sqrt(3.0) + 1e-12); // never above the equilateral bound
  }
}

TEST(LevelRule, CellIsAtLeastTheDiameterAndLessThanTwice) {
  GridParams g;
  g.cell0 = 0.25;
  g.inv_cell0 = 4;
  g.num_levels = 30;
  for (double d : {0.0, 0.1, 0.25, 0.2500001, 0.5, 0.7, 1.0, 3.0, 1000.0}) {
    const int l = levelFor(d, g);
    const double cell = g.cell0 * std::ldexp(1.0, l);
    EXPECT_GE(cell, d) << d;
    if (l > 0) EXPECT_LT(cell / 2, d) << d;  // the finest such level
  }
  EXPECT_EQ(levelFor(0.25, g), 0);
  EXPECT_EQ(levelFor(0.5, g), 1);
  EXPECT_EQ(levelFor(0.5000001, g), 2);
}

TEST(LevelRule, MonotoneAndClampedToTop) {
  GridParams g;
  g.cell0 = 1e-3;
  g.inv_cell0 = 1e3;
  g.num_levels = 5;
  int prev = 0;
  for (double d = 0; d < 100; d = d * 1.01 + 1e-6) {
    const int l = levelFor(d, g);
    EXPECT_GE(l, prev);
    EXPECT_LE(l, 4);
    prev = l;
  }
  EXPECT_EQ(prev, 4);
}

TEST(CellCoverage, BoxNoLargerThanCellTouchesAtMostTwoCellsPerAxis) {
  GridParams g;
  g.cell0 = 0.1;
  g.inv_cell0 = 10;
  g.num_levels = 10;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 50);
  std::uniform_real_distribution<double> s(0, 1);
  for (int k = 0; k < 5000; ++k) {
    const double d = 0.1 * std::ldexp(1.0, int(s(rng) * 8)) * (0.5 + 0.5 * s(rng));
    const int l = levelFor(d, g);
    const double x = u(rng), y = u(rng), z = u(rng);
    const Aabb<double> b{{x, y, z}, {x + d * s(rng), y + d * s(rng), z + d}};
    const CellRange r = cellRange(b, l, g);
    EXPECT_LE(r.count(), 8);
    EXPECT_GE(r.count(), 1);
  }
}

TEST(CellCoverage, CellCoordIsMonotoneAndClamped) {
  GridParams g;
  g.origin[0] = -5;
  g.cell0 = 0.3;
  g.inv_cell0 = 1 / 0.3;
  g.num_levels = 4;
  std::int64_t prev = 0;
  for (double x = -10; x < 10; x += 0.01) {
    const std::int64_t c = cellCoord(x, 0, 2, g);
    EXPECT_GE(c, prev);
    EXPECT_GE(c, 0);
    prev = c;
  }
  EXPECT_EQ(cellCoord(-1e300, 0, 0, g), 0);
  EXPECT_EQ(cellCoord(1e300, 0, 0, g), (std::int64_t(1) << kCellBits) - 1);
}

TEST(CellCoverage, CanonicalCellIsUniqueInTheCommonRange) {
  // For any two overlapping boxes, exactly one cell of the common range is canonical.
  GridParams g;
  g.cell0 = 1;
  g.inv_cell0 = 1;
  g.num_levels = 3;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 3), s(0, 2.5);
  int tested = 0;
  for (int k = 0; k < 3000; ++k) {
    const Vec3<double> p0{u(rng), u(rng), u(rng)}, q0{u(rng), u(rng), u(rng)};
    const Aabb<double> p{p0, {p0.x + s(rng), p0.y + s(rng), p0.z + s(rng)}};
    const Aabb<double> q{q0, {q0.x + s(rng), q0.y + s(rng), q0.z + s(rng)}};
    if (!boxesOverlap(p, q)) continue;
    ++tested;
    const int L = 1;
    const CellRange a = cellRange(p, L, g), b = cellRange(q, L, g);
    int canonical = 0;
    for (std::int64_t x = std::max(a.lo[0], b.lo[0]); x <= std::min(a.hi[0], b.hi[0]); ++x)
      for (std::int64_t y = std::max(a.lo[1], b.lo[1]); y <= std::min(a.hi[1], b.hi[1]); ++y)
        for (std::int64_t z = std::max(a.lo[2], b.lo[2]); z <= std::min(a.hi[2], b.hi[2]); ++z) {
          const bool c = isCanonicalCell(p, q, levelScale(L), g, x, y, z);
          canonical += c ? 1 : 0;
          // The form both backends' lookups use (CPU Entry::lo_mask, GPU entryValue's bits): in
          // the common range, canonical iff on every axis the cell is the first cell of p or q.
          const bool first_cells = (x == a.lo[0] || x == b.lo[0]) && (y == a.lo[1] || y == b.lo[1]) &&
                                   (z == a.lo[2] || z == b.lo[2]);
          EXPECT_EQ(first_cells, c) << x << " " << y << " " << z;
        }
    EXPECT_EQ(canonical, 1);
  }
  EXPECT_GT(tested, 500);
}

TEST(SubcellSpan, PackedTestEqualsTheFieldByFieldComparison) {
  std::mt19937_64 rng(3);
  auto field = [](std::uint32_t s, int k) { return (s >> (5 * k)) & 15u; };
  auto make = [&](std::uint32_t lo[3], std::uint32_t hi[3]) {
    std::uint32_t s = 0;
    for (int a = 0; a < 3; ++a) s |= (lo[a] << (5 * a)) | (hi[a] << (15 + 5 * a));
    return s;
  };
  int overlapping = 0;
  for (int k = 0; k < 200000; ++k) {
    std::uint32_t pl[3], ph[3], ql[3], qh[3];
    for (int a = 0; a < 3; ++a) {  // small ranges, so both outcomes are common
      pl[a] = rng() % 16, ph[a] = std::min<std::uint32_t>(15, pl[a] + rng() % 6);
      ql[a] = rng() % 16, qh[a] = std::min<std::uint32_t>(15, ql[a] + rng() % 6);
    }
    const std::uint32_t p = make(pl, ph), q = make(ql, qh);
    bool want = true;
    for (int a = 0; a < 3; ++a)
      want = want && field(p, a) <= field(q, 3 + a) && field(q, a) <= field(p, 3 + a);
    ASSERT_EQ(subcellSpansOverlap(p, q), want) << std::hex << p << " " << q;
    ASSERT_EQ(subcellSpansOverlap(q, p), want);
    overlapping += want ? 1 : 0;
  }
  EXPECT_GT(overlapping, 5000);
  EXPECT_LT(overlapping, 190000);
}

TEST(SubcellSpan, OverlappingBoxesHaveOverlappingSpansInEveryCommonCell) {
  // A grid whose origin and cell size are not powers of two (rounding in every coordinate),
  // boxes of all sizes up to two cells, touching boxes (a shared face coordinate) included.
  GridParams g;
  g.origin[0] = -0.3, g.origin[1] = 1.7, g.origin[2] = 0.1;
  g.cell0 = 0.37;
  g.inv_cell0 = 1 / g.cell0;
  g.num_levels = 4;
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0, 4), s(0, 1.4);
  int overlapping_cells = 0, separated_cells = 0, separated_rejected = 0;
  for (int k = 0; k < 20000; ++k) {
    const int L = static_cast<int>(rng() % 4);
    const double w = g.cell0 * levelScale(-L);  // cell edge on level L
    const Vec3<double> p0{u(rng), u(rng), u(rng)};
    const Aabb<double> p{p0, {p0.x + w * s(rng), p0.y + w * s(rng), p0.z + w * s(rng)}};
    Vec3<double> q0{p0.x + w * (s(rng) - 0.7), p0.y + w * (s(rng) - 0.7),
                    p0.z + w * (s(rng) - 0.7)};
    Aabb<double> q{q0, {q0.x + w * s(rng), q0.y + w * s(rng), q0.z + w * s(rng)}};
    if (k % 4 == 0) {  // touching along x: q starts exactly where p ends
      q.lo.x = p.hi.x;
      q.hi.x = std::max(q.hi.x, q.lo.x);
    }
    const bool overlap = boxesOverlap(p, q);
    const CellRange a = cellRange(p, L, g), b = cellRange(q, L, g);
    for (std::int64_t x = std::max(a.lo[0], b.lo[0]); x <= std::min(a.hi[0], b.hi[0]); ++x)
      for (std::int64_t y = std::max(a.lo[1], b.lo[1]); y <= std::min(a.hi[1], b.hi[1]); ++y)
        for (std::int64_t z = std::max(a.lo[2], b.lo[2]); z <= std::min(a.hi[2], b.hi[2]); ++z) {
          const std::uint32_t sp = subcellSpan(p, L, x, y, z, g);
          const bool spans = subcellSpansOverlap(sp, subcellSpan(q, L, x, y, z, g));
          // The lookups' form of the query's span: per range, then per cell.
          const unsigned int ends = (x == b.lo[0] ? 1u : 0u) | (y == b.lo[1] ? 2u : 0u) |
                                    (z == b.lo[2] ? 4u : 0u) | (x == b.hi[0] ? 8u : 0u) |
                                    (y == b.hi[1] ? 16u : 0u) | (z == b.hi[2] ? 32u : 0u);
          const std::uint32_t q_cell = subcellSpanInCell(subcellSpanCorners(q, L, b, g), ends);
          EXPECT_EQ(q_cell, subcellSpan(q, L, x, y, z, g));  // equal on this grid
          if (overlap) {
            ++overlapping_cells;
            ASSERT_TRUE(spans) << "level " << L << " cell " << x << " " << y << " " << z;
            ASSERT_TRUE(subcellSpansOverlap(sp, q_cell));
          } else {
            ++separated_cells;
            separated_rejected += spans ? 0 : 1;
          }
        }
  }
  EXPECT_GT(overlapping_cells, 5000);
  // It is a filter worth having: most separated boxes that share a cell are told apart (76 %).
  EXPECT_GT(separated_cells, 2000);
  EXPECT_GT(separated_rejected, separated_cells * 2 / 3)
      << separated_rejected << " of " << separated_cells;
}

TEST(CellKey, DistinctCellsHaveDistinctKeys) {
  std::set<std::tuple<std::uint64_t, std::uint64_t>> seen;
  const std::int64_t big = (std::int64_t(1) << kCellBits) - 1;
  const std::int64_t coords[] = {0, 1, 2, (std::int64_t(1) << 24) - 1, std::int64_t(1) << 24,
                                 big - 1, big};
  int n = 0;
  for (int l : {0, 1, 63})
    for (auto x : coords)
      for (auto y : coords)
        for (auto z : coords) {
          const CellKey k = makeCellKey(l, x, y, z);
          seen.insert({k.hi, k.lo});
          const CellId c = cellOfKey(k);  // and the key gives the cell back
          EXPECT_EQ(c.level, l);
          EXPECT_EQ(c.x, x);
          EXPECT_EQ(c.y, y);
          EXPECT_EQ(c.z, z);
          ++n;
        }
  EXPECT_EQ(seen.size(), std::size_t(n));
}

TEST(CellKey, HashSpreadsNeighbouringCells) {
  std::set<std::uint64_t> buckets;
  for (int x = 0; x < 32; ++x)
    for (int y = 0; y < 32; ++y) buckets.insert(hashCellKey(makeCellKey(0, x, y, 0)) & 4095);
  EXPECT_GT(buckets.size(), 700u);  // 1024 keys into 4096 buckets: few collisions
}

TEST(Pose, RelativePoseMapsAIntoBFrame) {
  std::mt19937_64 rng(5);
  for (int k = 0; k < 50; ++k) {
    const auto pa = kdet_test::randomPose<double>(rng, -10, 10);
    const auto pb = kdet_test::randomPose<double>(rng, -10, 10);
    const RelativePose rp = relativePose(pa, pb);
    const Vec3<double> p{1.5, -2, 0.25};
    const Vec3<double> world = pa.apply(p);
    const Vec3<double> in_b = rp.a_to_b.apply(p);
    const Vec3<double> back = pb.apply(in_b);
    EXPECT_NEAR(back.x, world.x, 1e-12);
    EXPECT_NEAR(back.y, world.y, 1e-12);
    EXPECT_NEAR(back.z, world.z, 1e-12);
    const Vec3<double> again = rp.b_to_a.apply(in_b);
    EXPECT_NEAR(again.x, p.x, 1e-12);
    EXPECT_LT(rp.orthonormal_defect, 1e-14);
    EXPECT_FALSE(rp.identity);
  }
  EXPECT_TRUE(relativePose(Transform<double>(), Transform<double>()).identity);
}

TEST(TestUtil, RandomPoseIsARotation) {
  std::mt19937_64 rng(1);
  const auto T = kdet_test::randomPose<double>(rng, 0, 1);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += T.R[k][i] * T.R[k][j];
      EXPECT_NEAR(s, i == j ? 1 : 0, 1e-12);
    }
  EXPECT_GE(T.t.x, 0);
  EXPECT_LE(T.t.x, 1);
}

TEST(LevelRule, Pow2IsExact) {
  for (int e = -1022; e <= 1023; ++e) EXPECT_EQ(pow2(e), std::ldexp(1.0, e)) << e;
  EXPECT_EQ(levelScale(3), 0.125);
}
