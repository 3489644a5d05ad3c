// The hierarchical hash itself, and HashedMesh's life cycle (poses, deformation, topology
// changes, bad input).

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "cpu/hierarchical_hash.h"
#include "test_util.h"

using namespace kdet_fcl;

namespace {

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
          bool found = false;
          for (std::uint32_t k = 0; k < s->count; ++k) found |= h.entries[s->begin + k].id == i;
          EXPECT_TRUE(found) << "triangle " << i;
        }
  }
  std::size_t expected_entries = 0;
  for (std::size_t i = 0; i < hm.numTriangles(); ++i)
    expected_entries += std::size_t(detail::cellRange(h.boxes[i], h.level[i], h.grid).count());
  EXPECT_EQ(h.entries.size(), expected_entries);  // and nothing else
}

}  // namespace

TEST(Hierarchy, EveryTriangleIsInExactlyTheCellsItsBoxCovers) {
  HashedMesh<double> cloth(makeDrapedCloth<double>(30, 4.0, 1.0, 0.02, 1.0));
  expectEveryTriangleInItsCells(cloth);
  HashedMesh<float> soup(makeRandomSoup<float>(3000, 10.f, 0.001f, 3.f, 9));
  expectEveryTriangleInItsCells(soup);
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
  // The current hash, the spare a rebuild writes into, and the build scratch (kept so a deforming
  // mesh rebuilds without allocating): a few hundred bytes per triangle, independent of n.
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

TEST(HashedMesh, PoseChangesDoNotRehashDeformationsDo) {
  HashedMesh<double> hm(makeSphere<double>({0, 0, 0}, 1.0, 16, 8));
  const auto v0 = hm.version();
  const auto* entries = hm.hash().entries.data();
  hm.setPose(makeTransform<double>({0, 1, 0}, 0.5, {1, 2, 3}));
  EXPECT_EQ(hm.version(), v0);
  EXPECT_EQ(hm.hash().entries.data(), entries);  // the same table, untouched
  auto v = hm.mesh().vertices;
  for (auto& p : v) p.x *= 2;
  hm.updateVertices(v);
  EXPECT_GT(hm.version(), v0);
  HashedMesh<double> other(hm.mesh());
  EXPECT_NE(other.version(), hm.version());  // versions are unique in the process
  EXPECT_DOUBLE_EQ(hm.hash().bounds.hi.x, 2.0);
}
