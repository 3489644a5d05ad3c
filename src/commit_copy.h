#pragma once
// A vertex buffer copied to the device while commitVertices checks it, or while updateVertices
// writes it.
//
// In kdet_bench's GPU frame of a deforming mesh, commitVertices checks the positions on the host
// and the next query copies them to the device by DMA from the buffer's registration
// (detail::HostPin): on the 16-thread host of an H200, the 1M cloth's 13.5 MB took 0.31-0.43 ms
// to check and about 0.26 ms to copy, one after the other. Here the check goes through the buffer
// in pieces (at most kCommitPieceBytes, taken in address order by its threads), and the run of
// pieces found finite from the start of the buffer goes to the device as it grows (one copy per
// batch of it, kCommitBatchBytes by default, and the rest at the end), while the later pieces are
// still being checked. updateVertices, which checks the new positions first and then copies them
// into the registered buffer, sends the run of pieces written in the same way.
// The backend (the CUDA one: cuda_backend.h, startCommitCopy) decides whether to take the
// buffer; the pass decides what it may send, and reports its verdict:
//   - on success the device holds the new positions, and the next query skips their upload;
//   - on failure (commitVertices: a coordinate that is not finite) the commit throws as always,
//     and the backend forgets what the device held, so that the next query uploads the positions
//     the mesh kept.
// Either way, no copy reads the buffer once the call has returned (finish() waits for them).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/vec3.h"

namespace kdet_fcl {
namespace detail {

/// Pieces of the buffer that the check takes one at a time (a thread's unit of work), at most;
/// smaller where the copy's batch is.
constexpr std::size_t kCommitPieceBytes = std::size_t(256) << 10;
/// By default, the checked run from the buffer's start goes to the device whenever it has grown
/// by this much since the last copy (and in full once the check is done); a copy may ask for
/// another batch (CommitCopy::batchBytes). On an H200's host, 128 KiB batches made the 90k
/// cloth's commit 0.01-0.03 ms shorter than 1 MiB batches, and the 200k and 250k cloths' frames
/// up to 6 %; at 13.5 MB every batch was level (benchmarks/RESULTS-gpu.md, "The commit's copy").
constexpr std::size_t kCommitBatchBytes = std::size_t(128) << 10;

/// A backend's copy of the buffer of one commitVertices or updateVertices (see above).
class CommitCopy {
 public:
  virtual ~CommitCopy() = default;
  /// Copies bytes [offset, offset + bytes) of the buffer, which the pass has finished (checked
  /// and found finite, or written). Called by one thread at a time, for consecutive ranges from
  /// offset 0 on. Never throws: a copy that fails makes finish() forget the device's positions.
  virtual void piece(std::size_t offset, std::size_t bytes) noexcept = 0;
  /// The pass's verdict, once it is over: `ok` with the mesh's new version() (the buffer is now
  /// the mesh's positions), or not ok (the commit throws). Waits until no copy reads the buffer.
  /// A copy dropped without finish() counts as not ok.
  virtual void finish(bool ok, std::uint64_t version) noexcept = 0;
  /// The bytes by which the finished run grows between two copies (rounded up to whole pieces;
  /// the pieces are no larger than this).
  virtual std::size_t batchBytes() const noexcept { return kCommitBatchBytes; }
};

/// The check of commitVertices with a copy: the bounds of `v` into *out and true when every
/// coordinate is finite, false otherwise; meanwhile the run of finite pieces from the start goes
/// to copy.piece() (see above), a batch at a time. `threads` threads take the pieces in address
/// order; `demote`: each line leaves the reading core's private caches once read
/// (cpu/dma_passes.h). The same bounds and verdict as the check without a copy.
/// (hashed_mesh.cpp; float and double.)
template <class S>
bool checkedPieces(const std::vector<Vec3<S>>& v, int threads, bool demote, CommitCopy& copy,
                   Aabb<double>* out);

/// The copy of updateVertices with a copy to the device: `src` (checked already) into `dst` (as
/// many), in pieces taken in address order by `threads` threads, by non-temporal stores where
/// `stream` (cpu::streamCopy); meanwhile the run of pieces written from the start goes to
/// copy.piece(), as checkedPieces sends it. (hashed_mesh.cpp; float and double.)
template <class S>
void copiedPieces(const std::vector<Vec3<S>>& src, Vec3<S>* dst, int threads, bool stream,
                  CommitCopy& copy);

}  // namespace detail
}  // namespace kdet_fcl
