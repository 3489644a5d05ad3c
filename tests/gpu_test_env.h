#pragma once
// Shared by the GPU test binaries (test_cuda_query, test_cuda_bvh, test_cuda_upload).

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>

namespace kdet_test {

/// Sets (or, with nullptr, unsets) an environment variable for the scope, then restores it.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) saved_ = std::string(old);
    if (value != nullptr) setenv(name, value, 1);
    else unsetenv(name);
  }
  ~ScopedEnv() {
    if (saved_) setenv(name_, saved_->c_str(), 1);
    else unsetenv(name_);
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> saved_;
};

/// A gtest environment that turns the kept self results of unchanged meshes off
/// (KDET_FCL_CUDA_SELF_CACHE=0) unless the variable is set already. The GPU test binaries
/// exercise the device kernels through repeated queries on unchanged meshes under varying knobs
/// (span filter, plane filter, tiny buffers); kept results would answer those without running the
/// kernels. The tests of the kept results set the variable themselves. Register it once per
/// binary: ::testing::AddGlobalTestEnvironment(new kdet_test::SelfCacheOffByDefault).
class SelfCacheOffByDefault : public ::testing::Environment {
 public:
  void SetUp() override {
    if (std::getenv("KDET_FCL_CUDA_SELF_CACHE") == nullptr)
      setenv("KDET_FCL_CUDA_SELF_CACHE", "0", 1);
  }
};

}  // namespace kdet_test
