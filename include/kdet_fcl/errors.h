#pragma once
/// \file
/// Typed exceptions. The library never exits or aborts on bad input: it throws one of these.

#include <stdexcept>
#include <string>

namespace kdet_fcl {

/// Base class of every exception kdet_fcl throws.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

/// Invalid geometry or arguments: NaN/Inf coordinates, out-of-range indices, an empty mesh where
/// one is required, a non-orthonormal rotation, mismatched sizes.
class InvalidInputError : public Error {
 public:
  using Error::Error;
};

/// A mesh file that cannot be read: missing, truncated, malformed or of an unknown format.
/// The message names the file and, where known, the line or byte offset.
class MeshFileError : public Error {
 public:
  using Error::Error;
};

/// A backend was requested that this build or this machine does not have (e.g. Backend::Cuda
/// without nvcc at build time or without a device at run time).
class BackendUnavailableError : public Error {
 public:
  using Error::Error;
};

/// A CUDA runtime error, with the CUDA error text.
class CudaError : public Error {
 public:
  using Error::Error;
};

/// A query FCL 0.7 cannot answer: it has no test for the pair, or it crashes, hangs or answers
/// wrongly there (kdet_fcl::guardedCollide and guardedDistance, fcl_guarded.h).
class UnsupportedQueryError : public Error {
 public:
  using Error::Error;
};

}  // namespace kdet_fcl
