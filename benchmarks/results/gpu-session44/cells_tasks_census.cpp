// Census (session 44, CPU only): the warp tasks of the cells' pairs, rows (8 per task, the
// default on crowded meshes, and 32) against windows of 32 entries (call 1's kernel). A row of a
// cell of m entries has about m / 2 partners (its cyclic list), and a rows' task tests its rows'
// partners 32 at a time (rounds); a window's task takes one shuffle step per partner position
// inside the window (as many as the longest run of later entries of one cell there), and 32
// steps at most for each later window of its last cell. Per form: the tasks, the rounds or steps
// in all, the longest task, the mean per resident warp (4,224: 132 SMs x 8 blocks x 4 warps) and
// the tail (the longest task against that mean). Cells in the CPU table's order (the device's
// order differs, the cells' sizes do not). Build and run: census_common.h.
#include <algorithm>
#include <cmath>

#include "census_common.h"

int main(int argc, char** argv) {
  census::forEachSelfMesh(argc, argv, [](const std::string& name, const auto&,
                                         const census::Hash& h) {
    std::vector<std::uint32_t> begin, end;  // the cells' entries, contiguous
    std::uint32_t at = 0;
    for (const auto* t : census::tablesOf(h))
      for (const auto& sl : t->slots)
        if (sl.count) {
          begin.push_back(at);
          at += sl.count;
          end.push_back(at);
        }
    const std::uint32_t entries = at;
    std::vector<std::uint32_t> cell_of(entries);
    for (std::size_t c = 0; c < begin.size(); ++c)
      for (auto e = begin[c]; e < end[c]; ++e) cell_of[e] = std::uint32_t(c);
    constexpr double kWarps = 4224;
    const auto report = [&](const char* form, std::size_t tasks, double total, double longest) {
      std::printf("%s %s: tasks %zu, %s %.0f, longest %.0f, mean per warp %.1f, tail x%.1f\n",
                  name.c_str(), form, tasks, *form == 'r' ? "rounds" : "steps", total, longest,
                  total / kWarps, longest / (total / kWarps));
    };
    for (std::uint32_t rows : {8u, 32u}) {
      double total = 0, longest = 0;
      std::size_t tasks = 0;
      for (std::uint32_t first = 0; first < entries; first += rows, ++tasks) {
        double visits = 0;
        for (std::uint32_t k = first; k < std::min(entries, first + rows); ++k) {
          const std::uint32_t c = cell_of[k], m = end[c] - begin[c], a = k - begin[c];
          visits += (m - 1) / 2 + ((m % 2 == 0 && a < m / 2) ? 1 : 0);
        }
        const double rounds = std::ceil(visits / 32);
        total += rounds;
        longest = std::max(longest, rounds);
      }
      report(rows == 8 ? "rows 8" : "rows 32", tasks, total, longest);
    }
    double total = 0, longest = 0;
    std::size_t tasks = 0;
    for (std::uint32_t first = 0; first < entries; first += 32, ++tasks) {
      double steps = 0;
      for (std::uint32_t e = first; e < std::min(entries, first + 32); ++e)
        steps = std::max(steps, double(std::min(first + 32, end[cell_of[e]]) - e - 1));
      const std::uint32_t last_end = end[cell_of[std::min(entries, first + 32) - 1]];
      for (std::uint32_t next = first + 32; next < last_end; next += 32)
        steps += std::min(32u, last_end - next);
      total += steps;
      longest = std::max(longest, steps);
    }
    report("windows", tasks, total, longest);
  });
  return 0;
}
