// The checksum by which kdet_fcl::collide notices that a plain BVHModel changed in place
// (CacheValidation::Checksum): FCL's replace calls and direct writes leave the pointers and counts
// as they were, so every query reads the vertex and triangle arrays.
#pragma once

#include <cstddef>
#include <cstdint>

namespace kdet_fcl::detail {

/// The instruction sets the checksum runs on. Every kernel gives the same value for the same
/// bytes and seed; the CPU picks the fastest once.
enum class ChecksumKernel {
  Portable,  ///< the build's baseline instruction set (SSE2 on x86-64, NEON on AArch64)
  Sse41,     ///< x86-64 with SSE4.1 (a native 32-bit vector multiply)
  Avx2,      ///< x86-64 with AVX2 (eight lanes a multiply)
};

/// Whether this CPU runs kernel k (Portable always; the x86 kernels only on x86-64 builds).
bool checksumKernelAvailable(ChecksumKernel k);

/// The fastest available kernel.
ChecksumKernel bestChecksumKernel();

/// 64-bit checksum of `bytes` bytes at `data` (any alignment; `data` may be null when bytes is 0).
///
/// The bytes are cut into pages of 96 KiB, hashed apart (by up to `threads` threads, which do not
/// change the value) and folded in order with the length. In a page, the bytes are read as 4-byte
/// words into 96 lanes of 32 bits, 12 accumulators of 8: word i goes to lane i mod 96. Each
/// word's step is a bijection of its accumulator's 256 bits (the word is xor-ed in, every lane
/// multiplied by an odd constant, then x ^= (x ^ rotate(x)) >> 15 with rotate turning each group
/// of four lanes by one), so a change of any one word always changes its accumulator, and later
/// words cannot undo it. A zero-padded last block and the page's length end the page, and its
/// accumulators are folded into 64 bits. Not cryptographic: it only has to notice that a mesh
/// changed, and an unnoticed change needs a 64-bit collision. The 12 independent chains let the
/// vector units run at about the cache's bandwidth (several times the 64-bit scalar chain this
/// replaced).
std::uint64_t checksumBytes(const void* data, std::size_t bytes, std::uint64_t seed,
                            int threads = 1);

/// The same with a named kernel (tests compare the kernels). Throws BackendUnavailableError if
/// this CPU cannot run k.
std::uint64_t checksumBytes(const void* data, std::size_t bytes, std::uint64_t seed,
                            ChecksumKernel k, int threads = 1);

}  // namespace kdet_fcl::detail
