#pragma once
// The result of a mesh's self query, kept while the mesh's geometry does not change. Shared by
// the CPU backend (one per HashedMesh) and the CUDA backend (one per cached device mesh).

#include <cstdint>
#include <mutex>
#include <vector>

#include "kdet_fcl/query.h"
#include "kdet_fcl/detail/knobs.h"

namespace kdet_fcl {
namespace detail {

/// A self query's pairs depend on the mesh's geometry alone, not on its pose. The rule:
///  - A self query that sees the same geometry as the mesh's previous self query keeps its
///    result, with its predicate and max_pairs.
///  - A later self query of that geometry with the same predicate and max_pairs returns the kept
///    result: no work runs, QueryResult::kept is true, the statistics are zero.
///  - Any other geometry drops it. A mesh with new geometry at every self query (a deforming
///    mesh) never keeps one, so it never pays for the copy.
/// A geometry is a number that changes with every change of geometry: HashedMesh::version() on
/// the CPU, the device cache's count of builds on the GPU. Thread-safe: concurrent self queries
/// of one mesh may each compute; each keeps or answers under the mutex.
class KeptSelfResult {
 public:
  /// `knob`: the environment variable whose value 0 turns keeping off (KDET_FCL_CPU_SELF_CACHE
  /// for the CPU backend, KDET_FCL_CUDA_SELF_CACHE for the CUDA one and the LBVH baseline). It is
  /// read at every query, so a test or a benchmark can change it between queries; a value other
  /// than 0 or 1 throws InvalidInputError from the query.
  explicit KeptSelfResult(const char* knob) : knob_(knob) {}

  /// Whether the knob `knob` lets a mesh keep its self result: unset, empty or 1 yes, 0 no; any
  /// other value throws InvalidInputError (kdet_fcl/detail/knobs.h).
  static bool on(const char* knob) { return switchKnob(knob, true); }

  /// What find() decided for the query: whether offer() keeps its result, and for which geometry.
  struct Ticket {
    bool keep = false;
    std::uint64_t geometry = 0;
  };

  /// At the start of a self query of `geometry` with `options`. Returns true, with the kept
  /// result in *out, when that answers the query. Otherwise the query runs, and its result goes
  /// to offer() with *ticket. With the knob at 0, nothing is answered or kept.
  bool find(std::uint64_t geometry, const QueryOptions& options, QueryResult* out,
            Ticket* ticket) {
    const bool enabled = on(knob_);
    std::lock_guard<std::mutex> lock(mutex_);
    ticket->geometry = geometry;
    ticket->keep = enabled && seen_ == geometry;  // the same geometry as the previous self query
    seen_ = geometry;
    if (!ticket->keep || !cached_ || geometry_ != geometry ||
        predicate_ != options.predicate || max_pairs_ != options.max_pairs)
      return false;
    *out = result_;
    return true;
  }

  /// After the query that find() let run: keeps `result` when the ticket says so and no self
  /// query has seen another geometry since.
  void offer(const Ticket& ticket, const QueryOptions& options, const QueryResult& result) {
    if (!ticket.keep) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (seen_ != ticket.geometry) return;
    result_ = result;
    result_.stats = QueryStats{};  // answering from it does no work
    result_.kept = true;
    geometry_ = ticket.geometry;
    predicate_ = options.predicate;
    max_pairs_ = options.max_pairs;
    cached_ = true;
  }

  /// Frees a kept result (after a change of geometry, which would never be answered from it).
  void drop() noexcept {
    std::lock_guard<std::mutex> lock(mutex_);
    cached_ = false;
    std::vector<TrianglePair>().swap(result_.pairs);
  }

 private:
  const char* knob_;
  std::mutex mutex_;
  std::uint64_t seen_ = ~std::uint64_t{0};  // the geometry of the previous self query
  bool cached_ = false;
  std::uint64_t geometry_ = 0;
  Predicate predicate_ = Predicate::Exact;
  std::size_t max_pairs_ = 0;
  QueryResult result_;
};

}  // namespace detail
}  // namespace kdet_fcl
