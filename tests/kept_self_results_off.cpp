// Linked into every test binary (kdet_add_test in tests/CMakeLists.txt): the kept self results
// of unchanged meshes (QueryResult::kept) are off unless the variable is set already.
//
// Many tests repeat self queries on one unchanged mesh under varying thread counts, knobs and
// buffer sizes to exercise the CPU scan and the device kernels; kept results would answer those
// without running either. The tests of the kept results turn them on themselves
// (kdet_test::ScopedEnv), and a binary run with the variable set keeps that setting.

#include <gtest/gtest.h>

#include <cstdlib>

namespace {

class KeptSelfResultsOffByDefault : public ::testing::Environment {
 public:
  void SetUp() override {
    for (const char* knob : {"KDET_FCL_CPU_SELF_CACHE", "KDET_FCL_CUDA_SELF_CACHE"})
      if (std::getenv(knob) == nullptr) setenv(knob, "0", 1);
  }
};

const auto* const kKeptSelfResultsOff =
    ::testing::AddGlobalTestEnvironment(new KeptSelfResultsOffByDefault);

}  // namespace
