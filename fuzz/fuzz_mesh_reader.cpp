// libFuzzer target: one mesh reader (KDET_FUZZ_EXTENSION picks the format). The input is written
// to a temporary file with that extension and read in float and in double. A MeshFileError is a
// correct answer; any other exception, a crash or a sanitizer report is a bug. A mesh that loads
// must be valid, and writing and re-reading it must give it back (exactly for .obj/.off/.ply,
// which keep the precision; STL stores float soups).

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "kdet_fcl/errors.h"
#include "kdet_fcl/mesh_io.h"

namespace {

std::string tempPath(const char* tag) {
  return "/tmp/kdet_fuzz_" + std::to_string(::getpid()) + tag + KDET_FUZZ_EXTENSION;
}

template <class S>
void readOne(const std::string& path) {
  kdet_fcl::TriangleMesh<S> m;
  try {
    m = kdet_fcl::readMesh<S>(path);
  } catch (const kdet_fcl::MeshFileError&) {
    return;
  }
  m.validate();  // throws (a bug) if the reader let an invalid mesh through
  const std::string out = tempPath("_rt");
  if (std::string(KDET_FUZZ_EXTENSION) == ".stl") {
    // Binary STL stores floats: the writer must refuse exactly the meshes with a referenced
    // coordinate beyond float's range (a double read of an ASCII STL can hold one).
    bool fits = true;
    for (const auto& t : m.triangles)
      for (const std::uint32_t v : t)
        for (int k = 0; k < 3; ++k) fits = fits && std::isfinite(static_cast<float>(m.vertices[v][k]));
    if (!fits) {
      try {
        kdet_fcl::writeMesh(m, out);
      } catch (const kdet_fcl::MeshFileError&) {
        return;
      }
      std::abort();  // an unrepresentable coordinate was written
    }
  }
  kdet_fcl::writeMesh(m, out);
  const kdet_fcl::TriangleMesh<S> back = kdet_fcl::readMesh<S>(out);
  std::remove(out.c_str());
  if (std::string(KDET_FUZZ_EXTENSION) != ".stl" &&
      (back.vertices.size() != m.vertices.size() || back.triangles != m.triangles ||
       (!m.vertices.empty() && std::memcmp(back.vertices.data(), m.vertices.data(),
                                           m.vertices.size() * sizeof m.vertices[0]) != 0)))
    std::abort();  // a written mesh does not read back the same
  if (back.triangles.size() != m.triangles.size()) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = tempPath("");
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    if (size) std::fwrite(data, 1, size, f);
    std::fclose(f);
  } else {
    return 0;
  }
  readOne<float>(path);
  readOne<double>(path);
  std::remove(path.c_str());
  return 0;
}
