#pragma once
// Decoding fuzzer bytes into numbers and triangles (shared by fuzz_triangle and fuzz_hash).

#include <cmath>
#include <cstdint>
#include <cstring>

#include "kdet_fcl/vec3.h"

namespace kdet_fuzz {

/// Reads bytes in order; past the end it yields zeros (so every input decodes to something).
class ByteReader {
 public:
  ByteReader(const std::uint8_t* d, std::size_t n) : d_(d), n_(n) {}
  std::uint8_t u8() { return i_ < n_ ? d_[i_++] : 0; }
  std::uint32_t u32() {
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v = (v << 8) | u8();
    return v;
  }
  double f64() {
    std::uint64_t b = 0;
    for (int k = 0; k < 8; ++k) b = (b << 8) | u8();
    double v;
    std::memcpy(&v, &b, 8);
    return v;
  }
  bool empty() const { return i_ >= n_; }

 private:
  const std::uint8_t* d_;
  std::size_t n_, i_ = 0;
};

/// A coordinate inside the exact predicates' validity range (0 or magnitude in [2^-247, 2^330]),
/// chosen by a mode byte: a small integer, a dyadic fraction, a raw double (clamped into the
/// range), or one ulp next to a small integer.
inline double coordinate(ByteReader& r) {
  const std::uint8_t mode = r.u8();
  switch (mode % 4) {
    case 0:
      return double(int(r.u8() % 9) - 4);
    case 1:
      return std::ldexp(double(int(r.u8()) - 128), -int(r.u8() % 40));
    case 2: {
      double v = r.f64();
      if (!std::isfinite(v)) return 0;
      const double a = std::fabs(v);
      if (a != 0 && a < std::ldexp(1.0, -240)) return 0;
      if (a > std::ldexp(1.0, 300)) return std::copysign(std::ldexp(1.0, 300), v);
      return v;
    }
    default: {
      // Next to a non-zero small integer (next to 0 would be subnormal: outside the range).
      const int b = int(r.u8() % 4);
      const double base = b < 2 ? double(b - 2) : double(b - 1);
      return (mode & 4) ? std::nextafter(base, 10.0) : std::nextafter(base, -10.0);
    }
  }
}

inline kdet_fcl::Vec3<double> point(ByteReader& r) { return {coordinate(r), coordinate(r), coordinate(r)}; }

/// Three points with a construction picked by a byte: free, a repeated vertex, collinear
/// (the third the midpoint of the first two), a point, or all in the plane z = c.
inline void triangle(ByteReader& r, kdet_fcl::Vec3<double> t[3]) {
  const std::uint8_t kind = r.u8() % 6;
  for (int k = 0; k < 3; ++k) t[k] = point(r);
  if (kind == 1) t[2] = t[0];
  if (kind == 2) t[2] = {0.5 * (t[0].x + t[1].x), 0.5 * (t[0].y + t[1].y), 0.5 * (t[0].z + t[1].z)};
  if (kind == 3) t[1] = t[2] = t[0];
  if (kind == 4) t[1].z = t[2].z = t[0].z;
}

}  // namespace kdet_fuzz
