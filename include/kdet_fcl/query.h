#pragma once
/// \file
/// The kDet queries: every intersecting triangle pair between two meshes, or inside one mesh.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "kdet_fcl/backend.h"
#include "kdet_fcl/hashed_mesh.h"
#include "kdet_fcl/predicate.h"

namespace kdet_fcl {

/// What a query asks for. Pay only for what is asked: `max_pairs = 1` is a yes/no query that
/// stops at the first intersecting pair.
struct QueryOptions {
  /// Stop once this many pairs are found (0: find every pair). The reported pairs are the first
  /// ones in a deterministic order, the same for any thread count. On the CPU, a cap of at most
  /// 4096 visits a spread sample of each mesh's triangles first, so that a contact anywhere is
  /// met early (a first-contact check pays for little more than the way to its first pair); its
  /// pairs are then not a prefix of the uncapped query's order, but a smaller cap's pairs are a
  /// prefix of a larger one's. The CUDA backend reports the first pairs in (a, b) order.
  std::size_t max_pairs = 0;
  /// Worker threads (0: std::thread::hardware_concurrency()). Results do not depend on it.
  int threads = 0;
  /// Which backend runs the query.
  Backend backend = Backend::Cpu;
  /// How candidate pairs are decided (Exact: the exact closed-triangle test; Double/Float: the
  /// same test in plain floating point, faster and inexact near degeneracies).
  Predicate predicate = Predicate::Exact;
};

/// One intersecting pair: triangle `a` of the first mesh and triangle `b` of the second (for a
/// self query: a < b, both in the same mesh). Indices are positions in TriangleMesh::triangles.
struct TrianglePair {
  std::uint32_t a, b;
  bool operator==(const TrianglePair& o) const { return a == o.a && b == o.b; }
  bool operator!=(const TrianglePair& o) const { return !(*this == o); }
  bool operator<(const TrianglePair& o) const { return a != o.a ? a < o.a : b < o.b; }
};

/// Counters of one query (for profiling and the benchmarks).
struct QueryStats {
  std::uint64_t lookups = 0;          ///< hash lookups (occupied cells or not)
  std::uint64_t cells_visited = 0;    ///< hash lookups that found an occupied cell
  std::uint64_t box_tests = 0;        ///< candidate pairs whose boxes were compared
  std::uint64_t triangle_tests = 0;   ///< exact triangle-triangle tests run
};

/// Result of a query.
struct QueryResult {
  /// The intersecting pairs, each exactly once. The order is deterministic (the same input gives
  /// the same order for any thread count) but not sorted; sort it if you need (a, b) order.
  std::vector<TrianglePair> pairs;
  /// False when max_pairs pairs were found: the query stopped there and more pairs may exist.
  bool complete = true;
  /// True when a self query was answered from the result kept for the mesh's unchanged geometry:
  /// no work ran, and `stats` is zero. A self query that sees the same geometry (not pose) as
  /// the mesh's previous self query keeps its result; later self queries of that geometry with the
  /// same predicate and max_pairs return it, on either backend (each keeps its own). Any change of
  /// geometry drops it. KDET_FCL_CPU_SELF_CACHE=0 / KDET_FCL_CUDA_SELF_CACHE=0 turn it off.
  bool kept = false;
  QueryStats stats;
};

/// All pairs (i, j), i a triangle of `a` and j of `b`, whose closed triangles intersect (touching
/// at a point or an edge and coplanar overlap count), decided exactly on the coordinates of `a`
/// mapped into `b`'s frame (rounded in precision S) and `b`'s own coordinates.
template <class S>
QueryResult intersectMeshes(const HashedMesh<S>& a, const HashedMesh<S>& b,
                            const QueryOptions& options = {});

/// All pairs (i < j) of intersecting triangles of one mesh, except pairs that share a vertex
/// (the same vertex index, or vertices with equal coordinates, so soups work too).
template <class S>
QueryResult intersectSelf(const HashedMesh<S>& mesh, const QueryOptions& options = {});

/// intersectMeshes into `out`, a result the caller keeps from frame to frame: `out` is replaced
/// by the same result (pairs, order, flags), and on the CUDA backend the pairs are read back
/// into the storage `out` already holds, by several host threads when they are many (from 1 MiB)
/// and `out` held at least half as many (KDET_FCL_CUDA_DOWNLOAD_THREADS, default 4). The by-value
/// call cannot do that: a new vector would have to be zero-filled before several threads could
/// write it. On an H100 host a probe's read-back of 445,614 pairs (after a 0.1 ms kernel) took
/// 0.30 ms this way against 0.48 ms into a new result, and the two cloth-ball frames 1.48 against
/// 1.62–1.65 ms (benchmarks/RESULTS-gpu.md). The CPU backend fills a new result and moves it into
/// `out`. On an exception, `out`'s pairs are unspecified.
template <class S>
void intersectMeshes(const HashedMesh<S>& a, const HashedMesh<S>& b, QueryResult& out,
                     const QueryOptions& options = {});

/// intersectSelf into `out`, a result kept from frame to frame, as intersectMeshes into a result.
template <class S>
void intersectSelf(const HashedMesh<S>& mesh, QueryResult& out, const QueryOptions& options = {});

/// Every intersecting pair of two meshes: each one's self pairs and the pairs between them.
struct AllPairsResult {
  QueryResult self_a;  ///< intersectSelf(a)
  QueryResult self_b;  ///< intersectSelf(b)
  QueryResult inter;   ///< intersectMeshes(a, b)
};

/// The three queries of two meshes at once (a simulation step of two deforming bodies): the same
/// pairs, in the same order, as intersectSelf(a), intersectSelf(b) and intersectMeshes(a, b) with
/// the same options (max_pairs applies to each). The CPU backend runs the three queries. The
/// CUDA backend hashes both meshes as one and runs one self query when that gives exactly the
/// same pairs (every pair asked for, and poses that map one mesh's frame onto the other's
/// exactly, such as two meshes in world coordinates): the paper's single hash for a whole scene
/// (cuda/cuda_backend.h). Backend::Auto counts the triangles of both meshes.
template <class S>
AllPairsResult intersectAll(const HashedMesh<S>& a, const HashedMesh<S>& b,
                            const QueryOptions& options = {});

/// intersectAll into `out`, kept from frame to frame, as intersectMeshes into a result: each of
/// its three results is replaced, and the CUDA backend reads the pairs back into their storage.
template <class S>
void intersectAll(const HashedMesh<S>& a, const HashedMesh<S>& b, AllPairsResult& out,
                  const QueryOptions& options = {});

/// The outcome of a query whose pairs went to device memory (intersectSelfOnDevice,
/// intersectMeshesOnDevice).
struct DevicePairsResult {
  /// The pairs the query found (at most max_pairs when that is set). The first
  /// min(count, capacity) of them were written to the caller's buffer; when count exceeds the
  /// capacity the rest were not written: ask again with a buffer of at least `count` pairs.
  std::size_t count = 0;
  /// As QueryResult::complete: false when max_pairs pairs were found and more may exist.
  bool complete = true;
  /// As QueryResult::kept: a self query answered from the result kept for the mesh's unchanged
  /// geometry, whose pairs were copied into the buffer (no query ran on the device).
  bool kept = false;
};

/// For GPU consumers (a simulation whose state lives on the device): intersectSelf on the CUDA
/// backend, with the pairs written to `device_pairs`, device memory of the backend's CUDA device
/// (cudaDevice(): 0 unless setCudaDevice or KDET_FCL_CUDA_DEVICE chose another) that the caller
/// owns (cudaMalloc or managed memory), instead of a host vector. The pairs are the same
/// as intersectSelf's with Backend::Cuda, in the same order (sorted by (a, b)); they are in
/// place when the call returns (the library's stream has finished), so any stream may read them.
/// No copy to the host is made, which saves the read-back of the pairs (H100: 0.07 ms of the
/// UNC cloth ball's 0.80 ms frame, 61,530 pairs; benchmarks/RESULTS-gpu.md). A self query here
/// follows QueryResult::kept's rule, sharing the mesh's kept result with intersectSelf: a rigid
/// mesh's self query runs on the device until its result is kept (the query that keeps it reads
/// the pairs back once), and from then on the kept pairs are copied into the buffer (a host to
/// device copy of as many as fit; nothing when a rigid mesh has no self pairs, its usual case).
/// `device_pairs` may be null when `capacity` is 0 (the count alone). Throws InvalidInputError
/// when options.backend is Backend::Cpu (Auto and Cuda both mean the GPU here), when
/// device_pairs is null with a non-zero capacity or is not device memory (or is another
/// device's), and BackendUnavailableError without a CUDA build or device, as Backend::Cuda does.
template <class S>
DevicePairsResult intersectSelfOnDevice(const HashedMesh<S>& mesh, TrianglePair* device_pairs,
                                        std::size_t capacity, const QueryOptions& options = {});

/// intersectMeshes on the CUDA backend with the pairs written to device memory, as
/// intersectSelfOnDevice.
template <class S>
DevicePairsResult intersectMeshesOnDevice(const HashedMesh<S>& a, const HashedMesh<S>& b,
                                          TrianglePair* device_pairs, std::size_t capacity,
                                          const QueryOptions& options = {});

/// The outcome of intersectAllOnDevice: the three results' counts, their pairs one run after
/// another in the caller's buffer.
struct AllDevicePairsResult {
  DevicePairsResult self_a;  ///< intersectSelf(a): the buffer's first self_a.count pairs
  DevicePairsResult self_b;  ///< intersectSelf(b): the next self_b.count
  DevicePairsResult inter;   ///< intersectMeshes(a, b): the last inter.count
  /// Pairs of all three: the buffer holds the first min(total(), capacity) of the runs.
  std::size_t total() const { return self_a.count + self_b.count + inter.count; }
};

/// intersectAll with the pairs written to device memory, as intersectSelfOnDevice: the three
/// results' pairs, each in its own order and indices as intersectAll with Backend::Cuda returns
/// them, one run after another (self_a, self_b, inter); a buffer smaller than total() gets the
/// first `capacity` pairs of those runs. When intersectAll on the CUDA backend would hash both
/// meshes as one (see cuda_backend.h), so does this; otherwise it runs the three device queries
/// into the three places. Errors as intersectSelfOnDevice.
template <class S>
AllDevicePairsResult intersectAllOnDevice(const HashedMesh<S>& a, const HashedMesh<S>& b,
                                          TrianglePair* device_pairs, std::size_t capacity,
                                          const QueryOptions& options = {});

/// Yes/no: do the two meshes have at least one intersecting triangle pair?
template <class S>
bool meshesIntersect(const HashedMesh<S>& a, const HashedMesh<S>& b, QueryOptions options = {}) {
  options.max_pairs = 1;
  return !intersectMeshes(a, b, options).pairs.empty();
}

/// O(n*m) reference: the same predicate on every pair, on the same coordinates as the queries
/// (tests and regressions use it; with Predicate::Exact it is the ground truth). Sorted by (a, b).
template <class S>
std::vector<TrianglePair> bruteForceIntersectMeshes(const TriangleMesh<S>& a,
                                                    const Transform<S>& pose_a,
                                                    const TriangleMesh<S>& b,
                                                    const Transform<S>& pose_b,
                                                    Predicate predicate = Predicate::Exact);

/// O(n^2) reference for intersectSelf. Sorted by (a, b).
template <class S>
std::vector<TrianglePair> bruteForceIntersectSelf(const TriangleMesh<S>& mesh,
                                                  Predicate predicate = Predicate::Exact);

}  // namespace kdet_fcl
