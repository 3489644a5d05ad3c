#pragma once
/// \file
/// kdet_fcl::CollisionManager: an FCL broadphase manager (fcl::BroadPhaseCollisionManager) whose
/// broadphase is kDet's hierarchical spatial hash applied to the objects' world AABBs.
///
/// A drop-in for fcl::DynamicAABBTreeCollisionManager:
/// \code
///   // std::unique_ptr<fcl::BroadPhaseCollisionManagerd> m(new fcl::DynamicAABBTreeCollisionManagerd);
///   std::unique_ptr<fcl::BroadPhaseCollisionManagerd> m(new kdet_fcl::CollisionManagerd);
///   m->registerObjects(objects);          // queryable at once; setup() is optional
///   m->collide(&data, fcl::DefaultCollisionFunction<double>);
/// \endcode
///
/// Semantics (the same as DynamicAABBTreeCollisionManager unless noted):
/// - The callback is called exactly once for every pair whose stored AABBs overlap (closed boxes,
///   as fcl::AABB::overlap: touching boxes overlap), and for no other pair. Returning true stops
///   the query at once.
/// - Argument order:
///   - collide(obj, ...) / distance(obj, ...): cb(managed_object, obj). If obj is itself managed,
///     the pair (obj, obj) is reported too (its box overlaps itself), as FCL's managers do.
///   - collide(other, ...) / distance(other, ...): cb(object_of_this, object_of_other). `other` may
///     be any BroadPhaseCollisionManager (read through getObjects() and the objects' current
///     getAABB(); FCL's own managers static_cast it to their own type instead). other == this is
///     the self query, as in FCL's NaiveCollisionManager.
///   - collide(cdata, cb) / distance(cdata, cb) (self): cb(o1, o2) with o1 registered before o2
///     (the order of NaiveCollisionManager; DynamicAABBTree's order follows its tree shape).
/// - Boxes are snapshots: registerObject and the update() family read obj->getAABB(); a pose change
///   is seen after computeAABB() plus update()/update(obj), exactly as with FCL's managers.
/// - The manager never owns the objects. Registering an object twice just refreshes its box;
///   unregistering or updating an unknown object does nothing. A callback must not modify the
///   manager it is called from.
/// - Bad input is an exception, never a crash: an AABB with a NaN bound (FCL's tree segfaults on
///   one, fcl#535), a null object or a null callback throws InvalidInputError and leaves the
///   manager unchanged.
/// - Distance: the callback gets FCL's in/out upper bound `dist` (std::numeric_limits<S>::max() at
///   the start) and is called for an object pair only while the pair's AABB distance is below it,
///   so the minimum found equals that of FCL's NaiveCollisionManager. distance(obj) visits the
///   objects nearest box first (O(n log n)); the self and manager forms sweep along the widest
///   axis (O(n^2) at worst). Exact rather than fast.
///
/// How it works (README "Broadphase: kdet_fcl::CollisionManager"): an object whose AABB has largest
/// extent d lives on the finest level l with cell edge cell0 * 2^l >= d / 2, so it covers at most 3
/// cells per axis there; cell0 is the smallest positive extent. The hash (a flat open-addressing
/// table, entries contiguous per cell) is a snapshot rebuilt lazily; objects changed since are
/// tested directly. A pair is examined only
/// in the cell holding the minimum corner of the overlap of the two boxes, on the coarser object's
/// level: pairs of one level inside each cell, pairs of different levels by the finer object
/// querying each coarser occupied level. So no de-duplication set is needed. Objects with
/// unbounded or empty boxes (fcl::Halfspace, fcl::Plane: +-max()) are kept in a side list and
/// tested against everything.

#include <cstddef>
#include <memory>
#include <vector>

#include <fcl/broadphase/broadphase_collision_manager.h>

#include "kdet_fcl/detail/fcl_float_instances.h"

namespace kdet_fcl {

/// FCL broadphase manager on kDet's hierarchical hash of object AABBs (see the file comment).
template <class S>
class CollisionManager : public fcl::BroadPhaseCollisionManager<S> {
 public:
  CollisionManager();
  ~CollisionManager() override;
  CollisionManager(const CollisionManager&) = delete;
  CollisionManager& operator=(const CollisionManager&) = delete;

  /// Adds objects (their current getAABB()); on an empty manager this is one O(n) bulk build.
  void registerObjects(const std::vector<fcl::CollisionObject<S>*>& other_objs) override;
  /// Adds one object; it is queryable at once (no setup() needed).
  void registerObject(fcl::CollisionObject<S>* obj) override;
  /// Removes one object (unknown objects are ignored).
  void unregisterObject(fcl::CollisionObject<S>* obj) override;
  /// Optional: re-derives the grid (origin, level-0 cell size) from the stored boxes. O(n).
  void setup() override;
  /// Re-reads every object's getAABB() and rebuilds the grid for them. O(n).
  void update() override;
  /// Re-reads one object's getAABB(). O(1): the object leaves the hash snapshot and is tested
  /// directly by queries until the next rebuild, which the first query after more than
  /// 16 + n/64 such changes performs (O(n), once per burst of updates).
  void update(fcl::CollisionObject<S>* updated_obj) override;
  /// update(obj) for each object (one rebuild when most objects changed).
  void update(const std::vector<fcl::CollisionObject<S>*>& updated_objs) override;
  /// Removes every object.
  void clear() override;
  /// The managed objects, in registration order (replaces the contents of objs).
  void getObjects(std::vector<fcl::CollisionObject<S>*>& objs) const override;

  /// cb(managed, obj) for each managed object whose box overlaps obj->getAABB().
  void collide(fcl::CollisionObject<S>* obj, void* cdata,
               fcl::CollisionCallBack<S> callback) const override;
  /// cb(managed, obj, cdata, dist), nearest box first, while the AABB distance is below dist.
  void distance(fcl::CollisionObject<S>* obj, void* cdata,
                fcl::DistanceCallBack<S> callback) const override;
  /// cb(o1, o2) once for each overlapping pair of managed objects, o1 registered first.
  void collide(void* cdata, fcl::CollisionCallBack<S> callback) const override;
  /// cb(o1, o2, cdata, dist) for managed pairs (o1 registered first) while AABB distance < dist.
  void distance(void* cdata, fcl::DistanceCallBack<S> callback) const override;
  /// cb(ours, theirs) once for each overlapping pair; any manager type (other == this: self).
  void collide(fcl::BroadPhaseCollisionManager<S>* other_manager, void* cdata,
               fcl::CollisionCallBack<S> callback) const override;
  /// cb(ours, theirs, cdata, dist) while the pair's AABB distance is below dist; any manager type.
  void distance(fcl::BroadPhaseCollisionManager<S>* other_manager, void* cdata,
                fcl::DistanceCallBack<S> callback) const override;

  bool empty() const override;
  size_t size() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

using CollisionManagerf = CollisionManager<float>;
using CollisionManagerd = CollisionManager<double>;

extern template class CollisionManager<float>;
extern template class CollisionManager<double>;

}  // namespace kdet_fcl
