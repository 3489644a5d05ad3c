#pragma once
// The CPU hierarchical spatial hash of one mesh, built in the mesh's own frame.

#include <cstdint>
#include <vector>

#include "kdet_fcl/detail/aabb.h"
#include "kdet_fcl/detail/hierarchy.h"
#include "kdet_fcl/hashed_mesh.h"
#include "kdet_fcl/triangle_mesh.h"

namespace kdet_fcl {
namespace detail {

/// Owning CPU structure. Per triangle: box, enclosing diameter, level. Cells: an open-addressing
/// table of full 128-bit keys, each slot pointing at a contiguous run of `entries`, sorted by
/// decreasing diameter (ties: increasing id) inside a cell. Memory is linear in the triangle count.
template <class S>
class HierarchicalHash {
 public:
  /// One (cell, triangle) entry. The triangle's box and diameter are copied next to its id so
  /// that scanning a cell reads memory sequentially.
  struct Entry {
    Aabb<double> box;
    double diameter;
    std::uint32_t id;
    /// Bit a set: this cell is the first of the triangle's cells along axis a. Then the
    /// canonical-cell test of a lookup (see scan.h) is three integer comparisons.
    std::uint8_t lo_mask;
  };

  struct Slot {
    CellKey key;
    std::uint32_t begin;
    std::uint32_t count;  // 0: empty slot (an occupied cell always holds a triangle)
  };

  /// Builds from a mesh's local coordinates (validated by the caller). On an exception (only
  /// std::bad_alloc or a too-large mesh) the object is left empty; HashedMesh builds into a spare
  /// one so that its own state survives.
  void build(const std::vector<Vec3<S>>& vertices, const std::vector<Triangle>& triangles,
             int threads);
  void build(const TriangleMesh<S>& mesh, int threads) { build(mesh.vertices, mesh.triangles, threads); }

  /// The slot of a cell, or nullptr when the cell is empty.
  const Slot* find(const CellKey& key) const {
    if (slots_.empty()) return nullptr;
    std::uint64_t i = hashCellKey(key) & mask_;
    while (true) {
      const Slot& s = slots_[i];
      if (s.count == 0) return nullptr;
      if (s.key == key) return &s;
      i = (i + 1) & mask_;
    }
  }

  std::size_t numTriangles() const { return diameter.size(); }
  bool empty() const { return diameter.empty(); }
  bool levelOccupied(int l) const { return (level_mask >> l) & 1u; }
  HierarchyStats stats() const;
  /// Bytes allocated by this structure.
  std::size_t memoryBytes() const;

  // Per triangle (local frame).
  std::vector<Aabb<double>> boxes;
  std::vector<double> diameter;
  std::vector<std::uint8_t> level;
  // The hierarchy.
  GridParams grid;
  Aabb<double> bounds{};   // box of all triangles
  std::uint64_t level_mask = 0;
  int top_level = 0;
  double d_min = 0, d_max = 0;
  std::vector<Entry> entries;

 private:
  std::vector<Slot> slots_;
  // Build scratch, kept so that rebuilding a deforming mesh reuses its memory.
  std::vector<std::uint64_t> scratch_offset_;
  std::vector<std::uint32_t> scratch_slot_, scratch_order_, scratch_fill_;
  std::vector<std::uint8_t> scratch_mask_;
  std::uint64_t mask_ = 0;
  std::size_t cells_ = 0;
};

}  // namespace detail
}  // namespace kdet_fcl
