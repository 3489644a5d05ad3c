#include "cpu/hierarchical_hash.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "cpu/parallel.h"
#include "kdet_fcl/detail/enclosing_sphere.h"
#include "kdet_fcl/errors.h"

namespace kdet_fcl {
namespace detail {

namespace {

/// Bits of the cell key per coordinate, as makeCellKey packs them (decoded by cellOfKey).
static_assert(kCellBits == 40, "cellOfKey decodes 40-bit coordinates");

/// The cell coordinates of a key (the inverse of makeCellKey).
inline void cellOfKey(const CellKey& k, std::int64_t c[3]) {
  constexpr std::uint64_t m40 = (std::uint64_t(1) << 40) - 1;
  c[0] = std::int64_t((k.hi >> 16) & m40);
  c[1] = std::int64_t(((k.hi & 0xFFFFull) << 24) | (k.lo >> 40));
  c[2] = std::int64_t(k.lo & m40);
}

/// Triangles per hash bucket, about (a bucket is a fixed range of home slots whose records are
/// sorted together in cache); the bucket count is a power of two >= n / kTrianglesPerBucket.
constexpr std::size_t kTrianglesPerBucket = 256;
/// Digits of the counting sort inside a bucket (the hash bits just below the bucket's).
constexpr int kSubBits = 9;
/// Records ahead whose triangle box the last pass prefetches.
constexpr std::uint32_t kPrefetch = 24;

inline void prefetch(const void* p) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(p);
#else
  (void)p;
#endif
}

/// Smallest chunk of the per-triangle passes.
constexpr std::size_t kMinTriangleChunk = 2048;

}  // namespace

template <class S>
void HierarchicalHash<S>::clear() {
  boxes.clear();
  diameter.clear();
  level.clear();
  upper_.clear();
  lower_.clear();
  split_ = 0;
  covered_from_ = kNoTable;
  grid = GridParams{};
  bounds = Aabb<double>{};
  level_mask = 0;
  top_level = 0;
  d_min = d_max = d_smallest = 0;
}

template <class S>
void HierarchicalHash<S>::build(const std::vector<Vec3<S>>& vertices,
                                const std::vector<Triangle>& triangles, int threads,
                                int from_level) {
  try {
    upper_.clear();  // (keeps the buffers)
    lower_.clear();
    split_ = 0;
    covered_from_ = kNoTable;
    perTriangle(vertices, triangles, threads);
    if (from_level < kNoTable) {
      split_ = std::max(from_level, 0);
      buildTable(upper_, split_, kMaxLevels - 1, threads);
      covered_from_ = split_;
    }
  } catch (...) {
    clear();
    throw;
  }
}

template <class S>
void HierarchicalHash<S>::cover(int from_level, int threads) {
  from_level = std::max(from_level, 0);
  if (from_level >= covered_from_) return;
  if (covered_from_ == kNoTable) {  // no table yet: the first one, from this level up
    try {
      split_ = from_level;
      buildTable(upper_, split_, kMaxLevels - 1, threads);
    } catch (...) {
      upper_.clear();
      split_ = 0;
      throw;
    }
    covered_from_ = split_;
  } else {  // the levels below the first table: the second one (upper_ is not touched)
    try {
      buildTable(lower_, 0, split_ - 1, threads);
    } catch (...) {
      lower_.clear();
      throw;
    }
    covered_from_ = 0;
  }
}

namespace {
/// Chunks of the per-triangle passes: a few per thread (scheduled dynamically).
struct Chunking {
  std::size_t chunks, size;
};
Chunking chunking(std::size_t n, int threads) {
  const int want = cpu::resolveThreads(threads, std::numeric_limits<std::size_t>::max());
  const std::size_t chunks =
      std::max<std::size_t>(1, std::min((n + kMinTriangleChunk - 1) / kMinTriangleChunk,
                                        std::size_t(4) * std::size_t(want)));
  return {chunks, (n + chunks - 1) / chunks};
}
}  // namespace

// The per-triangle data, in two parallel passes over chunks of triangles: box and enclosing
// diameter (per chunk: bounds and the diameters' range), then, once the grid is known, the level.
template <class S>
void HierarchicalHash<S>::perTriangle(const std::vector<Vec3<S>>& vertices,
                                      const std::vector<Triangle>& triangles, int threads) {
  const std::size_t n = triangles.size();
  // resize, not assign: every element is overwritten below, and a rebuild of a mesh of the same
  // size (a deforming mesh) then touches no allocator and zeroes nothing.
  boxes.resize(n);
  diameter.resize(n);
  level.resize(n);
  level_mask = 0;
  top_level = 0;
  d_min = d_max = d_smallest = 0;
  bounds = Aabb<double>{};
  grid = GridParams{};
  if (n == 0) return;

  const Chunking ck = chunking(n, threads);
  const std::size_t chunks = ck.chunks, chunk_size = ck.size;
  const Vec3<S>* v = vertices.data();
  const Triangle* t = triangles.data();

  // ---- 1. boxes, diameters, bounds ----
  struct Partial {
    Aabb<double> box;
    double d_max, d_min_pos, d_smallest;
    std::uint64_t level_mask;
  };
  std::vector<Partial> part(chunks);
  cpu::forEachChunk(chunks, threads, [&](std::size_t c) {
    const std::size_t b = c * chunk_size, e = std::min(n, b + chunk_size);
    const double inf = std::numeric_limits<double>::infinity();
    Partial p{{{inf, inf, inf}, {-inf, -inf, -inf}}, 0.0, inf, inf, 0};
    for (std::size_t i = b; i < e; ++i) {
      const Vec3<S>&p0 = v[t[i][0]], &p1 = v[t[i][1]], &p2 = v[t[i][2]];
      const Aabb<double> box = triangleBox<double>(p0, p1, p2);
      const double d = enclosingDiameter(p0, p1, p2);
      boxes[i] = box;
      diameter[i] = d;
      for (int a = 0; a < 3; ++a) {
        p.box.lo[a] = std::min(p.box.lo[a], box.lo[a]);
        p.box.hi[a] = std::max(p.box.hi[a], box.hi[a]);
      }
      p.d_max = std::max(p.d_max, d);
      p.d_smallest = std::min(p.d_smallest, d);
      if (d > 0) p.d_min_pos = std::min(p.d_min_pos, d);
    }
    part[c] = p;
    return true;
  });
  bounds = part[0].box;
  double dmin_pos = part[0].d_min_pos;
  d_max = part[0].d_max;
  d_smallest = part[0].d_smallest;
  for (std::size_t c = 1; c < chunks; ++c) {
    for (int a = 0; a < 3; ++a) {
      bounds.lo[a] = std::min(bounds.lo[a], part[c].box.lo[a]);
      bounds.hi[a] = std::max(bounds.hi[a], part[c].box.hi[a]);
    }
    d_max = std::max(d_max, part[c].d_max);
    dmin_pos = std::min(dmin_pos, part[c].d_min_pos);
    d_smallest = std::min(d_smallest, part[c].d_smallest);
  }
  d_min = std::isfinite(dmin_pos) ? dmin_pos : 0.0;
  const double extent = std::max({bounds.hi.x - bounds.lo.x, bounds.hi.y - bounds.lo.y,
                                  bounds.hi.z - bounds.lo.z});
  // Level-0 cells are as small as the smallest triangle, but not so small that cell coordinates
  // would overflow the key (a point-like triangle must not make the grid infinitely fine).
  double cell0 = d_min;
  const double floor_cell = std::ldexp(extent, -kCellRange);
  if (cell0 < floor_cell) cell0 = floor_cell;
  if (!(cell0 > 0) || !std::isfinite(1.0 / cell0)) cell0 = extent > 0 ? extent : 1.0;
  for (int a = 0; a < 3; ++a) grid.origin[a] = bounds.lo[a];
  grid.cell0 = cell0;
  grid.inv_cell0 = 1.0 / cell0;
  grid.num_levels = kMaxLevels;
  top_level = levelFor(d_max, grid);
  grid.num_levels = top_level + 1;

  // ---- levels ----
  cpu::forEachChunk(chunks, threads, [&](std::size_t c) {
    const std::size_t b = c * chunk_size, e = std::min(n, b + chunk_size);
    std::uint64_t mask = 0;
    for (std::size_t i = b; i < e; ++i) {
      const int l = levelFor(diameter[i], grid);
      level[i] = std::uint8_t(l);
      mask |= std::uint64_t(1) << l;
    }
    part[c].level_mask = mask;
    return true;
  });
  for (std::size_t c = 0; c < chunks; ++c) level_mask |= part[c].level_mask;
}

// A cell table of the triangles on levels [lo, hi], in passes over triangles, then over hash
// buckets (every pass parallel, every parallel pass writing disjoint memory, so the result does
// not depend on the thread count):
//  2. per (chunk, bucket): how many of the chunk's (cell, triangle) records hash into the bucket.
//     A bucket is a range of home slots: the top bits of the key's hash;
//  3. per triangle: the records, scattered to their buckets (stable);
//  4. per bucket, in cache: sort the records by (hash, key, decreasing diameter, increasing id):
//     a counting sort on the next hash bits, then the tiny runs that share a digit. This groups
//     each cell's records, largest triangle first, and orders the cells by home slot;
//  5. placing the cells by linear probing in increasing home order writes the table
//     sequentially: per bucket, where its cells end if none overflowed into it, then (serially,
//     per bucket) the overflow each bucket passes on, then per bucket the slots and the entries.
// (Pass 1 is perTriangle.) The order of the records after pass 4 is a total order on (cell,
// triangle), so the entries and the table are a function of the mesh and [lo, hi] alone. Every
// buffer is reused, and nothing is zeroed that is overwritten anyway.
template <class S>
void HierarchicalHash<S>::buildTable(Table& out, int lo, int hi, int threads) {
  const std::size_t n = level.size();
  const int want = cpu::resolveThreads(threads, std::numeric_limits<std::size_t>::max());
  const Chunking ck = chunking(n, threads);
  const std::size_t chunks = ck.chunks, chunk_size = ck.size;

  // Hash buckets: the top `bucket_bits` bits of a key's hash. Fixed by the triangles on the
  // table's levels alone.
  std::size_t n_in = 0;
  for (std::size_t i = 0; i < n; ++i) n_in += (level[i] >= lo && level[i] <= hi) ? 1 : 0;
  if (n_in == 0) {
    out.clear();
    return;
  }
  int bucket_bits = 0;
  while ((std::size_t(1) << bucket_bits) * kTrianglesPerBucket < n_in) ++bucket_bits;
  const std::size_t num_buckets = std::size_t(1) << bucket_bits;
  auto bucketOf = [bucket_bits](std::uint64_t h) -> std::size_t {
    return bucket_bits == 0 ? 0 : std::size_t(h >> (64 - bucket_bits));
  };

  // ---- 2. records per (chunk, bucket), of the triangles on levels [lo, hi] ----
  std::vector<std::uint32_t>& hist = scratch_hist_;  // becomes each chunk's write cursors
  hist.resize(chunks * num_buckets);
  std::vector<std::uint64_t> records(chunks);
  cpu::forEachChunk(chunks, threads, [&](std::size_t c) {
    const std::size_t b = c * chunk_size, e = std::min(n, b + chunk_size);
    std::uint32_t* hc = hist.data() + c * num_buckets;
    std::fill(hc, hc + num_buckets, 0u);
    std::uint64_t count = 0;
    for (std::size_t i = b; i < e; ++i) {
      const int l = level[i];
      if (l < lo || l > hi) continue;
      const CellRange r = cellRange(boxes[i], l, grid);
      count += std::uint64_t(r.count());
      for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
        for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
          for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z)
            ++hc[bucketOf(hashCellKey(makeCellKey(l, x, y, z)))];
    }
    records[c] = count;
    return true;
  });
  std::uint64_t total = 0;
  for (std::size_t c = 0; c < chunks; ++c) total += records[c];
  if (total >= std::numeric_limits<std::uint32_t>::max())
    throw InvalidInputError("mesh too large for the hierarchical hash: " + std::to_string(total) +
                            " cell entries");

  std::vector<BucketInfo>& bucket = scratch_bucket_;
  bucket.resize(num_buckets);
  {
    std::uint32_t running = 0;  // total < 2^32
    for (std::size_t k = 0; k < num_buckets; ++k) {
      bucket[k].begin = running;
      for (std::size_t c = 0; c < chunks; ++c) {
        const std::uint32_t count = hist[c * num_buckets + k];
        hist[c * num_buckets + k] = running;
        running += count;
      }
    }
  }

  // ---- 3. the records, bucketed (in triangle order inside a bucket) ----
  std::vector<Rec>& rec = scratch_rec_;
  rec.resize(total);
  cpu::forEachChunk(chunks, threads, [&](std::size_t c) {
    const std::size_t b = c * chunk_size, e = std::min(n, b + chunk_size);
    std::uint32_t* cursor = hist.data() + c * num_buckets;
    for (std::size_t i = b; i < e; ++i) {
      const int l = level[i];
      if (l < lo || l > hi) continue;
      const CellRange r = cellRange(boxes[i], l, grid);
      std::uint64_t dbits = 0;  // diameters are >= 0 (and never -0: sqrt of a sum of squares)
      if (diameter[i] > 0) std::memcpy(&dbits, &diameter[i], sizeof dbits);
      for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
        for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
          for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z) {
            const CellKey key = makeCellKey(l, x, y, z);
            const std::uint64_t h = hashCellKey(key);
            rec[cursor[bucketOf(h)]++] = Rec{key, std::uint32_t(h >> 32), std::uint32_t(i), dbits};
          }
    }
    return true;
  });

  // Bucket groups for the per-bucket passes.
  const std::size_t groups = std::min(num_buckets, std::size_t(8) * std::size_t(want));
  const std::size_t group_size = (num_buckets + groups - 1) / groups;
  auto bucketEnd = [&](std::size_t k) -> std::uint32_t {
    return k + 1 < num_buckets ? bucket[k + 1].begin : std::uint32_t(total);
  };

  // ---- 4. sort each bucket; list its cells. Then size the table, and find where each bucket's
  //         cells end when nothing overflows into it ----
  std::vector<std::uint32_t>& cell_h32 = scratch_cell_;
  cell_h32.resize(total);
  // Record order: by hash, key (grouping each cell), then decreasing diameter, increasing id.
  auto less = [](const Rec& a, const Rec& b) {
    if (a.h32 != b.h32) return a.h32 < b.h32;
    if (a.key.hi != b.key.hi) return a.key.hi < b.key.hi;
    if (a.key.lo != b.key.lo) return a.key.lo < b.key.lo;
    if (a.dbits != b.dbits) return a.dbits > b.dbits;
    return a.tri < b.tri;
  };
  // The same inside one cell.
  auto lessInCell = [](const Rec& a, const Rec& b) {
    return a.dbits != b.dbits ? a.dbits > b.dbits : a.tri < b.tri;
  };
  auto insertionSort = [](Rec* b, Rec* e, auto&& lt) {
    for (Rec* p = b + 1; p < e; ++p) {
      const Rec x = *p;
      Rec* q = p;
      while (q > b && lt(x, q[-1])) {
        *q = q[-1];
        --q;
      }
      *q = x;
    }
  };
  cpu::forEachChunk(groups, threads, [&](std::size_t g) {
    std::vector<Rec> tmp;
    std::uint32_t digit_start[(1u << kSubBits) + 1];
    const std::size_t kb = g * group_size, ke = std::min(num_buckets, kb + group_size);
    for (std::size_t k = kb; k < ke; ++k) {
      Rec* r = rec.data() + bucket[k].begin;
      const std::size_t m = bucketEnd(k) - bucket[k].begin;
      if (m > 1) {
        // Counting sort on the (up to kSubBits) hash bits below the bucket's, about one digit
        // per two records.
        int sub_bits = 1;
        while (sub_bits < kSubBits && (std::size_t(2) << sub_bits) < m) ++sub_bits;
        const unsigned digits = 1u << sub_bits;
        auto digit = [&](const Rec& x) {
          return unsigned(((std::uint64_t(x.h32) << (32 + bucket_bits)) >> (64 - sub_bits)));
        };
        std::fill(digit_start, digit_start + digits + 1, 0u);
        for (std::size_t j = 0; j < m; ++j) ++digit_start[digit(r[j]) + 1];
        for (unsigned d = 0; d < digits; ++d) digit_start[d + 1] += digit_start[d];
        if (tmp.size() < m) tmp.resize(m);
        {
          std::uint32_t cur[1u << kSubBits];
          std::copy(digit_start, digit_start + digits, cur);
          for (std::size_t j = 0; j < m; ++j) tmp[cur[digit(r[j])]++] = r[j];
        }
        // Runs sharing a digit: usually one cell's records.
        for (unsigned d = 0; d < digits; ++d) {
          Rec* rb = tmp.data() + digit_start[d];
          Rec* re = tmp.data() + digit_start[d + 1];
          const std::size_t len = std::size_t(re - rb);
          if (len <= 1) continue;
          bool one_cell = true;
          for (const Rec* p = rb + 1; p < re && one_cell; ++p) one_cell = p->key == rb->key;
          if (one_cell) {
            if (len > 16) {
              std::sort(rb, re, lessInCell);
            } else {
              insertionSort(rb, re, lessInCell);
            }
          } else if (len > 16) {
            std::sort(rb, re, less);
          } else {
            insertionSort(rb, re, less);
          }
        }
        std::copy(tmp.data(), tmp.data() + m, r);
      }
      // The bucket's cells, in order: the hash of each (its home slot is a prefix of it).
      std::uint32_t* ch = cell_h32.data() + bucket[k].begin;
      std::uint32_t cells = 0;
      for (std::size_t j = 0; j < m; ++j)
        if (j == 0 || !(r[j].key == r[j - 1].key)) ch[cells++] = r[j].h32;
      bucket[k].cells = cells;
    }
    return true;
  });
  std::uint64_t cells = 0;
  for (std::size_t k = 0; k < num_buckets; ++k) cells += bucket[k].cells;

  // Open addressing, 2 to 4 slots per cell: capacity >= 1.25 * entries as long as that is
  // between 2 and 4 times the cells (load factor <= 1/2 keeps linear probes short: a query
  // looks up many empty cells; <= 4 slots per cell keeps a table of crowded cells small).
  // Keys are compared in full. Home slots are the top capacity_bits (<= 32) bits of the hash.
  const std::uint64_t want_slots =
      std::min(std::max(total + total / 4, 2 * cells), 4 * cells);
  std::uint64_t capacity = std::max<std::uint64_t>(16, num_buckets);
  while (capacity < want_slots) capacity <<= 1;
  if (capacity > (std::uint64_t(1) << 32))
    throw InvalidInputError("mesh too large for the hierarchical hash: " + std::to_string(cells) +
                            " cells");
  int capacity_bits = 0;
  while ((std::uint64_t(1) << capacity_bits) < capacity) ++capacity_bits;
  const unsigned home_shift = unsigned(32 - capacity_bits);  // home = h32 >> home_shift
  const unsigned slots_per_bucket_bits = unsigned(capacity_bits - bucket_bits);
  cpu::forEachChunk(groups, threads, [&](std::size_t g) {
    const std::size_t kb = g * group_size, ke = std::min(num_buckets, kb + group_size);
    for (std::size_t k = kb; k < ke; ++k) {
      const std::uint32_t* ch = cell_h32.data() + bucket[k].begin;
      std::uint64_t pos = std::uint64_t(k) << slots_per_bucket_bits;
      for (std::uint32_t j = 0; j < bucket[k].cells; ++j)
        pos = std::max(pos, std::uint64_t(ch[j]) >> home_shift) + 1;
      bucket[k].end0 = pos;
    }
    return true;
  });

  // ---- 5. overflow between buckets (serial, per bucket), then slots and entries ----
  std::uint64_t in = 0;  // slots the previous buckets' cells occupy in this bucket's range
  std::uint64_t end = 0;
  for (std::size_t k = 0; k < num_buckets; ++k) {
    const std::uint64_t start = std::uint64_t(k) << slots_per_bucket_bits;
    bucket[k].write_begin = start + in;
    // Linear probing in home order: the j-th cell lands at max over i <= j of home_i + (j - i),
    // and an overflow `in` acts as `in` cells homed at `start`.
    end = std::max(bucket[k].end0, start + in + bucket[k].cells);
    const std::uint64_t next = std::uint64_t(k + 1) << slots_per_bucket_bits;
    in = end > next ? end - next : 0;
  }
  const std::uint64_t table_end = std::max(end, capacity);  // home slots + overflow tail
  std::vector<Slot>& slots = out.slots;
  std::vector<Entry>& entries = out.entries;
  slots.resize(table_end + 1);  // + an empty sentinel
  entries.resize(total);
  out.shift = unsigned(64 - capacity_bits);
  out.cells = std::size_t(cells);
  const Slot empty_slot{{0, 0}, 0, 0};
  slots[table_end] = empty_slot;
  cpu::forEachChunk(groups, threads, [&](std::size_t g) {
    const std::size_t kb = g * group_size, ke = std::min(num_buckets, kb + group_size);
    for (std::size_t k = kb; k < ke; ++k) {
      const std::uint32_t rb = bucket[k].begin, re = bucketEnd(k);
      std::uint64_t s = bucket[k].write_begin;
      for (std::uint32_t j = rb; j < re;) {
        const CellKey key = rec[j].key;
        const std::uint64_t home = std::uint64_t(rec[j].h32) >> home_shift;
        while (s < home) slots[s++] = empty_slot;
        const int l = int(key.hi >> 56);
        const double scale = levelScale(l);
        std::int64_t cell[3];
        cellOfKey(key, cell);
        std::uint32_t je = j;
        do {
          const std::uint32_t i = rec[je].tri;
          // The triangles of a bucket are spread over the mesh: fetch their boxes ahead.
          if (je + kPrefetch < total) prefetch(&boxes[rec[je + kPrefetch].tri]);
          const Aabb<double>& box = boxes[i];
          const std::uint8_t lo_mask =
              std::uint8_t((cellCoordScaled(box.lo.x, 0, scale, grid) == cell[0] ? 1 : 0) |
                           (cellCoordScaled(box.lo.y, 1, scale, grid) == cell[1] ? 2 : 0) |
                           (cellCoordScaled(box.lo.z, 2, scale, grid) == cell[2] ? 4 : 0));
          Entry& ent = entries[je];
          ent.box = entryBox(box, grid.origin);
          std::memcpy(&ent.diameter, &rec[je].dbits, sizeof ent.diameter);
          ent.id = i;
          ent.lo_mask = lo_mask;
          ++je;
        } while (je < re && rec[je].key == key);
        slots[s++] = Slot{key, j, je - j};
        j = je;
      }
      const std::uint64_t limit =
          k + 1 < num_buckets ? (std::uint64_t(k + 1) << slots_per_bucket_bits) : table_end;
      while (s < limit) slots[s++] = empty_slot;
    }
    return true;
  });
}

template <class S>
HierarchyStats HierarchicalHash<S>::stats() const {
  HierarchyStats st;
  st.triangles = diameter.size();
  if (diameter.empty()) return st;
  for (int l = 0; l < 64; ++l) st.levels += levelOccupied(l) ? 1 : 0;
  st.height = top_level + 1;
  st.d_min = d_min;
  st.d_max = d_max;
  st.cell_size0 = grid.cell0;
  st.cells = upper_.cells + lower_.cells;
  st.entries = numEntries();
  for (const Table* t : {&upper_, &lower_})
    for (const Slot& s : t->slots)
      st.max_cell_load = std::max<std::size_t>(st.max_cell_load, s.count);
  if (grid.cell0 > d_min)  // (else no positive diameter lies below the finest cell)
    for (const double d : diameter) st.below_cell0 += (d > 0 && d < grid.cell0) ? 1 : 0;
  st.memory_bytes = memoryBytes();
  return st;
}

template <class S>
std::size_t HierarchicalHash<S>::memoryBytes() const {
  return boxes.capacity() * sizeof(Aabb<double>) + diameter.capacity() * sizeof(double) +
         level.capacity() +
         (upper_.entries.capacity() + lower_.entries.capacity()) * sizeof(Entry) +
         (upper_.slots.capacity() + lower_.slots.capacity()) * sizeof(Slot) +
         scratch_rec_.capacity() * sizeof(Rec) +
         (scratch_hist_.capacity() + scratch_cell_.capacity()) * sizeof(std::uint32_t) +
         scratch_bucket_.capacity() * sizeof(BucketInfo);
}

template class HierarchicalHash<float>;
template class HierarchicalHash<double>;

}  // namespace detail
}  // namespace kdet_fcl
