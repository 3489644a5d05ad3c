// Bad input at every library entry point (issue 6): NaN/Inf coordinates, out-of-range indices and
// meshes whose largest coordinate lies outside [2^-247, 2^330] give InvalidInputError, files whose
// headers claim huge counts give MeshFileError at once, an allocation failure under an
// address-space limit becomes an exception (never an abort), and a failed call changes neither
// the caller's data nor a HashedMesh's state. The readers' own
// malformed-file cases live in test_mesh_io.cpp; the CLI's in cli_bad_input.cmake. An
// environment knob (KDET_FCL_*) with a value it does not accept gives InvalidInputError too.

#include <gtest/gtest.h>
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <new>
#include <string>
#include <vector>

#include "kdet_fcl/detail/knobs.h"
#include "oom_util.h"
#include "scoped_env.h"
#include "test_util.h"

using namespace kdet_fcl;
using kdet_test::kSanitized;
namespace fs = std::filesystem;

namespace {

template <class S>
class BadInput : public ::testing::Test {};
using Precisions = ::testing::Types<float, double>;
TYPED_TEST_SUITE(BadInput, Precisions);

template <class S>
TriangleMesh<S> twoCrossing() {
  TriangleMesh<S> m;
  m.addTriangle({0, 0, 0}, {2, 0, 0}, {0, 2, 0});
  m.addTriangle({S(0.5), S(0.5), -1}, {S(0.5), S(0.5), 1}, {S(0.8), S(0.2), 1});
  return m;
}

/// Byte-exact equality (NaN-safe: a NaN the caller put in must still be there, bit for bit).
template <class S>
bool sameBits(const TriangleMesh<S>& a, const TriangleMesh<S>& b) {
  return a.vertices.size() == b.vertices.size() && a.triangles.size() == b.triangles.size() &&
         std::memcmp(a.vertices.data(), b.vertices.data(), a.vertices.size() * sizeof(Vec3<S>)) == 0 &&
         std::memcmp(a.triangles.data(), b.triangles.data(), a.triangles.size() * sizeof(Triangle)) == 0;
}

/// Expects fn() to throw InvalidInputError whose message contains `needle`.
void expectInvalid(const std::function<void()>& fn, const std::string& needle, const char* what) {
  try {
    fn();
    ADD_FAILURE() << what << ": no InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << what << ": message '" << e.what() << "' lacks '" << needle << "'";
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << ": wrong exception type: " << e.what();
  }
}

/// Every way of making a mesh invalid, with the message part that must name the problem.
template <class S>
std::vector<std::pair<TriangleMesh<S>, std::string>> invalidMeshes() {
  std::vector<std::pair<TriangleMesh<S>, std::string>> out;
  const S bad[] = {std::numeric_limits<S>::quiet_NaN(), std::numeric_limits<S>::infinity(),
                   -std::numeric_limits<S>::infinity(), std::numeric_limits<S>::signaling_NaN()};
  for (const S b : bad)
    for (int k = 0; k < 3; ++k) {
      TriangleMesh<S> m = twoCrossing<S>();
      m.vertices[4][k] = b;
      out.push_back({m, "vertex 4"});
    }
  for (const std::uint32_t idx : {6u, 7u, 1000u, 0xFFFFFFFEu, 0xFFFFFFFFu}) {
    TriangleMesh<S> m = twoCrossing<S>();
    m.triangles[1][2] = idx;
    out.push_back({m, "triangle 1"});
  }
  {
    // An unused vertex is still validated.
    TriangleMesh<S> m = twoCrossing<S>();
    m.vertices.push_back({0, std::numeric_limits<S>::quiet_NaN(), 0});
    out.push_back({m, "vertex 6"});
  }
  return out;
}

}  // namespace

TYPED_TEST(BadInput, EveryEntryPointRejectsInvalidMeshesAndLeavesThemAlone) {
  using S = TypeParam;
  const TriangleMesh<S> good = twoCrossing<S>();
  for (const auto& [bad, needle] : invalidMeshes<S>()) {
    const TriangleMesh<S> copy = bad;
    expectInvalid([&] { HashedMesh<S> h(bad); }, needle, "HashedMesh");
    expectInvalid([&] { bad.validate(); }, needle, "validate");
    expectInvalid([&] { (void)analyzeKFree(bad); }, needle, "analyzeKFree");
    expectInvalid([&] { (void)analyzeKFreeBruteForce(bad); }, needle, "analyzeKFreeBruteForce");
    expectInvalid([&] { (void)bruteForceIntersectSelf(bad); }, needle, "bruteForceIntersectSelf");
    expectInvalid([&] { (void)bruteForceIntersectMeshes(bad, {}, good, {}); }, needle,
                  "bruteForceIntersectMeshes (first)");
    expectInvalid([&] { (void)bruteForceIntersectMeshes(good, {}, bad, {}); }, needle,
                  "bruteForceIntersectMeshes (second)");
    EXPECT_TRUE(sameBits(bad, copy)) << "a failed call changed the caller's mesh";
  }
}

TYPED_TEST(BadInput, AFailedChangeKeepsTheHashedMeshAsItWas) {
  using S = TypeParam;
  const TriangleMesh<S> mesh = makeDrapedCloth<S>(12, S(4), S(1), S(0.03), S(1));
  const TriangleMesh<S> ball = makeSphere<S>({0, 0, 0}, S(1), 16, 8);
  HashedMesh<S> h(mesh), b(ball);
  const auto self0 = kdet_test::sorted(intersectSelf(h).pairs);
  const auto pair0 = kdet_test::sorted(intersectMeshes(h, b).pairs);
  ASSERT_FALSE(self0.empty());
  ASSERT_FALSE(pair0.empty());
  const std::uint64_t v0 = h.version();
  const auto unchanged = [&](const char* what) {
    EXPECT_EQ(h.version(), v0) << what;
    EXPECT_TRUE(sameBits(h.mesh(), mesh)) << what;
    EXPECT_TRUE(h.pose().isIdentity()) << what;
    EXPECT_EQ(kdet_test::sorted(intersectSelf(h).pairs), self0) << what;
    EXPECT_EQ(kdet_test::sorted(intersectMeshes(h, b).pairs), pair0) << what;
  };
  // updateVertices: wrong counts, non-finite coordinates.
  for (const std::size_t n : {std::size_t(0), mesh.vertices.size() - 1, mesh.vertices.size() + 1}) {
    std::vector<Vec3<S>> v(n, Vec3<S>{0, 0, 0});
    EXPECT_THROW(h.updateVertices(v), InvalidInputError);
    unchanged("updateVertices(count)");
  }
  for (const S bad : {std::numeric_limits<S>::quiet_NaN(), std::numeric_limits<S>::infinity()}) {
    std::vector<Vec3<S>> v = mesh.vertices;
    v.back().y = bad;
    const std::vector<Vec3<S>> copy = v;
    expectInvalid([&] { h.updateVertices(v); }, "vertex " + std::to_string(v.size() - 1),
                  "updateVertices(NaN)");
    EXPECT_EQ(std::memcmp(v.data(), copy.data(), v.size() * sizeof v[0]), 0);
    unchanged("updateVertices(non-finite)");
  }
  // commitVertices: nothing written yet, then non-finite coordinates written in place.
  expectInvalid([&] { h.commitVertices(); }, "vertexWriteBuffer", "commitVertices(nothing)");
  unchanged("commitVertices(nothing)");
  for (const S bad : {std::numeric_limits<S>::quiet_NaN(), -std::numeric_limits<S>::infinity()}) {
    Vec3<S>* w = h.vertexWriteBuffer();
    std::copy(mesh.vertices.begin(), mesh.vertices.end(), w);
    w[1].z = bad;
    expectInvalid([&] { h.commitVertices(); }, "vertex 1", "commitVertices(non-finite)");
    unchanged("commitVertices(non-finite)");
  }
  // setMesh: every invalid mesh (passed by copy: the caller's copy must survive unchanged).
  for (const auto& [bad, needle] : invalidMeshes<S>()) {
    const TriangleMesh<S> copy = bad;
    expectInvalid([&] { h.setMesh(bad); }, needle, "setMesh");
    EXPECT_TRUE(sameBits(bad, copy));
    unchanged("setMesh");
  }
  // setPose: non-finite and non-rigid.
  Transform<S> P;
  P.t.z = std::numeric_limits<S>::quiet_NaN();
  EXPECT_THROW(h.setPose(P), InvalidInputError);
  P = Transform<S>{};
  P.R[0][1] = S(0.5);
  EXPECT_THROW(h.setPose(P), InvalidInputError);
  unchanged("setPose");
  // A HashedMesh built with a bad pose is not built at all.
  EXPECT_THROW(HashedMesh<S>(mesh, P), InvalidInputError);
  // The CUDA backend, where unavailable, is a typed error too, and changes nothing.
  if (!builtWithCuda() || cudaDeviceCount() == 0) {
    QueryOptions o;
    o.backend = Backend::Cuda;
    EXPECT_THROW(intersectSelf(h, o), BackendUnavailableError);
    EXPECT_THROW(intersectMeshes(h, b, o), BackendUnavailableError);
    unchanged("Backend::Cuda");
  }
}

/// A double mesh whose largest coordinate magnitude lies outside [2^-247, 2^330] is refused
/// wherever it would be hashed or queried (TriangleMesh::validateForQueries), naming the vertex
/// that has it, and a refused change leaves the HashedMesh as it was; both ends of the range are
/// accepted and give the pairs of the unscaled mesh; the readers' and writers' validate() takes
/// such meshes (files may hold them). Before, a pair of cubes at 1e154 or 1e-170 made a query run
/// on past 5-20 s and one at 1e150 or 1e-300 gave a wrong pair set (test_extremes.cpp's ladder).
TEST(BadInputRange, MeshesOutsideTheExactRangeAreRefusedWhereverTheyWouldBeQueried) {
  using S = double;
  const TriangleMesh<S> base = twoCrossing<S>();  // largest coordinate magnitude: 2 (vertex 1)
  const auto scaled = [&](double f) {
    TriangleMesh<S> m = base;
    for (auto& v : m.vertices) v = {v.x * f, v.y * f, v.z * f};
    return m;
  };
  const auto pairs0 = kdet_test::sorted(intersectSelf(HashedMesh<S>(base)).pairs);
  ASSERT_EQ(pairs0.size(), 1u);
  // The ends of the range: 2 * 2^329 = 2^330 and 2 * 2^-248 = 2^-247.
  for (const double f : {std::ldexp(1.0, 329), std::ldexp(1.0, -248)}) {
    const TriangleMesh<S> m = scaled(f);
    EXPECT_NO_THROW(m.validateForQueries());
    EXPECT_EQ(kdet_test::sorted(intersectSelf(HashedMesh<S>(m)).pairs), pairs0) << f;
    EXPECT_EQ(kdet_test::sorted(bruteForceIntersectSelf(m)), pairs0) << f;
  }
  // Every vertex at the origin: magnitude 0, accepted (degenerate triangles, no pairs).
  TriangleMesh<S> zero = base;
  for (auto& v : zero.vertices) v = {0, 0, 0};
  EXPECT_NO_THROW(zero.validateForQueries());
  EXPECT_TRUE(intersectSelf(HashedMesh<S>(zero)).pairs.empty());
  // Just outside either end (the largest coordinate one step beyond), and far outside.
  std::vector<std::pair<TriangleMesh<S>, std::string>> out;
  TriangleMesh<S> above = scaled(std::ldexp(1.0, 329));
  above.vertices[1].x = std::nextafter(std::ldexp(1.0, 330), 1e308);
  out.push_back({above, "2^330"});
  TriangleMesh<S> below = scaled(std::ldexp(1.0, -248));
  for (auto& v : below.vertices)
    for (int a = 0; a < 3; ++a)
      if (v[a] != 0) v[a] = std::nextafter(v[a], 0.0);
  out.push_back({below, "2^-247"});
  for (const double f : {1e154, 1e300, 1e-170, 1e-300, 1e-310})
    out.push_back({scaled(f), f > 1 ? "2^330" : "2^-247"});
  const TriangleMesh<S> good = base;
  for (const auto& [bad, bound] : out) {
    const TriangleMesh<S> copy = bad;
    const std::string needle = "vertex 1";  // the largest coordinate's vertex
    EXPECT_NO_THROW(bad.validate()) << bound;
    expectInvalid([&] { bad.validateForQueries(); }, needle, "validateForQueries");
    expectInvalid([&] { bad.validateForQueries(); }, bound, "validateForQueries (bound)");
    expectInvalid([&] { HashedMesh<S> h(bad); }, needle, "HashedMesh");
    expectInvalid([&] { (void)analyzeKFree(bad); }, needle, "analyzeKFree");
    expectInvalid([&] { (void)bruteForceIntersectSelf(bad); }, needle, "bruteForceIntersectSelf");
    expectInvalid([&] { (void)bruteForceIntersectMeshes(good, {}, bad, {}); }, needle,
                  "bruteForceIntersectMeshes");
    EXPECT_TRUE(sameBits(bad, copy)) << "a failed call changed the caller's mesh";
    // A HashedMesh of the unscaled mesh refuses the change and keeps its pairs.
    HashedMesh<S> h(good);
    expectInvalid([&] { h.setMesh(bad); }, needle, "setMesh");
    expectInvalid([&] { h.updateVertices(bad.vertices); }, needle, "updateVertices");
    std::copy(bad.vertices.begin(), bad.vertices.end(), h.vertexWriteBuffer());
    expectInvalid([&] { h.commitVertices(); }, needle, "commitVertices");
    EXPECT_TRUE(sameBits(h.mesh(), good)) << bound;
    EXPECT_EQ(kdet_test::sorted(intersectSelf(h).pairs), pairs0) << bound;
  }
  // Every float mesh lies inside the range: the largest and the smallest positive float.
  for (const float x :
       {std::numeric_limits<float>::max(), std::numeric_limits<float>::denorm_min()}) {
    TriangleMesh<float> m;
    m.addTriangle({0, 0, 0}, {x, 0, 0}, {0, x, 0});
    EXPECT_NO_THROW(m.validateForQueries()) << x;
    EXPECT_TRUE(intersectSelf(HashedMesh<float>(m)).pairs.empty()) << x;
  }
}

/// The brute-force references take poses without a HashedMesh to check them. Record what they do
/// with a non-finite pose: they must not crash (they may throw InvalidInputError).
TYPED_TEST(BadInput, BruteForceWithANonFinitePoseDoesNotCrash) {
  using S = TypeParam;
  const TriangleMesh<S> m = twoCrossing<S>();
  Transform<S> P;
  P.t.x = std::numeric_limits<S>::quiet_NaN();
  try {
    const auto pairs = bruteForceIntersectMeshes(m, P, m, Transform<S>{});
    std::printf("bruteForceIntersectMeshes with a NaN pose: no exception, %zu pairs\n", pairs.size());
  } catch (const InvalidInputError& e) {
    std::printf("bruteForceIntersectMeshes with a NaN pose: %s\n", e.what());
  }
}

// ---------------------------------------------------------------------------------------------
// Files whose headers claim huge counts: a MeshFileError at once, without a huge allocation.

class HugeCounts : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("kdet_bad_input_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& content) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }
  fs::path dir_;
};

TEST_F(HugeCounts, ClaimedCountsBeyondTheDataFailFast) {
  const std::string tri = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const std::string stl_head(80, ' ');
  const std::string files[][2] = {
      {"a.off", "OFF\n4000000000 1 0\n" + tri},
      {"b.off", "OFF\n3 4000000000 0\n" + tri},
      {"c.off", "OFF\n99999999999999999999 1 0\n" + tri},
      {"d.off", "OFF\n18446744073709551615 18446744073709551615 0\n" + tri},
      {"e.ply", "ply\nformat ascii 1.0\nelement vertex 4294967294\nproperty float x\nproperty float y\n"
                "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" + tri},
      {"f.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                "property float z\nelement face 18446744073709551615\nproperty list uchar int "
                "vertex_indices\nend_header\n" + tri},
      {"g.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty double x\n"
                "property double y\nproperty double z\nend_header\n" + std::string(48, '\0')},
      {"h.stl", stl_head + std::string("\xff\xff\xff\x7f", 4) + std::string(100, '\0')},
  };
  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& f : files) {
    const std::string p = write(f[0], f[1]);
    for (int prec = 0; prec < 2; ++prec) {
      try {
        if (prec)
          (void)readMesh<double>(p);
        else
          (void)readMesh<float>(p);
        ADD_FAILURE() << f[0] << ": no MeshFileError";
      } catch (const MeshFileError& e) {
        EXPECT_NE(std::string(e.what()).find(f[0]), std::string::npos) << e.what();
      } catch (const std::exception& e) {
        ADD_FAILURE() << f[0] << ": wrong exception: " << e.what();
      }
    }
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
}

// ---------------------------------------------------------------------------------------------
// Out of memory. Each case runs in a forked child whose address space is limited (soft
// RLIMIT_AS) to its current size plus a small headroom; the child reports how the allocation
// failure surfaced through its exit code. A signal (abort, std::terminate, a crash) fails the
// test. Skipped under AddressSanitizer, which reserves terabytes of shadow address space.

enum ChildResult : int {
  kOk = 0,             // the expected typed error
  kBadAlloc = 10,      // std::bad_alloc escaped (documented for HashedMesh and the queries)
  kOtherError = 11,    // some other std::exception
  kNoError = 12,       // the call succeeded despite the limit (limit too generous)
  kStateChanged = 13,  // after the failure, the object no longer behaves as before
};

using kdet_test::limitAddressSpace;
using kdet_test::unlimitAddressSpace;

/// Runs body() in a child; returns its exit code, or -signal.
int inChild(const std::function<int()>& body) { return kdet_test::runInChild(body, kOtherError); }

TEST(OutOfMemory, AReaderTurnsAllocationFailureIntoMeshFileError) {
  if (kSanitized) GTEST_SKIP() << "RLIMIT_AS and AddressSanitizer do not mix";
  // A valid binary STL of 400k triangles (20 MB); reading needs the file image plus ~30 MB.
  const std::string p = (fs::temp_directory_path() / ("kdet_oom_" + std::to_string(::getpid()) + ".stl")).string();
  {
    TriangleMesh<float> m = makeRandomSoup<float>(400000, 10.f, 0.01f, 0.1f, 1);
    writeMesh(m, p);
  }
  const int rc = inChild([&] {
    limitAddressSpace(8u << 20);
    try {
      (void)readMesh<double>(p);
      return int(kNoError);
    } catch (const MeshFileError& e) {
      return std::strstr(e.what(), "out of memory") ? int(kOk) : int(kOtherError);
    } catch (const std::bad_alloc&) {
      return int(kBadAlloc);
    }
  });
  fs::remove(p);
  EXPECT_EQ(rc, kOk) << "(negative: killed by signal " << -rc << ")";
}

/// HashedMesh (construction, setMesh, updateVertices) and the queries let std::bad_alloc
/// propagate: it is a typed standard exception, not an abort (documented in docs/numerics.md).
TEST(OutOfMemory, HashedMeshAllocationFailureIsAnException) {
  if (kSanitized) GTEST_SKIP() << "RLIMIT_AS and AddressSanitizer do not mix";
  const TriangleMesh<double> big = makeRandomSoup<double>(300000, 10.0, 0.01, 0.1, 2);
  for (const int threads : {1, 0}) {
    const int rc = inChild([&] {
      limitAddressSpace(4u << 20);
      try {
        HashedMesh<double> h(big, Transform<double>{}, threads);
        return int(kNoError);
      } catch (const std::bad_alloc&) {
        return int(kBadAlloc);
      } catch (const Error&) {
        return int(kOk);
      }
    });
    EXPECT_TRUE(rc == kBadAlloc || rc == kOk) << "threads " << threads << ": child result " << rc
                                              << " (negative: killed by signal)";
  }
}

/// README: "On error, a HashedMesh keeps its previous state." setMesh and updateVertices are run
/// under address-space limits growing in 2 MiB steps (each in a fresh child), from "fails at
/// once" to "succeeds", so that the failure hits every allocation on the way. The CPU re-hash is
/// lazy (the first CPU query after a change runs it; prepareCpuHash() here), so a failure either
/// hits the mutation itself, which must then leave the old geometry answering queries as before,
/// or the re-hash, which must leave the new geometry stored with a stale hash that the next call
/// rebuilds (test_hierarchy.cpp checks the answers after such a failure on a smaller mesh).
TEST(OutOfMemory, AFailedRebuildKeepsThePreviousState) {
  if (kSanitized) GTEST_SKIP() << "RLIMIT_AS and AddressSanitizer do not mix";
  // Large blocks always from mmap (no dynamic threshold): a freed vector leaves no reusable heap.
  ::mallopt(M_MMAP_THRESHOLD, 64 * 1024);
  const TriangleMesh<double> small = makeDrapedCloth<double>(10, 4.0, 1.0, 0.03, 1.0);
  const TriangleMesh<double> big = makeRandomSoup<double>(300000, 12.0, 0.01, 0.3, 3);
  const auto want_small = bruteForceIntersectSelf(small);
  ASSERT_FALSE(want_small.empty());
  for (const bool vertices_only : {false, true}) {
    // Built in the parent; every child inherits it (copy-on-write) and tries one limit.
    HashedMesh<double> h(vertices_only ? big : small, Transform<double>{}, 1);
    const auto want = kdet_test::sorted(intersectSelf(h).pairs);
    std::vector<Vec3<double>> moved = big.vertices;
    for (auto& p : moved) p = p * 1.0001;
    int failures = 0, successes = 0, broken = 0, signals = 0;
    for (std::size_t headroom = 0; headroom <= (256u << 20) && successes == 0; headroom += 2u << 20) {
      TriangleMesh<double> replacement = big;  // moved into setMesh: the call itself copies nothing
      ::malloc_trim(0);  // return free heap to the system, so that the limit bites
      const int rc = inChild([&] {
        limitAddressSpace(headroom);
        try {
          if (vertices_only)
            h.updateVertices(moved);
          else
            h.setMesh(std::move(replacement));
          h.prepareCpuHash();
        } catch (const std::bad_alloc&) {
          unlimitAddressSpace();
          const bool changed =
              vertices_only ? std::memcmp(h.mesh().vertices.data(), moved.data(),
                                          moved.size() * sizeof(Vec3<double>)) == 0
                            : h.numTriangles() == big.triangles.size();
          if (changed) {  // the re-hash failed: stale, and rebuilt by the next call
            if (h.cpuHashFresh()) return int(kStateChanged);
            h.prepareCpuHash();
            return int(h.cpuHashFresh() ? kOk : kStateChanged);
          }
          const bool same = (vertices_only ? std::memcmp(h.mesh().vertices.data(), big.vertices.data(),
                                                         big.vertices.size() * sizeof(Vec3<double>)) == 0
                                           : h.numTriangles() == small.triangles.size()) &&
                            kdet_test::sorted(intersectSelf(h).pairs) == want;
          return int(same ? kOk : kStateChanged);
        }
        return int(kNoError);
      });
      failures += rc == kOk;
      successes += rc == kNoError;
      broken += rc == kStateChanged || rc == kOtherError;
      signals += rc < 0;
    }
    std::printf("%s under growing memory limits: %d clean failures, %d left a changed state, "
                "%d killed by a signal, then success: %d\n",
                vertices_only ? "updateVertices" : "setMesh", failures, broken, signals, successes);
    // A same-size re-hash reuses every buffer of the last one, so updateVertices may find all
    // the memory it needs (its copy of the vertices can come from free heap).
    if (!vertices_only) EXPECT_GT(failures + broken + signals, 0) << "the limit never bit";
    EXPECT_EQ(broken, 0) << (vertices_only ? "updateVertices" : "setMesh")
                         << ": a failed rebuild left the HashedMesh changed";
    EXPECT_EQ(signals, 0) << "a failed rebuild crashed";
    EXPECT_EQ(successes, 1);
  }
}

// The environment knobs (kdet_fcl/detail/knobs.h): unset or empty gives the default, each knob
// accepts exactly its values, and anything else throws InvalidInputError naming the variable and
// its value (never read as something else).
TEST(Knobs, EachParserAcceptsItsValuesAndRejectsEveryOtherNamingTheVariable) {
  using namespace kdet_fcl::detail;
  const char* name = "KDET_FCL_TEST_KNOB";
  auto rejects = [&](const char* value, auto&& read) {
    kdet_test::ScopedEnv e(name, value);
    try {
      read();
      ADD_FAILURE() << "'" << value << "' was accepted";
    } catch (const InvalidInputError& err) {
      const std::string what = err.what();
      EXPECT_NE(what.find(std::string(name) + "='" + value + "'"), std::string::npos) << what;
      EXPECT_NE(what.find("expected"), std::string::npos) << what;
    }
  };
  auto with = [&](const char* value, auto&& read) {
    kdet_test::ScopedEnv e(name, value);
    return read();
  };
  // Switches.
  auto sw = [&](bool otherwise) { return [=] { return switchKnob(name, otherwise); }; };
  EXPECT_TRUE(with(nullptr, sw(true)));
  EXPECT_FALSE(with(nullptr, sw(false)));
  EXPECT_TRUE(with("", sw(true)));
  EXPECT_FALSE(with("0", sw(true)));
  EXPECT_TRUE(with("1", sw(false)));
  for (const char* bad : {"2", "00", "01", "yes", "no", "on", "true", " 1", "1 ", "-0", "0x1"})
    rejects(bad, sw(true));
  // Whole numbers in a range.
  auto num = [&] { return numberKnob(name, 3, 1000, 42); };
  EXPECT_EQ(with(nullptr, num), 42u);
  EXPECT_EQ(with("", num), 42u);
  EXPECT_EQ(with("3", num), 3u);
  EXPECT_EQ(with("1000", num), 1000u);
  EXPECT_EQ(with("0077", num), 77u);  // leading zeros are still the same decimal number
  for (const char* bad : {"2", "1001", "-5", "+5", "5x", "x5", "abc", "5.0", "1e2", " 5", "5 ",
                          "18446744073709551616", "99999999999999999999999"})
    rejects(bad, num);
  auto wide = [&] { return numberKnob(name, 0, ~std::uint64_t(0), 1); };
  EXPECT_EQ(with("18446744073709551615", wide), ~std::uint64_t(0));
  EXPECT_EQ(with("0", wide), 0u);
  rejects("18446744073709551616", wide);  // one past 2^64 - 1: no wrap-around
  // One of a list of numbers.
  auto choice = [&] { return choiceKnob(name, {1, 4, 8}, 8); };
  EXPECT_EQ(with(nullptr, choice), 8u);
  EXPECT_EQ(with("1", choice), 1u);
  EXPECT_EQ(with("4", choice), 4u);
  for (const char* bad : {"0", "2", "16", "four", "4k"}) rejects(bad, choice);
  // One of a list of words.
  auto word = [&] { return wordKnob(name, {"warp", "tile"}, 0); };
  EXPECT_EQ(with(nullptr, word), 0);
  EXPECT_EQ(with("warp", word), 0);
  EXPECT_EQ(with("tile", word), 1);
  for (const char* bad : {"Tile", "tiles", "1", "warp "}) rejects(bad, word);
  // The quick pass that lets an unset environment skip the checks sees a set variable.
  {
    kdet_test::ScopedEnv e(name, nullptr);
    EXPECT_FALSE(someKnobSet("KDET_FCL_TEST_KN"));
  }
  kdet_test::ScopedEnv e(name, "1");
  EXPECT_TRUE(someKnobSet("KDET_FCL_TEST_KN"));
  EXPECT_FALSE(someKnobSet("KDET_FCL_TEST_KNOBS"));
  // The setting that the CUDA backend's check compares: every entry of the prefix, names and
  // values, and nothing else; a changed value changes it.
  std::string setting = "kept:";
  ASSERT_TRUE(appendKnobEntries("KDET_FCL_TEST_KN", setting));
  EXPECT_EQ(setting, std::string("kept:") + name + "=1\n");
  {
    kdet_test::ScopedEnv other("KDET_FCL_TEST_KNOT", "");
    kdet_test::ScopedEnv changed(name, "0");
    std::string now;
    ASSERT_TRUE(appendKnobEntries("KDET_FCL_TEST_KN", now));
    EXPECT_NE(now.find(std::string(name) + "=0\n"), std::string::npos) << now;
    EXPECT_NE(now.find("KDET_FCL_TEST_KNOT=\n"), std::string::npos) << now;
    EXPECT_EQ(now.size(),
              std::string(name).size() + 3 + std::string("KDET_FCL_TEST_KNOT=\n").size());
  }
  std::string none;
  ASSERT_TRUE(appendKnobEntries("KDET_FCL_TEST_KNOBS", none));
  EXPECT_EQ(none, "");
}

// The CPU backend's one knob (KDET_FCL_CPU_SELF_CACHE) with a value it does not accept fails a
// self query with that error; the kept-result scenario (test_query.cpp) checks the same on a
// kept result.
TEST(Knobs, AMisspeltCpuKnobFailsTheSelfQueryAndTheMendedKnobRunsIt) {
  const HashedMesh<double> soup(makeRandomSoup<double>(300, 3.0, 0.3, 1.0, 5));
  const std::vector<TrianglePair> want = bruteForceIntersectSelf(soup.mesh());
  ASSERT_FALSE(want.empty());
  {
    kdet_test::ScopedEnv bad("KDET_FCL_CPU_SELF_CACHE", "false");
    EXPECT_THROW(intersectSelf(soup), InvalidInputError);
    // An inter query does not read that knob.
    EXPECT_NO_THROW(intersectMeshes(soup, soup));
  }
  kdet_test::ScopedEnv mended("KDET_FCL_CPU_SELF_CACHE", "0");
  EXPECT_EQ(kdet_test::sorted(intersectSelf(soup).pairs), want);
}
