// Census (session 45, CPU only): the cells' pairs (every pair of entries of one cell, the
// self query's same-level candidates) that cells grouped on one axis (as the counting build's
// KDET_FCL_CUDA_CELL_GROUPS) could skip: those of an entry wholly in the cell's lower half (its
// sub-cell span's high slab below 8) with one wholly in its upper half (low slab 8 or more),
// whose spans cannot overlap; and, of the pairs left, those whose spans overlap (what the
// kernel's span test passes either way).
// Build and run: ../gpu-session44/census_common.h (this file's path in its build line).
#include "../gpu-session44/census_common.h"

using namespace kdet_fcl::detail;

int main(int argc, char** argv) {
  census::forEachSelfMesh(argc, argv, [&](const std::string& name, const auto& m,
                                          const census::Hash& h) {
    const std::size_t n = m.triangles.size();
    const GridParams& g = h.grid;
    std::size_t cell_count = 0;
    double pairs = 0, spans = 0, skip[3] = {};
    for (const census::CellMap& level_cells : census::cellsOf(h))
      for (const auto& [key, e] : level_cells) {
        const CellId c = cellOfKey(key);
        ++cell_count;
        std::vector<std::uint32_t> sp(e.size());
        for (std::size_t k = 0; k < e.size(); ++k)
          sp[k] = subcellSpan(h.boxes[e[k]], c.level, c.x, c.y, c.z, g);
        for (std::size_t a = 0; a < e.size(); ++a)
          for (std::size_t b = a + 1; b < e.size(); ++b) {
            pairs += 1;
            spans += subcellSpansOverlap(sp[a], sp[b]);
            for (int x = 0; x < 3; ++x) {
              const bool a_low = census::spanHi(sp[a], x) < 8;
              const bool a_high = census::spanLo(sp[a], x) >= 8;
              const bool b_low = census::spanHi(sp[b], x) < 8;
              const bool b_high = census::spanLo(sp[b], x) >= 8;
              skip[x] += (a_low && b_high) || (a_high && b_low);
            }
          }
      }
    std::printf("== %s: %zu triangles, %zu cells, cell pairs %.0f, spans overlapping %.0f; pairs of "
                "the lower and upper groups: x %.0f (%.1f %%), y %.0f (%.1f %%), z %.0f (%.1f %%)\n",
                name.c_str(), n, cell_count, pairs, spans, skip[0], 100 * skip[0] / pairs, skip[1],
                100 * skip[1] / pairs, skip[2], 100 * skip[2] / pairs);
  });
  return 0;
}
