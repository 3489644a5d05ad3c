// Mesh file I/O: round trips, hand-written files of every format and variant, malformed files
// (each must give MeshFileError naming the file), and the shared data files.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "kdet_fcl/errors.h"
#include "kdet_fcl/mesh_io.h"

namespace fs = std::filesystem;
using kdet_fcl::MeshFileError;
using kdet_fcl::readMesh;
using kdet_fcl::Triangle;
using kdet_fcl::TriangleMesh;
using kdet_fcl::Vec3;
using kdet_fcl::writeMesh;

namespace {

/// Little byte builder for binary files (PLY in either byte order, STL).
struct Bytes {
  std::vector<unsigned char> b;
  bool big = false;
  explicit Bytes(bool big_endian = false) : big(big_endian) {}
  Bytes& text(const std::string& s) {
    b.insert(b.end(), s.begin(), s.end());
    return *this;
  }
  template <class T>
  Bytes& put(T v) {
    unsigned char tmp[sizeof(T)];
    std::memcpy(tmp, &v, sizeof(T));
    // Written byte by byte in the requested order, independent of the host.
    bool host_little;
    {
      const std::uint16_t one = 1;
      unsigned char c;
      std::memcpy(&c, &one, 1);
      host_little = c == 1;
    }
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      const std::size_t j = (host_little != big) ? i : sizeof(T) - 1 - i;
      b.push_back(tmp[j]);
    }
    return *this;
  }
  Bytes& f32(float v) { return put(v); }
  Bytes& f64(double v) { return put(v); }
  Bytes& i32(std::int32_t v) { return put(v); }
  Bytes& u32(std::uint32_t v) { return put(v); }
  Bytes& u8(std::uint8_t v) { return put(v); }
  Bytes& i8(std::int8_t v) { return put(v); }
  Bytes& i16(std::int16_t v) { return put(v); }
  Bytes& u16(std::uint16_t v) { return put(v); }
};

class MeshIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "_" + info->name();
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    dir_ =
        fs::temp_directory_path() /
        ("kdet_mesh_io_" +
         std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()) + "_" + name);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string writeText(const std::string& name, const std::string& content) const {
    const std::string p = path(name);
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }
  std::string writeBytes(const std::string& name, const Bytes& bytes) const {
    const std::string p = path(name);
    std::ofstream out(p, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.b.data()),
              static_cast<std::streamsize>(bytes.b.size()));
    return p;
  }

  fs::path dir_;
};

/// Expects readMesh<S>(p) to throw MeshFileError whose message names the file and contains
/// `needle` (when given).
template <class S = double>
void expectFileError(const std::string& p, const std::string& needle = "") {
  SCOPED_TRACE(p);
  try {
    (void)readMesh<S>(p);
    ADD_FAILURE() << "no MeshFileError for " << p;
  } catch (const MeshFileError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(fs::path(p).filename().string()), std::string::npos) << msg;
    if (!needle.empty()) {
      EXPECT_NE(msg.find(needle), std::string::npos)
          << "message: " << msg << "\nexpected: " << needle;
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

template <class S>
TriangleMesh<S> sampleMesh() {
  TriangleMesh<S> m;
  m.vertices = {{S(0), S(0), S(0)},
                {S(1), S(0), S(0)},
                {S(0), S(1), S(0)},
                {S(0), S(0), S(1)},
                {S(0.1), S(-1e-7), S(12345.678)},
                {S(-3.141592653589793), S(2.718281828459045), S(1e30)},
                {S(1e-30), S(-0.0), S(7)},
                {S(1) / S(3), S(2) / S(3), S(-5) / S(7)}};
  m.triangles = {{0, 1, 2}, {0, 1, 3}, {1, 2, 3}, {0, 2, 3}, {4, 5, 6}, {7, 6, 5}, {7, 7, 7}};
  return m;
}

template <class S>
class MeshIoRoundTrip : public MeshIoTest {};
using Precisions = ::testing::Types<float, double>;
TYPED_TEST_SUITE(MeshIoRoundTrip, Precisions);

TYPED_TEST(MeshIoRoundTrip, IndexedFormatsAreExact) {
  using S = TypeParam;
  const TriangleMesh<S> m = sampleMesh<S>();
  for (const char* ext : {".obj", ".off", ".ply", ".OBJ", ".Off", ".PLY"}) {
    SCOPED_TRACE(ext);
    const std::string p = this->path(std::string("rt") + ext);
    writeMesh(m, p);
    const TriangleMesh<S> r = readMesh<S>(p);
    ASSERT_EQ(r.vertices.size(), m.vertices.size());
    ASSERT_EQ(r.triangles, m.triangles);
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
      for (int k = 0; k < 3; ++k) EXPECT_EQ(r.vertices[i][k], m.vertices[i][k]) << "vertex " << i;
    }
  }
}

TYPED_TEST(MeshIoRoundTrip, StlIsAFloatSoup) {
  using S = TypeParam;
  const TriangleMesh<S> m = sampleMesh<S>();
  for (const char* ext : {".stl", ".STL"}) {
    const std::string p = this->path(std::string("rt") + ext);
    writeMesh(m, p);
    EXPECT_EQ(fs::file_size(p), 84u + 50u * m.triangles.size());
    const TriangleMesh<S> r = readMesh<S>(p);
    ASSERT_EQ(r.triangles.size(), m.triangles.size());
    ASSERT_EQ(r.vertices.size(), 3 * m.triangles.size());
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      const auto i = static_cast<std::uint32_t>(3 * t);
      EXPECT_EQ(r.triangles[t], (Triangle{i, i + 1, i + 2}));
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k)
          EXPECT_EQ(r.vertices[3 * t + c][k],
                    S(static_cast<float>(m.vertices[m.triangles[t][c]][k])));
    }
  }
}

TYPED_TEST(MeshIoRoundTrip, EmptyMesh) {
  using S = TypeParam;
  const TriangleMesh<S> m;
  for (const char* ext : {".obj", ".off", ".ply", ".stl"}) {
    const std::string p = this->path(std::string("empty") + ext);
    writeMesh(m, p);
    const TriangleMesh<S> r = readMesh<S>(p);
    EXPECT_TRUE(r.vertices.empty()) << ext;
    EXPECT_TRUE(r.triangles.empty()) << ext;
  }
}

TYPED_TEST(MeshIoRoundTrip, PlyHeaderMatchesPrecision) {
  using S = TypeParam;
  const std::string p = this->path("prec.ply");
  writeMesh(sampleMesh<S>(), p);
  std::ifstream in(p, std::ios::binary);
  std::string head(200, '\0');
  in.read(&head[0], 200);
  EXPECT_NE(head.find("binary_little_endian"), std::string::npos);
  EXPECT_NE(head.find(std::is_same<S, float>::value ? "property float x" : "property double x"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Writer errors.

TEST_F(MeshIoTest, WriteErrors) {
  const auto m = sampleMesh<double>();
  EXPECT_THROW(writeMesh(m, path("no_such_dir/x.obj")), MeshFileError);
  EXPECT_THROW(writeMesh(m, path("x.xyz")), MeshFileError);
  EXPECT_THROW(writeMesh(m, path("noext")), MeshFileError);
  auto bad = m;
  bad.triangles.push_back({0, 1, 99});
  EXPECT_THROW(writeMesh(bad, path("bad.ply")), kdet_fcl::InvalidInputError);
}

// Binary STL stores floats: a double coordinate beyond float's range is refused with the vertex
// named (before, it was written as an infinity that the reader then rejected), no file is left,
// and the formats that keep doubles still write it. Found by fuzz_read_stl.
TEST_F(MeshIoTest, StlRefusesCoordinatesBeyondFloat) {
  auto m = sampleMesh<double>();
  m.vertices[1].y = 1.1e70;
  const std::string p = path("huge.stl");
  try {
    writeMesh(m, p);
    ADD_FAILURE() << "writing 1.1e70 to binary STL did not throw";
  } catch (const MeshFileError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("vertex 1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1.1e+70"), std::string::npos) << msg;
    EXPECT_NE(msg.find("32-bit floats"), std::string::npos) << msg;
  }
  EXPECT_FALSE(fs::exists(p));
  for (const char* ext : {".obj", ".off", ".ply"}) {
    const std::string q = path(std::string("huge") + ext);
    writeMesh(m, q);
    EXPECT_EQ(readMesh<double>(q).vertices[1].y, 1.1e70) << ext;
  }
  // The largest float itself is representable, and so is a double that rounds down to it.
  m.vertices[1].y = double(std::numeric_limits<float>::max());
  writeMesh(m, p);
  EXPECT_EQ(readMesh<double>(p).triangles.size(), m.triangles.size());
  // An unreferenced vertex is not written to STL, so it does not matter.
  m.vertices[1].y = 0.5;
  m.vertices.push_back({1e300, 0, 0});
  EXPECT_NO_THROW(writeMesh(m, path("unref.stl")));
}

// ---------------------------------------------------------------------------------------------
// Generic failures.

TEST_F(MeshIoTest, MissingDirectoryEmptyAndUnknown) {
  expectFileError(path("missing.obj"), "no such file");
  expectFileError<float>(path("missing.ply"), "no such file");
  fs::create_directories(path("dir.ply"));
  expectFileError(path("dir.ply"), "directory");
  for (const char* ext : {".obj", ".off", ".ply", ".stl"})
    expectFileError(writeText(std::string("e") + ext, ""), "empty");
  expectFileError(writeText("a.xyz", "v 0 0 0\n"), "unknown mesh file extension");
  expectFileError(writeText("noext", "v 0 0 0\n"), "unknown mesh file extension");
}

// ---------------------------------------------------------------------------------------------
// OBJ.

TEST_F(MeshIoTest, ObjHandWritten) {
  const std::string p = writeText("hand.obj",
                                  "# comment\r\n"
                                  "mtllib missing.mtl\r\n"
                                  "o first\r\n"
                                  "v 0 0 0\r\n"
                                  "v 1 0 0 1.0\r\n"          // w component
                                  "v 1 1 0 0.5 0.5 0.5\r\n"  // vertex colour
                                  "v\t0 1 0\r\n"
                                  "vt 0 0\nvn 0 0 1\n"
                                  "f 1/1/1 2/1/1 3/1/1 4/1/1\n"  // quad -> 2 triangles
                                  "g second\n"
                                  "v 0 0 1\n"
                                  "f -1 -4 -5\n"  // relative: 5 4 1... -> 4,1,0 (0-based)
                                  "usemtl none\n"
                                  "f 1//1 2//1 5//1\n"
                                  "  f 1 2 3 4 5\n");  // pentagon -> 3 triangles
  const auto m = readMesh<double>(p);
  ASSERT_EQ(m.vertices.size(), 5u);
  EXPECT_EQ(m.vertices[1], (Vec3<double>{1, 0, 0}));
  EXPECT_EQ(m.vertices[3], (Vec3<double>{0, 1, 0}));
  const std::vector<Triangle> want = {{0, 1, 2}, {0, 2, 3}, {4, 1, 0}, {0, 1, 4},
                                      {0, 1, 2}, {0, 2, 3}, {0, 3, 4}};
  EXPECT_EQ(m.triangles, want);
}

TEST_F(MeshIoTest, ObjExactDecimalParsing) {
  // tinyobjloader's own float parser is not correctly rounded; the reader must be.
  const std::string p = writeText("exact.obj",
                                  "v 0.1 0.30000000000000004 1.7976931348623157e308\n"
                                  "v 2.2250738585072014e-308 -0.0 123456789.123456789\n"
                                  "v 1 2 3\nf 1 2 3\n");
  const auto m = readMesh<double>(p);
  EXPECT_EQ(m.vertices[0].x, 0.1);
  EXPECT_EQ(m.vertices[0].y, 0.30000000000000004);
  EXPECT_EQ(m.vertices[0].z, 1.7976931348623157e308);
  EXPECT_EQ(m.vertices[1].x, 2.2250738585072014e-308);
  EXPECT_EQ(m.vertices[1].z, 123456789.123456789);
  // 1.7976931348623157e308 does not fit a float.
  expectFileError<float>(p, "line 1");
}

TEST_F(MeshIoTest, ObjLargePolygon) {
  // tinyobjloader stores polygon sizes in an unsigned char: 300 vertices must still work.
  std::string s;
  const int n = 300;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    s += "v " + std::to_string(std::cos(a)) + " " + std::to_string(std::sin(a)) + " 0\n";
  }
  s += "f";
  for (int i = 1; i <= n; ++i) s += " " + std::to_string(i);
  s += "\nf 1 2 3\n";
  const auto m = readMesh<double>(writeText("big.obj", s));
  ASSERT_EQ(m.triangles.size(), std::size_t(n - 2 + 1));
  EXPECT_EQ(m.triangles[n - 3], (Triangle{0, std::uint32_t(n - 2), std::uint32_t(n - 1)}));
  EXPECT_EQ(m.triangles.back(), (Triangle{0, 1, 2}));
}

TEST_F(MeshIoTest, ObjErrors) {
  const std::string v3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  expectFileError(writeText("range.obj", v3 + "f 1 2 4\n"), "line 4");
  expectFileError(writeText("range2.obj", v3 + "f 1 2 99999999999\n"), "line 4");
  expectFileError(writeText("rel.obj", v3 + "f -1 -2 -4\n"), "line 4");
  expectFileError(writeText("zero.obj", v3 + "f 0 1 2\n"), "line 4");
  expectFileError(writeText("two.obj", v3 + "f 1 2\n"), "line 4");
  expectFileError(writeText("one.obj", v3 + "f 1\n"), "need at least 3");
  expectFileError(writeText("coords.obj", "v 0 0\n"), "line 1");
  expectFileError(writeText("nan.obj", "v 0 0 0\nv nan 0 0\n"), "line 2");
  expectFileError(writeText("inf.obj", "v 0 0 inf\n"), "line 1");
  expectFileError(writeText("huge.obj", "v 0 0 1e999\n"), "line 1");
  expectFileError(writeText("text.obj", "v 0 zero 0\n"), "line 1");
  expectFileError(writeText("idx.obj", v3 + "f 1 two 3\n"), "line 4");
  expectFileError(writeText("vt0.obj", v3 + "f 1/0 2/0 3/0\n"), "line 4");
  expectFileError(writeText("slash.obj", v3 + "f 1/1/1/1 2 3\n"), "line 4");
  expectFileError(writeText("nul.obj", std::string("v 0 0 0\nv 1\0 0 0\n", 18)), "NUL");
  expectFileError(writeText("badl.obj", v3 + "l 0 1\n"), "OBJ parse error");
}

// ---------------------------------------------------------------------------------------------
// OFF.

TEST_F(MeshIoTest, OffHandWritten) {
  const auto m = readMesh<double>(writeText("hand.off",
                                            "OFF # a comment\n"
                                            "# another\n"
                                            "\n"
                                            "5 3 0\n"
                                            "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1.25\n"
                                            "4 0 1 2 3\n"
                                            "3 0 1 4 255 0 0\n"  // face colour ignored
                                            "3 1 2 4\n"));
  ASSERT_EQ(m.vertices.size(), 5u);
  EXPECT_EQ(m.vertices[4], (Vec3<double>{0.5, 0.5, 1.25}));
  const std::vector<Triangle> want = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {1, 2, 4}};
  EXPECT_EQ(m.triangles, want);

  // Counts on the keyword line, colour variant with per-vertex colours, CRLF, no final newline.
  const auto c =
      readMesh<float>(writeText("c.off",
                                "COFF 3 1 0\r\n0 0 0 255 0 0 255\r\n1 0 0 0 255 0 255\r\n"
                                "0 1 0 0 0 255 255\r\n3 0 1 2"));
  EXPECT_EQ(c.vertices.size(), 3u);
  EXPECT_EQ(c.triangles, (std::vector<Triangle>{{0, 1, 2}}));
}

TEST_F(MeshIoTest, OffErrors) {
  expectFileError(writeText("hdr.off", "OFX\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                  "bad OFF header");
  expectFileError(writeText("v4.off", "4OFF\n3 1 0\n"), "unsupported");
  expectFileError(writeText("bin.off", "OFF BINARY\n"), "binary OFF");
  expectFileError(writeText("nocounts.off", "OFF\n"), "truncated");
  expectFileError(writeText("badcounts.off", "OFF\n3 x 0\n"), "line 2");
  expectFileError(writeText("negcounts.off", "OFF\n-3 1 0\n"), "line 2");
  expectFileError(writeText("truncv.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n"), "truncated");
  expectFileError(writeText("truncf.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                  "truncated");
  expectFileError(writeText("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                  "out of range");
  expectFileError(writeText("neg.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n"), "face 0");
  expectFileError(writeText("two.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
                  "need at least 3");
  expectFileError(writeText("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n"),
                  "fewer indices");
  expectFileError(writeText("coord.off", "OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n"), "vertex 1");
  expectFileError(writeText("nan.off", "OFF\n3 1 0\n0 0 0\n1 0 nan\n0 1 0\n3 0 1 2\n"), "line 4");
  // A lying header must fail at once, without allocating for a billion vertices.
  expectFileError(writeText("lie.off", "OFF\n2000000000 2000000000 0\n0 0 0\n"), "too large");
  expectFileError(writeText("lie2.off", "OFF\n99999999999999 1 0\n0 0 0\n"), "too large");
}

// ---------------------------------------------------------------------------------------------
// PLY.

const char* kAsciiPly =
    "ply\r\n"
    "format ascii 1.0\r\n"
    "comment made by hand\r\n"
    "obj_info nothing\r\n"
    "element material 1\r\n"
    "property list uchar float coeffs\r\n"
    "property uchar id\r\n"
    "element vertex 4\r\n"
    "property int32 id\r\n"
    "property double z\r\n"
    "property float y\r\n"
    "property short x\r\n"
    "property list uchar float extra\r\n"
    "property uchar red\r\n"
    "element face 2\r\n"
    "property list uchar float texcoord\r\n"
    "property list int uint vertex_index\r\n"
    "property uchar flags\r\n"
    "element edge 1\r\n"
    "property int vertex1\r\n"
    "property int vertex2\r\n"
    "end_header\r\n"
    "3 0.5 0.25 1 7\r\n"
    "0 0.5 0 3 2 9 9 255\r\n"
    "1 0.5 1 -4 0 255\r\n"
    "2 1.5 2 5 1 0.1 0\r\n"
    "3 2.5e1 3.0 6 0 0\r\n"
    "2 0 0 4 0 1 2 3 1\r\n"
    "0 3 3 2 1 0\r\n"
    "0 1\r\n";

TEST_F(MeshIoTest, PlyAsciiWithSkippedElementsAndProperties) {
  const auto m = readMesh<double>(writeText("a.ply", kAsciiPly));
  ASSERT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.vertices[0], (Vec3<double>{3, 0, 0.5}));
  EXPECT_EQ(m.vertices[1], (Vec3<double>{-4, 1, 0.5}));
  EXPECT_EQ(m.vertices[3], (Vec3<double>{6, 3, 25}));
  const std::vector<Triangle> want = {{0, 1, 2}, {0, 2, 3}, {3, 2, 1}};
  EXPECT_EQ(m.triangles, want);
}

/// The same small mesh (a quad and a triangle, extra colour property, a skipped list property)
/// in a binary PLY of either byte order, float or double coordinates.
Bytes binaryPly(bool big, bool dbl, std::uint32_t nv = 4, std::uint32_t nf = 2) {
  Bytes b(big);
  b.text("ply\nformat ").text(big ? "binary_big_endian" : "binary_little_endian").text(" 1.0\n");
  b.text("element vertex " + std::to_string(nv) + "\n");
  const std::string t = dbl ? "double" : "float";
  b.text("property " + t + " x\nproperty " + t + " y\nproperty " + t + " z\nproperty uchar red\n");
  b.text("element face " + std::to_string(nf) + "\nproperty list uchar int vertex_indices\n");
  b.text("property list ushort short extra\nend_header\n");
  const double v[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.5}, {0, 1, -2.25}};
  for (int i = 0; i < 4; ++i) {
    for (int k = 0; k < 3; ++k) dbl ? b.f64(v[i][k]) : b.f32(float(v[i][k]));
    b.u8(200);
  }
  b.u8(4).i32(0).i32(1).i32(2).i32(3).u16(2).i16(-1).i16(7);
  b.u8(3).i32(3).i32(2).i32(0).u16(0);
  return b;
}

// An element with no properties holds no data whatever its count: the reader must not walk its
// 7.7e18 declared items (found by fuzz_read_ply as a timeout in the unoptimized fuzz build).
TEST_F(MeshIoTest, PlyPropertylessElementWithAHugeCountIsNotWalked) {
  const auto m = readMesh<double>(writeText("empty_el.ply",
                                            "ply\nformat ascii 1.0\nelement junk 7777777777777777777\n"
                                            "element vertex 3\nproperty float x\nproperty float y\n"
                                            "property float z\nelement face 1\n"
                                            "property list uchar int vertex_indices\nend_header\n"
                                            "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_EQ(m.vertices.size(), 3u);
  EXPECT_EQ(m.triangles.size(), 1u);
}

TEST_F(MeshIoTest, PlyBinaryBothByteOrdersBothPrecisions) {
  for (bool big : {false, true})
    for (bool dbl : {false, true}) {
      SCOPED_TRACE(std::string(big ? "big" : "little") + (dbl ? " double" : " float"));
      const std::string p = writeBytes(
          std::string("b") + (big ? "B" : "L") + (dbl ? "d" : "f") + ".ply", binaryPly(big, dbl));
      const auto m = readMesh<double>(p);
      ASSERT_EQ(m.vertices.size(), 4u);
      EXPECT_EQ(m.vertices[2], (Vec3<double>{1, 1, 0.5}));
      EXPECT_EQ(m.vertices[3], (Vec3<double>{0, 1, -2.25}));
      EXPECT_EQ(m.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}, {3, 2, 0}}));
      const auto f = readMesh<float>(p);
      EXPECT_EQ(f.vertices[3], (Vec3<float>{0, 1, -2.25f}));
      EXPECT_EQ(f.triangles.size(), 3u);
    }
}

TEST_F(MeshIoTest, PlyBinaryIntegerCoordinatesAndOtherListTypes) {
  Bytes b(true);
  b.text(
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty char x\nproperty ushort y\n"
      "property int z\nelement face 1\nproperty list int uint vertex_index\nend_header\n");
  b.i8(-5).u16(60000).i32(-70000);
  b.i8(1).u16(2).i32(3);
  b.i8(4).u16(5).i32(6);
  b.i32(3).u32(2).u32(1).u32(0);
  const auto m = readMesh<double>(writeBytes("ints.ply", b));
  EXPECT_EQ(m.vertices[0], (Vec3<double>{-5, 60000, -70000}));
  EXPECT_EQ(m.triangles, (std::vector<Triangle>{{2, 1, 0}}));
}

TEST_F(MeshIoTest, PlyFacesBeforeVerticesAndNoFaces) {
  Bytes b(false);
  b.text(
      "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int "
      "vertex_indices\n"
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n");
  b.u8(3).i32(0).i32(1).i32(2);
  for (int i = 0; i < 9; ++i) b.f32(float(i));
  const auto m = readMesh<double>(writeBytes("order.ply", b));
  EXPECT_EQ(m.vertices[2], (Vec3<double>{6, 7, 8}));
  EXPECT_EQ(m.triangles.size(), 1u);

  const auto pts =
      readMesh<double>(writeText("pts.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                 "property float y\nproperty float z\nend_header\n1 2 3\n"));
  EXPECT_EQ(pts.vertices.size(), 1u);
  EXPECT_TRUE(pts.triangles.empty());
}

TEST_F(MeshIoTest, PlyErrors) {
  const std::string vh = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string fh = "element face 1\nproperty list uchar int vertex_indices\n";
  const std::string verts = "0 0 0\n1 0 0\n0 1 0\n";
  const std::string a = "ply\nformat ascii 1.0\n";
  expectFileError(writeText("magic.ply", "plx\nformat ascii 1.0\nend_header\n"), "first line");
  expectFileError(writeText("fmt.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n"),
                  "unknown PLY format");
  expectFileError(writeText("nofmt.ply", "ply\n" + vh + "end_header\n" + verts), "format");
  expectFileError(writeText("noend.ply", a + vh), "end_header");
  expectFileError(writeText("kw.ply", a + "elephant vertex 3\nend_header\n"), "line 3");
  expectFileError(writeText("type.ply", a + "element vertex 1\nproperty float128 x\nend_header\n"),
                  "unknown property type");
  expectFileError(
      writeText("ctype.ply",
                a + vh + "element face 1\nproperty list float int vertex_indices\nend_header\n"),
      "count type");
  expectFileError(writeText("prop.ply", a + "property float x\nend_header\n"),
                  "before any element");
  expectFileError(writeText("count.ply", a + "element vertex -3\nend_header\n"), "line 3");
  expectFileError(
      writeText("noxyz.ply",
                a + "element vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n"),
      "'z'");
  expectFileError(writeText("noidx.ply",
                            a + vh + "element face 1\nproperty list uchar int verts\nend_header\n" +
                                verts + "3 0 1 2\n"),
                  "vertex_indices");
  expectFileError(writeText("range.ply", a + vh + fh + "end_header\n" + verts + "3 0 1 3\n"),
                  "face 0");
  expectFileError(writeText("neg.ply", a + vh + fh + "end_header\n" + verts + "3 0 1 -1\n"),
                  "negative");
  expectFileError(writeText("two.ply", a + vh + fh + "end_header\n" + verts + "2 0 1\n"),
                  "need at least 3");
  expectFileError(writeText("truncA.ply", a + vh + fh + "end_header\n" + verts + "3 0 1\n"),
                  "truncated");
  expectFileError(
      writeText("badnum.ply", a + vh + fh + "end_header\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n"),
      "line 11");
  expectFileError(
      writeText("nanA.ply", a + vh + fh + "end_header\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n"),
      "vertex 1");
  expectFileError(
      writeText(
          "lieA.ply",
          a + "element vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n"
              "end_header\n0 0 0\n"),
      "too large");

  // Binary: truncation in the vertices and in a face list, NaN, negative list count, lying counts.
  {
    Bytes b = binaryPly(true, false);
    b.b.resize(b.b.size() - 30);
    expectFileError(writeBytes("truncV.ply", b), "truncated");
  }
  {
    Bytes b = binaryPly(false, true);
    b.b.resize(b.b.size() - 3);
    expectFileError(writeBytes("truncF.ply", b), "face");
  }
  {
    Bytes b(true);
    b.text("ply\nformat binary_big_endian 1.0\n" + vh + "end_header\n");
    b.f32(0)
        .f32(0)
        .f32(0)
        .f32(1)
        .f32(std::numeric_limits<float>::quiet_NaN())
        .f32(0)
        .f32(0)
        .f32(1)
        .f32(0);
    expectFileError(writeBytes("nanB.ply", b), "vertex 1");
  }
  {
    Bytes b(false);
    b.text("ply\nformat binary_little_endian 1.0\n" + vh +
           "element face 1\nproperty list char int vertex_indices\nend_header\n");
    for (int i = 0; i < 9; ++i) b.f32(0);
    b.i8(-1).i32(0).i32(1).i32(2);
    expectFileError(writeBytes("negcount.ply", b), "negative list count");
  }
  {
    Bytes b(false);
    b.text("ply\nformat binary_little_endian 1.0\n" + vh + fh + "end_header\n");
    for (int i = 0; i < 9; ++i) b.f32(0);
    b.u8(3).i32(0).i32(-7).i32(2);
    expectFileError(writeBytes("negidx.ply", b), "negative vertex index");
  }
  {
    // 2^31 vertices claimed, 12 bytes present: must fail fast, without a 24 GiB allocation.
    const auto t0 = std::chrono::steady_clock::now();
    Bytes b = binaryPly(false, false, 2147483647u, 2);
    expectFileError(writeBytes("lieV.ply", b), "element 'vertex'");
    Bytes c = binaryPly(true, false, 4, 4000000000u);
    expectFileError(writeBytes("lieF.ply", c), "element 'face'");
    Bytes d = binaryPly(true, false, 4, 2);
    d.text("");  // fine as is
    EXPECT_NO_THROW(readMesh<double>(writeBytes("ok.ply", d)));
    Bytes e = binaryPly(false, false, 4294967295u, 2);
    expectFileError(writeBytes("lieV2.ply", e), "too many vertices");
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  }
  {
    // A face whose list count claims far more indices than the file holds.
    Bytes b(false);
    b.text("ply\nformat binary_little_endian 1.0\n" + vh +
           "element face 1\nproperty list uint int vertex_indices\nend_header\n");
    for (int i = 0; i < 9; ++i) b.f32(0);
    b.u32(4000000000u).i32(0).i32(1).i32(2);
    expectFileError(writeBytes("lieList.ply", b), "truncated");
  }
}

// ---------------------------------------------------------------------------------------------
// STL.

TEST_F(MeshIoTest, StlAscii) {
  const auto m = readMesh<double>(writeText(
      "a.stl",
      "solid my part\n"
      "  facet normal 0 0 1\n"
      "    outer loop\n"
      "      vertex 0 0 0\n"
      "      vertex 1 0 0\n"
      "      vertex 0 1 0\n"
      "    endloop\n"
      "  endfacet\n"
      "  facet normal 0 0 -1.0e+00\n"
      "    outer loop\n"
      "      vertex 0 0 1\n      vertex 1 0 1\n"
      "      vertex 1 1 1\n      vertex 0 1 1.5\n"  // quad -> 2
      "    endloop\n"
      "  endfacet\n"
      "endsolid my part\n"
      "solid second\n"
      "facet normal 0 0 0 outer loop vertex 5 5 5 vertex 6 5 5 vertex 5 6 5 endloop endfacet\n"
      "endsolid\n"));
  ASSERT_EQ(m.triangles.size(), 4u);
  ASSERT_EQ(m.vertices.size(), 3u + 4u + 3u);
  EXPECT_EQ(m.triangles[1], (Triangle{3, 4, 5}));
  EXPECT_EQ(m.triangles[2], (Triangle{3, 5, 6}));
  EXPECT_EQ(m.vertices[6], (Vec3<double>{0, 1, 1.5}));
  EXPECT_EQ(m.vertices[9], (Vec3<double>{5, 6, 5}));
}

Bytes binaryStl(std::uint32_t count, std::uint32_t actual, const std::string& header = "binary") {
  Bytes b(false);
  std::string h = header;
  h.resize(80, ' ');
  b.text(h).u32(count);
  for (std::uint32_t t = 0; t < actual; ++t) {
    b.f32(0).f32(0).f32(1);
    b.f32(float(t)).f32(0).f32(0);
    b.f32(float(t) + 1).f32(0).f32(0);
    b.f32(float(t)).f32(1).f32(0.25f);
    b.u16(0);
  }
  return b;
}

TEST_F(MeshIoTest, StlBinary) {
  const auto m = readMesh<float>(writeBytes("b.stl", binaryStl(2, 2)));
  ASSERT_EQ(m.triangles.size(), 2u);
  ASSERT_EQ(m.vertices.size(), 6u);
  EXPECT_EQ(m.vertices[5], (Vec3<float>{1, 1, 0.25f}));
  EXPECT_EQ(m.triangles[1], (Triangle{3, 4, 5}));
  // A binary file whose header starts with "solid" is still binary when the size fits.
  const auto s = readMesh<double>(writeBytes("solid.stl", binaryStl(3, 3, "solid but binary")));
  EXPECT_EQ(s.triangles.size(), 3u);
}

TEST_F(MeshIoTest, StlErrors) {
  expectFileError(writeBytes("count.stl", binaryStl(3, 2)), "disagrees with the file size");
  expectFileError(writeBytes("count2.stl", binaryStl(0xFFFFFFFFu, 1)),
                  "disagrees with the file size");
  {
    Bytes b = binaryStl(1, 1);
    b.b.resize(60);
    expectFileError(writeBytes("hdr.stl", b), "truncated binary STL header");
  }
  {
    Bytes b = binaryStl(1, 1);
    b.u8(0);
    expectFileError(writeBytes("extra.stl", b), "disagrees");
  }
  const std::string f =
      "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 "
      "0\nendloop\nendfacet\n";
  expectFileError(
      writeText("trunc.stl", "solid x\n" + f + "facet normal 0 0 1\nouter loop\nvertex 0 0 0\n"),
      "truncated");
  expectFileError(writeText("noend.stl", "solid x\n" + f), "endsolid");
  expectFileError(writeText("kw.stl", "solid x\n" + f + "facet normal 0 0 1\nouter lop\n"),
                  "line 10");
  expectFileError(
      writeText("num.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 q 0\n"),
      "line 5");
  expectFileError(writeText("two.stl",
                            "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 "
                            "0\nendloop\nendfacet\nendsolid\n"),
                  "need at least 3");
  expectFileError(
      writeText("nan.stl",
                "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 inf\n"),
      "line 5");
  expectFileError(writeText("short.stl", "not an stl file"), "truncated binary STL header");
}

// ---------------------------------------------------------------------------------------------
// Robustness: every truncation and many byte mutations of valid files either load or throw
// MeshFileError (never another exception, a crash or a hang). Run under ASan/UBSan too.

TEST_F(MeshIoTest, MutatedFilesLoadOrThrowMeshFileError) {
  std::vector<std::pair<std::string, std::vector<unsigned char>>> seeds;
  const auto fromText = [](const std::string& s) {
    return std::vector<unsigned char>(s.begin(), s.end());
  };
  seeds.push_back({"a.ply", fromText(kAsciiPly)});
  seeds.push_back({"b.ply", binaryPly(true, false).b});
  seeds.push_back({"c.ply", binaryPly(false, true).b});
  seeds.push_back({"d.stl", binaryStl(2, 2).b});
  seeds.push_back(
      {"e.stl", fromText("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                         "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n")});
  seeds.push_back(
      {"f.off", fromText("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n")});
  seeds.push_back(
      {"g.obj", fromText("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf -1 -2 -3\n")});
  std::uint64_t rng = 12345;
  const auto next = [&rng]() {
    rng = rng * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<std::uint32_t>(rng >> 33);
  };
  const unsigned char specials[] = {0,   1,   2,   3,    0x7f, 0x80, 0xff,
                                    '-', '9', ' ', '\n', '.',  'e',  '/'};
  int loaded = 0, failed = 0;
  for (const auto& seed : seeds) {
    std::vector<std::vector<unsigned char>> variants;
    for (std::size_t n = 1; n < seed.second.size(); ++n)
      variants.emplace_back(seed.second.begin(),
                            seed.second.begin() + static_cast<std::ptrdiff_t>(n));
    for (int i = 0; i < 300; ++i) {
      auto v = seed.second;
      const int flips = 1 + int(next() % 3);
      for (int f = 0; f < flips; ++f) v[next() % v.size()] = specials[next() % sizeof specials];
      variants.push_back(std::move(v));
    }
    for (const auto& v : variants) {
      const std::string p = path(seed.first);
      {
        std::ofstream out(p, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size()));
      }
      try {
        const auto m = readMesh<float>(p);
        for (const auto& t : m.triangles)
          for (auto i : t) ASSERT_LT(i, m.vertices.size());
        ++loaded;
      } catch (const MeshFileError&) {
        ++failed;
      }
    }
  }
  EXPECT_GT(loaded, 0);
  EXPECT_GT(failed, 0);
}

// ---------------------------------------------------------------------------------------------
// The shared data files (skipped when ../shared/data is absent).

#ifndef KDET_FCL_SHARED_DATA
#define KDET_FCL_SHARED_DATA ""
#endif

std::string sharedData(const std::string& rel) {
  return std::string(KDET_FCL_SHARED_DATA) + "/" + rel;
}

template <class S>
void checkShared(const std::string& rel, std::size_t tris, std::size_t verts) {
  SCOPED_TRACE(rel);
  const auto m = readMesh<S>(sharedData(rel));
  EXPECT_EQ(m.triangles.size(), tris);
  if (verts) {
    EXPECT_EQ(m.vertices.size(), verts);
  }
}

class SharedData : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::string(KDET_FCL_SHARED_DATA).empty() || !fs::is_directory(KDET_FCL_SHARED_DATA))
      GTEST_SKIP() << "shared data folder not found: " << KDET_FCL_SHARED_DATA;
  }
};

TEST_F(SharedData, ClothBallBigEndianFloatPly) {
  if (!fs::exists(sharedData("unc/cloth-ball/cloth_ball92.ply"))) GTEST_SKIP();
  checkShared<double>("unc/cloth-ball/cloth_ball92.ply", 92230, 46598);
  checkShared<float>("unc/cloth-ball/cloth_ball92.ply", 92230, 46598);
}

TEST_F(SharedData, ClothFunnelLittleEndianDoublePly) {
  if (!fs::exists(sharedData("unc/cloth-funnel/227.ply"))) GTEST_SKIP();
  checkShared<double>("unc/cloth-funnel/227.ply", 18484, 9450);
  checkShared<float>("unc/cloth-funnel/227.ply", 18484, 9450);
}

TEST_F(SharedData, FclObjSoups) {
  if (!fs::exists(sharedData("fcl/env.obj"))) GTEST_SKIP();
  checkShared<double>("fcl/env.obj", 2180, 3 * 2180);
  checkShared<float>("fcl/rob.obj", 216, 3 * 216);
}

TEST_F(SharedData, SharedPlyRoundTripsThroughEveryFormat) {
  const std::string src = sharedData("unc/cloth-funnel/227.ply");
  if (!fs::exists(src)) GTEST_SKIP();
  const auto m = readMesh<double>(src);
  const fs::path dir =
      fs::temp_directory_path() /
      ("kdet_mesh_io_shared_" +
       std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
  fs::create_directories(dir);
  for (const char* ext : {".obj", ".off", ".ply"}) {
    const std::string p = (dir / (std::string("m") + ext)).string();
    writeMesh(m, p);
    const auto r = readMesh<double>(p);
    EXPECT_EQ(r.triangles, m.triangles) << ext;
    EXPECT_TRUE(r.vertices == m.vertices) << ext;
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace
