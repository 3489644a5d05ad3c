#pragma once
/// \file
/// The speed/accuracy trade of the triangle test (docs/numerics.md has the measurements).

namespace kdet_fcl {

/// How a candidate triangle pair is decided.
enum class Predicate {
  /// Exact orientation signs (a floating-point filter with an exact expansion fallback): the
  /// decision is exact on the coordinates. The default, and what the tests hold every backend to.
  Exact,
  /// The same test with orientation signs in plain double arithmetic, no fallback: faster; may
  /// misjudge touching, coplanar and nearly parallel pairs.
  Double,
  /// Orientation signs in plain float arithmetic: the fastest and least accurate.
  Float,
};

}  // namespace kdet_fcl
