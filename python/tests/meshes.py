"""Small procedural meshes for the Python tests and the Python benchmark (NumPy), and the
python-fcl-style model of one (fcl_mesh)."""
import numpy as np


def sphere(radius=1.0, nu=24, nv=12, center=(0.0, 0.0, 0.0)):
    """A UV sphere: nu segments around, nv rings from pole to pole (the library's makeSphere)."""
    import kdet_fcl
    v, t = kdet_fcl.make_sphere(radius, nu, nv, center=center)
    return v, t.astype(np.int64)


def torus(R=1.0, r=0.3, nu=32, nv=12):
    verts, tris = [], []
    for i in range(nu):
        u = 2 * np.pi * i / nu
        for j in range(nv):
            v = 2 * np.pi * j / nv
            verts.append([(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u),
                          r * np.sin(v)])
    idx = lambda i, j: (i % nu) * nv + (j % nv)  # noqa: E731
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1)
            tris.append([a, b, c])
            tris.append([c, b, d])
    return np.asarray(verts), np.asarray(tris, dtype=np.int64)


def cloth(n=20, size=2.0, height=None):
    """An n x n grid of quads (2 n^2 triangles) over [-size/2, size/2]^2; height(x, y) -> z."""
    xs = np.linspace(-size / 2, size / 2, n + 1)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    Z = np.zeros_like(X) if height is None else height(X, Y)
    verts = np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)
    tris = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = i * (n + 1) + j, (i + 1) * (n + 1) + j, i * (n + 1) + j + 1, (i + 1) * (n + 1) + j + 1
            tris.append([a, b, c])
            tris.append([c, b, d])
    return verts, np.asarray(tris, dtype=np.int64)


def folded_cloth(n=20, t=1.0):
    """A cloth rolled around the y axis past a full turn, so its layers cross (self-pairs)."""
    v, f = cloth(n, 2.0)
    ang = t * 1.35 * np.pi * (v[:, 0] + 1.0)  # 0 .. 2.7 pi along x
    rad = 0.5 + 0.1 * v[:, 0] * v[:, 1]  # layers a turn apart cross where y changes sign
    out = np.stack([rad * np.cos(ang), v[:, 1], rad * np.sin(ang)], axis=1)
    return out, f


def rotation(axis, angle):
    axis = np.asarray(axis, float)
    axis = axis / np.linalg.norm(axis)
    x, y, z = axis
    c, s, C = np.cos(angle), np.sin(angle), 1 - np.cos(angle)
    return np.array([[x * x * C + c, x * y * C - z * s, x * z * C + y * s],
                     [y * x * C + z * s, y * y * C + c, y * z * C - x * s],
                     [z * x * C - y * s, z * y * C + x * s, z * z * C + c]])


def pair_set(pairs):
    return {(int(a), int(b)) for a, b in np.asarray(pairs).reshape(-1, 2)}


def fcl_mesh(v, t, **kw):
    """A built kdet_fcl.fcl.BVHModel of vertices v and triangles t (kw: kdet_only=...)."""
    from kdet_fcl import fcl
    m = fcl.BVHModel(**kw)
    m.beginModel(len(t), len(v))
    m.addSubModel(v, t)
    m.endModel()
    return m
