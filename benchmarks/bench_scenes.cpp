#include "bench_scenes.h"
#include "mesh_append.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <sys/stat.h>

namespace kdet_bench {

using kdet_fcl::Triangle;
using V = kdet_fcl::Vec3<double>;

const char* motionName(Motion m) {
  switch (m) {
    case Motion::Static: return "static";
    case Motion::Deform: return "deform";
    case Motion::Fracture: return "fracture";
    case Motion::Rigid: return "rigid";
  }
  return "?";
}

std::size_t Scene::triangles(std::size_t f) const {
  std::size_t n = 0;
  for (const auto& m : frames[f].meshes) n += m->numTriangles();
  return n;
}

bool Scene::deforming() const {
  for (Motion m : motion)
    if (m == Motion::Deform || m == Motion::Fracture) return true;
  return false;
}

Mesh mergedWorld(const Scene& s, std::size_t f) {
  Mesh out;
  for (std::size_t o = 0; o < s.frames[f].meshes.size(); ++o) {
    const Mesh& m = *s.frames[f].meshes[o];
    const Pose& p = s.frames[f].poses[o];
    const auto base = static_cast<std::uint32_t>(out.vertices.size());
    for (const V& v : m.vertices) out.vertices.push_back(p.apply(v));
    for (const Triangle& t : m.triangles) out.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  return out;
}

namespace {

MeshPtr share(Mesh m) { return std::make_shared<const Mesh>(std::move(m)); }

// A capped-free tube (a "pipe") from a to b, `around` segments around and `along` along: with few
// segments along, its triangles are long and thin, as in CAD exports.
Mesh makePipe(const V& a, const V& b, double r, int around, int along) {
  Mesh m;
  const V d = b - a;
  const double len = std::sqrt(kdet_fcl::dot(d, d));
  const V w = d * (1.0 / len);
  const V h = std::fabs(w.x) < 0.9 ? V{1, 0, 0} : V{0, 1, 0};
  V u = kdet_fcl::cross(w, h);
  u = u * (1.0 / std::sqrt(kdet_fcl::dot(u, u)));
  const V v = kdet_fcl::cross(w, u);
  for (int j = 0; j <= along; ++j)
    for (int i = 0; i < around; ++i) {
      const double ang = 2 * M_PI * i / around;
      m.vertices.push_back(a + d * (double(j) / along) + u * (r * std::cos(ang)) + v * (r * std::sin(ang)));
    }
  for (int j = 0; j < along; ++j)
    for (int i = 0; i < around; ++i) {
      const auto p = [&](int jj, int ii) { return std::uint32_t(jj * around + (ii % around)); };
      m.triangles.push_back({p(j, i), p(j, i + 1), p(j + 1, i + 1)});
      m.triangles.push_back({p(j, i), p(j + 1, i + 1), p(j + 1, i)});
    }
  return m;
}

// A flat n x n grid in z = 0 over [-s/2, s/2]^2.
Mesh makeGrid(int n, double s) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.push_back({s * (double(i) / n - 0.5), s * (double(j) / n - 0.5), 0});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
  return m;
}

std::vector<double> frameTimes(int frames, double t0, double t1) {
  std::vector<double> t;
  for (int f = 0; f < frames; ++f) t.push_back(frames > 1 ? t0 + (t1 - t0) * f / (frames - 1) : t1);
  return t;
}

// ---- Cloth draped over a sphere (the paper's "cloth on Buddha" sweep) ----
Scene clothScene(int n, int frames, std::size_t nominal) {
  Scene s;
  s.name = "cloth-" + std::to_string(nominal / 1000) + "k";
  s.group = "cloth";
  s.label = "Cloth on sphere " + std::to_string(nominal / 1000) + "k";
  s.nominal = nominal;
  s.note = "makeDrapedCloth(n=" + std::to_string(n) +
           ") falling onto makeSphere, time 0.3..1 over the frames; cloth deforms, sphere static";
  s.objects = {"cloth", "sphere"};
  s.motion = {Motion::Deform, Motion::Static};
  s.self = {0, 1};
  s.inter = {{0, 1}};
  const int seg = std::max(16, std::min(512, n / 2));
  MeshPtr sphere = share(kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, seg, std::max(8, seg / 2)));
  for (double t : frameTimes(frames, 0.3, 1.0))
    s.frames.push_back({{share(kdet_fcl::makeDrapedCloth<double>(n, 3.0, 1.0, 0.02, t)), sphere},
                        {Pose::identity(), Pose::identity()}});
  return s;
}

// ---- A fracturing sphere whose pieces fly apart onto a floor plate ----
// Frame f cuts the sphere's bounding cube into (f+1)^3 chunks; triangles that straddle a crack are
// lost (so the count drops each frame) and each chunk flies outward and falls. Topology changes.
Scene fractureScene(int seg, int frames) {
  Scene s;
  const Mesh ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 1.0, seg, seg / 2);
  s.name = "fracture-" + std::to_string(ball.numTriangles() / 1000) + "k";
  s.group = "fracture";
  s.label = "Fracturing sphere " + std::to_string(ball.numTriangles() / 1000) + "k";
  s.note = "sphere cut into (f+1)^3 chunks at frame f, cracked triangles removed, chunks fly "
           "outward and fall through a static floor grid; topology changes every frame";
  s.objects = {"pieces", "floor"};
  s.motion = {Motion::Fracture, Motion::Static};
  s.self = {0, 1};
  s.inter = {{0, 1}};
  MeshPtr floor = share(makeGrid(std::max(8, seg / 4), 6.0));
  Pose floor_pose = Pose::identity();
  floor_pose.t = {0, 0, -0.7};
  for (int f = 0; f < frames; ++f) {
    const int g = f + 1;
    const auto chunkOf = [&](const V& p) {
      const auto c = [&](double x) { return std::min(g - 1, std::max(0, int((x + 1.0) * 0.5 * g))); };
      return (c(p.x) * g + c(p.y)) * g + c(p.z);
    };
    const double tt = double(f) / std::max(1, frames - 1);
    Mesh m;
    std::vector<std::int64_t> remap(ball.vertices.size(), -1);
    for (const Triangle& t : ball.triangles) {
      const int c0 = chunkOf(ball.vertices[t[0]]);
      if (chunkOf(ball.vertices[t[1]]) != c0 || chunkOf(ball.vertices[t[2]]) != c0) continue;
      // Chunk centre -> outward direction.
      const int cx = c0 / (g * g), cy = (c0 / g) % g, cz = c0 % g;
      V dir = {(cx + 0.5) / g * 2 - 1, (cy + 0.5) / g * 2 - 1, (cz + 0.5) / g * 2 - 1};
      const double dl = std::sqrt(kdet_fcl::dot(dir, dir));
      dir = dl > 0 ? dir * (1.0 / dl) : V{0, 0, 0};
      const V shift = dir * (0.6 * tt) + V{0, 0, -0.5 * tt * tt};
      Triangle nt;
      for (int k = 0; k < 3; ++k) {
        if (remap[t[k]] < 0) {
          remap[t[k]] = std::int64_t(m.vertices.size());
          m.vertices.push_back(ball.vertices[t[k]] + shift);
        }
        nt[k] = std::uint32_t(remap[t[k]]);
      }
      m.triangles.push_back(nt);
    }
    s.frames.push_back({{share(std::move(m)), floor}, {Pose::identity(), floor_pose}});
  }
  return s;
}

// ---- N-body: one mesh of many spheres on analytic orbits ----
Scene nbodyScene(int per_axis, int seg, int frames) {
  Scene s;
  const Mesh ball = kdet_fcl::makeSphere<double>({0, 0, 0}, 0.5, seg, seg / 2);
  const int count = per_axis * per_axis * per_axis;
  s.name = "nbody-" + std::to_string(count * ball.numTriangles() / 1000) + "k";
  s.group = "nbody";
  s.label = "N-body " + std::to_string(count) + " balls";
  s.note = std::to_string(count) + " spheres of " + std::to_string(ball.numTriangles()) +
           " triangles in ONE mesh on a lattice (spacing 1.05, radius 0.5) oscillating on "
           "analytic paths, so neighbours touch and overlap; one object, self-collision only";
  s.objects = {"balls"};
  s.motion = {Motion::Deform};
  s.self = {0};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 2 * M_PI);
  std::vector<V> base, phase;
  for (int i = 0; i < count; ++i) {
    base.push_back({1.05 * (i % per_axis), 1.05 * ((i / per_axis) % per_axis), 1.05 * (i / (per_axis * per_axis))});
    phase.push_back({u(rng), u(rng), u(rng)});
  }
  for (double t : frameTimes(frames, 0.0, 1.0)) {
    Mesh m;
    for (int i = 0; i < count; ++i) {
      const V c = base[i] + V{0.08 * std::sin(2 * M_PI * t + phase[i].x), 0.08 * std::sin(2 * M_PI * t + phase[i].y),
                              0.08 * std::sin(2 * M_PI * t + phase[i].z)};
      Mesh b = ball;
      for (V& v : b.vertices) v = v + c;
      appendMesh(m, b);
    }
    s.frames.push_back({{share(std::move(m))}, {Pose::identity()}});
  }
  return s;
}

// ---- A chair of pipes (long thin triangles) with a cloth sinking onto it ----
Scene chairScene(int cloth_n, int frames, std::size_t nominal) {
  Scene s;
  s.name = "chair-" + std::to_string(nominal / 1000) + "k";
  s.group = "chair";
  s.label = "Chair (pipes) + cloth " + std::to_string(nominal / 1000) + "k";
  s.nominal = nominal;
  s.note = "chair of 12-sided pipes, one segment along (long thin triangles), legs/frame/slats "
           "meeting at joints; a wavy cloth sinks through the seat; cloth deforms, chair static";
  s.objects = {"cloth", "chair"};
  s.motion = {Motion::Deform, Motion::Static};
  s.self = {0, 1};
  s.inter = {{0, 1}};
  Mesh chair;
  const double r = 0.02, h = 1.0, w = 0.5;
  const auto pipe = [&](V a, V b) { appendMesh(chair, makePipe(a, b, r, 12, 1)); };
  for (double x : {-w, w})
    for (double y : {-w, w}) pipe({x, y, 0}, {x, y, h});                    // legs
  pipe({-w, -w, h}, {w, -w, h}); pipe({-w, w, h}, {w, w, h});              // seat frame
  pipe({-w, -w, h}, {-w, w, h}); pipe({w, -w, h}, {w, w, h});
  for (int i = 1; i < 24; ++i) {                                            // seat slats, close
    const double y = -w + 2 * w * i / 24;
    pipe({-w, y, h + r}, {w, y, h + r});
  }
  for (double x : {-w, w}) pipe({x, w, h}, {x, w, 2 * h});                  // back posts
  for (int i = 1; i <= 12; ++i) {                                           // back rails
    const double z = h + h * i / 12.5;
    pipe({-w, w, z}, {w, w, z});
  }
  MeshPtr chair_p = share(std::move(chair));
  const Mesh flat = makeGrid(cloth_n, 1.6);
  for (double t : frameTimes(frames, 0.0, 1.0)) {
    Mesh c = flat;
    for (V& v : c.vertices)
      v.z = 1.25 - 0.35 * t + 0.03 * std::sin(9 * v.x + 3 * t) * std::cos(7 * v.y) -
            0.15 * t * std::exp(-8 * (v.x * v.x + v.y * v.y));
    s.frames.push_back({{share(std::move(c)), chair_p}, {Pose::identity(), Pose::identity()}});
  }
  return s;
}

// ---- Adversarial: a Chazelle-like pair (gpu-notes section 4, with eps < 0) ----
// A: 2N walls in planes y = i +- d/2 up to the ruling z = y x; B: 2N walls in x = j +- d/2 down to
// z = x y + eps. With eps < 0 every A wall crosses every B wall: Theta(N^2) true pairs.
Scene chazelleScene(int N) {
  Scene s;
  s.name = "chazelle-" + std::to_string(N);
  s.group = "adversarial";
  s.label = "Chazelle-like pair N=" + std::to_string(N);
  s.note = "two grids of 2N long thin walls (2 triangles each) on the rulings of z=xy, "
           "interpenetrating by eps=-0.5: Theta(N^2) true intersecting pairs";
  s.objects = {"bottom", "top"};
  s.motion = {Motion::Static, Motion::Static};
  s.self = {0, 1};
  s.inter = {{0, 1}};
  const double X = N + 1, d = 0.05, zlo = -1, zhi = X * X + 1, eps = -0.5;
  Mesh a, b;
  for (int i = 1; i <= N; ++i)
    for (double y : {i - d / 2, i + d / 2}) {
      a.addTriangle({0, y, zlo}, {X, y, zlo}, {X, y, y * X});
      a.addTriangle({0, y, zlo}, {X, y, y * X}, {0, y, 0});
    }
  for (int j = 1; j <= N; ++j)
    for (double x : {j - d / 2, j + d / 2}) {
      b.addTriangle({x, 0, zhi}, {x, X, x * X + eps}, {x, X, zhi});
      b.addTriangle({x, 0, zhi}, {x, 0, eps}, {x, X, x * X + eps});
    }
  s.frames.push_back({{share(std::move(a)), share(std::move(b))}, {Pose::identity(), Pose::identity()}});
  return s;
}

// ---- Adversarial: one large triangle among many tiny ones ----
Scene hugeRatioScene(std::size_t tiny) {
  Scene s;
  s.name = "huge-ratio-" + std::to_string(tiny / 1000) + "k";
  s.group = "adversarial";
  s.label = "1 large + " + std::to_string(tiny / 1000) + "k tiny";
  s.note = "one triangle across the unit cube vs makeRandomSoup(tiny, extent 1, sizes 2e-4..1e-3): "
           "size ratio ~1e4";
  s.objects = {"large", "tiny"};
  s.motion = {Motion::Static, Motion::Static};
  s.self = {0, 1};
  s.inter = {{0, 1}};
  Mesh big;
  big.addTriangle({-0.1, -0.1, 0.2}, {1.1, -0.05, 0.5}, {0.4, 1.1, 0.8});
  s.frames.push_back({{share(std::move(big)), share(kdet_fcl::makeRandomSoup<double>(tiny, 1.0, 2e-4, 1e-3, 11))},
                      {Pose::identity(), Pose::identity()}});
  return s;
}

// ---- Adversarial: a stack of coplanar (partly duplicate) triangles ----
// A: M copies of one triangle shifted in the plane z = 0 (coplanar overlaps, no shared vertex);
// B: an exact copy of A (every triangle of B has an exact duplicate in A).
Scene coplanarScene(int M) {
  Scene s;
  s.name = "coplanar-" + std::to_string(M);
  s.group = "adversarial";
  s.label = "Coplanar stack M=" + std::to_string(M);
  s.note = "M shifted copies of one triangle in z=0 (self: Theta(M^2) coplanar overlaps) and an "
           "exact duplicate of that stack as a second object (inter: Theta(M^2), M exact duplicates)";
  s.objects = {"stack", "duplicate"};
  s.motion = {Motion::Static, Motion::Static};
  s.self = {0, 1};
  s.inter = {{0, 1}};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 0.25);
  Mesh a;
  for (int i = 0; i < M; ++i) {
    const double dx = u(rng), dy = u(rng);
    a.addTriangle({dx, dy, 0}, {1 + dx, dy, 0}, {dx, 1 + dy, 0});
  }
  MeshPtr ap = share(std::move(a));
  s.frames.push_back({{ap, ap}, {Pose::identity(), Pose::identity()}});
  return s;
}

// ---- Files ----
bool exists(const std::string& p) {
  struct stat st;
  return ::stat(p.c_str(), &st) == 0;
}

// UNC: the two frames of one scene as a 2-frame animation of one object (self only; frame 1 is
// an update of frame 0), and as a pair of objects in one frame.
void uncScenes(const std::string& dir, const std::string& id, const std::string& label,
               const std::string& f0, const std::string& f1, bool want_anim, bool want_pair,
               std::vector<Scene>& out) {
  const std::string p0 = dir + "/" + f0, p1 = dir + "/" + f1;
  if (!exists(p0) || !exists(p1)) {
    std::fprintf(stderr, "kdet_bench: %s missing: UNC scene '%s' skipped\n", p0.c_str(), id.c_str());
    return;
  }
  MeshPtr a = share(kdet_fcl::readMesh<double>(p0)), b = share(kdet_fcl::readMesh<double>(p1));
  const bool same_topology = a->triangles == b->triangles && a->vertices.size() == b->vertices.size();
  if (want_anim) {
    Scene s;
    s.name = "unc-" + id;
    s.group = "unc";
    s.label = label + " (frames " + f0 + ", " + f1 + ")";
    s.note = "UNC frames as a 2-frame animation of one mesh: frame 0 built, frame 1 " +
             std::string(same_topology ? "a deformation (same topology)" : "a new topology") +
             "; self-collision only";
    s.objects = {id};
    s.motion = {same_topology ? Motion::Deform : Motion::Fracture};
    s.self = {0};
    s.frames.push_back({{a}, {Pose::identity()}});
    s.frames.push_back({{b}, {Pose::identity()}});
    out.push_back(std::move(s));
  }
  if (want_pair) {
    Scene s;
    s.name = "unc-" + id + "-pair";
    s.group = "unc";
    s.label = label + " pair";
    s.note = "two consecutive UNC frames as two objects: inter + both selfs (nearly coincident)";
    s.objects = {f0, f1};
    s.motion = {Motion::Static, Motion::Static};
    s.self = {0, 1};
    s.inter = {{0, 1}};
    s.frames.push_back({{a, b}, {Pose::identity(), Pose::identity()}});
    out.push_back(std::move(s));
  }
}

// Rigid pair: FCL's env.obj against rob.obj under random poses (as FCL's test_mesh_mesh: env moved
// by translations in [-3000,3000]^2 x [0,3000] and Euler angles, rob fixed).
void rigidScene(const std::string& dir, int poses, bool swapped, std::vector<Scene>& out) {
  const std::string pe = dir + "/env.obj", pr = dir + "/rob.obj";
  if (!exists(pe) || !exists(pr)) {
    std::fprintf(stderr, "kdet_bench: %s missing: rigid scene skipped\n", pe.c_str());
    return;
  }
  Scene s;
  s.name = swapped ? "rigid-rob-env" : "rigid-env-rob";
  s.group = "rigid";
  s.label = swapped ? "rob.obj vs env.obj, " + std::to_string(poses) + " poses"
                    : "env.obj vs rob.obj, " + std::to_string(poses) + " poses";
  s.note = "FCL's test meshes, both structures prebuilt; env moved by random rigid poses (seed 42), "
           "rob fixed; inter only; query " + std::string(swapped ? "(rob, env): kDet maps rob's 216 triangles into env's frame"
                                                                 : "(env, rob) as in FCL's test: kDet maps env's 2180 triangles into rob's frame");
  s.objects = {"env", "rob"};
  s.motion = {Motion::Rigid, Motion::Static};
  s.inter = {swapped ? std::pair<int, int>{1, 0} : std::pair<int, int>{0, 1}};
  MeshPtr env = share(kdet_fcl::readMesh<double>(pe)), rob = share(kdet_fcl::readMesh<double>(pr));
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> uxy(-3000, 3000), uz(0, 3000), ua(0, 2 * M_PI);
  for (int i = 0; i < poses; ++i) {
    const double a = ua(rng), b = ua(rng), c = ua(rng);
    // R = Rx(a) Ry(b) Rz(c), built in double; orthonormal to rounding.
    const double ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b), cc = std::cos(c),
                 sc = std::sin(c);
    Pose p;
    const double R[3][3] = {{cb * cc, -cb * sc, sb},
                            {sa * sb * cc + ca * sc, -sa * sb * sc + ca * cc, -sa * cb},
                            {-ca * sb * cc + sa * sc, ca * sb * sc + sa * cc, ca * cb}};
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) p.R[r][k] = R[r][k];
    p.t = {uxy(rng), uxy(rng), uz(rng)};
    s.frames.push_back({{env, rob}, {p, Pose::identity()}});
  }
  out.push_back(std::move(s));
}

bool wanted(const std::string& name, const std::vector<std::string>& only) {
  if (only.empty()) return true;
  for (const auto& o : only)
    if (name.find(o) != std::string::npos) return true;
  return false;
}

}  // namespace

std::vector<Scene> makeAllScenes(const SceneConfig& cfg, const std::vector<std::string>& only) {
  // Registry: (name, builder); a builder runs only when its name is wanted.
  std::vector<std::pair<std::string, std::function<void(std::vector<Scene>&)>>> reg;
  const int F = cfg.frames;
  const std::string unc = cfg.data_dir + "/unc", fcl = cfg.data_dir + "/fcl";
  if (!cfg.quick) {
    reg.push_back({"unc-cloth-ball", [&](auto& o) { uncScenes(unc + "/cloth-ball", "cloth-ball", "Whirling cloth (UNC)", "cloth_ball92.ply", "cloth_ball93.ply", true, true, o); }});
    reg.push_back({"unc-funnel", [&](auto& o) { uncScenes(unc + "/cloth-funnel", "funnel", "Funnel (UNC)", "227.ply", "228.ply", true, true, o); }});
    reg.push_back({"unc-n-body", [&](auto& o) { uncScenes(unc + "/n-body-simulation", "n-body", "N-body (UNC)", "balls16_18.ply", "balls16_19.ply", true, true, o); }});
    const std::pair<int, std::size_t> sweep[] = {{100, 20000}, {141, 40000}, {212, 90000}, {316, 200000}, {354, 250000}};
    for (auto [n, nom] : sweep) reg.push_back({"cloth-" + std::to_string(nom / 1000) + "k", [=](auto& o) { o.push_back(clothScene(n, F, nom)); }});
    if (cfg.include_1m) reg.push_back({"cloth-1000k", [=](auto& o) { o.push_back(clothScene(707, F, 1000000)); }});
    reg.push_back({"fracture", [=](auto& o) { o.push_back(fractureScene(240, F)); }});
    reg.push_back({"nbody", [=](auto& o) { o.push_back(nbodyScene(7, 24, F)); }});
    reg.push_back({"chair", [=](auto& o) { o.push_back(chairScene(212, F, 90000)); }});
    reg.push_back({"chazelle", [=](auto& o) { o.push_back(chazelleScene(250)); }});
    reg.push_back({"huge-ratio", [=](auto& o) { o.push_back(hugeRatioScene(cfg.huge_ratio_tiny)); }});
    reg.push_back({"coplanar", [=](auto& o) { o.push_back(coplanarScene(400)); }});
    reg.push_back({"rigid-env-rob", [&](auto& o) { rigidScene(fcl, cfg.rigid_poses, false, o); }});
    reg.push_back({"rigid-rob-env", [&](auto& o) { rigidScene(fcl, cfg.rigid_poses, true, o); }});
  } else {
    // CI smoke test: every kind of scene, small.
    reg.push_back({"unc-funnel", [&](auto& o) { uncScenes(unc + "/cloth-funnel", "funnel", "Funnel (UNC)", "227.ply", "228.ply", true, true, o); }});
    reg.push_back({"cloth-2k", [=](auto& o) { o.push_back(clothScene(32, 3, 2000)); }});
    reg.push_back({"cloth-4k", [=](auto& o) { o.push_back(clothScene(45, 3, 4000)); }});
    reg.push_back({"fracture", [=](auto& o) { o.push_back(fractureScene(40, 3)); }});
    reg.push_back({"nbody", [=](auto& o) { o.push_back(nbodyScene(3, 12, 3)); }});
    reg.push_back({"chair", [=](auto& o) { o.push_back(chairScene(30, 3, 2000)); }});
    reg.push_back({"chazelle", [=](auto& o) { o.push_back(chazelleScene(12)); }});
    reg.push_back({"huge-ratio", [=](auto& o) { o.push_back(hugeRatioScene(5000)); }});
    reg.push_back({"coplanar", [=](auto& o) { o.push_back(coplanarScene(40)); }});
    reg.push_back({"rigid-env-rob", [&](auto& o) { rigidScene(fcl, 10, false, o); }});
    reg.push_back({"rigid-rob-env", [&](auto& o) { rigidScene(fcl, 10, true, o); }});
  }
  std::vector<Scene> out;
  for (auto& [name, build] : reg) {
    if (!wanted(name, only)) continue;
    std::fprintf(stderr, "kdet_bench: generating %s ...\n", name.c_str());
    build(out);
  }
  return out;
}

}  // namespace kdet_bench
