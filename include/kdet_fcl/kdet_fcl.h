#pragma once
/// \file
/// Umbrella header: everything kdet_fcl offers. Host-only C++17; no CUDA headers needed.
///
/// Quick start:
/// \code
///   kdet_fcl::HashedMesh<double> a(meshA, poseA), b(meshB, poseB);
///   kdet_fcl::QueryResult r = kdet_fcl::intersectMeshes(a, b);  // every intersecting pair
///   kdet_fcl::QueryResult s = kdet_fcl::intersectSelf(a);       // self-collisions of a
/// \endcode

#include "kdet_fcl/backend.h"
#include "kdet_fcl/errors.h"
#include "kdet_fcl/hashed_mesh.h"
#include "kdet_fcl/kfree.h"
#include "kdet_fcl/mesh_io.h"
#include "kdet_fcl/query.h"
#include "kdet_fcl/scenes.h"
#include "kdet_fcl/triangle_mesh.h"
#include "kdet_fcl/vec3.h"
#include "kdet_fcl/fcl_collide.h"
#include "kdet_fcl/fcl_guarded.h"
#include "kdet_fcl/fcl_mesh.h"
#include "kdet_fcl/collision_manager.h"
