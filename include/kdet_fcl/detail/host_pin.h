#pragma once
/// \file
/// detail::HostPin: a HashedMesh's record of its vertex buffer's registration with a device
/// runtime (page-locked memory, which a GPU copies from directly, with no staging copy).

#include <memory>

namespace kdet_fcl {
namespace detail {

/// Made by the CUDA backend, owned by the HashedMesh whose vertex buffer it is for, and dropped
/// by the mesh before that buffer can be freed or replaced (setMesh, move assignment, the
/// destructor; updateVertices writes into the same buffer and keeps it; commitVertices swaps
/// the mesh's two buffers and their two records together). Dropping the last
/// handle runs the backend's release (cudaHostUnregister). The record also says whether the
/// buffer was seen before (the backend registers a buffer on its second upload, so that a mesh
/// uploaded once pays no registration) and whether registering it failed (not tried again).
class HostPin {
 public:
  HostPin() = default;
  HostPin(const HostPin&) = delete;
  HostPin& operator=(const HostPin&) = delete;
  HostPin(HostPin&& o) noexcept
      : at_(o.at_), tried_(o.tried_), handle_(std::move(o.handle_)) {
    o.at_ = nullptr;
    o.tried_ = false;
  }
  HostPin& operator=(HostPin&& o) noexcept {
    if (this != &o) {
      reset();  // this buffer's registration goes first
      at_ = o.at_;
      tried_ = o.tried_;
      handle_ = std::move(o.handle_);
      o.at_ = nullptr;
      o.tried_ = false;
    }
    return *this;
  }
  ~HostPin() = default;

  /// The buffer this record is for (nullptr: none).
  const void* at() const { return at_; }
  /// Whether registering that buffer was tried (set() ran for it).
  bool tried() const { return tried_; }
  /// Whether that buffer is registered.
  bool pinned() const { return handle_ != nullptr; }
  /// Records a first upload of the buffer at `at` (not registered yet), dropping any earlier
  /// record.
  void see(const void* at) {
    reset();
    at_ = at;
  }
  /// Records the registration `handle` (nullptr: it failed) of the buffer at `at`, dropping any
  /// earlier one first.
  void set(const void* at, std::shared_ptr<void> handle) {
    reset();
    at_ = at;
    tried_ = true;
    handle_ = std::move(handle);
  }
  /// Drops the record (and with it the registration, once no copy of the handle is left).
  void reset() {
    handle_.reset();
    at_ = nullptr;
    tried_ = false;
  }

 private:
  const void* at_ = nullptr;
  bool tried_ = false;
  std::shared_ptr<void> handle_;
};

}  // namespace detail
}  // namespace kdet_fcl
