#pragma once
/// \file
/// The scenes of the benchmark suite (issue 5), each modelled with the minimum it needs: meshes
/// per frame, moved by analytic functions of time (no physics). Frames are generated up front so
/// no generator time lands inside a timed region.

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <kdet_fcl/kdet_fcl.h>

namespace kdet_bench {

using Mesh = kdet_fcl::TriangleMesh<double>;
using MeshPtr = std::shared_ptr<const Mesh>;
using Pose = kdet_fcl::Transform<double>;

/// How an object changes from one frame to the next; it decides what each method has to do:
///  - Static:   nothing (same mesh, same pose).
///  - Deform:   new vertex positions, same topology (kDet: updateVertices; FCL: refit).
///  - Fracture: new topology (kDet: setMesh; FCL: a full rebuild).
///  - Rigid:    new pose only (kDet: setPose; FCL: nothing, the pose goes with the query).
enum class Motion { Static, Deform, Fracture, Rigid };
const char* motionName(Motion m);

/// One frame: for every object its mesh (in its own frame) and its pose.
struct Frame {
  std::vector<MeshPtr> meshes;
  std::vector<Pose> poses;
};

/// A scene: objects, their frames, and which queries a frame asks for.
struct Scene {
  std::string name;      ///< unique id (used in JSON and file names)
  std::string group;     ///< "unc", "cloth", "fracture", "nbody", "chair", "adversarial", "rigid"
  std::string label;     ///< the Table 1 row label
  std::string note;      ///< one line on how it is modelled
  std::vector<std::string> objects;
  std::vector<Motion> motion;                  ///< per object
  std::vector<int> self;                       ///< objects whose self-collision is asked
  std::vector<std::pair<int, int>> inter;      ///< object pairs whose intersection is asked
  std::vector<Frame> frames;
  std::size_t nominal = 0;                     ///< nominal size for sweeps (cloth triangles)

  std::size_t triangles(std::size_t frame) const;
  bool deforming() const;   ///< some object deforms or fractures
};

/// What to build: quick = small sizes, CI smoke test.
struct SceneConfig {
  bool quick = false;
  bool include_1m = false;      ///< the 1M-triangle cloth
  std::size_t huge_ratio_tiny = 1000000;
  int frames = 6;               ///< frames of the procedural animations
  int rigid_poses = 100;        ///< poses of the env/rob rigid pair
  std::string data_dir;         ///< ../shared/data ("" or missing: UNC and FCL scenes skipped)
};

/// Every scene of the suite (those whose data is missing are left out with a note on stderr).
std::vector<Scene> makeAllScenes(const SceneConfig& cfg, const std::vector<std::string>& only);

/// All objects of frame `f` merged into one mesh in world coordinates (for the k-free analysis).
Mesh mergedWorld(const Scene& s, std::size_t f);

}  // namespace kdet_bench
