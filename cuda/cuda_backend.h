#pragma once
// Host-only seam of the CUDA query backend (cuda_backend.cu). Plain C++17: no CUDA header, so
// src/cpu/query.cpp, the tests and the benchmarks can include it with any compiler. Only defined
// when the library is built with CUDA (KDET_FCL_HAVE_CUDA=1).
//
// Device-resident state: each HashedMesh that reaches the GPU gets a cache entry (keyed by the
// HashedMesh's address, its version() and a cheap fingerprint of its arrays) holding its vertices,
// triangles, per-triangle box/diameter/level and cell table on the device. A new pose uploads
// nothing but the relative pose; a new version() (updateVertices) uploads the vertices and
// re-hashes on the device; a topology change (setMesh) uploads the triangles too and rebuilds.
// A first build (and a rebuild after a topology change) reads the grid, the entry count and the
// cell count back to size the arrays (1/8 slack). A re-hash of a mesh with compact 64-bit cell
// keys reads nothing back: the grid stays on the device (the query kernels read it from
// constant memory), the arrays keep their capacities, and the query's own read-back of its pair
// counts also checks that the re-hash fitted; if not (more entries or cells, or keys that outgrew
// the compact sort), the mesh is rebuilt with read-backs and the query reruns.
//
// Output: every pair is found (the device buffer grows and the query reruns on overflow, which
// the device detects; a query whose candidates would exceed 14 per query triangle finds
// and tests them in rounds that reuse one candidate buffer, and KDET_FCL_CUDA_ROUND_CANDIDATES=k
// sets that limit, 0 for none, read at every query), then radix-sorted on the device: the result is sorted by (a, b), so it is
// deterministic but ordered differently from the CPU backend. With max_pairs = k > 0 the GPU
// computes all pairs and returns the first k of the sorted order (no early stop on the device).
// intersectSelfOnDevice/intersectMeshesOnDevice write that sorted order (as much as fits) into
// the caller's device buffer instead, with no read-back.
//
// Thread safety: one mutex serialises all GPU queries of the process.
//
// Device: one CUDA device of the process (setDevice, kdet_fcl::setCudaDevice; until one is chosen,
// KDET_FCL_CUDA_DEVICE=n, read at the first call, else 0). Every call makes it the calling
// thread's current device while it runs and then gives the thread back its own.
//
// Knobs (environment, for tests and tuning): KDET_FCL_CUDA_PAIR_CAPACITY=k caps the first pass's
// candidate and pair buffers at k (forces the overflow path); KDET_FCL_CUDA_TILE=1|4|8|16|32
// sets the lanes per query triangle of the candidate search (default 8) and
// KDET_FCL_CUDA_MINBLOCKS=1|8|12 its register cap (none, 64 or 40 registers; default 8 (64));
// KDET_FCL_CUDA_PLANE_FILTER=0 turns off the plane filter between the candidate search and the
// exact tests (default on, Predicate::Exact only; read at every query),
// KDET_FCL_CUDA_FILTER_DECIDES=0 makes that filter only drop pairs (default: it also finishes
// the pairs its floating-point filters decide, and only the others take the exact kernel),
// KDET_FCL_CUDA_FILTER_QUEUE=0 makes the deciding filter finish each pair in its own thread
// (default: the pairs that need its last two orientations are queued per warp and finished 32
// at a time) and KDET_FCL_CUDA_FILTER_MINBLOCKS=6 caps the filter kernel at 40 registers
// (default uncapped);
// these are read at every query; KDET_FCL_CUDA_SYNC_REHASH=1 makes every re-hash read its
// sizes back (the round-3 flow, for comparisons); KDET_FCL_CUDA_FULL_KEYS=1 uses 128-bit cell
// keys everywhere and KDET_FCL_CUDA_REHASH_CAP=k caps a re-hash at k entries and k cells (forces
// its fallback); these three are read at every build, for tests. KDET_FCL_CUDA_SPANS=0|1 forces
// the sub-cell span filter off or on (default: on in the warp-wide scan, chosen per query by the
// last query's candidate density in the tile scan; read at every query).
// KDET_FCL_CUDA_SCAN=tile runs the older per-query tiles instead of the warp-wide candidate
// search (read at every query; a mesh hashed while it is set lists each cell's triangles by size,
// which only the tile scan uses, and a build for the warp scan skips that sort); KDET_FCL_CUDA_WARP_LANES=1..32 forces the
// warp scan's lanes per query, KDET_FCL_CUDA_WARP_VISIT=k cuts its cells into visits of k entries
// and KDET_FCL_CUDA_WARP_TASKS=0 gives each warp one task instead of a counter to take them from;
// KDET_FCL_CUDA_SELF_CELLS=0|1 makes a self query scan every level from each triangle's own, or
// take the pairs within a level from the cells and scan only the coarser levels (default: the
// cells, in a kernel that runs beside the scan of the coarser levels, on a second stream, in a
// round that runs both; KDET_FCL_CUDA_SELF_OVERLAP=0 runs the cells' kernel first, then the
// scan, and takes the cells only for meshes of about 200k cell entries and more), and
// KDET_FCL_CUDA_CELL_ROWS=1|2|4|8|16|32 sets the entries per warp task of those cells' pairs
// (default 8 or 32 by the density and the entries), and KDET_FCL_CUDA_CELL_SPANS=0|1 whether
// they test sub-cell spans before boxes (default: where the scan does, and on meshes of many
// sparse cells; all read at every query, for tests and comparisons). Every query first checks
// every knob (checkKnobs), reading them all only when the KDET_FCL_CUDA_* setting differs from
// the last one it found good.
// KDET_FCL_CUDA_UPPER_LEVELS=0|1 (read at every build) makes the builds never or always record,
// per triangle, the levels above its own that hold a cell of its range, which self queries then
// skip without a lookup (upperLevels(); by default recorded while the mesh's last self query
// found at most 4 candidates per triangle). A counting build lists each cell's entries in three
// groups by where their sub-cell span lies on one axis (the cell's lower half, across its middle,
// its upper half), and the warp-wide scans visit only the groups a query's span can meet
// (cellLayout(); KDET_FCL_CUDA_CELL_GROUPS=0|1|2|3: none, x, y, z, default y; read at every
// counting build). The pairs are put
// in (a, b) order by counting them per segment of first indices as the exact tests emit them (a
// scan, a scatter, a rank within each segment) when there are at least kCountOrderMinPairs and no
// segment holds more than 1024 (KDET_FCL_CUDA_COUNT_ORDER_SEGMENT=n: n), else by the radix sort;
// KDET_FCL_CUDA_COUNT_ORDER=0 always sorts, =1 counts whatever the number of pairs (read at every
// query). The counting order is queued behind each pass's exact tests, sized on the device from
// the pass's counters, and a host result of at most kOneTripMaxChunks read-back chunks
// (KDET_FCL_CUDA_ONE_TRIP_COPY=k: k, 0 to 4; read at every query) is written by a kernel into
// the page-locked stage in the same trip, so the host waits once per pass for the counts
// and the pairs (any pair count; the radix sort still runs, after the counts, where a segment
// holds more than 1024; not for a host result after one of more than kOneTripMaxChunks
// chunks; KDET_FCL_CUDA_ONE_TRIP=0: the counts first, then the order; read at every query).
// A host query whose last host result (same meshes, same kind) held one to kOneTripMaxChunks
// read-back chunks of pairs instead has them delivered into device memory and read back by DMA
// queued right behind the counts, sized from that forecast (KDET_FCL_CUDA_ONE_TRIP_FORECAST=0:
// never; read at every query). The
// counting order's steps (the scan, the scatter, the rank and delivery, a small host result's
// straight into the stage) run as one cooperative launch whose grid meets between them: in one
// trip k blocks per SM, at most as many as fit at once (KDET_FCL_CUDA_FUSED_ORDER=k, default 2;
// 0: five launches; read at every query), after the counts as many as the pairs fill. The
// warp-wide candidate scan passes the entries of the levels above a query's own by the size
// rule without loading their diameters (KDET_FCL_CUDA_SIZE_BY_LEVEL=0 loads them), and a self
// query of a mesh of at most 1.5 vertices per triangle applies the adjacency rule by
// vertex index in phase 1, leaving the pairs that share a vertex by coordinates alone to the
// exact kernel (KDET_FCL_CUDA_INDEX_ADJACENCY=0|1: never, always; read at every query). Uploads of deformed
// vertices and new triangles go through pinned memory in 1 MiB chunks staged by up to 8 host
// threads (cuda/staged_upload.h); KDET_FCL_CUDA_UPLOAD_THREADS=n and KDET_FCL_CUDA_UPLOAD_CHUNK=b
// force the thread count and the chunk size (read at every upload). A vertex array of 256 KiB or
// more is instead registered as page-locked memory on its second upload (the registration kept
// with the HashedMesh, detail::HostPin, and dropped by it before that buffer can go;
// updateVertices writes into the same buffer) and copied by one DMA from there, with no staging
// copy (QueryProfile::pinned_uploads); KDET_FCL_CUDA_PIN_VERTICES=0 keeps the staged copy.
// Such a buffer of kCommitCopyMinBytes or more goes to the device while commitVertices checks
// it or updateVertices writes it, and the next query skips its upload (startCommitCopy,
// QueryProfile::commit_uploads; KDET_FCL_CUDA_COMMIT_COPY=0 leaves it to the query,
// KDET_FCL_CUDA_COMMIT_BATCH=b sets the copy's batch; both read at every such call).
// HashedMesh's passes in threads over such a buffer leave its lines out of the cores' private
// caches, which halved that DMA's rate (src/cpu/dma_passes.h, KDET_FCL_DMA_PASSES).
// The pairs come back through pinned memory in 256 KiB chunks, each appended to the result as it
// arrives; KDET_FCL_CUDA_DOWNLOAD_CHUNK=b sets that chunk size (read at every query). Into a
// result the caller keeps across frames (intersectSelf/intersectMeshes/intersectAll into a
// result), from 4 chunks and where the result held at least half as many pairs, 4 threads of a
// pool kept by the backend copy the chunks into the result's own storage
// (staging::pooledThreads; KDET_FCL_CUDA_DOWNLOAD_THREADS=n, 1..64, sets the threads). Every
// query first reads every knob (checkKnobs()): a value a knob does not accept (not 0 or 1 for a
// switch, not one of its numbers, out of its range, "abc") throws InvalidInputError naming the
// variable, before any work; unset or empty means the default.
//
// Self queries of unchanged meshes: a self query's pairs depend on the geometry, not the pose.
// A self query that finds the same device geometry as the mesh's previous self query keeps its
// result (a host copy of its pairs) with the mesh, and later self queries with the same
// predicate and max_pairs return it without device work while the geometry stays
// (QueryResult::kept, QueryProfile::self_cached): a rigid mesh's self query runs on the device
// twice, then never again. Any new geometry (updateVertices, setMesh, markDeformed) drops it; a
// mesh with new geometry at every self query never keeps one. The rule and its code are the CPU
// backend's (src/kept_self_result.h). KDET_FCL_CUDA_SELF_CACHE=0 turns this off (read at every
// query).
//
// Cache identity: an entry is reused when the HashedMesh address, version() and a fingerprint
// (sizes, array addresses, 64 sampled vertices and triangles) all match. A new HashedMesh built
// at a destroyed one's address with identical sizes and samples would be mistaken for it; making
// version() unique per process (a global counter) would close that gap.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "commit_copy.h"
#include "kdet_fcl/hashed_mesh.h"
#include "kdet_fcl/query.h"

namespace kdet_fcl {
namespace cuda {

/// The fewest pairs that are put in order by counting (see above): below, CUB's radix sort of the
/// 64-bit keys runs as one single-tile kernel (up to 256 threads x 9 keys = 2,304 keys on sm_90);
/// above that it takes a histogram, a scan and one onesweep pass per 8 key bits, 37 us for 3,384
/// pairs of the 20k cloth against 14 us for the count's scan, scatter and rank (H100, ncu;
/// benchmarks/RESULTS-gpu.md). It was 4,096 until 2026-11-24.
constexpr std::size_t kCountOrderMinPairs = 2048;

/// The bits of the counting order's segment index by default (KDET_FCL_CUDA_COUNT_ORDER_BITS sets
/// 12 to 20): a segment holds the pairs whose first index, with a joint query's kind above it,
/// agrees in its top that many bits. 17 bits (512 KB of segment counts): on an H100 the two
/// cloth-ball frames' order (445,614 pairs, ncu, one launch) took 72 us at 16 bits, whose
/// segments of 16 first indices hold about 50 pairs each, and 50 us at 18; 18 bits took those
/// frames to 255 B/tri, next to issue 4's 256 (benchmarks/RESULTS-gpu.md).
constexpr int kCountOrderSegmentBits = 17;

/// A query into a host result queues its pairs' order in the same trip as the pass's counts
/// (KDET_FCL_CUDA_ONE_TRIP) unless the last query into a host result delivered more pairs than
/// this many read-back chunks hold (KDET_FCL_CUDA_DOWNLOAD_CHUNK, 256 KiB: 32,768 pairs). A
/// large list is read back in chunks whose copies and events the host enqueues after the counts
/// (a few us each; the likely cost, not profiled); with the order queued after the counts, that
/// enqueueing overlaps the order's kernels. In two trips the joint two cloth-ball frames (13.6
/// chunks) were 0.046 ms faster, the joint two n-body frames (2.1 chunks) 0.018-0.038 ms
/// slower, the cloth ball (1.9) level (H100, benchmarks/RESULTS-gpu.md). Queries into a device
/// buffer always take one trip.
constexpr std::size_t kOneTripMaxChunks = 4;

/// intersectMeshes() on the backend's device (setDevice). Throws CudaError on a CUDA failure (the device caches are then
/// dropped, so a later call starts from scratch).
template <class S>
QueryResult intersectMeshes(const HashedMesh<S>& a, const HashedMesh<S>& b,
                            const QueryOptions& options);

/// intersectSelf() on the backend's device.
template <class S>
QueryResult intersectSelf(const HashedMesh<S>& mesh, const QueryOptions& options);

/// intersectMeshes() into `out`, a result kept across frames: the pairs are read back into its
/// storage (by several threads where staging::pooledThreads allows: enough pairs, and `out`
/// held at least half as many). On an exception `out`'s pairs are unspecified.
template <class S>
void intersectMeshes(const HashedMesh<S>& a, const HashedMesh<S>& b, const QueryOptions& options,
                     QueryResult& out);

/// intersectSelf() into `out`, as intersectMeshes into a result.
template <class S>
void intersectSelf(const HashedMesh<S>& mesh, const QueryOptions& options, QueryResult& out);

/// intersectSelfOnDevice() on the backend's device: the pairs written to `out` (device memory, checked), at
/// most `capacity` of them; the count is of every pair found. It shares the mesh's kept result
/// with intersectSelf (copied into `out` when it answers; the query that keeps one reads its
/// pairs back).
template <class S>
DevicePairsResult intersectSelfOnDevice(const HashedMesh<S>& mesh, const QueryOptions& options,
                                        TrianglePair* out, std::size_t capacity);

/// intersectMeshesOnDevice() on the backend's device, as intersectSelfOnDevice.
template <class S>
DevicePairsResult intersectMeshesOnDevice(const HashedMesh<S>& a, const HashedMesh<S>& b,
                                          const QueryOptions& options, TrianglePair* out,
                                          std::size_t capacity);

/// intersectAllOnDevice()'s joint form on the backend's device: as intersectJoint (the same conditions,
/// false and nothing done when they do not hold), with the pairs left in `out` (device memory,
/// checked): the first mesh's own pairs, then the second's, then those across, as many as fit.
template <class S>
bool intersectJointOnDevice(const HashedMesh<S>& a, const HashedMesh<S>& b,
                            const QueryOptions& options, TrianglePair* out, std::size_t capacity,
                            AllDevicePairsResult* result);

/// intersectAll()'s joint form on the backend's device. Returns false, doing nothing, unless it applies; the
/// caller then runs the three queries. It applies when every pair is asked for (max_pairs 0),
/// both meshes have triangles (together at most 150,000,000) and the inter query would decide on
/// both meshes' own coordinates (their poses map one frame onto the other exactly:
/// detail::relativePose's identity, e.g. two deforming meshes in world coordinates). Then both
/// are hashed as one: a cache entry of their own holds the second mesh's vertices after the
/// first's (its triangles' indices shifted), one build and one self query find every pair, the
/// adjacency rule applies only within a mesh, and the sorted pairs are dealt out to the three
/// results as they arrive (QueryProfile::joint), into the storage of `out`'s three results (by
/// several threads as intersectSelf into a result, when they held at least half as many pairs:
/// a result kept across frames). The pair sets and their order are those of the
/// three separate queries, for every predicate. Such a joint query keeps no self result
/// (QueryResult::kept): for rigid meshes whose selfs are kept, the three queries cost less.
/// KDET_FCL_CUDA_JOINT=0 turns it off (read at every call).
template <class S>
bool intersectJoint(const HashedMesh<S>& a, const HashedMesh<S>& b, const QueryOptions& options,
                    AllPairsResult* out);

/// Device-side times of the last GPU query (CUDA events), for the benchmarks. Recorded only while
/// setProfiling(true); all zero otherwise.
struct QueryProfile {
  double build_ms = 0;    ///< uploads + device re-hash of the meshes that changed (0: rigid)
  double query_ms = 0;    ///< pose mapping + candidate search + exact tests (all passes)
  double candidates_ms = 0;  ///< part of query_ms: pose mapping + candidate search (phase 1)
  double filter_ms = 0;   ///< part of query_ms: the plane filter between the phases (0: off)
  double output_ms = 0;   ///< sort of the pairs + device->host copy
  double total_ms = 0;    ///< first event to last
  int passes = 0;         ///< query passes (> 1 after an output overflow)
  int rounds = 0;         ///< rounds of the last pass (> 1: the candidates were found and tested
                          ///< in parts, KDET_FCL_CUDA_ROUND_CANDIDATES)
  int cell_rounds = 0;    ///< of them, the rounds of the cells' pairs alone, the others being
                          ///< the scan's (0: every round ran both; a self query with cells)
  std::size_t pairs = 0;  ///< pairs found (before max_pairs truncation)
  std::size_t candidates = 0;  ///< candidate pairs of phase 1 (before the plane filter)
  int candidate_key_bytes = 0;  ///< bytes each candidate took in the candidate buffer: 4 or 5
                                ///< where its key fits (KDET_FCL_CUDA_PACKED_CANDIDATES), else 8
  std::size_t exact_tests = 0;  ///< pairs that reached the exact kernel (after the plane filter;
                                ///< with filter_decides, only those its filters left undecided)
  int rehashes_async = 0;       ///< device re-hashes without a host read-back
  int builds_with_readback = 0; ///< builds that read the sizes back (first build, new topology,
                                ///< 128-bit keys, KDET_FCL_CUDA_SYNC_REHASH=1, or a fallback)
  int rehash_fallbacks = 0;     ///< re-hashes that did not fit and were rebuilt (query rerun)
  int rehash_outgrown = 0;      ///< of them, those whose entries or cells outgrew the arrays:
                                ///< their rebuild left half as much again of room in both
  int rehash_graphs = 0;        ///< re-hashes run as a CUDA graph (captured or replayed)
  int rehash_captures = 0;      ///< of them, those whose graph was captured (the mesh's first,
                                ///< or its sizes or buffers changed since the last capture)
  double rehash_capture_ms = 0; ///< host time of those captures with their instantiation (0
                                ///< where every re-hash replayed its graph)
  int device_allocations = 0;   ///< device buffers allocated or grown during the query (each a
                                ///< device synchronisation, a cudaFree and a cudaMalloc)
  int count_builds = 0;         ///< of the re-hashes without read-back, those that grouped their
                                ///< entries by counting in the cell table, not by a sort
                                ///< (meshes of up to KDET_FCL_CUDA_COUNT_BUILD_MAX triangles;
                                ///< KDET_FCL_CUDA_COUNT_BUILD=0 never, 1 always)
  int topology_compares = 0;    ///< meshes whose triangles were compared on the host with the
                                ///< device's copy: a new topology version (setMesh, a new mesh);
                                ///< never after updateVertices or markDeformed
  int pinned_uploads = 0;       ///< vertex uploads copied straight from the mesh's page-locked
                                ///< buffer (KDET_FCL_CUDA_PIN_VERTICES; arrays of 256 KiB and up)
  int host_registrations = 0;   ///< vertex buffers registered as page-locked memory during the
                                ///< query (cudaHostRegister, on a buffer's second upload; once
                                ///< per buffer, a refused one counted too)
  double host_register_ms = 0;  ///< host time of those registrations (0 where there were none)
  int commit_uploads = 0;       ///< vertex uploads skipped because commitVertices or
                                ///< updateVertices had copied the positions to the device as
                                ///< it passed over them (startCommitCopy,
                                ///< KDET_FCL_CUDA_COMMIT_COPY)
  double density_forecast = 0;  ///< the candidates per query triangle forecast for this query:
                                ///< those of the last query of its kind on the same meshes (a
                                ///< self query's, or the largest of the two meshes' last inter
                                ///< queries'), 0 for the first; it steers the lanes, the spans,
                                ///< the cells' rows and the rounds, never the pairs. A new mesh
                                ///< at a freed mesh's address starts at 0 (HashedMesh::identity)
  std::size_t pairs_forecast = 0;  ///< the pairs the query's last host result of its kind on the
                                   ///< same meshes (an inter query: the same second mesh) held,
                                   ///< which sizes an early read-back (forecast_copy); 0: none
  bool spans = false;  ///< the candidate search tested sub-cell spans (KDET_FCL_CUDA_SPANS)
  bool warp_scan = false;  ///< the candidate search ran the warp-wide scan (KDET_FCL_CUDA_SCAN)
  int warp_lanes = 0;      ///< its lanes per query triangle (KDET_FCL_CUDA_WARP_LANES; 0: tile)
  bool size_by_level = false;  ///< the warp-wide scan passed the entries above each query's own
                              ///< level by the size rule unloaded (KDET_FCL_CUDA_SIZE_BY_LEVEL)
  bool fixed_cells = false;  ///< the warp-wide scan took its cell ranges from fixed-point
                             ///< coordinates (KDET_FCL_CUDA_FIXED_CELLS; hashes whose level-0
                             ///< cell coordinates fit in 28 bits, as of their last build read
                             ///< back; the device decides on its own copy of the build info)
  bool filter_decides = false;  ///< the plane filter finished the pairs its filters decide
                                ///< (KDET_FCL_CUDA_FILTER_DECIDES; Predicate::Exact with the
                                ///< filter on)
  bool staged_pairs = false;  ///< the warp-wide phase 1 (warp scan, cells' pairs) emitted its
                              ///< candidates through a warp's stage in shared memory
                              ///< (KDET_FCL_CUDA_STAGE_PAIRS; the tile scan's never are)
  bool index_adjacency = false;  ///< a self query's phase 1 dropped the pairs sharing a vertex by
                                 ///< index only; those sharing one by coordinates alone were
                                 ///< candidates, dropped by the exact kernel
                                 ///< (KDET_FCL_CUDA_INDEX_ADJACENCY)
  bool warp_tasks = false;  ///< its warps took their queries from a counter (a grid of the
                            ///< resident warps; KDET_FCL_CUDA_WARP_TASKS=0: one warp per task)
  bool cells_by_size = false;  ///< the queried meshes' cells list their triangles by decreasing
                               ///< diameter (built for the tile scan, whose early exit needs it)
  bool self_cell_pairs = false;  ///< a self query took its same-level pairs from the cells and
                                 ///< scanned only coarser levels (KDET_FCL_CUDA_SELF_CELLS)
  std::size_t cell_candidates = 0;  ///< of `candidates`, those the cells gave (self_cell_pairs)
  int cell_rows = 0;  ///< entries per warp task of the cells' pairs (KDET_FCL_CUDA_CELL_ROWS)
  bool cell_spans = false;  ///< the cells' pairs tested sub-cell spans before boxes
                            ///< (KDET_FCL_CUDA_CELL_SPANS; unset: where `spans`, and on
                            ///< meshes of many sparse cells)
  bool self_overlap = false;  ///< the cells' pairs and the scan ran at the same time, on two
                              ///< streams, in some round (KDET_FCL_CUDA_SELF_OVERLAP)
  bool self_cached = false;  ///< a self query answered from the kept result of an unchanged mesh
                             ///< (no query on the device, all times 0; the device form copies the
                             ///< kept pairs into its buffer; KDET_FCL_CUDA_SELF_CACHE=0: never)
  bool joint = false;  ///< intersectAll hashed both meshes as one and ran one self query
                       ///< (KDET_FCL_CUDA_JOINT)
  bool pairs_counted = false;  ///< the pairs were put in order by counting them per segment of
                               ///< first indices, not by the radix sort (a segment of more than
                               ///< 1024, or, ordered after the counts (one_trip false), fewer
                               ///< than kCountOrderMinPairs pairs: the sort;
                               ///< KDET_FCL_CUDA_COUNT_ORDER =0: always the sort, =1: counted
                               ///< whatever the pair count).
                               ///< False when no pair was delivered (none found, or capacity 0)
  bool one_trip = false;  ///< the last pass queued the counting order behind its exact tests,
                          ///< sized on the device, so the host waited once for the counts and
                          ///< the ordered pairs (KDET_FCL_CUDA_ONE_TRIP; any pair count; not
                          ///< after a segment of more than 1024 pairs, nor for a host result
                          ///< after one of more than kOneTripMaxChunks read-back chunks).
                          ///< False as pairs_counted
  bool one_trip_copy = false;  ///< and a host result's pairs (at most kOneTripMaxChunks
                               ///< read-back chunks, KDET_FCL_CUDA_DOWNLOAD_CHUNK;
                               ///< KDET_FCL_CUDA_ONE_TRIP_COPY) came in that same trip, written
                               ///< by a kernel into the page-locked stage
  bool forecast_copy = false;  ///< or came by DMA queued in that trip behind the counts, sized
                               ///< from the pairs this query delivered last time (one to
                               ///< kOneTripMaxChunks read-back chunks;
                               ///< KDET_FCL_CUDA_ONE_TRIP_FORECAST), and held them all
  unsigned int order_blocks = 0;  ///< the counting order ran as one cooperative launch of this
                                  ///< many blocks (KDET_FCL_CUDA_FUSED_ORDER); 0: in five
                                  ///< launches, or not counted
};
void setProfiling(bool on);
QueryProfile lastQueryProfile();

/// Forces the next GPU query of `mesh` to treat it as deformed: re-upload its vertices and
/// re-hash on the device (what updateVertices() costs on the GPU path). For benchmarks, which
/// can then time a deforming frame on the same HashedMesh objects without copying new vertices
/// into them (updateVertices() itself only stores and validates them: the CPU re-hash is lazy).
template <class S>
void markDeformed(const HashedMesh<S>& mesh);

/// The smallest vertex buffer that commitVertices copies to the device while it checks it
/// (startCommitCopy): 1.5 MiB. On an H200's 16-thread host (kdet_bench's GPU frames, in one
/// process with and without the copy) the buffers of 1.8-13.5 MB gained 11-19 % a frame (the 1M
/// cloth 1.85-1.86 -> 1.58 ms); those of 0.5-1.2 MB moved by -5 to +4 %, within the runs'
/// spread: their check is too short to hide the copy, and the commit then waits for it
/// (benchmarks/RESULTS-gpu.md, "The commit's copy").
constexpr std::size_t kCommitCopyMinBytes = std::size_t(1536) << 10;

/// A copy of a vertex buffer of `mesh` (`bytes` at `buffer`, whose registration is `pin`) to the
/// device while commitVertices checks it or updateVertices writes it (src/commit_copy.h), or
/// nullptr where it would not pay or cannot be made: the buffer is smaller than
/// kCommitCopyMinBytes or not registered (detail::HostPin: from its second upload on), the
/// device holds no entry of `mesh` alone with as many vertices (one made by a query of it),
/// another thread is using the device at the moment (the call never waits for a query), or
/// KDET_FCL_CUDA_COMMIT_COPY=0 (read at every call; a value it does not accept is left for the
/// next query to report). KDET_FCL_CUDA_COMMIT_BATCH=b (4096 bytes to 1 GiB, read at every
/// call) sets the copy's batch (default detail::kCommitBatchBytes). The copy holds the backend
/// until finish(); on success the next query of `mesh` skips its vertex upload
/// (QueryProfile::commit_uploads). Never throws a CUDA error: a copy that fails leaves the
/// upload to the next query.
template <class S>
std::unique_ptr<detail::CommitCopy> startCommitCopy(const HashedMesh<S>& mesh, const void* buffer,
                                                    std::size_t bytes,
                                                    const detail::HostPin& pin);

/// Per triangle of `mesh`, the bits its last device build recorded for self queries: bit 0 set
/// (recorded), and bit k (1..15) set when level own + k holds a cell of the triangle's cell range
/// (levels above own + 15 are not recorded and always scanned). A self query scans only the
/// levels so marked, with no lookup on the others. Builds record them while the mesh's last self
/// query found at most 4 candidates per triangle (KDET_FCL_CUDA_UPPER_LEVELS=0|1: never, always;
/// read at every build). Empty when the mesh is not cached on the device on its own (an entry
/// another mesh left at its address counts as none), or its last build recorded nothing. For
/// tests.
template <class S>
std::vector<std::uint16_t> upperLevels(const HashedMesh<S>& mesh);

/// The cells of `mesh`'s last device build as the warp-wide scans see them, for tests: the axis
/// on which the build grouped each cell's entries (0, 1, 2; 3: not grouped, as a sort build or
/// KDET_FCL_CUDA_CELL_GROUPS=0 leaves them), each cell's first entry (cells + 1 values, the last
/// the entries' count), each grouped cell's ends of its groups 0 and 1 as offsets from its first
/// entry (empty when not grouped), and each entry's sub-cell span (detail::subcellSpan). On an
/// axis a, an entry's group is 0 when its span's high slab (bits 15 + 5a..) is below 8, 2 when
/// its low slab (bits 5a..) is 8 or more, else 1. Empty (axis 3, no cells) when the mesh is not
/// cached on the device on its own (as upperLevels) or its build was not stored whole.
struct CellLayout {
  int axis = 3;
  std::vector<std::uint32_t> cell_begin;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> split;
  std::vector<std::uint32_t> entry_span;
};
template <class S>
CellLayout cellLayout(const HashedMesh<S>& mesh);

/// Reads every environment knob of the CUDA backend (KDET_FCL_CUDA_*, README.md) and throws
/// InvalidInputError, naming the variable, its value and what it accepts, for a value it does
/// not accept (kdet_fcl/detail/knobs.h). Every query runs this first, so a bad knob fails the
/// query before any work. Needs no device (tests call it directly).
void checkKnobs();

/// Bytes of device memory the backend holds now (cached meshes + scratch buffers).
std::size_t deviceBytesInUse();

/// The same bytes, per buffer ("name bytes, ..."), for the benchmarks and tests.
std::string deviceMemoryReport();

/// Frees every cached mesh and scratch buffer (the next query re-uploads what it needs).
void releaseDeviceMemory();

/// Makes CUDA device `device` the backend's (kdet_fcl::setCudaDevice): throws InvalidInputError
/// unless it exists. A change drops everything the backend holds on the old device (meshes,
/// buffers, streams), so that the next call starts on the new one. Every call of the backend
/// makes its device the calling thread's current device for its duration and then gives the
/// thread back its own (DeviceScope in cuda_backend.cu).
void setDevice(int device);

/// The backend's device: setDevice()'s choice, else KDET_FCL_CUDA_DEVICE, else 0 (throws
/// InvalidInputError when that knob names a device that does not exist).
int currentDevice();

}  // namespace cuda
}  // namespace kdet_fcl
