/// \file
/// The `kdet` command-line tool: a built-in demo scene, mesh-mesh and self collision queries on
/// mesh files (on the CPU or, with --backend, the GPU), the k-free analysis, and what this build
/// and machine offer (info).
///
/// Exit codes: 0 success, 1 an error (unreadable file, invalid mesh, library error), 2 a usage
/// error (unknown option, missing argument, bad number). Every error is one line on stderr.

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <new>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "kdet_fcl/backend.h"
#include "kdet_fcl/errors.h"
#include "kdet_fcl/hashed_mesh.h"
#include "kdet_fcl/kfree.h"
#include "kdet_fcl/mesh_io.h"
#include "kdet_fcl/query.h"
#include "kdet_fcl/scenes.h"
#include "kdet_fcl/triangle_mesh.h"
#include "kdet_fcl/vec3.h"

#ifndef KDET_FCL_VERSION_STRING
#define KDET_FCL_VERSION_STRING "0.1.0"
#endif

namespace {

using namespace kdet_fcl;

/// A usage error: reported with exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A run-time error of the tool itself (e.g. an output file that cannot be written): exit 1.
struct ToolError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// ---------------------------------------------------------------------------------------------
// Help texts.

const char* kMainHelp =
    "kdet " KDET_FCL_VERSION_STRING
    " - kDet hierarchical-hash collision detection\n"
    "\n"
    "usage: kdet [COMMAND] [OPTIONS]\n"
    "\n"
    "commands:\n"
    "  demo       (default) a procedural cloth draped over a sphere: build, query, report\n"
    "  collide    intersecting triangle pairs between two mesh files\n"
    "  self       self-intersecting triangle pairs of one mesh file\n"
    "  analyze    the k-free analysis (kDet paper, Definition 3.1) of mesh files\n"
    "  info       the version, whether this build has the CUDA backend, and the CUDA devices\n"
    "\n"
    "  kdet COMMAND --help   options of one command\n"
    "  kdet --version        the version\n"
    "\n"
    "Mesh files: .obj .off .ply (ASCII or binary) .stl (ASCII or binary).\n"
    "Exit codes: 0 success, 1 error, 2 usage error.\n";

const char* kDemoHelp =
    "usage: kdet demo [--n N] [--threads T] [--frames F] [--backend B] [--device D]\n"
    "                 [--double|--float]\n"
    "\n"
    "A cloth of N x N quads (2 N^2 triangles) draped over a sphere, both procedural (no data\n"
    "files). Prints triangle counts, hierarchy statistics, the cloth-sphere, cloth-self and\n"
    "sphere-self intersecting pair counts and the build and query times.\n"
    "\n"
    "  --n N         cloth resolution (default 224: about 100k triangles)\n"
    "  --threads T   worker threads (default 0: all hardware threads)\n"
    "  --frames F    animate the drape over F frames, re-hashing the cloth each frame (default 1)\n"
    "  --backend B   cpu (default), cuda (the GPU; an error without one) or auto (the GPU when\n"
    "                there is one and the scene is large enough to pay)\n"
    "  --device D    the CUDA device of the GPU's queries (default: KDET_FCL_CUDA_DEVICE, else 0)\n"
    "  --double      double precision (default)\n"
    "  --float       single precision\n"
    "\n"
    "On the GPU the hashes are built on the device, inside the first query, whose time also\n"
    "holds the device's start-up; each later frame's query holds the cloth's re-hash.\n";

const char* kCollideHelp =
    "usage: kdet collide A B [OPTIONS]\n"
    "\n"
    "Every intersecting triangle pair (i of A, j of B) of two mesh files, A and B each placed by\n"
    "a rigid pose p' = R p + t (rotation first, then translation).\n"
    "\n"
    "  --translate X Y Z            translation of A\n"
    "  --rotate AX AY AZ DEG        rotation of A about axis (AX,AY,AZ) by DEG degrees\n"
    "  --pose X Y Z AX AY AZ DEG    translation and rotation of A at once\n"
    "  --translate-b X Y Z          translation of B\n"
    "  --rotate-b AX AY AZ DEG      rotation of B\n"
    "  --pose-b X Y Z AX AY AZ DEG  translation and rotation of B at once\n"
    "  --max-pairs N                stop after N pairs (0: all; 1: a yes/no query)\n"
    "  --threads T                  worker threads (0: all)\n"
    "  --backend B                  cpu (default), cuda (the GPU) or auto (the GPU when\n"
    "                               there is one and the meshes are large enough to pay)\n"
    "  --device D                   the CUDA device of a GPU query (default:\n"
    "                               KDET_FCL_CUDA_DEVICE, else 0)\n"
    "  --pairs FILE                 write the pairs, sorted, one 'i j' per line, to FILE\n"
    "  --print-pairs                print the pairs, sorted, to stdout\n"
    "  --double | --float           precision (default double)\n";

const char* kSelfHelp =
    "usage: kdet self MESH [OPTIONS]\n"
    "\n"
    "Every pair of intersecting triangles of one mesh that do not share a vertex.\n"
    "\n"
    "  --max-pairs N        stop after N pairs (0: all)\n"
    "  --threads T          worker threads (0: all)\n"
    "  --backend B          cpu (default), cuda (the GPU) or auto (the GPU when there is one\n"
    "                       and the mesh is large enough to pay)\n"
    "  --device D           the CUDA device of a GPU query (default: KDET_FCL_CUDA_DEVICE,\n"
    "                       else 0)\n"
    "  --pairs FILE         write the pairs, sorted, one 'i j' per line, to FILE\n"
    "  --print-pairs        print the pairs, sorted, to stdout\n"
    "  --double | --float   precision (default double)\n";

const char* kAnalyzeHelp =
    "usage: kdet analyze MESH... [--csv FILE] [--threads T] [--quiet] [--double|--float]\n"
    "\n"
    "The k-free analysis of each mesh: triangles, minimum k, mean and standard deviation of the\n"
    "neighbour counts, largest count, share of neighbours that are topologically adjacent, and\n"
    "the hierarchy height. One line per mesh on stdout; progress on stderr. A mesh that cannot be\n"
    "read is reported and skipped (exit code 1 at the end).\n"
    "\n"
    "  --csv FILE    also write the table as CSV to FILE\n"
    "  --threads T   worker threads (0: all)\n"
    "  --quiet       no progress output\n";

const char* kInfoHelp =
    "usage: kdet info\n"
    "\n"
    "The version, whether this build has the CUDA backend, the usable CUDA devices (the one the\n"
    "library uses marked: KDET_FCL_CUDA_DEVICE, else 0), and the smallest query --backend auto\n"
    "sends to the GPU.\n";

// ---------------------------------------------------------------------------------------------
// Argument parsing.

class Args {
 public:
  Args(std::vector<std::string> args, const char* command) : a_(std::move(args)), cmd_(command) {}
  bool done() const { return i_ >= a_.size(); }
  const std::string& peek() const { return a_[i_]; }
  std::string take() { return a_[i_++]; }
  /// The value of option `opt`.
  std::string value(const std::string& opt) {
    if (done()) throw UsageError(cmd_ + ": option " + opt + " needs a value");
    return take();
  }
  double number(const std::string& opt) {
    const std::string s = value(opt);
    double v = 0;
    const char* b = s.data();
    const char* e = s.data() + s.size();
    if (!s.empty() && *b == '+') ++b;
    const auto r = std::from_chars(b, e, v);
    if (s.empty() || r.ec != std::errc() || r.ptr != e || !std::isfinite(v))
      throw UsageError(cmd_ + ": option " + opt + ": '" + s + "' is not a finite number");
    return v;
  }
  long long integer(const std::string& opt, long long lo, long long hi) {
    const std::string s = value(opt);
    long long v = 0;
    const char* b = s.data();
    const char* e = s.data() + s.size();
    if (!s.empty() && *b == '+') ++b;
    const auto r = std::from_chars(b, e, v);
    if (s.empty() || r.ec != std::errc() || r.ptr != e)
      throw UsageError(cmd_ + ": option " + opt + ": '" + s + "' is not an integer");
    if (v < lo || v > hi)
      throw UsageError(cmd_ + ": option " + opt + ": " + s + " is out of range [" +
                       std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v;
  }
  [[noreturn]] void unknown(const std::string& opt) const {
    throw UsageError(cmd_ + ": unknown option '" + opt + "' (see kdet " + cmd_ + " --help)");
  }
  const std::string& command() const { return cmd_; }

 private:
  std::vector<std::string> a_;
  std::size_t i_ = 0;
  std::string cmd_;
};

bool isOption(const std::string& s) { return s.size() > 1 && s[0] == '-'; }

/// A pose given on the command line (applied as p' = R p + t).
struct PoseArg {
  double t[3] = {0, 0, 0};
  double axis[3] = {0, 0, 1};
  double angle_deg = 0;

  void parseTranslate(Args& a, const std::string& opt) {
    for (double& x : t) x = a.number(opt);
  }
  void parseRotate(Args& a, const std::string& opt) {
    for (double& x : axis) x = a.number(opt);
    angle_deg = a.number(opt);
    if (axis[0] == 0 && axis[1] == 0 && axis[2] == 0 && angle_deg != 0)
      throw UsageError(a.command() + ": option " + opt + ": the rotation axis is zero");
  }
  template <class S>
  Transform<S> get() const {
    const double kPi = 3.14159265358979323846;
    return makeTransform<S>(Vec3<S>{S(axis[0]), S(axis[1]), S(axis[2])}, S(angle_deg * kPi / 180.0),
                            Vec3<S>{S(t[0]), S(t[1]), S(t[2])});
  }
};

/// Options common to every command.
struct Common {
  bool use_float = false;
  int threads = 0;
  Backend backend = Backend::Cpu;
  int device = -1;  ///< --device: the CUDA device of GPU queries (-1: the library's choice)
  bool help = false;

  /// Consumes a common option; false when `opt` is none of them.
  bool parse(const std::string& opt, Args& a) {
    if (opt == "--double")
      use_float = false;
    else if (opt == "--float")
      use_float = true;
    else if (opt == "--threads")
      threads = static_cast<int>(a.integer(opt, 0, 4096));
    else if (opt == "--help" || opt == "-h")
      help = true;
    else if (opt == "--backend")
      backend = parseBackend(a.value(opt), a);
    else if (opt == "--device")
      device = static_cast<int>(a.integer(opt, 0, 1023));
    else
      return false;
    return true;
  }
  static Backend parseBackend(const std::string& v, const Args& a) {
    if (v == "cpu") return Backend::Cpu;
    if (v == "cuda") return Backend::Cuda;
    if (v == "auto") return Backend::Auto;
    throw UsageError(a.command() + ": option --backend: unknown backend '" + v +
                     "' (cpu, cuda or auto)");
  }
  int resolvedThreads() const {
    if (threads > 0) return threads;
    const unsigned h = std::thread::hardware_concurrency();
    return h ? static_cast<int>(h) : 1;
  }
};

/// Where a command's queries of `work` triangles (all meshes together) run for `c.backend`
/// (resolveBackend), with its description for the report: "cpu, T threads" or
/// "cuda, <device>". --backend cuda without a usable device is an error naming the option.
struct RunsOn {
  Backend backend = Backend::Cpu;
  std::string text;
  bool gpu() const { return backend == Backend::Cuda; }
};
RunsOn runsOn(const Common& c, std::size_t work) {
  RunsOn r;
  try {
    r.backend = resolveBackend(c.backend, work);
  } catch (const BackendUnavailableError& e) {
    throw BackendUnavailableError(std::string("--backend cuda: ") + e.what());
  }
  if (r.gpu() && c.device >= 0) {
    try {
      setCudaDevice(c.device);
    } catch (const InvalidInputError& e) {
      throw UsageError(std::string("option --device: ") + e.what());
    }
  }
  if (r.gpu()) {
    const int d = cudaDevice();
    r.text = "cuda, device " + std::to_string(d) + ": " + cudaDeviceDescription(d);
  } else {
    r.text = "cpu, " + std::to_string(c.resolvedThreads()) + " threads";
  }
  return r;
}

/// On the GPU: the device memory the backend holds for `triangles` (cudaDeviceBytesInUse), the
/// line led by `indent`.
void printDeviceMemory(FILE* info, const RunsOn& on, std::size_t triangles,
                       const char* indent = "") {
  if (!on.gpu()) return;
  const double bytes = double(cudaDeviceBytesInUse());
  std::fprintf(info, "%sdevice memory: %.2f MiB (%.0f B per triangle)\n", indent,
               bytes / (1024.0 * 1024.0), triangles > 0 ? bytes / double(triangles) : 0.0);
}

void writePairs(const std::vector<TrianglePair>& sorted_pairs, const std::string& file,
                bool print) {
  if (!file.empty()) {
    std::ofstream out(file);
    if (!out) throw ToolError("cannot open '" + file + "' for writing: " + std::strerror(errno));
    for (const auto& p : sorted_pairs) out << p.a << ' ' << p.b << '\n';
    out.close();
    if (!out) throw ToolError("write failed: '" + file + "'");
  }
  if (print)
    for (const auto& p : sorted_pairs) std::printf("%u %u\n", p.a, p.b);
}

void printHierarchy(const char* name, const HierarchyStats& s) {
  std::printf(
      "  hierarchy %-7s levels %d, height %d, d_min %.4g, d_max %.4g, cells %zu, entries %zu, "
      "max cell load %zu, memory %.2f MiB\n",
      name, s.levels, s.height, s.d_min, s.d_max, s.cells, s.entries, s.max_cell_load,
      double(s.memory_bytes) / (1024.0 * 1024.0));
}

const char* precisionName(bool use_float) { return use_float ? "float" : "double"; }

/// A note on stderr, before the query, for a mesh whose size ratio exceeds what the cell keys
/// hold (HierarchyStats::below_cell0): its smallest triangles share level 0 and those close
/// together are tested pairwise, so the query may take long.
void noteBelowCell0(const std::string& file, const HierarchyStats& s) {
  if (s.below_cell0 == 0) return;
  std::fprintf(stderr,
               "kdet: note: %s: %zu of %zu triangles are smaller than the finest cell (%.3g, the "
               "mesh's extent / 2^38; sizes %.3g to %.3g); they share level 0, and those close "
               "together are tested pairwise, so the query may take long (docs/numerics.md, "
               "section 1)\n",
               file.c_str(), s.below_cell0, s.triangles, s.cell_size0, s.d_min, s.d_max);
}

// ---------------------------------------------------------------------------------------------
// demo

struct DemoOptions {
  Common common;
  int n = 224;
  int frames = 1;
};

template <class S>
int runDemo(const DemoOptions& o) {
  const int threads = o.common.threads;
  const S sphere_radius = S(1);
  const S cloth_size = S(3);
  const S penetration = S(0.02);
  // The sphere's triangles are about as large as the cloth's, so both hierarchies stay shallow.
  const int segments = std::max(16, std::min(512, o.n / 2));
  const int rings = std::max(8, segments / 2);

  auto t0 = Clock::now();
  TriangleMesh<S> sphere_mesh = makeSphere<S>(Vec3<S>{0, 0, 0}, sphere_radius, segments, rings);
  const S t_first = o.frames > 1 ? S(0) : S(1);
  TriangleMesh<S> cloth_mesh =
      makeDrapedCloth<S>(o.n, cloth_size, sphere_radius, penetration, t_first);
  const double gen_ms = msSince(t0);
  const RunsOn on = runsOn(o.common, cloth_mesh.triangles.size() + sphere_mesh.triangles.size());
  std::printf("kdet demo: cloth (%dx%d quads) draped over a sphere, %s precision, %s\n", o.n, o.n,
              precisionName(std::is_same<S, float>::value), on.text.c_str());
  std::printf("  cloth:  %zu triangles, %zu vertices\n  sphere: %zu triangles, %zu vertices\n",
              cloth_mesh.triangles.size(), cloth_mesh.vertices.size(), sphere_mesh.triangles.size(),
              sphere_mesh.vertices.size());
  std::printf("  scene generation: %.2f ms\n", gen_ms);

  t0 = Clock::now();
  HashedMesh<S> sphere(std::move(sphere_mesh), Transform<S>::identity(), threads);
  // The CPU hash is built lazily; build it here so that it is timed. On the GPU the device
  // builds its own inside the first query, and no CPU hash is made.
  if (!on.gpu()) sphere.prepareCpuHash();
  const double build_sphere_ms = msSince(t0);
  t0 = Clock::now();
  HashedMesh<S> cloth(std::move(cloth_mesh), Transform<S>::identity(), threads);
  if (!on.gpu()) cloth.prepareCpuHash();
  const double build_cloth_ms = msSince(t0);
  if (on.gpu()) {
    std::printf("  build/hash: on the device, inside the first queries (which also hold the "
                "device's start-up)\n");
  } else {
    printHierarchy("cloth:", cloth.stats());
    printHierarchy("sphere:", sphere.stats());
    std::printf("  build/hash: cloth %.2f ms, sphere %.2f ms\n", build_cloth_ms, build_sphere_ms);
  }

  QueryOptions q;
  q.threads = threads;
  q.backend = on.backend;
  t0 = Clock::now();
  const QueryResult sphere_self = intersectSelf(sphere, q);
  const double sphere_self_ms = msSince(t0);

  for (int f = 0; f < o.frames; ++f) {
    double update_ms = 0;
    const S time = o.frames > 1 ? S(f) / S(o.frames - 1) : S(1);
    if (f > 0) {
      const TriangleMesh<S> next =
          makeDrapedCloth<S>(o.n, cloth_size, sphere_radius, penetration, time);
      t0 = Clock::now();
      cloth.updateVertices(next.vertices);
      // The re-hash is lazy: on the CPU run it here so that it is timed as such; the GPU
      // re-hashes on the device, inside the next query.
      if (!on.gpu()) cloth.prepareCpuHash();
      update_ms = msSince(t0);
    }
    t0 = Clock::now();
    const QueryResult cs = intersectMeshes(cloth, sphere, q);
    const double cs_ms = msSince(t0);
    t0 = Clock::now();
    const QueryResult cc = intersectSelf(cloth, q);
    const double cc_ms = msSince(t0);
    if (o.frames > 1) {
      char update[96] = "";
      if (f > 0)
        std::snprintf(update, sizeof update, " %s %.2f ms%s", on.gpu() ? "update" : "re-hash",
                      update_ms, on.gpu() ? " (the re-hash is in the next query)" : "");
      std::printf("  frame %d/%d (t=%.3f)%s\n", f + 1, o.frames, double(time), update);
    }
    std::printf("  cloth-sphere pairs: %zu (query %.2f ms)\n", cs.pairs.size(), cs_ms);
    std::printf("  cloth self pairs:   %zu (query %.2f ms)\n", cc.pairs.size(), cc_ms);
  }
  std::printf("  sphere self pairs:  %zu (query %.2f ms%s)\n", sphere_self.pairs.size(),
              sphere_self_ms, on.gpu() ? ", the first query: with the device's start-up" : "");
  printDeviceMemory(stdout, on, cloth.numTriangles() + sphere.numTriangles(), "  ");
  return 0;
}

int cmdDemo(Args& a) {
  DemoOptions o;
  while (!a.done()) {
    const std::string opt = a.take();
    if (o.common.parse(opt, a)) continue;
    if (opt == "--n")
      o.n = static_cast<int>(a.integer(opt, 1, 8192));
    else if (opt == "--frames")
      o.frames = static_cast<int>(a.integer(opt, 1, 100000));
    else if (isOption(opt))
      a.unknown(opt);
    else
      throw UsageError("demo: unexpected argument '" + opt + "' (see kdet demo --help)");
  }
  if (o.common.help) {
    std::fputs(kDemoHelp, stdout);
    return 0;
  }
  return o.common.use_float ? runDemo<float>(o) : runDemo<double>(o);
}

// ---------------------------------------------------------------------------------------------
// collide and self

struct QueryCliOptions {
  Common common;
  std::vector<std::string> files;
  PoseArg pose_a, pose_b;
  long long max_pairs = 0;
  std::string pairs_file;
  bool print_pairs = false;
};

void parseQueryOptions(Args& a, QueryCliOptions& o, bool with_poses) {
  while (!a.done()) {
    const std::string opt = a.take();
    if (o.common.parse(opt, a)) continue;
    if (opt == "--max-pairs")
      o.max_pairs = a.integer(opt, 0, std::numeric_limits<long long>::max());
    else if (opt == "--pairs")
      o.pairs_file = a.value(opt);
    else if (opt == "--print-pairs")
      o.print_pairs = true;
    else if (with_poses && opt == "--translate")
      o.pose_a.parseTranslate(a, opt);
    else if (with_poses && opt == "--rotate")
      o.pose_a.parseRotate(a, opt);
    else if (with_poses && opt == "--pose") {
      o.pose_a.parseTranslate(a, opt);
      o.pose_a.parseRotate(a, opt);
    } else if (with_poses && opt == "--translate-b")
      o.pose_b.parseTranslate(a, opt);
    else if (with_poses && opt == "--rotate-b")
      o.pose_b.parseRotate(a, opt);
    else if (with_poses && opt == "--pose-b") {
      o.pose_b.parseTranslate(a, opt);
      o.pose_b.parseRotate(a, opt);
    } else if (opt == "--") {
      while (!a.done()) o.files.push_back(a.take());
    } else if (isOption(opt))
      a.unknown(opt);
    else
      o.files.push_back(opt);
  }
  if (!o.pairs_file.empty() && o.print_pairs)
    throw UsageError(a.command() + ": --pairs and --print-pairs exclude each other");
}

/// The time line of collide and self. On the GPU the hash is built on the device inside the
/// query, whose time then also holds the device's start-up (a one-shot command pays both).
void printTimes(FILE* info, double read_ms, double build_ms, double query_ms, const char* precision,
                const RunsOn& on) {
  if (on.gpu())
    std::fprintf(info,
                 "time: read %.2f ms, query %.2f ms with the device's start-up and its build/hash "
                 "(%s, %s)\n",
                 read_ms, query_ms, precision, on.text.c_str());
  else
    std::fprintf(info, "time: read %.2f ms, build/hash %.2f ms, query %.2f ms (%s, %s)\n", read_ms,
                 build_ms, query_ms, precision, on.text.c_str());
}

template <class S>
int runCollide(const QueryCliOptions& o) {
  auto t0 = Clock::now();
  TriangleMesh<S> ma = readMesh<S>(o.files[0]);
  TriangleMesh<S> mb = readMesh<S>(o.files[1]);
  ma.validateForQueries(false, o.files[0]);  // a refusal names the file
  mb.validateForQueries(false, o.files[1]);
  const double read_ms = msSince(t0);
  const std::size_t na = ma.triangles.size(), nb = mb.triangles.size();
  const RunsOn on = runsOn(o.common, na + nb);
  t0 = Clock::now();
  HashedMesh<S> a(std::move(ma), o.pose_a.get<S>(), o.common.threads);
  HashedMesh<S> b(std::move(mb), o.pose_b.get<S>(), o.common.threads);
  if (!on.gpu()) {  // built lazily otherwise (inside the query; on the GPU, on the device)
    a.prepareCpuHash();
    b.prepareCpuHash();
  }
  const double build_ms = msSince(t0);
  if (!on.gpu()) {
    noteBelowCell0(o.files[0], a.stats());
    noteBelowCell0(o.files[1], b.stats());
  }
  QueryOptions q;
  q.threads = o.common.threads;
  q.backend = on.backend;
  q.max_pairs = static_cast<std::size_t>(o.max_pairs);
  t0 = Clock::now();
  QueryResult r = intersectMeshes(a, b, q);
  const double query_ms = msSince(t0);
  std::sort(r.pairs.begin(), r.pairs.end());
  // With --print-pairs stdout carries the pairs only; the summary goes to stderr.
  FILE* info = o.print_pairs ? stderr : stdout;
  std::fprintf(info, "A: %s (%zu triangles)\nB: %s (%zu triangles)\n", o.files[0].c_str(), na,
               o.files[1].c_str(), nb);
  std::fprintf(info, "pairs: %zu%s\n", r.pairs.size(),
               r.complete ? "" : " (stopped at --max-pairs)");
  printTimes(info, read_ms, build_ms, query_ms, precisionName(std::is_same<S, float>::value), on);
  printDeviceMemory(info, on, na + nb);
  writePairs(r.pairs, o.pairs_file, o.print_pairs);
  return 0;
}

template <class S>
int runSelf(const QueryCliOptions& o) {
  auto t0 = Clock::now();
  TriangleMesh<S> m = readMesh<S>(o.files[0]);
  m.validateForQueries(false, o.files[0]);  // a refusal names the file
  const double read_ms = msSince(t0);
  const std::size_t n = m.triangles.size();
  const RunsOn on = runsOn(o.common, n);
  t0 = Clock::now();
  HashedMesh<S> h(std::move(m), Transform<S>::identity(), o.common.threads);
  if (!on.gpu()) h.prepareCpuHash();  // built lazily otherwise (inside the query)
  const double build_ms = msSince(t0);
  if (!on.gpu()) noteBelowCell0(o.files[0], h.stats());
  QueryOptions q;
  q.threads = o.common.threads;
  q.backend = on.backend;
  q.max_pairs = static_cast<std::size_t>(o.max_pairs);
  t0 = Clock::now();
  QueryResult r = intersectSelf(h, q);
  const double query_ms = msSince(t0);
  std::sort(r.pairs.begin(), r.pairs.end());
  FILE* info = o.print_pairs ? stderr : stdout;
  std::fprintf(info, "mesh: %s (%zu triangles)\n", o.files[0].c_str(), n);
  std::fprintf(info, "self pairs: %zu%s\n", r.pairs.size(),
               r.complete ? "" : " (stopped at --max-pairs)");
  printTimes(info, read_ms, build_ms, query_ms, precisionName(std::is_same<S, float>::value), on);
  printDeviceMemory(info, on, n);
  writePairs(r.pairs, o.pairs_file, o.print_pairs);
  return 0;
}

int cmdCollide(Args& a) {
  QueryCliOptions o;
  parseQueryOptions(a, o, true);
  if (o.common.help) {
    std::fputs(kCollideHelp, stdout);
    return 0;
  }
  if (o.files.size() != 2)
    throw UsageError("collide: expected two mesh files, got " + std::to_string(o.files.size()) +
                     " (see kdet collide --help)");
  return o.common.use_float ? runCollide<float>(o) : runCollide<double>(o);
}

int cmdSelf(Args& a) {
  QueryCliOptions o;
  parseQueryOptions(a, o, false);
  if (o.common.help) {
    std::fputs(kSelfHelp, stdout);
    return 0;
  }
  if (o.files.size() != 1)
    throw UsageError("self: expected one mesh file, got " + std::to_string(o.files.size()) +
                     " (see kdet self --help)");
  return o.common.use_float ? runSelf<float>(o) : runSelf<double>(o);
}

// ---------------------------------------------------------------------------------------------
// analyze

struct AnalyzeOptions {
  Common common;
  std::vector<std::string> files;
  std::string csv;
  bool quiet = false;
};

std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + "\"";
}

template <class S>
int runAnalyze(const AnalyzeOptions& o) {
  std::ofstream csv;
  if (!o.csv.empty()) {
    csv.open(o.csv);
    if (!csv) throw ToolError("cannot open '" + o.csv + "' for writing: " + std::strerror(errno));
    csv << "file,triangles,k,mean,sd,max_count,adjacent_mean,adjacent_share,height,seconds\n";
  }
  std::printf("%-40s %10s %8s %9s %9s %9s %9s %6s %9s\n", "file", "triangles", "k", "mean", "sd",
              "max", "adj_share", "height", "time_s");
  int failures = 0;
  KFreeOptions ko;
  ko.threads = o.common.threads;
  for (std::size_t i = 0; i < o.files.size(); ++i) {
    const std::string& f = o.files[i];
    if (!o.quiet) std::fprintf(stderr, "[%zu/%zu] %s ...\n", i + 1, o.files.size(), f.c_str());
    try {
      const auto t0 = Clock::now();
      const TriangleMesh<S> m = readMesh<S>(f);
      m.validateForQueries(false, f);  // a refusal names the file
      const KFreeStats s = analyzeKFree(m, ko);
      const double sec = msSince(t0) / 1000.0;
      std::printf("%-40s %10zu %8u %9.3f %9.3f %9u %9.3f %6d %9.3f\n", f.c_str(), s.triangles, s.k,
                  s.mean, s.sd, s.max_count, s.adjacent_share, s.height, sec);
      std::fflush(stdout);
      if (csv.is_open()) {
        char line[512];
        std::snprintf(line, sizeof line, ",%zu,%u,%.6g,%.6g,%u,%.6g,%.6g,%d,%.6g\n", s.triangles,
                      s.k, s.mean, s.sd, s.max_count, s.adjacent_mean, s.adjacent_share, s.height,
                      sec);
        csv << csvField(f) << line;
      }
    } catch (const kdet_fcl::Error& e) {
      ++failures;
      std::fprintf(stderr, "kdet analyze: error: %s\n", e.what());
    }
  }
  if (csv.is_open()) {
    csv.close();
    if (!csv) throw ToolError("write failed: '" + o.csv + "'");
  }
  if (failures) {
    std::fprintf(stderr, "kdet analyze: %d of %zu meshes failed\n", failures, o.files.size());
    return 1;
  }
  return 0;
}

int cmdAnalyze(Args& a) {
  AnalyzeOptions o;
  while (!a.done()) {
    const std::string opt = a.take();
    if (o.common.parse(opt, a)) continue;
    if (opt == "--csv")
      o.csv = a.value(opt);
    else if (opt == "--quiet" || opt == "-q")
      o.quiet = true;
    else if (opt == "--") {
      while (!a.done()) o.files.push_back(a.take());
    } else if (isOption(opt))
      a.unknown(opt);
    else
      o.files.push_back(opt);
  }
  if (o.common.help) {
    std::fputs(kAnalyzeHelp, stdout);
    return 0;
  }
  if (o.files.empty())
    throw UsageError("analyze: expected at least one mesh file (see kdet analyze --help)");
  return o.common.use_float ? runAnalyze<float>(o) : runAnalyze<double>(o);
}

// ---------------------------------------------------------------------------------------------
// info

int cmdInfo(Args& a) {
  while (!a.done()) {
    const std::string opt = a.take();
    if (opt == "--help" || opt == "-h") {
      std::fputs(kInfoHelp, stdout);
      return 0;
    }
    if (isOption(opt)) a.unknown(opt);
    throw UsageError("info: unexpected argument '" + opt + "' (see kdet info --help)");
  }
  std::printf("kdet %s\n", KDET_FCL_VERSION_STRING);
  std::printf("CUDA backend: %s\n", builtWithCuda() ? "built" : "not built (no nvcc at build time)");
  const int devices = cudaDeviceCount();
  std::printf("CUDA devices: %d\n", devices);
  int used = -1;
  std::string device_error;
  try {
    used = devices > 0 ? cudaDevice() : -1;
  } catch (const InvalidInputError& e) {
    device_error = e.what();  // a KDET_FCL_CUDA_DEVICE that names no device: said below
  }
  for (int d = 0; d < devices; ++d)
    std::printf("  device %d: %s%s\n", d, cudaDeviceDescription(d).c_str(),
                d == used ? " (used)" : "");
  if (!device_error.empty()) std::printf("CUDA device: none usable: %s\n", device_error.c_str());
  std::printf("--backend auto: the GPU from %zu triangles%s\n", autoCudaMinTriangles(),
              devices > 0 ? "" : " (no device here: always the CPU)");
  const unsigned h = std::thread::hardware_concurrency();
  std::printf("CPU threads: %u\n", h ? h : 1u);
  return 0;
}

int run(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string cmd = "demo";
  if (!args.empty()) {
    const std::string& first = args[0];
    if (first == "--help" || first == "-h" || first == "help") {
      if (first == "help" && args.size() > 1) {
        args = {args[1], "--help"};
      } else {
        std::fputs(kMainHelp, stdout);
        return 0;
      }
    }
    if (args[0] == "--version" || args[0] == "-V") {
      std::printf("kdet %s\n", KDET_FCL_VERSION_STRING);
      return 0;
    }
    if (!isOption(args[0])) {
      cmd = args[0];
      args.erase(args.begin());
    }
  }
  Args a(args, cmd.c_str());
  if (cmd == "demo") return cmdDemo(a);
  if (cmd == "collide") return cmdCollide(a);
  if (cmd == "self") return cmdSelf(a);
  if (cmd == "analyze" || cmd == "analyse") return cmdAnalyze(a);
  if (cmd == "info") return cmdInfo(a);
  throw UsageError("unknown command '" + cmd + "' (see kdet --help)");
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "kdet: usage error: %s\n", e.what());
    return 2;
  } catch (const kdet_fcl::Error& e) {
    std::fprintf(stderr, "kdet: error: %s\n", e.what());
    return 1;
  } catch (const ToolError& e) {
    std::fprintf(stderr, "kdet: error: %s\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "kdet: error: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "kdet: error: %s\n", e.what());
    return 1;
  } catch (...) {
    std::fprintf(stderr, "kdet: error: unknown exception\n");
    return 1;
  }
}
