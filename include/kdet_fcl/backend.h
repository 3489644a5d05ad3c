#pragma once
/// \file
/// Backend selection and CUDA device discovery. Host-only: includes no CUDA header, so it is safe
/// to include from any C++17 translation unit, whether or not the library was built with CUDA.

#include <cstddef>
#include <string>

namespace kdet_fcl {

/// Where a query runs. Cpu is always available. Cuda needs a CUDA build and a device (otherwise
/// BackendUnavailableError). Auto picks the GPU when one is present and the work is large enough
/// to pay, else the CPU.
enum class Backend { Cpu, Cuda, Auto };

/// True when this library was compiled with the CUDA backend (nvcc found at build time).
bool builtWithCuda();

/// Number of usable CUDA devices. 0 when the library was built without CUDA, when there is no
/// device, or when no (or a too old) driver is installed. Never throws.
int cudaDeviceCount();

/// A one-line description of CUDA device `device`: "<name>, compute capability <major>.<minor>,
/// <N> MiB" (e.g. "NVIDIA H100 80GB HBM3, compute capability 9.0, 81079 MiB"), or "none" when
/// the library was built without CUDA or the device does not exist. Never throws.
std::string cudaDeviceDescription(int device = 0);

/// The backend that actually runs a query of about `work_triangles` triangles (both meshes
/// together) when `requested` is asked for:
///  - Backend::Cpu  -> Backend::Cpu.
///  - Backend::Auto -> Backend::Cpu in this version (there is no GPU query backend yet).
///  - Backend::Cuda -> throws BackendUnavailableError, saying why: the library was built
///    without CUDA, there is no usable device (with the CUDA error text), or the CUDA query
///    backend is not implemented in this version.
Backend resolveBackend(Backend requested, std::size_t work_triangles = 0);

}  // namespace kdet_fcl
