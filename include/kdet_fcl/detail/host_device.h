#pragma once
/// \file
/// The host/device qualifier shared by every algorithm piece that both backends run.
/// Plain C++ compilers see nothing; nvcc sees `__host__ __device__`, so one function body serves
/// the CPU loop and the CUDA kernel.

#if defined(__CUDACC__)
#define KDET_HD __host__ __device__
#define KDET_HD_INLINE __host__ __device__ __forceinline__
#else
#define KDET_HD
#define KDET_HD_INLINE inline
#endif

/// Before a loop of a fixed trip count: nvcc unrolls it completely, so that an array indexed by
/// its counter stays in registers instead of local memory. Plain C++ compilers see nothing.
#if defined(__CUDACC__)
#define KDET_UNROLL _Pragma("unroll")
#else
#define KDET_UNROLL
#endif
