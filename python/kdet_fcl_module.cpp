// The Python module kdet_fcl (its compiled part, kdet_fcl._kdet_fcl): kDet's meshes and queries
// on NumPy arrays, and the FCL-facing core under python/kdet_fcl/fcl.py's python-fcl-style API.
//
// - Every C++ error reaches Python as a kdet_fcl exception (InvalidInputError is also a
//   ValueError, MeshFileError an OSError, BackendUnavailableError and CudaError RuntimeErrors);
//   bad arrays (wrong shape, non-integer indices, negative indices) are InvalidInputErrors raised
//   here, before any C++ object changes.
// - Queries on Mesh/MeshF32 release the GIL. A mesh's wrapper holds a shared mutex: queries take
//   it shared, changes (new vertices, pose, topology) exclusively, so Python threads may query
//   and change meshes concurrently without a data race. A lock holder never needs the GIL. The
//   FCL-style calls keep the GIL (below).
// - Pairs come back as (k, 2) uint32 arrays that own the query's vector (no copy).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <fcl/config.h>
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cone.h>
#include <fcl/geometry/shape/convex.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/ellipsoid.h>
#include <fcl/geometry/shape/halfspace.h>
#include <fcl/geometry/shape/plane.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/geometry/shape/triangle_p.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>
#if FCL_HAVE_OCTOMAP
#include <fcl/geometry/octree/octree.h>
#include <octomap/OcTree.h>
#endif

#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "kdet_fcl/kdet_fcl.h"

namespace py = pybind11;
using namespace kdet_fcl;

namespace {

static_assert(sizeof(TrianglePair) == 2 * sizeof(std::uint32_t), "pairs are read as (k, 2) arrays");

std::string shapeOf(const py::array& a) {
  std::ostringstream s;
  s << '(';
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i);
  s << (a.ndim() == 1 ? ",)" : ")");
  return s.str();
}

/// An (n, 3) array of numbers (any real or integer dtype, any layout) as rows make(x, y, z) of
/// S coordinates; an empty array of any shape is no row.
template <class S, class Make>
auto toRows(const py::handle& obj, const std::string& what, Make make) {
  std::vector<decltype(make(S(), S(), S()))> out;
  py::array any = py::array::ensure(obj);
  if (!any) throw InvalidInputError(what + ": expected an (n, 3) array of numbers");
  if (any.size() == 0) return out;
  const char kind = any.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw InvalidInputError(what + ": expected numbers, got dtype " +
                            std::string(py::str(any.dtype())));
  auto a = py::array_t<S, py::array::c_style | py::array::forcecast>::ensure(any);
  if (!a) throw InvalidInputError(what + ": expected an (n, 3) array of numbers");
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw InvalidInputError(what + ": expected an (n, 3) array, got shape " + shapeOf(a));
  const S* p = a.data();
  out.reserve(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    out.push_back(make(p[3 * i], p[3 * i + 1], p[3 * i + 2]));
  return out;
}

/// An (n, 3) array of numbers as the library's points.
template <class S>
std::vector<Vec3<S>> toPoints(const py::handle& obj, const std::string& what) {
  return toRows<S>(obj, what, [](S x, S y, S z) { return Vec3<S>{x, y, z}; });
}

/// An (m, 3) array of integer vertex indices in [0, 2^32 - 1); an empty array of any shape is no
/// triangle. Whether an index names a vertex is the mesh's own check (TriangleMesh::validate).
std::vector<Triangle> toTriangles(const py::handle& obj, const std::string& what) {
  py::array any = py::array::ensure(obj);
  if (!any) throw InvalidInputError(what + ": expected an (m, 3) array of vertex indices");
  if (any.size() == 0) return {};
  const char kind = any.dtype().kind();
  if (kind != 'i' && kind != 'u')
    throw InvalidInputError(what + ": vertex indices must be integers, got dtype " +
                            std::string(py::str(any.dtype())));
  if (any.ndim() != 2 || any.shape(1) != 3)
    throw InvalidInputError(what + ": expected an (m, 3) array, got shape " + shapeOf(any));
  std::vector<Triangle> out(static_cast<std::size_t>(any.shape(0)));
  auto take = [&](std::size_t i, int c, long double v) {
    if (!(v >= 0 && v < 4294967295.0L)) {
      std::ostringstream s;
      s << what << ": triangle " << i << " has vertex index " << std::fixed << std::setprecision(0)
        << v << ", outside [0, 4294967295)";
      throw InvalidInputError(s.str());
    }
    out[i][c] = static_cast<std::uint32_t>(v);
  };
  if (kind == 'u') {
    auto a = py::array_t<unsigned long long, py::array::c_style | py::array::forcecast>::ensure(any);
    for (std::size_t i = 0; i < out.size(); ++i)
      for (int c = 0; c < 3; ++c) take(i, c, static_cast<long double>(a.data()[3 * i + c]));
  } else {
    auto a = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(any);
    for (std::size_t i = 0; i < out.size(); ++i)
      for (int c = 0; c < 3; ++c) take(i, c, static_cast<long double>(a.data()[3 * i + c]));
  }
  return out;
}

/// A 3x3 rotation (row-major as NumPy writes it) and a translation of 3 numbers; None is the
/// identity and zero. Rigidity is the mesh's check (validatePose).
template <class S>
Transform<S> toPose(const py::handle& rotation, const py::handle& translation,
                    const std::string& what) {
  Transform<S> T;
  if (!rotation.is_none()) {
    auto r = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(rotation);
    if (!r || r.ndim() != 2 || r.shape(0) != 3 || r.shape(1) != 3)
      throw InvalidInputError(what + ": the rotation must be a 3x3 array");
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) T.R[i][j] = static_cast<S>(r.at(i, j));
  }
  if (!translation.is_none()) {
    auto t = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(translation);
    if (!t || t.size() != 3 || t.ndim() > 2)
      throw InvalidInputError(what + ": the translation must be 3 numbers");
    T.t = {static_cast<S>(t.data()[0]), static_cast<S>(t.data()[1]), static_cast<S>(t.data()[2])};
  }
  return T;
}

/// The query's pairs as a (k, 2) uint32 array that owns their vector.
py::array_t<std::uint32_t> pairsArray(std::vector<TrianglePair>&& pairs) {
  auto* held = new std::vector<TrianglePair>(std::move(pairs));
  py::capsule owner(held, [](void* p) { delete static_cast<std::vector<TrianglePair>*>(p); });
  const auto k = static_cast<py::ssize_t>(held->size());
  return py::array_t<std::uint32_t>(
      {k, py::ssize_t(2)},
      {static_cast<py::ssize_t>(sizeof(TrianglePair)), static_cast<py::ssize_t>(sizeof(std::uint32_t))},
      reinterpret_cast<const std::uint32_t*>(held->data()), owner);
}

Backend toBackend(const std::string& name) {
  if (name == "cpu") return Backend::Cpu;
  if (name == "cuda") return Backend::Cuda;
  if (name == "auto") return Backend::Auto;
  throw InvalidInputError("backend must be 'cpu', 'cuda' or 'auto', not '" + name + "'");
}

Predicate toPredicate(const std::string& name) {
  if (name == "exact") return Predicate::Exact;
  if (name == "double") return Predicate::Double;
  if (name == "float") return Predicate::Float;
  throw InvalidInputError("predicate must be 'exact', 'double' or 'float', not '" + name + "'");
}

/// A `threads` argument: 0 (every hardware thread) to 4096.
int toThreads(long long threads, const std::string& what) {
  if (threads < 0 || threads > 4096)
    throw InvalidInputError(what + "threads must be in [0, 4096] (0: every hardware thread)");
  return static_cast<int>(threads);
}

QueryOptions toOptions(long long max_pairs, const std::string& backend, long long threads,
                       const std::string& predicate) {
  if (max_pairs < 0) throw InvalidInputError("max_pairs must be >= 0 (0: every pair)");
  QueryOptions o;
  o.max_pairs = static_cast<std::size_t>(max_pairs);
  o.threads = toThreads(threads, "");
  o.backend = toBackend(backend);
  o.predicate = toPredicate(predicate);
  return o;
}

/// A HashedMesh and the lock that orders Python threads' queries (shared) and changes
/// (exclusive) on it.
template <class S>
struct PyMesh {
  std::unique_ptr<HashedMesh<S>> mesh;
  mutable std::shared_mutex mutex;
};

/// Shared locks on one or two meshes (one when they are the same), taken without the GIL.
template <class S>
struct ReadLocks {
  std::shared_lock<std::shared_mutex> a, b;
  ReadLocks(const PyMesh<S>& x, const PyMesh<S>* y) : a(x.mutex) {
    if (y && y != &x) b = std::shared_lock<std::shared_mutex>(y->mutex);
  }
};

/// fn() without the GIL, under shared locks of a and b (b may be null or a itself): a query.
template <class S, class F>
auto reading(const PyMesh<S>& a, const PyMesh<S>* b, F&& fn) {
  py::gil_scoped_release nogil;
  ReadLocks<S> lk(a, b);
  return fn();
}

/// fn() without the GIL, under m's exclusive lock: a change of the mesh.
template <class S, class F>
void changing(PyMesh<S>& m, F&& fn) {
  py::gil_scoped_release nogil;
  std::unique_lock<std::shared_mutex> lk(m.mutex);
  fn();
}

template <class S>
py::array pointsArray(const std::vector<Vec3<S>>& v) {
  py::array_t<S> out({static_cast<py::ssize_t>(v.size()), py::ssize_t(3)});
  S* p = out.mutable_data();
  for (std::size_t i = 0; i < v.size(); ++i) p[3 * i] = v[i].x, p[3 * i + 1] = v[i].y, p[3 * i + 2] = v[i].z;
  return out;
}

py::array trianglesArray(const std::vector<Triangle>& t) {
  py::array_t<std::uint32_t> out({static_cast<py::ssize_t>(t.size()), py::ssize_t(3)});
  std::uint32_t* p = out.mutable_data();
  for (std::size_t i = 0; i < t.size(); ++i)
    for (int c = 0; c < 3; ++c) p[3 * i + c] = t[i][c];
  return out;
}

py::dict kfreeDict(const KFreeStats& k) {
  py::dict d;
  d["triangles"] = k.triangles;
  d["k"] = k.k;
  d["mean"] = k.mean;
  d["sd"] = k.sd;
  d["max_count"] = k.max_count;
  d["adjacent_mean"] = k.adjacent_mean;
  d["adjacent_share"] = k.adjacent_share;
  d["height"] = k.height;
  if (!k.counts.empty() || k.triangles == 0) {
    py::array_t<std::uint32_t> c(static_cast<py::ssize_t>(k.counts.size()));
    std::copy(k.counts.begin(), k.counts.end(), c.mutable_data());
    d["counts"] = c;
  }
  return d;
}

template <class S>
void bindMesh(py::module_& m, const char* name, const char* dtype) {
  using M = PyMesh<S>;
  const std::string cls = name;
  py::class_<M>(m, name,
                (std::string("A triangle mesh and its hierarchical hash (") + dtype +
                 " coordinates): rigid (set_pose), deforming (update_vertices) or changing "
                 "topology (set_mesh).")
                    .c_str())
      .def(py::init([cls](const py::object& vertices, const py::object& triangles,
                          const py::object& rotation, const py::object& translation,
                          long long threads) {
             const int t = toThreads(threads, cls + ": ");
             TriangleMesh<S> mesh;
             mesh.vertices = toPoints<S>(vertices, cls + " vertices");
             mesh.triangles = toTriangles(triangles, cls + " triangles");
             const Transform<S> pose = toPose<S>(rotation, translation, cls);
             auto out = std::make_unique<M>();
             py::gil_scoped_release nogil;
             out->mesh = std::make_unique<HashedMesh<S>>(std::move(mesh), pose, t);
             return out;
           }),
           py::arg("vertices"), py::arg("triangles"), py::kw_only(),
           py::arg("rotation") = py::none(), py::arg("translation") = py::none(),
           py::arg("threads") = 0)
      .def_property_readonly("num_vertices", [](const M& self) {
        std::shared_lock<std::shared_mutex> lk(self.mutex);
        return self.mesh->numVertices();
      })
      .def_property_readonly("num_triangles", [](const M& self) {
        std::shared_lock<std::shared_mutex> lk(self.mutex);
        return self.mesh->numTriangles();
      })
      .def_property_readonly("vertices", [](const M& self) {
        std::shared_lock<std::shared_mutex> lk(self.mutex);
        return pointsArray(self.mesh->mesh().vertices);
      }, "A copy of the vertex positions, (n, 3), in the mesh's own frame.")
      .def_property_readonly("triangles", [](const M& self) {
        std::shared_lock<std::shared_mutex> lk(self.mutex);
        return trianglesArray(self.mesh->mesh().triangles);
      }, "A copy of the triangles' vertex indices, (m, 3) uint32.")
      .def_property_readonly("pose", [](const M& self) {
        std::shared_lock<std::shared_mutex> lk(self.mutex);
        const Transform<S>& T = self.mesh->pose();
        py::array_t<double> R({3, 3}), t(3);
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) R.mutable_at(i, j) = T.R[i][j];
        }
        t.mutable_at(0) = T.t.x, t.mutable_at(1) = T.t.y, t.mutable_at(2) = T.t.z;
        return py::make_tuple(R, t);
      }, "(rotation 3x3, translation (3,)): where the mesh's frame lies in the world.")
      .def("set_pose", [cls](M& self, const py::object& rotation, const py::object& translation) {
        const Transform<S> pose = toPose<S>(rotation, translation, cls + ".set_pose");
        changing(self, [&] { self.mesh->setPose(pose); });
      }, py::arg("rotation") = py::none(), py::arg("translation") = py::none(),
         "A rigid motion: no re-hash. None is the identity rotation / zero translation.")
      .def("update_vertices", [cls](M& self, const py::object& vertices) {
        std::vector<Vec3<S>> v = toPoints<S>(vertices, cls + ".update_vertices");
        changing(self, [&] { self.mesh->updateVertices(v); });
      }, py::arg("vertices"),
         "New positions for the same vertices (a deformation): the next query re-hashes.")
      .def("set_mesh", [cls](M& self, const py::object& vertices, const py::object& triangles) {
        TriangleMesh<S> mesh;
        mesh.vertices = toPoints<S>(vertices, cls + ".set_mesh vertices");
        mesh.triangles = toTriangles(triangles, cls + ".set_mesh triangles");
        changing(self, [&] { self.mesh->setMesh(std::move(mesh)); });
      }, py::arg("vertices"), py::arg("triangles"),
         "New topology (fracture, remeshing): the next query rebuilds.")
      .def("stats", [](const M& self) {
        const HierarchyStats s = reading<S>(self, nullptr, [&] { return self.mesh->stats(); });
        py::dict d;
        d["triangles"] = s.triangles;
        d["levels"] = s.levels;
        d["height"] = s.height;
        d["d_min"] = s.d_min;
        d["d_max"] = s.d_max;
        d["cell_size0"] = s.cell_size0;
        d["cells"] = s.cells;
        d["entries"] = s.entries;
        d["max_cell_load"] = s.max_cell_load;
        d["below_cell0"] = s.below_cell0;
        d["memory_bytes"] = s.memory_bytes;
        return d;
      }, "The hierarchy's statistics (builds the CPU hash if it is not current).")
      .def("__repr__", [cls](const M& self) {
        std::shared_lock<std::shared_mutex> lk(self.mutex);
        return "<kdet_fcl." + cls + ": " + std::to_string(self.mesh->numTriangles()) +
               " triangles, " + std::to_string(self.mesh->numVertices()) + " vertices>";
      });

  m.def("intersect", [](const M& a, const M& b, long long max_pairs, const std::string& backend,
                        long long threads, const std::string& predicate) {
    const QueryOptions o = toOptions(max_pairs, backend, threads, predicate);
    QueryResult r = reading(a, &b, [&] { return intersectMeshes(*a.mesh, *b.mesh, o); });
    return pairsArray(std::move(r.pairs));
  }, py::arg("a"), py::arg("b"), py::kw_only(), py::arg("max_pairs") = 0,
     py::arg("backend") = "cpu", py::arg("threads") = 0, py::arg("predicate") = "exact");

  m.def("intersect_self", [](const M& a, long long max_pairs, const std::string& backend,
                             long long threads, const std::string& predicate) {
    const QueryOptions o = toOptions(max_pairs, backend, threads, predicate);
    QueryResult r = reading<S>(a, nullptr, [&] { return intersectSelf(*a.mesh, o); });
    return pairsArray(std::move(r.pairs));
  }, py::arg("mesh"), py::kw_only(), py::arg("max_pairs") = 0, py::arg("backend") = "cpu",
     py::arg("threads") = 0, py::arg("predicate") = "exact");

  m.def("intersect_all", [](const M& a, const M& b, const std::string& backend, long long threads,
                            const std::string& predicate) {
    const QueryOptions o = toOptions(0, backend, threads, predicate);
    AllPairsResult r = reading(a, &b, [&] { return intersectAll(*a.mesh, *b.mesh, o); });
    return py::make_tuple(pairsArray(std::move(r.self_a.pairs)),
                          pairsArray(std::move(r.self_b.pairs)),
                          pairsArray(std::move(r.inter.pairs)));
  }, py::arg("a"), py::arg("b"), py::kw_only(), py::arg("backend") = "cpu",
     py::arg("threads") = 0, py::arg("predicate") = "exact");

  m.def("intersects", [](const M& a, const M& b, const std::string& backend, long long threads) {
    const QueryOptions o = toOptions(1, backend, threads, "exact");
    return reading(a, &b, [&] { return meshesIntersect(*a.mesh, *b.mesh, o); });
  }, py::arg("a"), py::arg("b"), py::kw_only(), py::arg("backend") = "cpu",
     py::arg("threads") = 0);

  m.def("brute_force_intersect", [](const M& a, const M& b, const std::string& predicate) {
    const Predicate p = toPredicate(predicate);
    return pairsArray(reading(a, &b, [&] {
      return bruteForceIntersectMeshes(a.mesh->mesh(), a.mesh->pose(), b.mesh->mesh(),
                                       b.mesh->pose(), p);
    }));
  }, py::arg("a"), py::arg("b"), py::kw_only(), py::arg("predicate") = "exact");

  m.def("brute_force_intersect_self", [](const M& a, const std::string& predicate) {
    const Predicate p = toPredicate(predicate);
    return pairsArray(
        reading<S>(a, nullptr, [&] { return bruteForceIntersectSelf(a.mesh->mesh(), p); }));
  }, py::arg("mesh"), py::kw_only(), py::arg("predicate") = "exact");

  m.def("analyze_kfree", [](const M& a, bool keep_counts, long long threads) {
    KFreeOptions o;
    o.keep_counts = keep_counts;
    o.threads = toThreads(threads, "analyze_kfree: ");
    return kfreeDict(reading<S>(a, nullptr, [&] { return analyzeKFree(a.mesh->mesh(), o); }));
  }, py::arg("mesh"), py::kw_only(), py::arg("keep_counts") = false, py::arg("threads") = 0);
}

// ---- The FCL-facing core (python/kdet_fcl/fcl.py wraps it in python-fcl's API) ----
// These calls keep the GIL, as python-fcl's do: FCL's objects and models have no lock of their
// own, so another Python thread must not move or update them while a query reads them.

using Geometry = fcl::CollisionGeometryd;

/// A python-fcl style BVHModel: kdet_fcl::Meshd (an fcl::BVHModel<OBBRSS>), whose endModel also
/// builds kDet's hash. Error codes raise as python-fcl's _check_ret_value does.
bool checkBvh(int code) {
  switch (code) {
    case fcl::BVH_OK: return true;
    case fcl::BVH_ERR_MODEL_OUT_OF_MEMORY: throw std::bad_alloc();  // MemoryError
    case fcl::BVH_ERR_BUILD_OUT_OF_SEQUENCE:
      throw InvalidInputError("BVH construction does not follow correct sequence");
    case fcl::BVH_ERR_BUILD_EMPTY_MODEL: throw InvalidInputError("BVH geometry is not prepared");
    case fcl::BVH_ERR_BUILD_EMPTY_PREVIOUS_FRAME:
      throw InvalidInputError("BVH geometry in previous frame is not prepared");
    case fcl::BVH_ERR_UNSUPPORTED_FUNCTION: throw InvalidInputError("BVH function is not supported");
    case fcl::BVH_ERR_UNUPDATED_MODEL: throw InvalidInputError("BVH model update failed");
    case fcl::BVH_ERR_INCORRECT_DATA: throw InvalidInputError("BVH data is not valid");
    default: throw InvalidInputError("BVH call failed with code " + std::to_string(code));
  }
}

/// An FCL vector as a NumPy array of 3 numbers.
py::array_t<double> vectorArray(const fcl::Vector3d& v) {
  py::array_t<double> a(3);
  for (int j = 0; j < 3; ++j) a.mutable_at(j) = v[j];
  return a;
}

fcl::Vector3d toVec3(const py::handle& p, const std::string& what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(p);
  if (!a || a.size() != 3) throw InvalidInputError(what + ": expected 3 numbers");
  return {a.data()[0], a.data()[1], a.data()[2]};
}

std::vector<fcl::Vector3d> toFclPoints(const py::handle& p, const std::string& what) {
  return toRows<double>(p, what, [](double x, double y, double z) { return fcl::Vector3d(x, y, z); });
}

/// A rigid pose (finite; the rotation orthonormal with determinant +1, as a mesh's pose): FCL
/// answers non-finite or scaling poses without an error.
fcl::Transform3d toFclTransform(const py::handle& rotation, const py::handle& translation,
                                const std::string& what = "CollisionObject") {
  const Transform<double> T = toPose<double>(rotation, translation, what);
  validatePose(T, what);
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  fcl::Matrix3d R;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R(i, j) = T.R[i][j];
  tf.linear() = R;
  tf.translation() = fcl::Vector3d(T.t.x, T.t.y, T.t.z);
  return tf;
}

/// Three finite numbers as a point.
fcl::Vector3d finiteVec3(const py::handle& p, const std::string& what) {
  const fcl::Vector3d v = toVec3(p, what);
  if (!v.allFinite()) throw InvalidInputError(what + ": the coordinates must be finite");
  return v;
}

/// A plane's or halfspace's (n, d): n finite and not zero, d finite.
std::pair<fcl::Vector3d, double> planeOf(const py::handle& n, double d, const std::string& what) {
  const fcl::Vector3d v = finiteVec3(n, what + " n");
  if (v.norm() == 0 || !std::isfinite(v.norm()))
    throw InvalidInputError(what + ": the normal n must not be zero");
  if (!std::isfinite(d)) throw InvalidInputError(what + ": d must be finite");
  return {v, d};
}

/// python-fcl's Convex(vertices, num_faces, faces), checked: FCL reads the face list unchecked
/// (an index outside the vertices, or a list shorter than its counts say, reads past the arrays).
std::shared_ptr<fcl::Convexd> makeConvex(const py::object& vertices, long long num_faces,
                                         const py::object& faces) {
  auto points = std::make_shared<std::vector<fcl::Vector3d>>(toFclPoints(vertices, "Convex vertices"));
  if (points->empty()) throw InvalidInputError("Convex: no vertices");
  for (const fcl::Vector3d& p : *points)
    if (!p.allFinite()) throw InvalidInputError("Convex vertices: the coordinates must be finite");
  if (num_faces < 1 || num_faces > std::numeric_limits<int>::max())
    throw InvalidInputError("Convex: num_faces must be in [1, 2^31)");
  py::array any = py::array::ensure(faces);
  if (!any || (any.size() > 0 && any.dtype().kind() != 'i' && any.dtype().kind() != 'u'))
    throw InvalidInputError("Convex faces: expected a flat array of integers");
  if (any.ndim() != 1)
    throw InvalidInputError("Convex faces: expected a flat array (count, indices..., count, ...), "
                            "got shape " + shapeOf(any));
  auto a = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(any);
  auto list = std::make_shared<std::vector<int>>();
  list->reserve(static_cast<std::size_t>(a.size()));
  const std::size_t size = static_cast<std::size_t>(a.size());
  std::size_t at = 0;
  for (long long f = 0; f < num_faces; ++f) {
    if (at >= size)
      throw InvalidInputError("Convex faces: the list ends after " + std::to_string(f) +
                              " faces, num_faces is " + std::to_string(num_faces));
    const long long count = a.data()[at];
    if (count < 3 || static_cast<unsigned long long>(count) > size - at - 1)
      throw InvalidInputError("Convex faces: face " + std::to_string(f) + " has vertex count " +
                              std::to_string(count) + " (at least 3, and no more than the " +
                              std::to_string(size - at - 1) + " entries left)");
    list->push_back(static_cast<int>(count));
    for (long long k = 1; k <= count; ++k) {
      const long long v = a.data()[at + static_cast<std::size_t>(k)];
      if (v < 0 || static_cast<unsigned long long>(v) >= points->size())
        throw InvalidInputError("Convex faces: face " + std::to_string(f) + " has vertex index " +
                                std::to_string(v) + ", but " + std::to_string(points->size()) +
                                " vertices were given");
      list->push_back(static_cast<int>(v));
    }
    at += static_cast<std::size_t>(count) + 1;
  }
  return std::make_shared<fcl::Convexd>(points, static_cast<int>(num_faces), list);
}

#if FCL_HAVE_OCTOMAP
/// octomap's binary node data, checked before octomap reads it: each node is two bytes that
/// mark its 8 children (2 bits each: 00 unknown, 10 free leaf, 01 occupied leaf, 11 inner
/// node, whose own node follows, depth first). octomap's reader recurses into every inner child
/// and reads past a short buffer: a tree deeper than octomap's 16 levels or data that ends
/// early (or goes on after the tree) is refused here.
void checkOcTreeData(const std::string& data) {
  static const char header[] = "# Octomap OcTree";
  if (data.compare(0, sizeof(header) - 1, header) == 0)
    throw InvalidInputError("OcTree: data starts with an octomap file header; pass the node data "
                            "after the header's 'data' line (OcTree::writeBinaryData's output)");
  std::vector<std::pair<int, int>> open;  // (depth of the nodes to read, how many are left)
  std::size_t at = 0;
  auto readNode = [&](int depth) {
    if (at + 2 > data.size())
      throw InvalidInputError("OcTree: the data ends inside the tree (" +
                              std::to_string(data.size()) + " bytes)");
    int inner = 0;
    for (int b = 0; b < 2; ++b) {
      const auto bits = static_cast<unsigned char>(data[at + static_cast<std::size_t>(b)]);
      for (int i = 0; i < 4; ++i) inner += ((bits >> (2 * i)) & 3u) == 3u;
    }
    at += 2;
    if (inner > 0) {
      if (depth + 2 > 16)
        throw InvalidInputError("OcTree: the data's tree is deeper than octomap's 16 levels");
      open.emplace_back(depth + 1, inner);
    }
  };
  readNode(0);
  while (!open.empty()) {
    if (open.back().second == 0) {
      open.pop_back();
      continue;
    }
    --open.back().second;
    readNode(open.back().first);
  }
  if (at != data.size())
    throw InvalidInputError("OcTree: " + std::to_string(data.size() - at) +
                            " bytes follow the tree's data");
}

std::shared_ptr<fcl::OcTreed> makeOcTree(double r, const py::bytes& data) {
  if (!(std::isfinite(r) && r > 0))
    throw InvalidInputError("OcTree: the resolution r must be finite and positive");
  const std::string bytes = data;
  checkOcTreeData(bytes);
  auto tree = std::make_shared<octomap::OcTree>(r);
  std::istringstream in(bytes);
  tree->readBinaryData(in);
  if (!in) throw InvalidInputError("OcTree: octomap could not read the data");
  return std::make_shared<fcl::OcTreed>(tree);
}
#endif

/// An fcl::CollisionObjectd over a geometry the Python object keeps alive (the holder).
struct ObjectCore {
  std::shared_ptr<Geometry> geometry;
  std::unique_ptr<fcl::CollisionObjectd> object;
};

/// A BVHModel that is being built or updated cannot be queried (FCL's traversal would read
/// half-written arrays).
void requireBuilt(const Geometry* g, const std::string& what) {
  if (auto* m = dynamic_cast<const Meshd*>(g))
    if (m->build_state != fcl::BVH_BUILD_STATE_PROCESSED &&
        m->build_state != fcl::BVH_BUILD_STATE_UPDATED)
      throw InvalidInputError(what + ": a BVHModel is not built (endModel not called, or refused "
                              "by FCL: a model with no triangles; or an update not ended)");
}


/// The cost sources of a result (octree pairs with enable_cost), as arrays; None for none.
py::object costsOf(fcl::CollisionResultd& result) {
  if (result.numCostSources() == 0) return py::none();
  std::vector<fcl::CostSourced> cs;
  result.getCostSources(cs);
  const auto k = static_cast<py::ssize_t>(cs.size());
  py::array_t<double> lo({k, py::ssize_t(3)}), hi({k, py::ssize_t(3)}), density(k), total(k);
  for (py::ssize_t i = 0; i < k; ++i) {
    const fcl::CostSourced& c = cs[static_cast<std::size_t>(i)];
    for (int j = 0; j < 3; ++j) lo.mutable_at(i, j) = c.aabb_min[j], hi.mutable_at(i, j) = c.aabb_max[j];
    density.mutable_at(i) = c.cost_density;
    total.mutable_at(i) = c.total_cost;
  }
  return py::make_tuple(lo, hi, density, total);
}

py::tuple contactsOf(fcl::CollisionResultd& result, const Geometry* first, std::size_t n) {
  std::vector<fcl::Contactd> cs;
  result.getContacts(cs);
  const auto k = static_cast<py::ssize_t>(cs.size());
  py::array_t<long long> ids({k, py::ssize_t(2)});
  py::array_t<double> normal({k, py::ssize_t(3)}), pos({k, py::ssize_t(3)}), depth(k);
  py::array_t<bool> swapped(k);
  for (py::ssize_t i = 0; i < k; ++i) {
    const fcl::Contactd& c = cs[static_cast<std::size_t>(i)];
    ids.mutable_at(i, 0) = c.b1, ids.mutable_at(i, 1) = c.b2;
    for (int j = 0; j < 3; ++j) normal.mutable_at(i, j) = c.normal[j], pos.mutable_at(i, j) = c.pos[j];
    depth.mutable_at(i) = c.penetration_depth;
    swapped.mutable_at(i) = c.o1 != first;
  }
  return py::make_tuple(n, result.isCollision(), ids, normal, pos, depth, swapped,
                        costsOf(result));
}

/// A Python value as T (bool, an integer or a number); another type is an InvalidInputError that
/// names it.
template <class T>
T attrValue(const py::handle& v, const std::string& name) {
  try {
    return py::cast<T>(v);
  } catch (const py::cast_error&) {
    const bool too_big = std::is_integral<T>::value && !std::is_same<T, bool>::value &&
                         py::isinstance<py::int_>(v);
    throw InvalidInputError(name + ": expected " +
                            (std::is_same<T, bool>::value ? "a bool"
                             : std::is_floating_point<T>::value ? "a number"
                             : too_big ? "an integer below 2^63" : "an integer") +
                            ", got " + std::string(py::repr(v)));
  }
}

/// An attribute of a python-fcl request object, as T; a missing attribute or one of another type
/// is an InvalidInputError that names it.
template <class T>
T attrOf(const py::handle& o, const char* name, const char* what) {
  PyObject* v = PyObject_GetAttrString(o.ptr(), name);
  if (!v) {
    PyErr_Clear();
    throw InvalidInputError(std::string(what) + " has no attribute '" + name + "'");
  }
  return attrValue<T>(py::reinterpret_steal<py::object>(v), std::string(what) + "." + name);
}

/// A count attribute: an integer in [0, 2^63).
std::size_t countOf(const py::handle& o, const char* name, const char* what) {
  const long long n = attrOf<long long>(o, name, what);
  if (n < 0) throw InvalidInputError(std::string(what) + "." + name + " must be >= 0");
  return static_cast<std::size_t>(n);
}

/// An enum attribute: an integer in [0, count).
template <class E>
E enumOf(const py::handle& o, const char* name, const char* what, int count) {
  const long long v = attrOf<long long>(o, name, what);
  if (v < 0 || v >= count)
    throw InvalidInputError(std::string(what) + "." + name + " must be in [0, " +
                            std::to_string(count) + "), got " + std::to_string(v));
  return static_cast<E>(v);
}

/// python-fcl's CollisionRequest as FCL's (all six fields, as python-fcl passes them).
fcl::CollisionRequestd toRequest(const py::handle& r) {
  const char* what = "CollisionRequest";
  const std::size_t contacts = countOf(r, "num_max_contacts", what);
  if (contacts == 0)  // FCL prints a warning and answers "no collision"
    throw InvalidInputError("CollisionRequest.num_max_contacts must be at least 1");
  return fcl::CollisionRequestd(
      contacts, attrOf<bool>(r, "enable_contact", what),
      countOf(r, "num_max_cost_sources", what), attrOf<bool>(r, "enable_cost", what),
      attrOf<bool>(r, "use_approximate_cost", what),
      enumOf<fcl::GJKSolverType>(r, "gjk_solver_type", what, 2));
}

// ---- What FCL 0.7 cannot answer: kdet_fcl::guardedCollide and guardedDistance ----
// (include/kdet_fcl/fcl_guarded.h; the sweep that found it: benchmarks/results/python-compat/,
// rerun by python/tests/fcl_pair_sweep.py). python-fcl forwards these and crashes, hangs or
// answers wrongly; here they raise UnsupportedQueryError, or take the path that answers them.

/// One discrete collision of two geometries at poses: kDet decides mesh pairs ("kdet") or FCL
/// 0.7 answers every pair ("fcl"), both guarded.
std::size_t collideAt(const Geometry* a, const fcl::Transform3d& ta, const Geometry* b,
                      const fcl::Transform3d& tb, const fcl::CollisionRequestd& request,
                      fcl::CollisionResultd& result, const std::string& engine) {
  requireBuilt(a, "collide");
  requireBuilt(b, "collide");
  if (engine != "kdet" && engine != "fcl")
    throw InvalidInputError("engine must be 'kdet' or 'fcl', not '" + engine + "'");
  return guardedCollide(a, ta, b, tb, request, result,
                        engine == "kdet" ? CollideEngine::Kdet : CollideEngine::Fcl);
}

/// One guarded distance of two geometries at poses.
double distanceAt(const Geometry* a, const fcl::Transform3d& ta, const Geometry* b,
                  const fcl::Transform3d& tb, const fcl::DistanceRequestd& request,
                  fcl::DistanceResultd& result) {
  requireBuilt(a, "distance");
  requireBuilt(b, "distance");
  return guardedDistance(a, ta, b, tb, request, result);
}

/// The core of fcl.py's collide and fcl_collide.
py::tuple collideCore(const ObjectCore& a, const ObjectCore& b, const py::object& py_request,
                      const std::string& engine) {
  const fcl::CollisionRequestd request = toRequest(py_request);
  fcl::CollisionResultd result;
  const std::size_t n = collideAt(a.geometry.get(), a.object->getTransform(), b.geometry.get(),
                                  b.object->getTransform(), request, result, engine);
  return contactsOf(result, a.geometry.get(), n);
}

py::tuple selfCollideCore(const ObjectCore& a, const py::object& py_request) {
  const fcl::CollisionRequestd request = toRequest(py_request);
  fcl::CollisionResultd result;
  requireBuilt(a.geometry.get(), "self_collide");
  const std::size_t n = kdet_fcl::selfCollide(a.object.get(), request, result);
  return contactsOf(result, a.geometry.get(), n);
}

/// The core of fcl.py's distance.
py::tuple distanceCore(const ObjectCore& a, const ObjectCore& b, const py::object& py_request) {
  const char* what = "DistanceRequest";
  fcl::DistanceRequestd request(attrOf<bool>(py_request, "enable_nearest_points", what));
  request.enable_signed_distance = attrOf<bool>(py_request, "enable_signed_distance", what);
  request.gjk_solver_type = enumOf<fcl::GJKSolverType>(py_request, "gjk_solver_type", what, 2);
  fcl::DistanceResultd result;
  const double d = distanceAt(a.geometry.get(), a.object->getTransform(), b.geometry.get(),
                              b.object->getTransform(), request, result);
  const bool swapped = result.o1 != a.geometry.get();
  return py::make_tuple(d, result.min_distance, vectorArray(result.nearest_points[0]),
                        vectorArray(result.nearest_points[1]), result.b1, result.b2, swapped);
}

/// A rigid motion from a start pose to an end pose: the translation linear in t, the rotation
/// constant (CCDM_TRANS: the start's, as FCL's TranslationMotion) or turning at a constant rate
/// about the object's origin (CCDM_LINEAR, as FCL's InterpMotion about its default reference point).
struct RigidMotion {
  fcl::Transform3d start;
  fcl::Vector3d move;
  Eigen::AngleAxisd turn;

  RigidMotion(const fcl::Transform3d& from, const fcl::Transform3d& to, bool rotates)
      : start(from), move(to.translation() - from.translation()),
        turn(rotates ? Eigen::AngleAxisd(fcl::Matrix3d(to.linear() * from.linear().transpose()))
                     : Eigen::AngleAxisd(0.0, fcl::Vector3d::UnitX())) {}

  fcl::Transform3d at(double t) const {
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    tf.linear() = Eigen::AngleAxisd(t * turn.angle(), turn.axis()).toRotationMatrix() * start.linear();
    tf.translation() = start.translation() + t * move;
    return tf;
  }

  /// A bound on how far any point of a geometry within `radius` of its origin moves per unit t.
  double speedBound(double radius) const {
    return move.norm() + (turn.angle() == 0 ? 0.0 : std::abs(turn.angle()) * radius);
  }
};

/// The radius about a geometry's origin that holds it (from its local bounding box).
double reachOf(const Geometry* g) { return g->aabb_center.norm() + g->aabb_radius; }

/// The core of fcl.py's continuousCollide. FCL 0.7's own continuous collision crashes, misses
/// contacts or is not implemented for most pairs (the sweep's log), so it is not called: both
/// solvers run here on the discrete queries above.
/// - CCDC_NAIVE: FCL's rule: n = min(num_max_iterations, ceil(1 / toc_err)) poses at t = i/(n-1);
///   the first that collides (kdet_fcl::collide: kDet decides mesh pairs) is the time of contact.
/// - CCDC_CONSERVATIVE_ADVANCEMENT: from t = 0, advance by distance / (a bound on the points'
///   relative speed), which cannot pass a contact; a contact is reported where that step falls
///   below toc_err: the time is never later than the first touch, and the objects are then closer
///   than toc_err times that speed bound.
/// Returns (time of contact, is_collide, time_of_contact); 1.0 and False for none.
py::tuple continuousCore(const ObjectCore& a, const py::object& r1, const py::object& t1,
                         const ObjectCore& b, const py::object& r2, const py::object& t2,
                         const py::object& py_request) {
  const char* what = "ContinuousCollisionRequest";
  const std::size_t iterations = countOf(py_request, "num_max_iterations", what);
  const double toc_err = attrOf<double>(py_request, "toc_err", what);
  const auto motion = enumOf<fcl::CCDMotionType>(py_request, "ccd_motion_type", what, 4);
  const auto gjk = enumOf<fcl::GJKSolverType>(py_request, "gjk_solver_type", what, 2);
  const auto solver = enumOf<fcl::CCDSolverType>(py_request, "ccd_solver_type", what, 4);
  if (!(std::isfinite(toc_err) && toc_err > 0 && toc_err <= 1))
    throw InvalidInputError("ContinuousCollisionRequest.toc_err must be in (0, 1]");
  if (motion == fcl::CCDM_SCREW || motion == fcl::CCDM_SPLINE)
    throw UnsupportedQueryError("continuousCollide: only CCDM_TRANS and CCDM_LINEAR motions are "
                           "supported (FCL 0.7's screw and spline motions miss contacts)");
  if (solver == fcl::CCDC_RAY_SHOOTING || solver == fcl::CCDC_POLYNOMIAL_SOLVER)
    throw UnsupportedQueryError("continuousCollide: only CCDC_NAIVE and CCDC_CONSERVATIVE_ADVANCEMENT "
                           "are supported (FCL 0.7 implements neither of the others)");
  const Geometry* ga = a.geometry.get();
  const Geometry* gb = b.geometry.get();
  const RigidMotion ma(a.object->getTransform(), toFclTransform(r1, t1, "continuousCollide tf1_end"),
                       motion == fcl::CCDM_LINEAR);
  const RigidMotion mb(b.object->getTransform(), toFclTransform(r2, t2, "continuousCollide tf2_end"),
                       motion == fcl::CCDM_LINEAR);
  auto hit = [](double t) { return py::make_tuple(t, true, t); };
  const py::tuple none = py::make_tuple(1.0, false, 1.0);
  if (solver == fcl::CCDC_NAIVE) {
    const double n = std::min(double(iterations), std::ceil(1 / toc_err));
    if (n < 2)
      throw InvalidInputError("continuousCollide (CCDC_NAIVE): num_max_iterations and 1 / toc_err "
                              "must both be at least 2 (the poses at t = 0 and t = 1)");
    fcl::CollisionRequestd request(1, false);
    request.gjk_solver_type = gjk;
    for (double i = 0; i < n; ++i) {
      const double t = i / (n - 1);
      fcl::CollisionResultd result;
      if (collideAt(ga, ma.at(t), gb, mb.at(t), request, result, "kdet") > 0) return hit(t);
    }
    return none;
  }
  // Conservative advancement.
  const double speed = ma.speedBound(reachOf(ga)) + mb.speedBound(reachOf(gb));
  if (!std::isfinite(speed))
    throw UnsupportedQueryError("continuousCollide (CCDC_CONSERVATIVE_ADVANCEMENT): an unbounded "
                           "geometry cannot turn; use CCDM_TRANS or CCDC_NAIVE");
  fcl::DistanceRequestd request;
  request.gjk_solver_type = gjk;
  for (double t = 0; t <= 1;) {
    fcl::DistanceResultd result;
    const double d = distanceAt(ga, ma.at(t), gb, mb.at(t), request, result);
    if (d <= 0) return hit(t);  // FCL's distance is -1 (shapes) or 0 (meshes) when they touch
    if (speed == 0) break;
    const double step = d / speed;
    if (step < toc_err) return hit(t);
    t += step;
  }
  return none;
}

/// A DynamicAABBTree manager whose callbacks are Python callables; the objects' user data is
/// their ObjectCore, which casts back to the registered Python object (fcl.py keeps it alive).
struct ManagerCore {
  fcl::DynamicAABBTreeCollisionManagerd manager;
};

py::object pythonObjectOf(fcl::CollisionObjectd* o) {
  auto* core = static_cast<ObjectCore*>(o->getUserData());
  return py::cast(core, py::return_value_policy::reference);
}

struct CallbackData {
  py::object callback;
  py::object cdata;
  std::exception_ptr error;  // the callback's exception, raised when the traversal returns

  /// Calls the Python callback on a pair; after an exception, stops the traversal.
  template <class Read>
  bool call(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, Read read) {
    if (error) return true;
    try {
      return read(callback(pythonObjectOf(o1), pythonObjectOf(o2), cdata));
    } catch (...) {
      error = std::current_exception();
      return true;
    }
  }
  void raise() {
    if (error) std::rethrow_exception(error);
  }

  /// Runs a manager traversal `run(&data)` with this callback and data, then raises what the
  /// callback raised.
  template <class Run>
  static void traverse(const py::object& callback, const py::object& cdata, Run run) {
    CallbackData d{callback, cdata, nullptr};
    run(&d);
    d.raise();
  }
};


/// A collision callback returns whether to stop (python-fcl: a bool).
bool managerCallback(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data) {
  return static_cast<CallbackData*>(data)->call(o1, o2, [](const py::object& r) {
    return py::cast<bool>(r);
  });
}

/// A distance callback returns (stop, distance so far) (python-fcl's DistanceFunction).
bool managerDistanceCallback(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data,
                             double& dist) {
  return static_cast<CallbackData*>(data)->call(o1, o2, [&dist](const py::object& r) {
    if (!py::isinstance<py::sequence>(r) || py::isinstance<py::str>(r) || py::len(r) != 2)
      throw InvalidInputError("a distance callback returns (done, distance), not " +
                              std::string(py::repr(r)));
    const py::sequence pair = py::reinterpret_borrow<py::sequence>(r);
    const double d = attrValue<double>(pair[1], "a distance callback's distance");
    if (std::isnan(d)) throw InvalidInputError("a distance callback returned a NaN distance");
    dist = d;
    return attrValue<bool>(pair[0], "a distance callback's done");
  });
}

std::vector<fcl::CollisionObjectd*> objectsOf(const std::vector<ObjectCore*>& cores) {
  std::vector<fcl::CollisionObjectd*> out;
  out.reserve(cores.size());
  for (ObjectCore* c : cores) {
    if (!c) throw InvalidInputError("a collision manager cannot hold None");
    out.push_back(c->object.get());
  }
  return out;
}

/// A public field of FCL's manager (`field` returns a reference to it) as a read-write property;
/// an int field refuses values outside [0, 2^31) (FCL uses them as tree levels and pass counts).
template <class Field>
void bindManagerField(py::class_<ManagerCore>& c, const char* name, Field field) {
  using T = std::remove_reference_t<decltype(field(std::declval<ManagerCore&>().manager))>;
  c.def_property(name, [field](ManagerCore& self) { return field(self.manager); },
                 [field, name](ManagerCore& self, const py::object& v) {
                   if constexpr (std::is_same<T, bool>::value) {
                     field(self.manager) = attrValue<bool>(v, name);
                   } else {
                     const long long x = attrValue<long long>(v, name);
                     if (x < 0 || x > std::numeric_limits<int>::max())
                       throw InvalidInputError(std::string(name) + " must be in [0, 2^31)");
                     field(self.manager) = static_cast<T>(x);
                   }
                 });
}

void bindFclCore(py::module_& m) {
  py::class_<Geometry, std::shared_ptr<Geometry>>(m, "CollisionGeometry",
      "A geometry FCL collides (its subclasses: BVHModel and the primitive shapes).")
      .def("getNodeType", [](const Geometry& g) { return int(g.getNodeType()); })
      .def("getObjectType", [](const Geometry& g) { return int(g.getObjectType()); })
      .def("computeLocalAABB", &Geometry::computeLocalAABB)
      .def_property_readonly("aabb_center", [](const Geometry& g) {
        return vectorArray(g.aabb_center);
      });

  py::class_<Meshd, Geometry, std::shared_ptr<Meshd>>(m, "BVHModel",
      "python-fcl's BVHModel (an OBBRSS mesh) whose endModel also builds kDet's hash; "
      "kdet_only=True skips FCL's refit on updates (FCL's own queries refit it on demand).")
      .def(py::init([](bool kdet_only) {
             return std::make_shared<Meshd>(kdet_only ? MeshMode::KdetOnly : MeshMode::Fcl);
           }), py::kw_only(), py::arg("kdet_only") = false)
      .def("beginModel", [](Meshd& self, long long num_tris, long long num_vertices) {
        if (num_tris < 0 || num_vertices < 0 || num_tris > std::numeric_limits<int>::max() ||
            num_vertices > std::numeric_limits<int>::max())
          throw InvalidInputError("beginModel: counts must be in [0, 2^31)");
        return self.beginModel(int(num_tris), int(num_vertices));
      }, py::arg("num_tris_") = 0, py::arg("num_vertices_") = 0)
      .def("endModel", [](Meshd& self) { return self.endModel(); })
      .def("addVertex", [](Meshd& self, double x, double y, double z) {
        return checkBvh(self.addVertex(fcl::Vector3d(x, y, z)));
      }, py::arg("x"), py::arg("y"), py::arg("z"))
      .def("addTriangle", [](Meshd& self, const py::object& a, const py::object& b,
                             const py::object& c) {
        return checkBvh(self.addTriangle(toVec3(a, "addTriangle"), toVec3(b, "addTriangle"),
                                         toVec3(c, "addTriangle")));
      }, py::arg("v1"), py::arg("v2"), py::arg("v3"))
      .def("addSubModel", [](Meshd& self, const py::object& verts, const py::object& triangles) {
        const std::vector<fcl::Vector3d> ps = toFclPoints(verts, "addSubModel vertices");
        const std::vector<Triangle> ts = toTriangles(triangles, "addSubModel triangles");
        // FCL's addSubModel offsets the indices by the vertices it already holds and does not
        // check them: indices outside this call's vertices would read past them later.
        std::vector<fcl::Triangle> ft(ts.size());
        for (std::size_t i = 0; i < ts.size(); ++i) {
          for (int c = 0; c < 3; ++c)
            if (ts[i][c] >= ps.size())
              throw InvalidInputError("addSubModel: triangle " + std::to_string(i) +
                                      " has vertex index " + std::to_string(ts[i][c]) + ", but " +
                                      std::to_string(ps.size()) + " vertices were given");
          ft[i] = fcl::Triangle(ts[i][0], ts[i][1], ts[i][2]);
        }
        if (ps.empty() && ft.empty()) return true;
        return checkBvh(self.addSubModel(ps, ft));
      }, py::arg("verts"), py::arg("triangles"))
      .def("beginUpdateModel", [](Meshd& self) { return checkBvh(self.beginUpdateModel()); })
      .def("updateVertex", [](Meshd& self, double x, double y, double z) {
        return checkBvh(self.updateVertex(fcl::Vector3d(x, y, z)));
      }, py::arg("x"), py::arg("y"), py::arg("z"))
      .def("updateSubModel", [](Meshd& self, const py::object& verts) {
        return checkBvh(self.updateSubModel(toFclPoints(verts, "updateSubModel")));
      }, py::arg("verts"))
      .def("endUpdateModel", [](Meshd& self, bool refit, bool bottomup) {
        return checkBvh(self.endUpdateModel(refit, bottomup));
      }, py::arg("refit") = true, py::arg("bottomup") = true)
      .def("num_tries_", [](const Meshd& self) { return self.num_tris; })
      .def_property_readonly("num_tris", [](const Meshd& self) { return self.num_tris; })
      .def_property_readonly("num_vertices", [](const Meshd& self) { return self.num_vertices; })
      .def("buildState", [](const Meshd& self) { return int(self.build_state); });

  // The shapes' sizes must be finite and positive: FCL answers a NaN-sized shape with no
  // contact and no error.
  auto sized = [](const char* shape, std::initializer_list<double> sizes) {
    for (double v : sizes)
      if (!(std::isfinite(v) && v > 0))
        throw InvalidInputError(std::string(shape) + ": sizes must be finite and positive, got " +
                                std::to_string(v));
  };
  py::class_<fcl::Boxd, Geometry, std::shared_ptr<fcl::Boxd>>(m, "Box")
      .def(py::init([sized](double x, double y, double z) {
             sized("Box", {x, y, z});
             return std::make_shared<fcl::Boxd>(x, y, z);
           }), py::arg("x"), py::arg("y"), py::arg("z"))
      .def_property_readonly("side", [](const fcl::Boxd& b) { return vectorArray(b.side); });
  py::class_<fcl::Sphered, Geometry, std::shared_ptr<fcl::Sphered>>(m, "Sphere")
      .def(py::init([sized](double r) {
             sized("Sphere", {r});
             return std::make_shared<fcl::Sphered>(r);
           }), py::arg("radius"))
      .def_readonly("radius", &fcl::Sphered::radius);
  py::class_<fcl::Ellipsoidd, Geometry, std::shared_ptr<fcl::Ellipsoidd>>(m, "Ellipsoid")
      .def(py::init([sized](double a, double b, double c) {
             sized("Ellipsoid", {a, b, c});
             return std::make_shared<fcl::Ellipsoidd>(a, b, c);
           }), py::arg("a"), py::arg("b"), py::arg("c"));
  py::class_<fcl::Capsuled, Geometry, std::shared_ptr<fcl::Capsuled>>(m, "Capsule")
      .def(py::init([sized](double r, double lz) {
             sized("Capsule", {r, lz});
             return std::make_shared<fcl::Capsuled>(r, lz);
           }), py::arg("radius"), py::arg("lz"))
      .def_readonly("radius", &fcl::Capsuled::radius)
      .def_readonly("lz", &fcl::Capsuled::lz);
  py::class_<fcl::Cylinderd, Geometry, std::shared_ptr<fcl::Cylinderd>>(m, "Cylinder")
      .def(py::init([sized](double r, double lz) {
             sized("Cylinder", {r, lz});
             return std::make_shared<fcl::Cylinderd>(r, lz);
           }), py::arg("radius"), py::arg("lz"))
      .def_readonly("radius", &fcl::Cylinderd::radius)
      .def_readonly("lz", &fcl::Cylinderd::lz);
  py::class_<fcl::Coned, Geometry, std::shared_ptr<fcl::Coned>>(m, "Cone")
      .def(py::init([sized](double r, double lz) {
             sized("Cone", {r, lz});
             return std::make_shared<fcl::Coned>(r, lz);
           }), py::arg("radius"), py::arg("lz"))
      .def_readonly("radius", &fcl::Coned::radius)
      .def_readonly("lz", &fcl::Coned::lz);

  py::class_<fcl::TrianglePd, Geometry, std::shared_ptr<fcl::TrianglePd>>(m, "TriangleP")
      .def(py::init([](const py::object& a, const py::object& b, const py::object& c) {
             return std::make_shared<fcl::TrianglePd>(finiteVec3(a, "TriangleP a"),
                                                      finiteVec3(b, "TriangleP b"),
                                                      finiteVec3(c, "TriangleP c"));
           }), py::arg("a"), py::arg("b"), py::arg("c"))
      .def_property_readonly("a", [](const fcl::TrianglePd& t) { return vectorArray(t.a); })
      .def_property_readonly("b", [](const fcl::TrianglePd& t) { return vectorArray(t.b); })
      .def_property_readonly("c", [](const fcl::TrianglePd& t) { return vectorArray(t.c); });
  py::class_<fcl::Convexd, Geometry, std::shared_ptr<fcl::Convexd>>(m, "Convex",
      "A convex polytope: vertices (n, 3) and faces encoded as python-fcl's (and FCL's): for each "
      "face its vertex count, then its vertex indices, counter-clockwise seen from outside.")
      .def(py::init(&makeConvex), py::arg("vertices"), py::arg("num_faces"), py::arg("faces"))
      .def_property_readonly("num_faces", &fcl::Convexd::getFaceCount);
  // Halfspace: the points x with n.x <= d; Plane: n.x = d. FCL stores n normalized (d scaled).
  py::class_<fcl::Halfspaced, Geometry, std::shared_ptr<fcl::Halfspaced>>(m, "Halfspace")
      .def(py::init([](const py::object& n, double d) {
             const auto nd = planeOf(n, d, "Halfspace");
             return std::make_shared<fcl::Halfspaced>(nd.first, nd.second);
           }), py::arg("n"), py::arg("d"))
      .def_property_readonly("n", [](const fcl::Halfspaced& h) { return vectorArray(h.n); })
      .def_readonly("d", &fcl::Halfspaced::d);
  py::class_<fcl::Planed, Geometry, std::shared_ptr<fcl::Planed>>(m, "Plane")
      .def(py::init([](const py::object& n, double d) {
             const auto nd = planeOf(n, d, "Plane");
             return std::make_shared<fcl::Planed>(nd.first, nd.second);
           }), py::arg("n"), py::arg("d"))
      .def_property_readonly("n", [](const fcl::Planed& h) { return vectorArray(h.n); })
      .def_readonly("d", &fcl::Planed::d);
#if FCL_HAVE_OCTOMAP
  py::class_<fcl::OcTreed, Geometry, std::shared_ptr<fcl::OcTreed>>(m, "OcTree",
      "An octomap occupancy tree of resolution r from octomap's binary node data (what "
      "OcTree::writeBinaryData writes: the binary file's part after its header), as python-fcl's.")
      .def(py::init(&makeOcTree), py::arg("r"), py::arg("data"));
#endif

  py::class_<ObjectCore>(m, "_ObjectCore")
      .def(py::init([](std::shared_ptr<Geometry> geometry, const py::object& rotation,
                       const py::object& translation) {
             if (!geometry) throw InvalidInputError("CollisionObject: the geometry is None");
             requireBuilt(geometry.get(), "CollisionObject");
             auto core = std::make_unique<ObjectCore>();
             core->geometry = geometry;
             core->object = std::make_unique<fcl::CollisionObjectd>(
                 geometry, toFclTransform(rotation, translation));
             core->object->setUserData(core.get());
             return core;
           }), py::arg("geometry"), py::arg("rotation") = py::none(),
           py::arg("translation") = py::none())
      .def("_set_transform", [](ObjectCore& self, const py::object& rotation,
                                const py::object& translation) {
        self.object->setTransform(toFclTransform(rotation, translation));
        self.object->computeAABB();
      })
      .def("_rotation", [](const ObjectCore& self) {
        py::array_t<double> R({3, 3});
        const fcl::Matrix3d& M = self.object->getRotation();
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) R.mutable_at(i, j) = M(i, j);
        return R;
      })
      .def("_translation", [](const ObjectCore& self) {
        return vectorArray(self.object->getTranslation());
      })
      .def("getObjectType", [](const ObjectCore& self) { return int(self.object->getObjectType()); })
      .def("getNodeType", [](const ObjectCore& self) { return int(self.object->getNodeType()); })
      .def("isOccupied", [](const ObjectCore& self) { return self.object->isOccupied(); })
      .def("isFree", [](const ObjectCore& self) { return self.object->isFree(); })
      .def("isUncertain", [](const ObjectCore& self) { return self.object->isUncertain(); });

  m.def("_collide", &collideCore);
  m.def("_self_collide", &selfCollideCore);
  m.def("_distance", &distanceCore);
  m.def("_continuous_collide", &continuousCore);

  py::class_<ManagerCore> manager(m, "_ManagerCore");
  manager.def(py::init<>())
      .def("_register", [](ManagerCore& self, const std::vector<ObjectCore*>& objs) {
        std::vector<fcl::CollisionObjectd*> os = objectsOf(objs);
        self.manager.registerObjects(os);
      })
      .def("_unregister", [](ManagerCore& self, ObjectCore* o) {
        if (o) self.manager.unregisterObject(o->object.get());
      })
      .def("_update", [](ManagerCore& self, const std::vector<ObjectCore*>& objs) {
        if (objs.empty()) self.manager.update();
        else {
          std::vector<fcl::CollisionObjectd*> os = objectsOf(objs);
          self.manager.update(os);
        }
      })
      .def("setup", [](ManagerCore& self) { self.manager.setup(); })
      .def("clear", [](ManagerCore& self) { self.manager.clear(); })
      .def("empty", [](const ManagerCore& self) { return self.manager.empty(); })
      .def("size", [](const ManagerCore& self) { return self.manager.size(); })
      .def("_collide", [](ManagerCore& self, const py::object& cdata, const py::object& cb) {
        CallbackData::traverse(cb, cdata, [&](void* d) { self.manager.collide(d, managerCallback); });
      })
      .def("_collide_object", [](ManagerCore& self, ObjectCore& o, const py::object& cdata,
                                 const py::object& cb) {
        CallbackData::traverse(cb, cdata, [&](void* d) {
          self.manager.collide(o.object.get(), d, managerCallback);
        });
      })
      .def("_collide_manager", [](ManagerCore& self, ManagerCore& other, const py::object& cdata,
                                  const py::object& cb) {
        CallbackData::traverse(cb, cdata, [&](void* d) {
          self.manager.collide(&other.manager, d, managerCallback);
        });
      })
      .def("_distance", [](ManagerCore& self, const py::object& cdata, const py::object& cb) {
        CallbackData::traverse(cb, cdata, [&](void* d) {
          self.manager.distance(d, managerDistanceCallback);
        });
      })
      .def("_distance_object", [](ManagerCore& self, ObjectCore& o, const py::object& cdata,
                                  const py::object& cb) {
        CallbackData::traverse(cb, cdata, [&](void* d) {
          self.manager.distance(o.object.get(), d, managerDistanceCallback);
        });
      })
      .def("_distance_manager", [](ManagerCore& self, ManagerCore& other, const py::object& cdata,
                                   const py::object& cb) {
        CallbackData::traverse(cb, cdata, [&](void* d) {
          self.manager.distance(&other.manager, d, managerDistanceCallback);
        });
      });
  // The tree's tuning fields (python-fcl's properties of the same names).
#define KDET_FCL_MANAGER_FIELD(name) \
  bindManagerField(manager, #name, [](fcl::DynamicAABBTreeCollisionManagerd& x) -> auto& { \
    return x.name;                                                                      \
  })
  KDET_FCL_MANAGER_FIELD(max_tree_nonbalanced_level);
  KDET_FCL_MANAGER_FIELD(tree_incremental_balance_pass);
  KDET_FCL_MANAGER_FIELD(tree_topdown_balance_threshold);
  KDET_FCL_MANAGER_FIELD(tree_topdown_level);
  KDET_FCL_MANAGER_FIELD(tree_init_level);
  KDET_FCL_MANAGER_FIELD(octree_as_geometry_collide);
  KDET_FCL_MANAGER_FIELD(octree_as_geometry_distance);
#undef KDET_FCL_MANAGER_FIELD
}

}  // namespace

PYBIND11_MODULE(_kdet_fcl, m) {
  m.doc() = "kdet_fcl: kDet's hierarchical-hash collision detection (every intersecting "
            "triangle pair, self-collision, CPU and CUDA backends) and an FCL-style API";

  // Exceptions: kdet_fcl.Error, and its subclasses that are also the built-in kinds.
  py::object error = py::reinterpret_steal<py::object>(
      PyErr_NewException("kdet_fcl.Error", PyExc_RuntimeError, nullptr));
  auto sub = [&](const char* name, PyObject* builtin) {
    py::tuple bases = py::make_tuple(error, py::handle(builtin));
    return py::reinterpret_steal<py::object>(
        PyErr_NewException(name, bases.ptr(), nullptr));
  };
  py::object invalid = sub("kdet_fcl.InvalidInputError", PyExc_ValueError);
  py::object mesh_file = sub("kdet_fcl.MeshFileError", PyExc_OSError);
  py::object unavailable = sub("kdet_fcl.BackendUnavailableError", PyExc_RuntimeError);
  py::object cuda = sub("kdet_fcl.CudaError", PyExc_RuntimeError);
  py::object unsupported = sub("kdet_fcl.UnsupportedQueryError", PyExc_NotImplementedError);
  m.attr("Error") = error;
  m.attr("InvalidInputError") = invalid;
  m.attr("MeshFileError") = mesh_file;
  m.attr("BackendUnavailableError") = unavailable;
  m.attr("CudaError") = cuda;
  m.attr("UnsupportedQueryError") = unsupported;
  // The translator's own references, never dropped (the module's attributes may be deleted).
  static PyObject* e_error = error.inc_ref().ptr();
  static PyObject* e_invalid = invalid.inc_ref().ptr();
  static PyObject* e_mesh_file = mesh_file.inc_ref().ptr();
  static PyObject* e_unavailable = unavailable.inc_ref().ptr();
  static PyObject* e_cuda = cuda.inc_ref().ptr();
  static PyObject* e_unsupported = unsupported.inc_ref().ptr();
  // Local: only this module's calls are translated by it.
  py::register_local_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InvalidInputError& e) {
      PyErr_SetString(e_invalid, e.what());
    } catch (const MeshFileError& e) {
      PyErr_SetString(e_mesh_file, e.what());
    } catch (const BackendUnavailableError& e) {
      PyErr_SetString(e_unavailable, e.what());
    } catch (const CudaError& e) {
      PyErr_SetString(e_cuda, e.what());
    } catch (const UnsupportedQueryError& e) {
      PyErr_SetString(e_unsupported, e.what());
    } catch (const Error& e) {
      PyErr_SetString(e_error, e.what());
    }
  });

  bindMesh<double>(m, "Mesh", "double");
  bindMesh<float>(m, "MeshF32", "float");

  m.def("read_mesh", [](const std::string& path) {
    TriangleMesh<double> mesh;
    {
      py::gil_scoped_release nogil;
      mesh = readMesh<double>(path);
    }
    return py::make_tuple(pointsArray(mesh.vertices), trianglesArray(mesh.triangles));
  }, py::arg("path"), "(vertices (n, 3) float64, triangles (m, 3) uint32) of an OBJ, OFF, PLY or STL file.");
  m.def("write_mesh", [](const std::string& path, const py::object& vertices,
                         const py::object& triangles) {
    TriangleMesh<double> mesh;
    mesh.vertices = toPoints<double>(vertices, "write_mesh vertices");
    mesh.triangles = toTriangles(triangles, "write_mesh triangles");
    mesh.validate(false, "write_mesh");
    py::gil_scoped_release nogil;
    writeMesh(mesh, path);
  }, py::arg("path"), py::arg("vertices"), py::arg("triangles"));

  // The library's procedural scenes (kdet_fcl/scenes.h), as (vertices, triangles).
  m.def("make_sphere", [](double radius, int segments, int rings, const py::object& center) {
    const Vec3<double> c = toPose<double>(py::none(), center, "make_sphere center").t;
    const TriangleMesh<double> mesh = makeSphere<double>(c, radius, segments, rings);
    return py::make_tuple(pointsArray(mesh.vertices), trianglesArray(mesh.triangles));
  }, py::arg("radius"), py::arg("segments"), py::arg("rings"), py::kw_only(),
     py::arg("center") = py::none(),
     "A UV sphere: `segments` around, `rings` from pole to pole (one vertex at each pole).");
  m.def("make_draped_cloth", [](int n, double size, double sphere_radius, double penetration,
                                double time) {
    const TriangleMesh<double> mesh =
        makeDrapedCloth<double>(n, size, sphere_radius, penetration, time);
    return py::make_tuple(pointsArray(mesh.vertices), trianglesArray(mesh.triangles));
  }, py::arg("n"), py::arg("size"), py::arg("sphere_radius"), py::arg("penetration"),
     py::arg("time"), "An n x n cloth draped over a sphere at the origin (time 0 to 1).");

  m.def("built_with_cuda", &builtWithCuda);
  m.def("cuda_device_count", &cudaDeviceCount);
  m.def("cuda_device_description", &cudaDeviceDescription, py::arg("device") = 0);
  m.def("set_cuda_device", &setCudaDevice, py::arg("device"),
        "Chooses the CUDA device of the GPU backend for the process (default: "
        "KDET_FCL_CUDA_DEVICE, else 0). A query leaves the thread's current CUDA device as it "
        "found it. InvalidInputError for a device that does not exist, BackendUnavailableError "
        "without CUDA.");
  m.def("cuda_device", &cudaDevice,
        "The CUDA device the GPU backend uses (-1 without CUDA or a device).");

  bindFclCore(m);
}
