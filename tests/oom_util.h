#pragma once
// Out-of-memory test helpers (Linux): run a body in a forked child whose address space can be
// limited (soft RLIMIT_AS) to its current size plus a headroom; the child's exit code reports how
// an allocation failure surfaced. Shared by test_bad_input.cpp and test_hierarchy.cpp.

#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstddef>
#include <cstdio>
#include <fstream>
#include <functional>

namespace kdet_test {

/// Bytes of address space the process holds now (/proc/self/statm).
inline std::size_t currentAddressSpace() {
  std::ifstream in("/proc/self/statm");
  std::size_t pages = 0;
  in >> pages;
  return pages * std::size_t(::sysconf(_SC_PAGESIZE));
}

/// One malloc arena for the whole program, set before main() (before any thread exists). glibc
/// gives other threads arenas of their own, each reserving 64 MB of address space up front, and
/// when an allocation of the main thread fails it retries in one of those: inside a limit set
/// after some threads ran (a whole test program in one process, a CPU query before), the body's
/// allocations then fit the reserve and the limit never bites. With one arena every allocation
/// takes new address space (brk or mmap) that the limit counts.
inline const int kOneMallocArena = ::mallopt(M_ARENA_MAX, 1);

/// Limits the address space to its current size plus `headroom` bytes.
inline void limitAddressSpace(std::size_t headroom) {
  rlimit r{};
  ::getrlimit(RLIMIT_AS, &r);
  r.rlim_cur = currentAddressSpace() + headroom;
  ::setrlimit(RLIMIT_AS, &r);
}

/// Lifts the limit again (up to the hard limit).
inline void unlimitAddressSpace() {
  rlimit r{};
  ::getrlimit(RLIMIT_AS, &r);
  r.rlim_cur = r.rlim_max;
  ::setrlimit(RLIMIT_AS, &r);
}

/// Runs body() in a forked child and returns its exit code (body's return value, or
/// `on_exception` when it throws), or -signal when the child died of a signal.
inline int runInChild(const std::function<int()>& body, int on_exception) {
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    int code = on_exception;
    try {
      code = body();
    } catch (...) {
      code = on_exception;
    }
    std::fflush(nullptr);
    ::_exit(code);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (WIFSIGNALED(status)) return -WTERMSIG(status);
  return WEXITSTATUS(status);
}

}  // namespace kdet_test
