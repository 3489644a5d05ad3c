#pragma once
// unc-n-body-pair's two objects (frame 0) as double meshes with their CPU hashes, whose grids,
// levels and boxes are the device's: the input of skip_rule_check.cpp and missed_pair.cpp.
#include <stdexcept>

#include "../gpu-session44/census_common.h"

struct NbodyPair {
  kdet_fcl::TriangleMesh<double> A, B;
  census::Hash ha, hb;
};

/// Fills `p` from the UNC n-body frames under `data_dir` (throws when the scene is missing).
inline void loadNbodyPair(NbodyPair& p, const char* data_dir = "../shared/data") {
  kdet_bench::SceneConfig cfg;
  cfg.data_dir = data_dir;
  for (const auto& s : kdet_bench::makeAllScenes(cfg, {"unc-n-body"})) {
    if (s.name != "unc-n-body-pair") continue;
    p.A = census::doubleMesh(*s.frames[0].meshes[0]);
    p.B = census::doubleMesh(*s.frames[0].meshes[1]);
    p.ha.build(p.A, 0);
    p.hb.build(p.B, 0);
    return;
  }
  throw std::runtime_error("unc-n-body-pair: no such scene (is the UNC data missing?)");
}
