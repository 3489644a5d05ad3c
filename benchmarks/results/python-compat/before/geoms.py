v, t = __import__("kdet_fcl").make_sphere(0.7, 12, 8)
def mesh():
    m = fcl.BVHModel(); m.beginModel(len(t), len(v)); m.addSubModel(v, t); m.endModel(); return m
cube_v = np.array([[x, y, z] for x in (-.5, .5) for y in (-.5, .5) for z in (-.5, .5)])
faces = [[0,1,3,2],[4,6,7,5],[0,4,5,1],[2,3,7,6],[0,2,6,4],[1,5,7,3]]
flat = np.concatenate([[4] + f for f in faces])
data = bytes([0, 0xC0] + [3, 0] * 14 + [2, 0])
geoms = {
    "box": lambda: fcl.Box(1, 1, 1), "sphere": lambda: fcl.Sphere(0.5),
    "ellipsoid": lambda: fcl.Ellipsoid(.5, .4, .3), "capsule": lambda: fcl.Capsule(.3, 1),
    "cone": lambda: fcl.Cone(.5, 1), "cylinder": lambda: fcl.Cylinder(.5, 1),
    "convex": lambda: fcl.Convex(cube_v, 6, flat),
    "halfspace": lambda: fcl.Halfspace(np.array([1., 0, 0]), 0.0),
    "plane": lambda: fcl.Plane(np.array([1., 0, 0]), 0.0),
    "triangle": lambda: fcl.TriangleP([0, 0, 0], [1, 0, 0], [0, 1, 0]),
    "mesh": mesh, "octree": lambda: fcl.OcTree(0.1, data),
}
