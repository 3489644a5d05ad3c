#pragma once
/// \file
/// Backend selection and CUDA device discovery. Host-only: includes no CUDA header, so it is safe
/// to include from any C++17 translation unit, whether or not the library was built with CUDA.

#include <cstddef>
#include <string>

namespace kdet_fcl {

/// Where a query runs. Cpu is always available. Cuda needs a CUDA build and a device (otherwise
/// BackendUnavailableError). Auto picks the GPU when one is present and the work is large enough
/// to pay, else the CPU. Both backends return the same pair set; the CPU's order is its own
/// deterministic order, the GPU's is sorted by (a, b).
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
///  - Backend::Auto -> Backend::Cuda when a CUDA device is usable and work_triangles >=
///    autoCudaMinTriangles(), else Backend::Cpu.
///  - Backend::Cuda -> Backend::Cuda when a device is usable; otherwise throws
///    BackendUnavailableError saying why (built without CUDA, or no usable device, with the CUDA
///    error text). CUDA failures during a query throw CudaError with the CUDA error text.
Backend resolveBackend(Backend requested, std::size_t work_triangles = 0);

/// Bytes of device memory the CUDA backend holds now: the meshes it keeps on the device (their
/// vertices, triangles and hashes, kept between queries) and its scratch buffers. 0 when the
/// library was built without CUDA, when there is no usable device, or before the first GPU
/// query. Never throws.
std::size_t cudaDeviceBytesInUse();

/// Chooses the CUDA device that Backend::Cuda (and Auto's GPU queries) run on, for the whole
/// process. Until a call chooses, the backend uses the device named by the environment variable
/// KDET_FCL_CUDA_DEVICE (an ordinal), else device 0. Choosing another device than the one in use
/// frees everything the backend holds on the old one; each mesh is uploaded and hashed on the new
/// device by its next GPU query. Whatever the device, a query leaves the calling thread's CUDA
/// context (its current device, or none) as it found it, and the library's own threads make no
/// context on another GPU, so the backend can share a process and a thread with other CUDA code
/// on any GPU. Device buffers given to the *OnDevice queries must be memory of the chosen device.
/// Thread-safe (waits for a query in flight).
/// Throws InvalidInputError when `device` is negative or not below cudaDeviceCount(), and
/// BackendUnavailableError when the library was built without CUDA or no device is usable.
void setCudaDevice(int device);

/// The CUDA device the backend uses (or will use at its first GPU query): the one
/// setCudaDevice() chose, else KDET_FCL_CUDA_DEVICE's, else 0; -1 when the library was built
/// without CUDA or no device is usable. Throws InvalidInputError when KDET_FCL_CUDA_DEVICE is
/// not an ordinal of an existing device (a query would fail the same way).
int cudaDevice();

/// The smallest query (triangles of both meshes together) that Backend::Auto sends to the GPU:
/// the measured break-even against the CPU backend (benchmarks/RESULTS-gpu.md).
std::size_t autoCudaMinTriangles();

}  // namespace kdet_fcl
