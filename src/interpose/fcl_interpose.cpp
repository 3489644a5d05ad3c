// libkdet_fcl_interpose.so: kDet under an unmodified FCL program (a MoveIt-style planner, a
// python-fcl script), loaded with LD_PRELOAD. See README "Unmodified FCL programs".
//
// It defines, under their mangled names, the functions of libfcl.so (FCL 0.7, double) that such
// programs call, so the dynamic linker binds their calls here first:
//  - fcl::collide<double>(const CollisionObject*, const CollisionObject*, request, result) and
//    the (geometry, transform, geometry, transform, request, result) overload. They call
//    kdet_fcl::collide: mesh-mesh pairs go through kDet, every other pair to FCL's own collide.
//  - the destructors of fcl::CollisionGeometry<double>, which every geometry's destructor ends
//    in. They drop the geometry's entry from kdet_fcl's cache of plain BVHModels
//    (kdet_fcl::forget), which a program written for FCL never calls, then run FCL's.
// FCL's own definitions are found with dlsym(RTLD_NEXT). libkdet_fcl's forwarding calls to
// fcl::collide come back here too (the dynamic linker binds them here as well): a thread-local
// flag set around every call into kdet_fcl sends them on to FCL.
//
// Environment (read once, at the first call):
//   KDET_FCL_INTERPOSE=0            every call goes to FCL unchanged (an A/B on the same binary)
//   KDET_FCL_INTERPOSE_BACKEND=cpu|cuda|auto   the backend of kDet's queries (default cpu)
//   KDET_FCL_INTERPOSE_THREADS=n    worker threads of kDet's queries (default 0: all)
//   KDET_FCL_INTERPOSE_CACHE=checksum|trust   how a cached model is checked at each query
//                                   (kdet_fcl::setCacheValidation; default checksum). trust
//                                   compares pointers and counts only: it misses FCL's replace
//                                   calls and direct writes, which change a model in place, so it
//                                   suits programs whose models never change after endModel
//   KDET_FCL_INTERPOSE_STATS=1      one line on stderr at exit: calls, kDet pairs, forwards,
//                                   fallbacks, destructor calls, cache entries left
// A pair that kdet_fcl refuses (kdet_fcl::Error: NaN vertices, indices out of range, a rotation
// that is not orthonormal, a CUDA backend without a device) goes to FCL instead, which is what
// the program got before; the first three such refusals are printed on stderr, and the stats
// line counts them all. A library loaded into someone else's process never exits it.

#include <dlfcn.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>

#include <fcl/geometry/collision_geometry.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/collision_request.h>
#include <fcl/narrowphase/collision_result.h>

#include "kdet_fcl/backend.h"
#include "kdet_fcl/errors.h"
#include "kdet_fcl/fcl_collide.h"

using Geometry = fcl::CollisionGeometry<double>;
using Object = fcl::CollisionObject<double>;
using Request = fcl::CollisionRequest<double>;
using Result = fcl::CollisionResult<double>;
using Transform = fcl::Transform3<double>;

// The mangled names of FCL 0.7's exports (nm -D libfcl.so.0.7).
#define KDET_COLLIDE_OBJECTS                                                      \
  "_ZN3fcl7collideIdEEmPKNS_15CollisionObjectIT_EES5_RKNS_16CollisionRequestIS2_EERNS_" \
  "15CollisionResultIS2_EE"
#define KDET_COLLIDE_GEOMETRIES                                                               \
  "_ZN3fcl7collideIdEEmPKNS_17CollisionGeometryIT_EERKN5Eigen9TransformIS2_Li3ELi1ELi0EEES5_" \
  "SA_RKNS_16CollisionRequestIS2_EERNS_15CollisionResultIS2_EE"

namespace {

using CollideObjectsFn = std::size_t (*)(const Object*, const Object*, const Request&, Result&);
using CollideGeometriesFn = std::size_t (*)(const Geometry*, const Transform&, const Geometry*,
                                            const Transform&, const Request&, Result&);
using DestructorFn = void (*)(void*);

void say(const std::string& line) {
  std::fprintf(stderr, "kdet_fcl interpose: %s\n", line.c_str());
}

/// FCL's definition of a symbol this library also defines. Without it nothing can go on, so a
/// missing one is reported and the process aborted (it means libfcl.so is not FCL 0.7's).
void* fclsOwn(const char* symbol) {
  dlerror();  // clears an earlier error
  void* f = dlsym(RTLD_NEXT, symbol);
  if (f == nullptr) {
    const char* why = dlerror();
    say(std::string("FCL's ") + symbol + " was not found after this library (" +
        (why != nullptr ? why : "no definition") +
        "): is libfcl.so FCL 0.7? Remove libkdet_fcl_interpose.so from LD_PRELOAD.");
    std::abort();
  }
  return f;
}

struct Stats {
  std::atomic<unsigned long long> calls{0};      // fcl::collide calls that came here
  std::atomic<unsigned long long> kdet_pairs{0};  // mesh-mesh pairs decided by kDet
  std::atomic<unsigned long long> forwarded{0};   // other pairs, sent to FCL by kdet_fcl
  std::atomic<unsigned long long> fallbacks{0};   // pairs kdet_fcl refused, sent to FCL
  std::atomic<unsigned long long> destroyed{0};   // geometry destructor calls that came here
};

struct Config {
  bool enabled = true;
  bool stats = false;
  std::string backend = "cpu";
};

Stats g_stats;
Config g_config;
std::once_flag g_once;
std::atomic<bool> g_configured{false};  // configure() has run: kdet_fcl's cache exists
std::atomic<bool> g_exiting{false};     // exit() has begun: the cache may be gone soon
thread_local bool t_inside = false;  // in a call into kdet_fcl on this thread

void printStats() {
  const bool trust = kdet_fcl::cacheValidation() == kdet_fcl::CacheValidation::Trust;
  char line[512];
  std::snprintf(line, sizeof line,
                "%s; backend %s; cache %s; fcl::collide calls %llu, mesh pairs by kDet %llu, "
                "forwarded to FCL %llu, fell back to FCL %llu; geometry destructor calls %llu; "
                "cache entries at exit %zu",
                g_config.enabled ? "on" : "off (KDET_FCL_INTERPOSE=0)", g_config.backend.c_str(),
                trust ? "trust" : "checksum",
                g_stats.calls.load(), g_stats.kdet_pairs.load(), g_stats.forwarded.load(),
                g_stats.fallbacks.load(), g_stats.destroyed.load(), kdet_fcl::cacheSize());
  say(line);
}

// Registered with atexit after kdet_fcl's cache was built, so it runs before the cache is
// destroyed; models destroyed after it (static ones, an interpreter's last objects) leave the
// cache alone.
void onExit() {
  g_exiting.store(true);
  if (g_config.stats) printStats();
}

void configure() {
  const char* on = std::getenv("KDET_FCL_INTERPOSE");
  g_config.enabled = !(on != nullptr && std::strcmp(on, "0") == 0);
  const char* stats = std::getenv("KDET_FCL_INTERPOSE_STATS");
  g_config.stats = stats != nullptr && std::strcmp(stats, "0") != 0 && *stats != '\0';

  kdet_fcl::QueryOptions options = kdet_fcl::collideOptions();
  if (const char* b = std::getenv("KDET_FCL_INTERPOSE_BACKEND")) {
    const std::string v = b;
    if (v == "cpu") {
      options.backend = kdet_fcl::Backend::Cpu;
    } else if (v == "cuda" || v == "auto") {
      options.backend = v == "cuda" ? kdet_fcl::Backend::Cuda : kdet_fcl::Backend::Auto;
      g_config.backend = v;
      if (v == "cuda" && kdet_fcl::cudaDeviceCount() == 0) {
        say("KDET_FCL_INTERPOSE_BACKEND=cuda, but " +
            std::string(kdet_fcl::builtWithCuda() ? "no CUDA device was found"
                                                  : "this kdet_fcl was built without CUDA") +
            "; the CPU backend runs instead");
        options.backend = kdet_fcl::Backend::Cpu;
        g_config.backend = "cpu";
      } else if (kdet_fcl::cudaDeviceCount() > 0) {
        try {
          (void)kdet_fcl::cudaDevice();  // KDET_FCL_CUDA_DEVICE names a device that exists
        } catch (const std::exception& e) {
          say(std::string(e.what()) + "; the CPU backend runs instead");
          options.backend = kdet_fcl::Backend::Cpu;
          g_config.backend = "cpu";
        }
      }
    } else {
      say("KDET_FCL_INTERPOSE_BACKEND='" + v + "' is not cpu, cuda or auto; using cpu");
    }
  }
  if (const char* t = std::getenv("KDET_FCL_INTERPOSE_THREADS")) {
    char* end = nullptr;
    const long n = std::strtol(t, &end, 10);
    if (end == t || *end != '\0' || n < 0 || n > 4096)
      say(std::string("KDET_FCL_INTERPOSE_THREADS='") + t +
          "' is not a thread count (0..4096); using 0 (all hardware threads)");
    else
      options.threads = int(n);
  }
  kdet_fcl::setCollideOptions(options);
  if (const char* c = std::getenv("KDET_FCL_INTERPOSE_CACHE")) {
    const std::string v = c;
    if (v == "trust")
      kdet_fcl::setCacheValidation(kdet_fcl::CacheValidation::Trust);
    else if (v != "checksum")
      say("KDET_FCL_INTERPOSE_CACHE='" + v + "' is not checksum or trust; using checksum");
  }
  (void)kdet_fcl::cacheSize();  // builds the cache's statics before onExit is registered
  std::atexit(onExit);
  g_configured.store(true);
}

const Config& config() {
  std::call_once(g_once, configure);
  return g_config;
}

CollideObjectsFn fclCollideObjects() {
  static const auto f = reinterpret_cast<CollideObjectsFn>(fclsOwn(KDET_COLLIDE_OBJECTS));
  return f;
}

CollideGeometriesFn fclCollideGeometries() {
  static const auto f = reinterpret_cast<CollideGeometriesFn>(fclsOwn(KDET_COLLIDE_GEOMETRIES));
  return f;
}

struct Inside {
  Inside() { t_inside = true; }
  ~Inside() { t_inside = false; }
};

/// One intercepted call: kdet_fcl::collide (through `kdet`) unless this thread is already inside
/// kdet_fcl or the shim is off; FCL's own collide (through `fcl`) otherwise or on a refusal.
template <class Kdet, class Fcl>
std::size_t intercept(const Geometry* g1, const Geometry* g2, const Result& result, Kdet kdet,
                      Fcl fcl) {
  if (t_inside || !config().enabled) return fcl();
  g_stats.calls.fetch_add(1, std::memory_order_relaxed);
  const std::size_t before = result.numContacts();
  try {
    Inside inside;
    const std::size_t n = kdet();
    // Which way the pair went matters only to the statistics line: without it, no look at the
    // geometries' types beyond kdet_fcl's own.
    if (g_config.stats) {
      const bool meshes = g1 != nullptr && g2 != nullptr && kdet_fcl::isKdetMesh(g1) &&
                          kdet_fcl::isKdetMesh(g2);
      (meshes ? g_stats.kdet_pairs : g_stats.forwarded).fetch_add(1, std::memory_order_relaxed);
    }
    return n;
  } catch (const kdet_fcl::Error& e) {
    const unsigned long long k = g_stats.fallbacks.fetch_add(1) + 1;
    if (k <= 3)
      say(std::string(e.what()) + " (this pair went to FCL" +
          (k == 3 ? "; further refusals are counted, not printed)" : ")"));
    if (result.numContacts() != before) return result.numContacts();  // never twice
    return fcl();
  }
}

/// A geometry is being destroyed: its cache entry, if any, goes (kdet_fcl::forget).
void forgetGeometry(void* self) {
  // No collide call yet: nothing is cached (and nothing is configured during exit).
  if (!g_configured.load() || g_exiting.load() || !g_config.enabled) return;
  g_stats.destroyed.fetch_add(1, std::memory_order_relaxed);
  kdet_fcl::forget<double>(static_cast<const Geometry*>(self));
}

}  // namespace

// ---- fcl::collide<double>, both overloads ----

std::size_t kdetInterposedCollideObjects(const Object* o1, const Object* o2, const Request& request,
                                         Result& result) __asm__(KDET_COLLIDE_OBJECTS);
std::size_t kdetInterposedCollideObjects(const Object* o1, const Object* o2, const Request& request,
                                         Result& result) {
  const Geometry* g1 = o1 != nullptr ? o1->collisionGeometry().get() : nullptr;
  const Geometry* g2 = o2 != nullptr ? o2->collisionGeometry().get() : nullptr;
  return intercept(
      g1, g2, result, [&] { return kdet_fcl::collide(o1, o2, request, result); },
      [&] { return fclCollideObjects()(o1, o2, request, result); });
}

std::size_t kdetInterposedCollideGeometries(const Geometry* o1, const Transform& tf1,
                                            const Geometry* o2, const Transform& tf2,
                                            const Request& request, Result& result)
    __asm__(KDET_COLLIDE_GEOMETRIES);
std::size_t kdetInterposedCollideGeometries(const Geometry* o1, const Transform& tf1,
                                            const Geometry* o2, const Transform& tf2,
                                            const Request& request, Result& result) {
  return intercept(
      o1, o2, result, [&] { return kdet_fcl::collide(o1, tf1, o2, tf2, request, result); },
      [&] { return fclCollideGeometries()(o1, tf1, o2, tf2, request, result); });
}

// ---- The destructors of fcl::CollisionGeometry<double>: D0 deleting, D1 complete, D2 base ----
// Every geometry's destructor ends in D2 (a derived class's destructor calls it), and libfcl
// exports it (FCL's headers declare CollisionGeometry<double> extern), so a program's own
// BVHModel destructors reach it through the dynamic linker too. By then the object is being
// destroyed; only its address is used.

#define KDET_GEOMETRY_DESTRUCTOR(KIND)                                             \
  void kdetInterposedGeometry##KIND(void* self)                                    \
      __asm__("_ZN3fcl17CollisionGeometryIdE" #KIND "Ev");                         \
  void kdetInterposedGeometry##KIND(void* self) {                                  \
    forgetGeometry(self);                                                          \
    static const auto f = reinterpret_cast<DestructorFn>(                          \
        fclsOwn("_ZN3fcl17CollisionGeometryIdE" #KIND "Ev"));                      \
    f(self);                                                                       \
  }

KDET_GEOMETRY_DESTRUCTOR(D0)
KDET_GEOMETRY_DESTRUCTOR(D1)
KDET_GEOMETRY_DESTRUCTOR(D2)
#undef KDET_GEOMETRY_DESTRUCTOR
