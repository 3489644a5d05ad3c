// The k-free analysis (Definition 3.1) against its direct O(n^2) computation.

#include <gtest/gtest.h>

#include "test_util.h"

using namespace kdet_fcl;

namespace {
void expectSameStats(const KFreeStats& a, const KFreeStats& b) {
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.k, b.k);
  EXPECT_EQ(a.max_count, b.max_count);
  EXPECT_DOUBLE_EQ(a.mean, b.mean);
  EXPECT_DOUBLE_EQ(a.sd, b.sd);
  EXPECT_DOUBLE_EQ(a.adjacent_mean, b.adjacent_mean);
  EXPECT_DOUBLE_EQ(a.adjacent_share, b.adjacent_share);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.counts, b.counts);
}
}  // namespace

TEST(KFree, MatchesDirectComputationOnSmallMeshes) {
  KFreeOptions o;
  o.keep_counts = true;
  const TriangleMesh<double> meshes[] = {
      makeSphere<double>({0, 0, 0}, 1.0, 16, 8), makeDrapedCloth<double>(16, 4.0, 1.0, 0.03, 1.0),
      makeRandomSoup<double>(600, 4.0, 0.05, 2.0, 3)};
  for (const auto& m : meshes) {
    const KFreeStats fast = analyzeKFree(m, o), slow = analyzeKFreeBruteForce(m, o);
    expectSameStats(fast, slow);
    EXPECT_GT(fast.k, 1u);
    EXPECT_EQ(fast.counts.size(), m.triangles.size());
  }
  const auto mf = makeRandomSoup<float>(500, 4.f, 0.05f, 2.f, 5);
  expectSameStats(analyzeKFree(mf, o), analyzeKFreeBruteForce(mf, o));
}

TEST(KFree, KnownSmallCase) {
  // A regular sphere: each triangle's larger neighbours within d/4 are its edge and vertex
  // neighbours, all adjacent, so the adjacent share is 1.
  const auto s = makeSphere<double>({0, 0, 0}, 1.0, 12, 6);
  const KFreeStats st = analyzeKFree(s);
  EXPECT_DOUBLE_EQ(st.adjacent_share, 1.0);
  // Two far-apart triangles: nobody is near anybody.
  TriangleMesh<double> two;
  two.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  two.addTriangle({10, 0, 0}, {11, 0, 0}, {10, 1, 0});
  const KFreeStats t = analyzeKFree(two);
  EXPECT_EQ(t.k, 1u);
  EXPECT_EQ(t.max_count, 0u);
  EXPECT_EQ(t.mean, 0.0);
  // A stack of 5 equal parallel triangles 0.01 apart: each sees the 4 others.
  TriangleMesh<double> stack;
  for (int i = 0; i < 5; ++i) stack.addTriangle({0, 0, 0.01 * i}, {1, 0, 0.01 * i}, {0, 1, 0.01 * i});
  const KFreeStats u = analyzeKFree(stack);
  EXPECT_EQ(u.k, 5u);
  EXPECT_DOUBLE_EQ(u.mean, 4.0);
  EXPECT_DOUBLE_EQ(u.adjacent_share, 0.0);
}

TEST(KFree, EmptyMeshAndBadInput) {
  const KFreeStats st = analyzeKFree(TriangleMesh<double>{});
  EXPECT_EQ(st.triangles, 0u);
  EXPECT_EQ(st.k, 0u);
  TriangleMesh<double> bad;
  bad.addTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  bad.triangles[0][0] = 7;
  EXPECT_THROW(analyzeKFree(bad), InvalidInputError);
}
