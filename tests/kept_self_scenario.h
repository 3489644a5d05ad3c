#pragma once
// The scenario of the kept-self-result tests (QueryResult::kept), shared by the CPU backend's
// test (test_query.cpp) and the CUDA backend's (test_cuda_query.cpp).

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "kdet_fcl/errors.h"
#include "scoped_env.h"
#include "test_util.h"

namespace kdet_test {

/// Runs the scenario on `soup` (a makeRandomSoup<double>(1500, 6.0, 0.3, 1.2, 17)).
/// `self(what, max_pairs, predicate)` runs one self query of `soup` on the backend under test,
/// checks its pairs against a reference, and returns them with whether the query was answered
/// from a kept result. `backend` runs the inter query in between; `knob` turns kept results off.
/// Ends with half of the triangles, after three queries with kept results off.
template <class Self>
void runKeptSelfScenario(kdet_fcl::HashedMesh<double>& soup, kdet_fcl::Backend backend,
                         const char* knob, Self&& self) {
  using kdet_fcl::Predicate;
  ScopedEnv keep_on(knob, nullptr);  // the default: on
  const kdet_fcl::TriangleMesh<double> original = soup.mesh();
  const kdet_fcl::TriangleMesh<double> moved =
      kdet_fcl::makeRandomSoup<double>(1500, 6.0, 0.3, 1.2, 18);
  ASSERT_EQ(moved.triangles, original.triangles);  // same topology, other vertices
  const auto first = self("first query", 0, Predicate::Exact);
  EXPECT_FALSE(first.second);
  ASSERT_GT(first.first.size(), 20u);
  EXPECT_FALSE(self("same geometry, computed and kept", 0, Predicate::Exact).second);
  EXPECT_TRUE(self("kept", 0, Predicate::Exact).second);
  // A value the knob does not accept fails the query with InvalidInputError naming the variable,
  // before any work; the kept result survives it.
  for (const char* bad : {"yes", "2", "01", " 1", "off"}) {
    ScopedEnv misspelt(knob, bad);
    try {
      self("misspelt knob", 0, Predicate::Exact);
      ADD_FAILURE() << knob << "='" << bad << "' was accepted";
    } catch (const kdet_fcl::InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string(knob) + "='" + bad + "'"),
                std::string::npos)
          << e.what();
    }
  }
  EXPECT_TRUE(self("kept after the misspelt knob", 0, Predicate::Exact).second);
  // The pose does not change a self query's pairs; an inter query does not change the geometry.
  soup.setPose(kdet_fcl::makeTransform<double>({0, 0, 1}, 0.7, {3.0, -1.0, 2.0}));
  const kdet_fcl::HashedMesh<double> other(kdet_fcl::makeSphere<double>({0, 0, 0}, 2.0, 24, 12));
  kdet_fcl::QueryOptions inter;
  inter.backend = backend;
  EXPECT_EQ(sorted(kdet_fcl::intersectMeshes(soup, other, inter).pairs),
            kdet_fcl::bruteForceIntersectMeshes(soup.mesh(), soup.pose(), other.mesh(),
                                                other.pose()));
  EXPECT_TRUE(self("kept after a new pose and an inter query", 0, Predicate::Exact).second);
  // Other options: computed (the kept result answered other options), then kept for those.
  EXPECT_FALSE(self("Double predicate", 0, Predicate::Double).second);
  EXPECT_TRUE(self("Double predicate again", 0, Predicate::Double).second);
  const auto seven = self("max_pairs 7", 7, Predicate::Exact);
  EXPECT_FALSE(seven.second);
  EXPECT_EQ(seven.first.size(), 7u);
  EXPECT_TRUE(self("max_pairs 7 again", 7, Predicate::Exact).second);
  EXPECT_FALSE(self("back to all pairs", 0, Predicate::Exact).second);
  EXPECT_TRUE(self("all pairs kept", 0, Predicate::Exact).second);
  // New geometry drops it: new vertices (other pairs), then the old ones back.
  soup.updateVertices(moved.vertices);
  const auto after = self("new vertices", 0, Predicate::Exact);
  EXPECT_FALSE(after.second);
  EXPECT_NE(sorted(after.first), sorted(first.first));
  soup.updateVertices(original.vertices);
  EXPECT_FALSE(self("old vertices back", 0, Predicate::Exact).second);
  EXPECT_FALSE(self("old vertices, computed and kept", 0, Predicate::Exact).second);
  EXPECT_TRUE(self("old vertices kept", 0, Predicate::Exact).second);
  // A new topology drops it.
  kdet_fcl::TriangleMesh<double> half = original;
  half.triangles.resize(half.triangles.size() / 2);
  soup.setMesh(half);
  EXPECT_FALSE(self("half the triangles", 0, Predicate::Exact).second);
  EXPECT_FALSE(self("half, computed and kept", 0, Predicate::Exact).second);
  EXPECT_TRUE(self("half kept", 0, Predicate::Exact).second);
  // Turned off: always computed.
  ScopedEnv keep_off(knob, "0");
  for (int k = 0; k < 3; ++k) EXPECT_FALSE(self("turned off", 0, Predicate::Exact).second);
}

}  // namespace kdet_test
