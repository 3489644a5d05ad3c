#pragma once
// Small helpers shared by the benchmarks that compare FCL's answers with kDet's.

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <utility>
#include <vector>

#include <string>

#include "kdet_fcl/backend.h"
#include "kdet_fcl/query.h"
#include "kdet_fcl/triangle_mesh.h"

namespace kdet_bench_util {

/// A command-line integer: the whole of `s` must be a decimal number in [lo, hi]; anything else
/// ("abc", "3x", "-3" where lo is 1, out of range) prints one line naming the tool and the flag
/// and exits with `exit_code` (the tool's usage-error code).
inline long parseIntArg(const char* tool, const char* flag, const char* s, long lo, long hi,
                        int exit_code) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(s, &end, 10);
  if (end == s || *end != '\0' || errno == ERANGE || v < lo || v > hi) {
    std::fprintf(stderr, "%s: %s wants a whole number from %ld to %ld, got '%s'\n", tool, flag, lo,
                 hi, s);
    std::exit(exit_code);
  }
  return v;
}

/// FCL's answer to "self-collision" (the mesh against itself) brought to intersectSelf's rules:
/// (i, i) and vertex-sharing pairs (TriangleMesh::sharesVertex) dropped, each pair once as
/// (lower, higher), sorted.
template <class S>
std::vector<kdet_fcl::TrianglePair> selfFromPair(const kdet_fcl::TriangleMesh<S>& m,
                                                 const std::vector<kdet_fcl::TrianglePair>& raw) {
  std::vector<kdet_fcl::TrianglePair> out;
  out.reserve(raw.size() / 2);
  for (kdet_fcl::TrianglePair p : raw) {
    if (p.a == p.b) continue;
    if (p.a > p.b) std::swap(p.a, p.b);
    if (!m.sharesVertex(p.a, p.b)) out.push_back(p);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// The GPU the CUDA backend runs on, for the reports: "device N: <name, capability, memory>"
/// (kdet_fcl::cudaDevice(): setCudaDevice's, else KDET_FCL_CUDA_DEVICE's, else 0), or "none".
/// Throws InvalidInputError where KDET_FCL_CUDA_DEVICE names no device.
inline std::string backendGpu() {
  const int d = kdet_fcl::cudaDevice();
  return d < 0 ? std::string("none")
               : "device " + std::to_string(d) + ": " + kdet_fcl::cudaDeviceDescription(d);
}

}  // namespace kdet_bench_util
