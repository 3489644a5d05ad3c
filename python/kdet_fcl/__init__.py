"""kdet_fcl: every intersecting triangle pair between meshes and inside one mesh (kDet's
hierarchical spatial hash), on the CPU or a CUDA GPU, from NumPy arrays.

    import numpy as np, kdet_fcl
    a = kdet_fcl.Mesh(vertices, triangles)              # (n, 3) floats, (m, 3) ints
    b = kdet_fcl.Mesh(v2, t2, rotation=R, translation=t)
    pairs = kdet_fcl.intersect(a, b)                    # (k, 2) uint32: (triangle of a, of b)
    self_pairs = kdet_fcl.intersect_self(a)             # i < j, vertex-sharing pairs excluded
    b.set_pose(R2, t2)                                  # rigid motion: no re-hash
    a.update_vertices(next_vertices)                    # deformation: re-hashed by the next query
    kdet_fcl.intersect(a, b, backend="cuda")            # the same pairs, sorted, on the GPU

`kdet_fcl.fcl` speaks python-fcl's API (BVHModel, CollisionObject, collide, managers) with
kDet deciding mesh pairs: `from kdet_fcl import fcl` in place of `import fcl`.

Pairs: each intersecting pair exactly once, decided by an exact predicate (touching counts);
the order is deterministic but not sorted on the CPU (np.unique(pairs, axis=0) sorts it).
`max_pairs=k` stops after k pairs (fewer than k rows: the list is complete).
Errors: InvalidInputError (a ValueError) for bad arrays, NaN/Inf coordinates, out-of-range
indices and non-rigid poses; MeshFileError (an OSError); BackendUnavailableError and CudaError;
UnsupportedQueryError (a NotImplementedError) for what FCL 0.7 cannot answer (kdet_fcl.fcl).
"""
from ._kdet_fcl import (  # noqa: F401
    BackendUnavailableError,
    CudaError,
    Error,
    InvalidInputError,
    Mesh,
    MeshF32,
    MeshFileError,
    UnsupportedQueryError,
    analyze_kfree,
    brute_force_intersect,
    brute_force_intersect_self,
    built_with_cuda,
    cuda_device,
    cuda_device_count,
    cuda_device_description,
    intersect,
    intersect_all,
    intersect_self,
    intersects,
    make_draped_cloth,
    make_sphere,
    read_mesh,
    set_cuda_device,
    write_mesh,
)

__all__ = [
    "Mesh", "MeshF32", "intersect", "intersect_self", "intersect_all", "intersects",
    "brute_force_intersect", "brute_force_intersect_self", "analyze_kfree", "read_mesh",
    "write_mesh", "make_sphere", "make_draped_cloth", "built_with_cuda", "cuda_device_count", "cuda_device_description",
    "cuda_device", "set_cuda_device",
    "cuda_available", "Error", "InvalidInputError", "MeshFileError",
    "BackendUnavailableError", "CudaError", "UnsupportedQueryError",
]


def cuda_available():
    """True when the CUDA backend was built and a device is present."""
    return built_with_cuda() and cuda_device_count() > 0
