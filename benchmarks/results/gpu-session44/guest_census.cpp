// Census (session 44, CPU only): each triangle also stored, as a guest, in the cells of the next
// finer occupied level; a cell then gives its native-native and native-guest pairs (guest-guest
// pairs skipped by order), and the scan runs from a triangle's level to the levels two or more
// above it only. Per mesh: the native and guest entries, the present scheme's visits (the cells'
// pairs and the scan's entries), and the guests' scheme's: visits, and of the canonical ones
// those whose sub-cell spans overlap (what reaches the box test), against the present scheme's
// canonical span passes. Build and run: census_common.h.
#include <unordered_map>

#include "census_common.h"

using namespace kdet_fcl::detail;

int main(int argc, char** argv) {
  census::forEachSelfMesh(argc, argv, [](const std::string& name, const auto& m,
                                         const census::Hash& h) {
    const GridParams g = h.grid;
    const int top = h.top_level;
    const std::size_t n = m.triangles.size();
    std::vector<int> finer(top + 1, -1);  // the next finer occupied level
    for (int l = 0; l <= top; ++l)
      for (int k = l - 1; k >= 0; --k)
        if (h.levelOccupied(k)) {
          finer[l] = k;
          break;
        }
    using Lists = std::pair<std::vector<std::uint32_t>, std::vector<std::uint32_t>>;  // native, guest
    std::vector<std::unordered_map<CellKey, Lists, census::KeyHash>> cells(top + 1);
    double native_entries = 0, guest_entries = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const auto put = [&](int l, bool guest) {
        census::forEachCell(h.boxes[i], l, g, [&](const CellId& c) {
          Lists& lists = cells[l][makeCellKey(l, c.x, c.y, c.z)];
          (guest ? lists.second : lists.first).push_back(std::uint32_t(i));
          (guest ? guest_entries : native_entries) += 1;
        });
      };
      put(h.level[i], false);
      if (finer[h.level[i]] >= 0) put(finer[h.level[i]], true);
    }
    const auto spanIn = [&](std::uint32_t t, const CellId& c) {
      return subcellSpan(h.boxes[t], c.level, c.x, c.y, c.z, g);
    };
    const auto canonSpans = [&](std::uint32_t a, std::uint32_t b, const CellId& c) {
      return isCanonicalCell(h.boxes[a], h.boxes[b], levelScale(c.level), g, c.x, c.y, c.z) &&
             subcellSpansOverlap(spanIn(a, c), spanIn(b, c));
    };
    // The cells: present (native pairs) and with guests (native-native and native-guest).
    double now_cells = 0, now_pass = 0, cells_visits = 0, cells_pass = 0;
    for (int l = 0; l <= top; ++l)
      for (const auto& kv : cells[l]) {
        const CellId c = cellOfKey(kv.first);
        const auto& a = kv.second.first;
        const auto& b = kv.second.second;
        const double na = a.size(), nb = b.size();
        now_cells += na * (na - 1) / 2;
        cells_visits += na * (na - 1) / 2 + na * nb;
        for (std::size_t p = 0; p < a.size(); ++p) {
          for (std::size_t q = p + 1; q < a.size(); ++q) {
            const bool pass = canonSpans(a[p], a[q], c);
            now_pass += pass;
            cells_pass += pass;
          }
          for (std::uint32_t t : b) cells_pass += canonSpans(a[p], t, c);
        }
      }
    // The scan: present (every coarser level) and with guests (from two occupied levels up).
    double now_scan = 0, scan_visits = 0, scan_pass = 0;
    for (std::size_t i = 0; i < n; ++i) {
      int next = -1;  // the next occupied level above: its pairs come from the guests
      for (int l = h.level[i] + 1; l <= top; ++l)
        if (h.levelOccupied(l)) {
          next = l;
          break;
        }
      for (int l = h.level[i] + 1; l <= top; ++l) {
        if (!h.levelOccupied(l)) continue;
        census::forEachCell(h.boxes[i], l, g, [&](const CellId& c) {
          const auto it = cells[l].find(makeCellKey(l, c.x, c.y, c.z));
          if (it == cells[l].end()) return;
          for (std::uint32_t j : it->second.first) {
            const bool pass = canonSpans(std::uint32_t(i), j, c);
            now_scan += 1;
            now_pass += pass;
            if (l == next) continue;
            scan_visits += 1;
            scan_pass += pass;
          }
        });
      }
    }
    std::printf("%s: entries native %.0f guest %.0f | now: visits cells %.0f + scan %.0f = %.0f, "
                "canonical span passes %.0f | guests: visits cells %.0f + scan %.0f = %.0f, "
                "canonical span passes %.0f\n",
                name.c_str(), native_entries, guest_entries, now_cells, now_scan,
                now_cells + now_scan, now_pass, cells_visits, scan_visits,
                cells_visits + scan_visits, cells_pass + scan_pass);
  });
  return 0;
}
