"""Tests of the Python module kdet_fcl (ctest python_module; run: PYTHONPATH=<build>/python
python3 -m unittest discover -s python/tests). The pairs are checked against the exact brute
force of the same module, and the FCL-style API against FCL 0.7 itself in the same process."""
import os
import tempfile
import threading
import unittest

import numpy as np

import kdet_fcl
from kdet_fcl import fcl

import meshes as M

SHARED_DATA = os.environ.get("KDET_FCL_SHARED_DATA", "")


def scene(angle=0.4, shift=(0.9, 0.1, 0.05)):
    a = kdet_fcl.Mesh(*M.sphere(0.6, 24, 12))
    b = kdet_fcl.Mesh(*M.torus(), rotation=M.rotation([1, 1, 0], angle), translation=shift)
    return a, b


class CoreQueries(unittest.TestCase):
    def test_pairs_equal_the_exact_brute_force(self):
        for k, (angle, shift) in enumerate([(0.4, (0.9, 0.1, 0.05)), (1.3, (0.2, 0.8, -0.1)),
                                            (2.0, (1.1, -0.2, 0.3)), (0.0, (3.0, 0.0, 0.0))]):
            a, b = scene(angle, shift)
            pairs = kdet_fcl.intersect(a, b)
            self.assertEqual(pairs.dtype, np.uint32)
            self.assertEqual(pairs.shape[1], 2)
            truth = M.pair_set(kdet_fcl.brute_force_intersect(a, b))
            self.assertEqual(M.pair_set(pairs), truth)
            self.assertEqual(len(pairs), len(truth), "each pair exactly once")
            self.assertEqual(kdet_fcl.intersects(a, b), bool(truth))
            if k < 3:
                self.assertTrue(truth, "the scene must touch")
            else:
                self.assertFalse(truth)
            # b1 indexes a's triangles, b2 b's.
            if len(pairs):
                self.assertLess(pairs[:, 0].max(), a.num_triangles)
                self.assertLess(pairs[:, 1].max(), b.num_triangles)

    def test_self_pairs_equal_the_exact_brute_force(self):
        for n in (10, 24):
            m = kdet_fcl.Mesh(*M.folded_cloth(n))
            pairs = kdet_fcl.intersect_self(m)
            truth = M.pair_set(kdet_fcl.brute_force_intersect_self(m))
            self.assertTrue(truth)
            self.assertEqual(M.pair_set(pairs), truth)
            self.assertTrue(np.all(pairs[:, 0] < pairs[:, 1]))
            tris = m.triangles
            for i, j in pairs:
                self.assertFalse(set(tris[i]) & set(tris[j]), "vertex-sharing pairs excluded")

    def test_float_meshes_and_predicates(self):
        v1, t1 = M.sphere(0.6, 24, 12)
        v2, t2 = M.torus()
        R, t = M.rotation([1, 1, 0], 0.4), (0.9, 0.1, 0.05)
        a, b = kdet_fcl.MeshF32(v1, t1), kdet_fcl.MeshF32(v2, t2, rotation=R, translation=t)
        truth = M.pair_set(kdet_fcl.brute_force_intersect(a, b))
        self.assertTrue(truth)
        self.assertEqual(M.pair_set(kdet_fcl.intersect(a, b)), truth)
        for p in ("double", "float"):
            got = M.pair_set(kdet_fcl.intersect(a, b, predicate=p))
            self.assertEqual(got, M.pair_set(kdet_fcl.brute_force_intersect(a, b, predicate=p)))
        with self.assertRaises(TypeError):  # a double mesh with a float one
            kdet_fcl.intersect(a, kdet_fcl.Mesh(v2, t2))

    def test_capped_queries_are_subsets(self):
        a, b = scene()
        full = M.pair_set(kdet_fcl.intersect(a, b))
        for k in (1, 7, len(full) - 1, len(full), len(full) + 5):
            got = kdet_fcl.intersect(a, b, max_pairs=k)
            self.assertEqual(len(got), min(k, len(full)))
            self.assertTrue(M.pair_set(got) <= full)
        self.assertEqual(len(kdet_fcl.intersect(a, b, max_pairs=0)), len(full))

    def test_threads_do_not_change_the_pairs(self):
        a, b = scene()
        one = kdet_fcl.intersect(a, b, threads=1)
        for t in (2, 3, 0):
            np.testing.assert_array_equal(kdet_fcl.intersect(a, b, threads=t), one)

    def test_intersect_all_is_the_three_queries(self):
        a = kdet_fcl.Mesh(*M.folded_cloth(16))
        b = kdet_fcl.Mesh(*M.folded_cloth(12), translation=(0.05, 0.1, 0.02))
        sa, sb, inter = kdet_fcl.intersect_all(a, b)
        self.assertEqual(M.pair_set(sa), M.pair_set(kdet_fcl.intersect_self(a)))
        self.assertEqual(M.pair_set(sb), M.pair_set(kdet_fcl.intersect_self(b)))
        self.assertEqual(M.pair_set(inter), M.pair_set(kdet_fcl.intersect(a, b)))
        self.assertTrue(sa.size and sb.size and inter.size)

    def test_pose_deformation_and_topology_changes(self):
        a, b = scene()
        # Rigid motion.
        R2, t2 = M.rotation([0, 0, 1], 0.7), np.array([0.7, 0.4, -0.1])
        b.set_pose(R2, t2)
        R, t = b.pose
        np.testing.assert_allclose(R, R2)
        np.testing.assert_allclose(t, t2)
        self.assertEqual(M.pair_set(kdet_fcl.intersect(a, b)),
                         M.pair_set(kdet_fcl.brute_force_intersect(a, b)))
        # Deformation: the same vertices moved.
        v = a.vertices * 1.4
        a.update_vertices(v)
        np.testing.assert_array_equal(a.vertices, v)
        truth = M.pair_set(kdet_fcl.brute_force_intersect(a, b))
        self.assertTrue(truth)
        self.assertEqual(M.pair_set(kdet_fcl.intersect(a, b)), truth)
        # Topology: a finer sphere.
        a.set_mesh(*M.sphere(0.84, 40, 20))
        self.assertEqual(a.num_triangles, 2 * 40 * 19)
        self.assertEqual(M.pair_set(kdet_fcl.intersect(a, b)),
                         M.pair_set(kdet_fcl.brute_force_intersect(a, b)))

    def test_hierarchy_statistics_and_kfree(self):
        m = kdet_fcl.Mesh(*M.folded_cloth(20))
        s = m.stats()
        self.assertEqual(s["triangles"], 800)
        self.assertGreaterEqual(s["levels"], 1)
        self.assertGreaterEqual(s["entries"], 800)
        self.assertEqual(s["below_cell0"], 0)  # a size ratio within 2^38
        # One triangle of 2e12 over two of about 1.6e-3 that cross it: a ratio beyond 2^38.
        v = np.array([[-1e12, -1e12, 0], [1e12, -1e12, 0], [0, 1e12, 0], [0, 0, -5e-4],
                      [1e-3, 0, 5e-4], [0, 1e-3, 5e-4], [2e-3, 0, -5e-4], [3e-3, 0, 5e-4],
                      [2e-3, 1e-3, 5e-4]])
        wide = kdet_fcl.Mesh(v, np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8]]))
        self.assertEqual(wide.stats()["below_cell0"], 2)
        self.assertEqual(len(kdet_fcl.intersect_self(wide)), 2)
        k = kdet_fcl.analyze_kfree(m, keep_counts=True)
        self.assertEqual(k["triangles"], 800)
        self.assertEqual(len(k["counts"]), 800)
        self.assertEqual(k["max_count"], int(k["counts"].max()))
        self.assertEqual(k["k"], k["max_count"] + 1)
        self.assertAlmostEqual(k["mean"], float(k["counts"].mean()), places=9)

    def test_mesh_files_round_trip(self):
        v, t = M.torus(1.0, 0.3, 16, 8)
        with tempfile.TemporaryDirectory() as d:
            for ext in ("obj", "off", "ply", "stl"):
                path = os.path.join(d, "torus." + ext)
                kdet_fcl.write_mesh(path, v, t)
                v2, t2 = kdet_fcl.read_mesh(path)
                self.assertEqual(len(t2), len(t), ext)
                if ext != "stl":  # STL stores triangles, not shared vertices
                    np.testing.assert_allclose(v2, v, rtol=0, atol=1e-6)
                    np.testing.assert_array_equal(t2, t)

    def test_concurrent_queries_and_changes(self):
        """Python threads query and change meshes at once: every answer is the pair set of a
        state the mesh was in (the wrapper's lock orders them; no torn state)."""
        a, b = scene()
        poses = [(M.rotation([1, 1, 0], 0.4), (0.9, 0.1, 0.05)),
                 (M.rotation([0, 1, 1], 1.1), (0.5, 0.5, 0.1))]
        expected = []
        for R, t in poses:
            b.set_pose(R, t)
            expected.append(M.pair_set(kdet_fcl.brute_force_intersect(a, b)))
        self.assertNotEqual(expected[0], expected[1])
        errors, seen = [], set()

        def query():
            try:
                for _ in range(60):
                    got = M.pair_set(kdet_fcl.intersect(a, b, threads=1))
                    if got not in expected:
                        errors.append("a pair set of no pose")
                    seen.add(expected.index(got) if got in expected else -1)
            except Exception as e:  # noqa: BLE001 - reported below
                errors.append(repr(e))

        def move():
            try:
                for i in range(60):
                    b.set_pose(*poses[i % 2])
            except Exception as e:  # noqa: BLE001
                errors.append(repr(e))

        threads = [threading.Thread(target=query) for _ in range(3)] + [threading.Thread(target=move)]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        self.assertEqual(errors, [])


class BadInput(unittest.TestCase):
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)

    def assertInvalid(self, fn, text):
        with self.assertRaises(kdet_fcl.InvalidInputError) as cm:
            fn()
        self.assertIsInstance(cm.exception, ValueError)
        self.assertIsInstance(cm.exception, kdet_fcl.Error)
        self.assertIn(text, str(cm.exception))

    def test_bad_arrays_and_options(self):
        V = self.V
        self.assertInvalid(lambda: kdet_fcl.Mesh(V, [[0, 1, 3]]), "refers to vertex 3")
        self.assertInvalid(lambda: kdet_fcl.Mesh(V, [[0, 1, -1]]), "vertex index -1")
        self.assertInvalid(lambda: kdet_fcl.Mesh(V, np.full((1, 3), 2 ** 63, dtype=np.uint64)),
                           "vertex index 9223372036854775808,")
        self.assertInvalid(lambda: kdet_fcl.Mesh(V, [[0, 1.0, 2]]), "must be integers")
        self.assertInvalid(lambda: kdet_fcl.Mesh(V, [0, 1, 2]), "(m, 3)")
        self.assertInvalid(lambda: kdet_fcl.Mesh(V[:, :2], [[0, 1, 2]]), "(n, 3)")
        self.assertInvalid(lambda: kdet_fcl.Mesh("abc", [[0, 1, 2]]), "expected numbers")
        self.assertInvalid(lambda: kdet_fcl.Mesh([[np.nan, 0, 0], [1, 0, 0], [0, 1, 0]],
                                                 [[0, 1, 2]]), "non-finite")
        self.assertInvalid(lambda: kdet_fcl.Mesh([[np.inf, 0, 0], [1, 0, 0], [0, 1, 0]],
                                                 [[0, 1, 2]]), "non-finite")
        # Beyond the range where the hierarchy and the exact predicates hold (a query of such a
        # mesh did not finish or answered wrongly before); its ends are fine.
        self.assertInvalid(lambda: kdet_fcl.Mesh(V * 1e154, [[0, 1, 2]]), "2^330")
        self.assertInvalid(lambda: kdet_fcl.Mesh(V * 1e-170, [[0, 1, 2]]), "2^-247")
        kdet_fcl.Mesh(V * 2.0 ** 330, [[0, 1, 2]])
        kdet_fcl.Mesh(V * 2.0 ** -247, [[0, 1, 2]])
        self.assertInvalid(lambda: kdet_fcl.Mesh(V, [[0, 1, 2]], rotation=np.eye(3) * 2),
                           "orthonormal")
        self.assertInvalid(lambda: kdet_fcl.Mesh(V, [[0, 1, 2]], rotation=np.eye(4)), "3x3")
        self.assertInvalid(lambda: kdet_fcl.Mesh(V, [[0, 1, 2]], translation=[1, 2]), "3 numbers")
        self.assertInvalid(lambda: kdet_fcl.Mesh(V, [[0, 1, 2]], threads=-1), "threads")
        m = kdet_fcl.Mesh(V, [[0, 1, 2]])
        self.assertInvalid(lambda: kdet_fcl.intersect(m, m, backend="gpu"), "backend")
        self.assertInvalid(lambda: kdet_fcl.intersect(m, m, predicate="robust"), "predicate")
        self.assertInvalid(lambda: kdet_fcl.intersect(m, m, max_pairs=-1), "max_pairs")
        self.assertInvalid(lambda: kdet_fcl.intersect_self(m, threads=-2), "threads")
        self.assertInvalid(lambda: m.set_pose([[1, 0, 0], [0, 1, 0], [0, 0, np.nan]], None),
                           "set")
        with self.assertRaises(TypeError):
            kdet_fcl.intersect(m, None)

    def test_a_refused_change_leaves_the_mesh_as_it_was(self):
        a, b = scene()
        before_v, before_pairs = a.vertices, M.pair_set(kdet_fcl.intersect(a, b))
        bad = a.vertices
        bad[5, 1] = np.nan
        self.assertInvalid(lambda: a.update_vertices(bad), "non-finite")
        self.assertInvalid(lambda: a.update_vertices(a.vertices[:10]), "")
        self.assertInvalid(lambda: a.set_mesh(a.vertices, [[0, 1, 10 ** 6]]), "")
        self.assertInvalid(lambda: b.set_pose(np.eye(3) * 1.5, (0, 0, 0)), "orthonormal")
        np.testing.assert_array_equal(a.vertices, before_v)
        self.assertEqual(M.pair_set(kdet_fcl.intersect(a, b)), before_pairs)

    def test_empty_meshes_meet_nothing(self):
        e = kdet_fcl.Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
        a, _ = scene()
        self.assertEqual(kdet_fcl.intersect(a, e).shape, (0, 2))
        self.assertEqual(kdet_fcl.intersect_self(e).shape, (0, 2))
        self.assertFalse(kdet_fcl.intersects(e, a))

    def test_unreadable_files(self):
        with self.assertRaises(kdet_fcl.MeshFileError) as cm:
            kdet_fcl.read_mesh("/nonexistent/mesh.obj")
        self.assertIsInstance(cm.exception, OSError)
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "bad.obj")
            with open(p, "w") as f:
                f.write("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
            with self.assertRaises(kdet_fcl.Error):
                kdet_fcl.read_mesh(p)


class Cuda(unittest.TestCase):
    def test_cuda_backend_or_a_clear_error(self):
        a, b = scene()
        cpu = kdet_fcl.intersect(a, b)
        if kdet_fcl.cuda_available():
            gpu = kdet_fcl.intersect(a, b, backend="cuda")
            cpu_sorted = cpu[np.lexsort((cpu[:, 1], cpu[:, 0]))]
            np.testing.assert_array_equal(gpu, cpu_sorted)  # sorted by (a, b) on the GPU
            m = kdet_fcl.Mesh(*M.folded_cloth(24))
            self.assertEqual(M.pair_set(kdet_fcl.intersect_self(m, backend="cuda")),
                             M.pair_set(kdet_fcl.intersect_self(m)))
            n = kdet_fcl.Mesh(*M.folded_cloth(16), translation=(0.05, 0.1, 0.02))
            for g, c in zip(kdet_fcl.intersect_all(m, n, backend="cuda"), kdet_fcl.intersect_all(m, n)):
                self.assertTrue(len(c))
                self.assertEqual(M.pair_set(g), M.pair_set(c))
            # A deformation and a float mesh on the device.
            m.update_vertices(m.vertices * 1.01)
            self.assertEqual(M.pair_set(kdet_fcl.intersect_self(m, backend="cuda")),
                             M.pair_set(kdet_fcl.brute_force_intersect_self(m)))
            f1, f2 = kdet_fcl.MeshF32(*M.sphere(0.6, 24, 12)), kdet_fcl.MeshF32(
                *M.torus(), rotation=M.rotation([1, 1, 0], 0.4), translation=(0.9, 0.1, 0.05))
            self.assertEqual(M.pair_set(kdet_fcl.intersect(f1, f2, backend="cuda")),
                             M.pair_set(kdet_fcl.brute_force_intersect(f1, f2)))
            print("GPU:", kdet_fcl.cuda_device_description())
        else:
            with self.assertRaises(kdet_fcl.BackendUnavailableError) as cm:
                kdet_fcl.intersect(a, b, backend="cuda")
            self.assertIsInstance(cm.exception, RuntimeError)
            self.assertTrue(str(cm.exception))
            # auto falls back to the CPU.
            np.testing.assert_array_equal(kdet_fcl.intersect(a, b, backend="auto"), cpu)

    def test_the_cuda_device_is_chosen_or_refused(self):
        with self.assertRaises(kdet_fcl.InvalidInputError):
            kdet_fcl.set_cuda_device(-1)
        n = kdet_fcl.cuda_device_count()
        if not kdet_fcl.cuda_available():
            self.assertEqual(kdet_fcl.cuda_device(), -1)
            with self.assertRaises(kdet_fcl.BackendUnavailableError):
                kdet_fcl.set_cuda_device(0)
            return
        with self.assertRaisesRegex(kdet_fcl.InvalidInputError, "this machine has %d" % n):
            kdet_fcl.set_cuda_device(n)
        m = kdet_fcl.Mesh(*M.folded_cloth(24))
        want = M.pair_set(kdet_fcl.intersect_self(m))
        for d in (n - 1, 0):  # the last device, then device 0 again
            kdet_fcl.set_cuda_device(d)
            self.assertEqual(kdet_fcl.cuda_device(), d)
            self.assertEqual(M.pair_set(kdet_fcl.intersect_self(m, backend="cuda")), want)


ALL = 10 ** 9


class FclApi(unittest.TestCase):
    def setUp(self):
        self.vs, self.ts = M.sphere(0.6, 24, 12)
        self.vt, self.tt = M.torus()
        self.ms, self.mt = M.fcl_mesh(self.vs, self.ts), M.fcl_mesh(self.vt, self.tt)

    def pairs(self, o1, o2, engine=fcl.collide):
        res = fcl.CollisionResult()
        n = engine(o1, o2, fcl.CollisionRequest(num_max_contacts=ALL, enable_contact=True), res)
        self.assertEqual(n, len(res.contacts))
        return {(c.b1, c.b2) for c in res.contacts}, res

    def test_contacts_equal_the_exact_pairs_and_fcl(self):
        for angle, shift in [(0.4, (0.9, 0.1, 0.05)), (1.3, (0.2, 0.8, -0.1)),
                             (2.0, (1.1, -0.2, 0.3))]:
            R = M.rotation([1, 1, 0], angle)
            o1 = fcl.CollisionObject(self.ms)
            o2 = fcl.CollisionObject(self.mt, fcl.Transform(R, shift))
            got, res = self.pairs(o1, o2)
            a = kdet_fcl.Mesh(self.vs, self.ts)
            b = kdet_fcl.Mesh(self.vt, self.tt, rotation=R, translation=shift)
            self.assertEqual(got, M.pair_set(kdet_fcl.brute_force_intersect(a, b)))
            self.assertTrue(res.is_collision)
            ref, _ = self.pairs(o1, o2, fcl.fcl_collide)
            self.assertEqual(got, ref, "FCL 0.7 finds the same pairs on these generic poses")
            for c in res.contacts:
                self.assertIs(c.o1, self.ms)
                self.assertIs(c.o2, self.mt)
                self.assertTrue(np.all(np.isfinite(c.pos)))
                self.assertAlmostEqual(float(np.linalg.norm(c.normal)), 1.0, places=9)
                self.assertGreaterEqual(c.penetration_depth, 0.0)
            # Swapped arguments: b1 indexes the first argument's mesh.
            swapped, res2 = self.pairs(o2, o1)
            self.assertEqual(swapped, {(j, i) for i, j in got})
            self.assertIs(res2.contacts[0].o1, self.mt)

    def test_caps_defaults_and_accumulation(self):
        o1 = fcl.CollisionObject(self.ms)
        o2 = fcl.CollisionObject(self.mt, fcl.Transform(M.rotation([1, 1, 0], 0.4), [0.9, 0.1, 0.05]))
        res = fcl.CollisionResult()
        self.assertEqual(fcl.collide(o1, o2, fcl.CollisionRequest(), res), 1)  # default: 1 contact
        self.assertEqual(fcl.fcl_collide(o1, o2, fcl.CollisionRequest(), fcl.CollisionResult()), 1)
        self.assertEqual(fcl.collide(o1, o2, fcl.CollisionRequest(num_max_contacts=5), res), 5)
        self.assertEqual(len(res.contacts), 6, "results accumulate as in python-fcl")
        self.assertEqual(fcl.collide(o1, o2), 1)
        far = fcl.CollisionObject(self.mt, fcl.Transform([5.0, 0, 0]))
        res = fcl.CollisionResult()
        self.assertEqual(fcl.collide(o1, far, fcl.CollisionRequest(), res), 0)
        self.assertFalse(res.is_collision)
        with self.assertRaises(kdet_fcl.InvalidInputError):
            fcl.collide(o1, o2, fcl.CollisionRequest(num_max_contacts=-1))

    def test_transforms_and_object_poses(self):
        q = np.array([np.cos(0.3), 0.0, np.sin(0.3), 0.0])  # (w, x, y, z): 0.6 rad about y
        tf = fcl.Transform(q, [1, 2, 3])
        np.testing.assert_allclose(tf.getRotation(), M.rotation([0, 1, 0], 0.6), atol=1e-12)
        np.testing.assert_allclose(tf.getQuatRotation(), q, atol=1e-12)
        np.testing.assert_allclose(fcl.Transform([1, 2, 3]).getTranslation(), [1, 2, 3])
        np.testing.assert_allclose(fcl.Transform(tf).getTranslation(), [1, 2, 3])
        with self.assertRaises(ValueError):
            fcl.Transform(np.eye(2))
        o = fcl.CollisionObject(self.ms, tf)
        np.testing.assert_allclose(o.getRotation(), tf.getRotation(), atol=1e-12)
        o.setTranslation([0.9, 0.1, 0.05])
        o.setQuatRotation([1, 0, 0, 0])
        np.testing.assert_allclose(o.getTransform().getTranslation(), [0.9, 0.1, 0.05])
        np.testing.assert_allclose(o.getRotation(), np.eye(3))
        self.assertEqual(o.getObjectType(), fcl.OBJECT_TYPE.OT_BVH)
        self.assertEqual(o.getNodeType(), fcl.NODE_TYPE.BV_OBBRSS)
        self.assertIs(o.geometry, self.ms)
        # A moved object is seen by the next query.
        t = fcl.CollisionObject(self.mt)
        t.setTransform(fcl.Transform(M.rotation([1, 1, 0], 0.4), [0.9, 0.1, 0.05]))
        o.setTranslation([0, 0, 0])
        got, _ = self.pairs(o, t)
        ref, _ = self.pairs(o, t, fcl.fcl_collide)
        self.assertTrue(got)
        self.assertEqual(got, ref)

    def test_shapes_go_to_fcl(self):
        o = fcl.CollisionObject(self.ms)
        for shape, tf, hit in [(fcl.Box(0.2, 0.2, 0.2), fcl.Transform([0.6, 0, 0]), True),
                               (fcl.Sphere(0.1), fcl.Transform([0, 0, 0.65]), True),
                               (fcl.Capsule(0.1, 0.5), fcl.Transform([2.0, 0, 0]), False),
                               (fcl.Cylinder(0.1, 0.5), fcl.Transform([0, 0.6, 0]), True),
                               (fcl.Cone(0.1, 0.5), fcl.Transform([0, 0, 3.0]), False),
                               (fcl.Ellipsoid(0.1, 0.2, 0.3), fcl.Transform([0, 0, -0.7]), True)]:
            s = fcl.CollisionObject(shape, tf)
            req = fcl.CollisionRequest(num_max_contacts=100, enable_contact=True)
            mine, ref = fcl.CollisionResult(), fcl.CollisionResult()
            n = fcl.collide(o, s, req, mine)
            self.assertEqual(n, fcl.fcl_collide(o, s, req, ref), type(shape).__name__)
            self.assertEqual(mine.is_collision, hit, type(shape).__name__)
            self.assertEqual({(c.b1, c.b2) for c in mine.contacts}, {(c.b1, c.b2) for c in ref.contacts})
        d = fcl.DistanceResult()
        far = fcl.CollisionObject(fcl.Sphere(0.1), fcl.Transform([0, 0, 1.0]))
        dist = fcl.distance(o, far, fcl.DistanceRequest(True), d)
        self.assertAlmostEqual(dist, 0.3, places=2)
        self.assertAlmostEqual(d.min_distance, dist)
        self.assertIs(d.o1, self.ms)

    def test_self_collide(self):
        v, t = M.folded_cloth(20)
        o = fcl.CollisionObject(M.fcl_mesh(v, t))
        res = fcl.CollisionResult()
        n = fcl.self_collide(o, fcl.CollisionRequest(num_max_contacts=ALL, enable_contact=True), res)
        got = {(c.b1, c.b2) for c in res.contacts}
        self.assertEqual(n, len(got))
        self.assertEqual(got, M.pair_set(kdet_fcl.intersect_self(kdet_fcl.Mesh(v, t))))
        self.assertTrue(got)

    def test_deforming_models(self):
        for kdet_only in (False, True):
            m = M.fcl_mesh(self.vs, self.ts, kdet_only=kdet_only)
            t = fcl.CollisionObject(self.mt, fcl.Transform(M.rotation([1, 1, 0], 0.4), [0.9, 0.1, 0.05]))
            o = fcl.CollisionObject(m)
            before, _ = self.pairs(o, t)
            v2 = self.vs * 1.3
            m.beginUpdateModel()
            m.updateSubModel(v2)
            m.endUpdateModel()
            after, _ = self.pairs(o, t)
            a = kdet_fcl.Mesh(v2, self.ts)
            b = kdet_fcl.Mesh(self.vt, self.tt, rotation=M.rotation([1, 1, 0], 0.4), translation=(0.9, 0.1, 0.05))
            self.assertEqual(after, M.pair_set(kdet_fcl.brute_force_intersect(a, b)))
            self.assertNotEqual(before, after)
            ref, _ = self.pairs(o, t, fcl.fcl_collide)  # FCL refits a kdet_only model first
            self.assertEqual(after, ref)

    def test_bad_models(self):
        m = fcl.BVHModel()
        m.beginModel(1, 3)
        with self.assertRaises(kdet_fcl.InvalidInputError):
            m.addSubModel(np.eye(3), [[0, 1, 3]])
        with self.assertRaises(kdet_fcl.InvalidInputError):
            fcl.CollisionObject(m)  # not built
        m.addSubModel(np.eye(3), [[0, 1, 2]])
        m.endModel()
        o = fcl.CollisionObject(m)
        m.beginUpdateModel()
        with self.assertRaises(kdet_fcl.InvalidInputError):
            fcl.collide(o, o)
        with self.assertRaises(kdet_fcl.InvalidInputError):
            fcl.fcl_collide(o, o)
        with self.assertRaises(kdet_fcl.InvalidInputError):  # FCL: no vertex was updated
            m.endUpdateModel()
        nan = fcl.BVHModel()
        nan.beginModel()
        nan.addSubModel([[np.nan, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
        nan.endModel()  # FCL builds it; kDet refuses it at the query, where FCL answers garbage
        with self.assertRaises(kdet_fcl.InvalidInputError) as cm:
            fcl.collide(fcl.CollisionObject(nan), fcl.CollisionObject(self.ms))
        self.assertIn("non-finite", str(cm.exception))
        with self.assertRaises(TypeError):
            fcl.collide(o, "not an object")
        with self.assertRaises(ValueError):
            fcl.CollisionObject(None)
        self.assertLess(fcl.BVHModel().endModel(), 0)  # FCL's own sequence check: a code
        # Vertices without triangles (a point cloud: FCL 0.7 crashed building it in endModel,
        # and crashes in every query of one): not built, a code, then a clear error.
        cloud = fcl.BVHModel()
        cloud.beginModel(3, 0)
        cloud.addSubModel(np.eye(3), np.zeros((0, 3), int))
        self.assertLess(cloud.endModel(), 0)
        with self.assertRaises(kdet_fcl.InvalidInputError):
            fcl.CollisionObject(cloud)
        huge = fcl.BVHModel()
        huge.beginModel()
        huge.addSubModel(np.eye(3) * 1e200, [[0, 1, 2]])
        huge.endModel()
        with self.assertRaises(kdet_fcl.InvalidInputError) as cm:
            fcl.collide(fcl.CollisionObject(huge), fcl.CollisionObject(self.ms))
        self.assertIn("2^330", str(cm.exception))
        # Shapes of non-finite or non-positive size (FCL answers a NaN sphere with no contact).
        for make in (lambda: fcl.Sphere(np.nan), lambda: fcl.Box(1, np.inf, 1),
                     lambda: fcl.Capsule(0.1, -1), lambda: fcl.Cylinder(0, 1),
                     lambda: fcl.Cone(np.nan, 1), lambda: fcl.Ellipsoid(1, 1, -np.inf)):
            with self.assertRaises(kdet_fcl.InvalidInputError) as cm:
                make()
            self.assertIn("finite and positive", str(cm.exception))
        # The scene makers refuse bad sizes too.
        with self.assertRaises(kdet_fcl.InvalidInputError):
            kdet_fcl.make_sphere(-1.0, 12, 6)
        with self.assertRaises(kdet_fcl.InvalidInputError):
            kdet_fcl.make_sphere(1.0, 2, 6)
        with self.assertRaises(kdet_fcl.InvalidInputError):
            kdet_fcl.make_sphere(1.0, 12, 6, center=[0, 0])
        with self.assertRaises(kdet_fcl.InvalidInputError):
            kdet_fcl.make_draped_cloth(0, 4.0, 1.0, 0.03, 1.0)
        v, t = kdet_fcl.make_draped_cloth(10, 4.0, 1.0, 0.03, 1.0)
        self.assertEqual((len(t), v.shape[1]), (200, 3))

    def test_managers(self):
        objs = []
        rng = np.random.default_rng(7)
        for i in range(6):
            geom = self.ms if i % 2 else self.mt
            R = M.rotation(rng.normal(size=3), rng.uniform(0, np.pi))
            objs.append(fcl.CollisionObject(geom, fcl.Transform(R, rng.uniform(-0.8, 0.8, 3))))
        mgr = fcl.DynamicAABBTreeCollisionManager()
        mgr.registerObjects(objs)
        mgr.setup()
        self.assertEqual(mgr.size(), 6)
        self.assertEqual(mgr.getObjects(), objs)

        def exhaustive(engine):
            seen = {}

            def callback(o1, o2, cdata):
                res = fcl.CollisionResult()
                engine(o1, o2, fcl.CollisionRequest(num_max_contacts=ALL), res)
                key = tuple(sorted((objs.index(o1), objs.index(o2))))
                flip = objs.index(o1) > objs.index(o2)
                seen[key] = {(c.b2, c.b1) if flip else (c.b1, c.b2) for c in res.contacts}
                return False
            mgr.collide(fcl.CollisionData(), callback)
            return seen

        mine, ref = exhaustive(fcl.collide), exhaustive(fcl.fcl_collide)
        self.assertEqual(mine.keys(), ref.keys())
        self.assertGreater(sum(len(s) for s in mine.values()), 0)
        for k in mine:
            self.assertEqual(mine[k], ref[k], k)
        # defaultCollisionCallback: python-fcl's stop rule (more than num_max_contacts).
        cd = fcl.CollisionData(fcl.CollisionRequest(num_max_contacts=3))
        mgr.collide(cd, fcl.defaultCollisionCallback)
        self.assertTrue(cd.result.is_collision)
        self.assertGreater(len(cd.result.contacts), 3)
        self.assertTrue(cd.done)
        # One object against the manager, and manager against manager.
        probe = fcl.CollisionObject(self.ms, fcl.Transform([0.0, 0.0, 0.0]))
        cd = fcl.CollisionData(fcl.CollisionRequest(num_max_contacts=ALL))
        mgr.collide(probe, cd, fcl.defaultCollisionCallback)
        other = fcl.DynamicAABBTreeCollisionManager()
        other.registerObject(probe)
        other.setup()
        cd2 = fcl.CollisionData(fcl.CollisionRequest(num_max_contacts=ALL))
        mgr.collide(other, cd2, fcl.defaultCollisionCallback)
        self.assertEqual(len(cd.result.contacts), len(cd2.result.contacts))
        # A callback's exception reaches the caller; unregister and clear.

        def boom(o1, o2, cdata):
            raise KeyError("from the callback")
        with self.assertRaises(KeyError):
            mgr.collide(fcl.CollisionData(), boom)
        mgr.unregisterObject(objs[0])
        mgr.update()
        self.assertEqual(mgr.size(), 5)
        mgr.clear()
        self.assertTrue(mgr.empty())
        with self.assertRaises(ValueError):
            mgr.collide(1, 2, 3, 4)


@unittest.skipUnless(SHARED_DATA and os.path.isdir(os.path.join(SHARED_DATA, "fcl")),
                     "../shared/data is absent")
class SharedData(unittest.TestCase):
    def test_fcl_env_and_rob(self):
        ve, te = kdet_fcl.read_mesh(os.path.join(SHARED_DATA, "fcl", "env.obj"))
        vr, tr = kdet_fcl.read_mesh(os.path.join(SHARED_DATA, "fcl", "rob.obj"))
        env, rob = M.fcl_mesh(ve, te), M.fcl_mesh(vr, tr)
        rng = np.random.default_rng(3)
        lo, hi = ve.min(axis=0), ve.max(axis=0)
        hits = 0
        for _ in range(8):
            R = M.rotation(rng.normal(size=3), rng.uniform(0, np.pi))
            t = rng.uniform(lo, hi)
            o1, o2 = fcl.CollisionObject(env), fcl.CollisionObject(rob, fcl.Transform(R, t))
            res = fcl.CollisionResult()
            fcl.collide(o1, o2, fcl.CollisionRequest(num_max_contacts=ALL), res)
            got = {(c.b1, c.b2) for c in res.contacts}
            a = kdet_fcl.Mesh(ve, te)
            b = kdet_fcl.Mesh(vr, tr, rotation=R, translation=t)
            self.assertEqual(got, M.pair_set(kdet_fcl.intersect(a, b)))
            self.assertEqual(got, M.pair_set(kdet_fcl.brute_force_intersect(a, b)))
            ref = fcl.CollisionResult()
            fcl.fcl_collide(o1, o2, fcl.CollisionRequest(num_max_contacts=ALL), ref)
            self.assertEqual(got, {(c.b1, c.b2) for c in ref.contacts}, "FCL 0.7 agrees here")
            hits += bool(got)
        self.assertGreater(hits, 0)


if __name__ == "__main__":
    unittest.main()
