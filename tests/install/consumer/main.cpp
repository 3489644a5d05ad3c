// Smallest real use of an installed kdet_fcl: two meshes, one expected intersecting pair.
// Exit status 0 on success, 1 on a wrong answer, 2 on an exception.

#include <kdet_fcl/kdet_fcl.h>

#include <cstdio>
#include <exception>
#include <utility>

int main() {
  using kdet_fcl::Vec3;
  try {
    // a: triangle 0 lies in the plane z = 0 around the origin; triangle 1 is far away (+x).
    kdet_fcl::TriangleMesh<double> a;
    a.addTriangle(Vec3<double>{-1, -1, 0}, Vec3<double>{1, -1, 0}, Vec3<double>{0, 1, 0});
    a.addTriangle(Vec3<double>{10, 0, 0}, Vec3<double>{11, 0, 0}, Vec3<double>{10, 1, 0});
    // b: triangle 0 is far away (-x); triangle 1 stands upright (plane y = 0) and pierces a's
    // triangle 0 through its interior.
    kdet_fcl::TriangleMesh<double> b;
    b.addTriangle(Vec3<double>{-10, 0, 0}, Vec3<double>{-11, 0, 0}, Vec3<double>{-10, 1, 0});
    b.addTriangle(Vec3<double>{-0.2, 0, -1}, Vec3<double>{0.2, 0, -1}, Vec3<double>{0, 0, 1});

    const kdet_fcl::HashedMesh<double> ha(std::move(a));
    const kdet_fcl::HashedMesh<double> hb(std::move(b));

    const kdet_fcl::QueryResult result = kdet_fcl::intersectMeshes(ha, hb);
    std::printf("kdet_fcl consumer: %zu pair(s)", result.pairs.size());
    for (const auto& p : result.pairs) std::printf(" (%u, %u)", unsigned(p.a), unsigned(p.b));
    std::printf("\n");

    const bool ok = result.complete && result.pairs.size() == 1 && result.pairs[0].a == 0 &&
                    result.pairs[0].b == 1 && kdet_fcl::meshesIntersect(ha, hb);
    if (!ok) {
      std::fprintf(stderr, "kdet_fcl consumer: expected exactly the pair (0, 1)\n");
      return 1;
    }
    std::printf("kdet_fcl consumer: OK\n");
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kdet_fcl consumer: exception: %s\n", e.what());
    return 2;
  }
}
