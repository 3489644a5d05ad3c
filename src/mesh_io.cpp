/// \file
/// Mesh readers and writers: OBJ (through tinyobjloader), OFF, PLY (ASCII and binary, both byte
/// orders) and STL (ASCII and binary).
///
/// Every reader works on the whole file held in memory and checks every bound itself: a lying
/// header count is compared against the bytes that are actually there before anything is
/// allocated for it, binary values are read with memcpy (no unaligned access), and every failure
/// becomes a MeshFileError that starts with the file name.

#include "kdet_fcl/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

// The library links tinyobjloader::tinyobjloader_double, whose real_t is double; the header must
// agree with the library it is linked against (the CMake target also defines this).
#ifndef TINYOBJLOADER_USE_DOUBLE
#define TINYOBJLOADER_USE_DOUBLE
#endif
#include <tiny_obj_loader.h>

#include "kdet_fcl/errors.h"

namespace kdet_fcl {
namespace {

/// Largest vertex or triangle count a mesh may hold (indices are 32-bit; validate() agrees).
constexpr std::uint64_t kMaxCount = 0xFFFFFFFEull;

[[noreturn]] void fail(const std::string& path, const std::string& msg) {
  throw MeshFileError(path + ": " + msg);
}

std::string lowerExtension(const std::string& path) {
  const std::size_t slash = path.find_last_of("/\\");
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::string readWholeFile(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (st.type() == fs::file_type::not_found) fail(path, "no such file");
  if (ec) fail(path, "cannot access file: " + ec.message());
  if (st.type() == fs::file_type::directory) fail(path, "is a directory, not a mesh file");
  if (st.type() != fs::file_type::regular) fail(path, "not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open file: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) fail(path, "cannot determine the file size");
  if (size == 0) fail(path, "file is empty");
  in.seekg(0, std::ios::beg);
  std::string data(static_cast<std::size_t>(size), '\0');
  in.read(&data[0], size);
  if (in.gcount() != size) fail(path, "read error (file changed or unreadable)");
  return data;
}

// ---------------------------------------------------------------------------------------------
// Text helpers (locale-independent: std::from_chars, never strtod/atoi).

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; }

/// Splits a text buffer into lines; "\n", "\r\n" and a lone "\r" all end a line (as in
/// tinyobjloader, so line numbers agree with its messages).
class LineReader {
 public:
  explicit LineReader(std::string_view text) : p_(text.data()), end_(text.data() + text.size()) {}
  bool next(std::string_view& line) {
    if (p_ >= end_) return false;
    const char* s = p_;
    while (p_ < end_ && *p_ != '\n' && *p_ != '\r') ++p_;
    line = std::string_view(s, static_cast<std::size_t>(p_ - s));
    if (p_ < end_) {
      if (*p_ == '\r' && p_ + 1 < end_ && p_[1] == '\n') ++p_;
      ++p_;
    }
    ++line_;
    return true;
  }
  std::size_t line() const { return line_; }
  std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }

 private:
  const char* p_;
  const char* end_;
  std::size_t line_ = 0;
};

void splitTokens(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isBlank(line[i])) ++i;
    if (i >= line.size()) break;
    const std::size_t s = i;
    while (i < line.size() && !isBlank(line[i])) ++i;
    out.push_back(line.substr(s, i - s));
  }
}

bool parseDouble(std::string_view tok, double& out) {
  if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
  if (tok.empty()) return false;
  const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  if (r.ec == std::errc::result_out_of_range) {
    // Overflow: report it as an infinite value (rejected by the caller with a clear message);
    // underflow rounds to zero.
    bool has_big_exp = false;
    const std::size_t e = tok.find_first_of("eE");
    if (e != std::string_view::npos && e + 1 < tok.size() && tok[e + 1] != '-') has_big_exp = true;
    if (e == std::string_view::npos) has_big_exp = true;
    out = has_big_exp ? (tok[0] == '-' ? -HUGE_VAL : HUGE_VAL) : 0.0;
    return true;
  }
  return r.ec == std::errc() && r.ptr == tok.data() + tok.size();
}

bool parseInt(std::string_view tok, long long& out) {
  if (!tok.empty() && tok[0] == '+') tok.remove_prefix(1);
  if (tok.empty()) return false;
  const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  return r.ec == std::errc() && r.ptr == tok.data() + tok.size();
}

std::string quoteTok(std::string_view tok) {
  std::string s(tok.substr(0, 40));
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return "'" + s + (tok.size() > 40 ? "...'" : "'");
}

template <class S>
S toCoord(const std::string& path, double v, std::string_view tok, const std::string& where) {
  const S s = static_cast<S>(v);
  if (!std::isfinite(v) || !std::isfinite(s))
    fail(path, "coordinate " + quoteTok(tok) + " is not a finite " +
                   (std::is_same<S, float>::value ? "float" : "double") + " value (" + where + ")");
  return s;
}

void checkNoNul(const std::string& path, const std::string& data) {
  const std::size_t nul = data.find('\0');
  if (nul == std::string::npos) return;
  const std::size_t line =
      1 + static_cast<std::size_t>(
              std::count(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(nul), '\n'));
  fail(path, "unexpected NUL byte in a text file (line " + std::to_string(line) + ")");
}

/// Appends the fan triangulation (v0, vi, vi+1) of one polygon.
void fan(std::vector<Triangle>& tris, const std::uint32_t* idx, std::size_t n) {
  for (std::size_t i = 1; i + 1 < n; ++i) tris.push_back({idx[0], idx[i], idx[i + 1]});
}

// ---------------------------------------------------------------------------------------------
// OBJ. tinyobjloader parses the structure (faces, relative indices, groups). A pre-scan of our
// own checks what tinyobjloader silently accepts or gets wrong (missing or non-numeric
// coordinates, NaN, out-of-range and zero indices, faces with fewer than three vertices,
// index overflow in atoi) and gives line numbers; it also supplies the coordinates, because
// tinyobjloader's fast float parser is not correctly rounded and double round trips must be exact,
// and the polygon sizes, because tinyobjloader stores those in an unsigned char.

template <class S>
TriangleMesh<S> readObj(const std::string& path, const std::string& data) {
  checkNoNul(path, data);
  TriangleMesh<S> mesh;
  std::vector<std::size_t> face_sizes;
  std::uint64_t max_positive = 0;
  std::size_t max_positive_line = 0;
  {
    LineReader lines(data);
    std::string_view line;
    std::vector<std::string_view> tok;
    while (lines.next(line)) {
      std::size_t i = 0;
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
      if (i + 1 >= line.size()) continue;
      const char c0 = line[i], c1 = line[i + 1];
      const std::string where = "line " + std::to_string(lines.line());
      if (c0 == 'v' && (c1 == ' ' || c1 == '\t')) {
        splitTokens(line.substr(i + 2), tok);
        if (tok.size() < 3)
          fail(path,
               "vertex with " + std::to_string(tok.size()) + " coordinates (need 3), " + where);
        Vec3<S> p;
        for (int k = 0; k < 3; ++k) {
          double v;
          if (!parseDouble(tok[k], v))
            fail(path, "bad vertex coordinate " + quoteTok(tok[k]) + ", " + where);
          p[k] = toCoord<S>(path, v, tok[k], where);
        }
        if (mesh.vertices.size() >= kMaxCount) fail(path, "too many vertices, " + where);
        mesh.vertices.push_back(p);
      } else if (c0 == 'f' && (c1 == ' ' || c1 == '\t')) {
        splitTokens(line.substr(i + 2), tok);
        if (tok.size() < 3)
          fail(path,
               "face with " + std::to_string(tok.size()) + " vertices (need at least 3), " + where);
        for (std::string_view t : tok) {
          // v, v/vt, v//vn or v/vt/vn; every present index a non-zero integer that fits an int.
          std::string_view parts[3];
          int np = 0;
          std::size_t s = 0;
          while (np < 3) {
            const std::size_t slash = t.find('/', s);
            parts[np++] =
                t.substr(s, slash == std::string_view::npos ? std::string_view::npos : slash - s);
            if (slash == std::string_view::npos) break;
            s = slash + 1;
            if (np == 3) fail(path, "bad face vertex " + quoteTok(t) + ", " + where);
          }
          for (int k = 0; k < np; ++k) {
            if (k == 1 && parts[k].empty() && np == 3) continue;  // v//vn
            long long v;
            if (!parseInt(parts[k], v) || v == 0 || v > std::numeric_limits<int>::max() ||
                v < -static_cast<long long>(std::numeric_limits<int>::max()))
              fail(path,
                   "bad face index " + quoteTok(t) + " (indices are non-zero integers), " + where);
            if (k != 0) continue;
            if (v > 0) {
              if (static_cast<std::uint64_t>(v) > max_positive) {
                max_positive = static_cast<std::uint64_t>(v);
                max_positive_line = lines.line();
              }
            } else if (static_cast<long long>(mesh.vertices.size()) + v < 0) {
              fail(path, "relative face index " + std::to_string(v) +
                             " points before the first vertex (" +
                             std::to_string(mesh.vertices.size()) + " vertices so far), " + where);
            }
          }
        }
        face_sizes.push_back(tok.size());
      }
    }
  }
  if (max_positive > mesh.vertices.size())
    fail(path, "face index " + std::to_string(max_positive) + " out of range (" +
                   std::to_string(mesh.vertices.size()) + " vertices), line " +
                   std::to_string(max_positive_line));

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  {
    std::istringstream in(data);
    // No material reader: .mtl files are not needed for geometry. No triangulation: we fan
    // ourselves so the result does not depend on tinyobjloader's quad-splitting heuristic.
    const bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, nullptr,
                                     /*triangulate=*/false, /*default_vcols_fallback=*/false);
    if (!ok) {
      while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
      fail(path, "OBJ parse error: " + (err.empty() ? std::string("unknown error") : err));
    }
  }
  if (attrib.vertices.size() != 3 * mesh.vertices.size())
    fail(path, "OBJ parse error: inconsistent vertex count");

  std::size_t face = 0, total = 0;
  for (const auto& shape : shapes) total += shape.mesh.indices.size();
  std::size_t expected_total = 0;
  for (std::size_t n : face_sizes) expected_total += n;
  if (total != expected_total) fail(path, "OBJ parse error: inconsistent face data");
  std::size_t tri_count = 0;
  for (std::size_t n : face_sizes) tri_count += n - 2;
  if (tri_count > kMaxCount) fail(path, "too many triangles");
  mesh.triangles.reserve(tri_count);
  std::vector<std::uint32_t> poly;
  const auto nv = static_cast<long long>(mesh.vertices.size());
  for (const auto& shape : shapes) {
    const auto& m = shape.mesh;
    std::size_t off = 0;
    for (std::size_t f = 0; f < m.num_face_vertices.size(); ++f, ++face) {
      if (face >= face_sizes.size()) fail(path, "OBJ parse error: inconsistent face data");
      const std::size_t n = face_sizes[face];
      if ((n & 0xFFu) != m.num_face_vertices[f] || off + n > m.indices.size())
        fail(path, "OBJ parse error: inconsistent face data");
      poly.clear();
      for (std::size_t k = 0; k < n; ++k) {
        const long long vi = m.indices[off + k].vertex_index;
        if (vi < 0 || vi >= nv)
          fail(path, "face " + std::to_string(face) + " has vertex index out of range");
        poly.push_back(static_cast<std::uint32_t>(vi));
      }
      fan(mesh.triangles, poly.data(), n);
      off += n;
    }
  }
  if (face != face_sizes.size()) fail(path, "OBJ parse error: inconsistent face data");
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// OFF (ASCII): [ST][C][N]OFF, counts (on the keyword line or the next), one vertex per line
// (extra values such as colours ignored), one face per line "n i0 ... i(n-1) [colour]".

/// Next line with content, comments ('#' to end of line) removed.
bool nextContentLine(LineReader& lines, std::string_view& line) {
  while (lines.next(line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    for (char c : line)
      if (!isBlank(c)) return true;
  }
  return false;
}

template <class S>
TriangleMesh<S> readOff(const std::string& path, const std::string& data) {
  checkNoNul(path, data);
  LineReader lines(data);
  std::string_view line;
  std::vector<std::string_view> tok;
  if (!nextContentLine(lines, line))
    fail(path, "no OFF header (file holds only comments or blanks)");
  splitTokens(line, tok);
  std::string_view kw = tok[0];
  if (kw.size() >= 2 && kw.substr(0, 2) == "ST") kw.remove_prefix(2);
  if (!kw.empty() && kw[0] == 'C') kw.remove_prefix(1);
  if (!kw.empty() && kw[0] == 'N') kw.remove_prefix(1);
  if (kw != "OFF") {
    if (kw.size() > 3 && kw.substr(kw.size() - 3) == "OFF")
      fail(path, "unsupported OFF variant " + quoteTok(tok[0]) + " (line " +
                     std::to_string(lines.line()) + ")");
    fail(path, "bad OFF header: expected 'OFF', found " + quoteTok(tok[0]) + " (line " +
                   std::to_string(lines.line()) + ")");
  }
  std::size_t first = 1;
  if (tok.size() > 1 && tok[1] == "BINARY") fail(path, "binary OFF is not supported");
  if (tok.size() <= first) {
    if (!nextContentLine(lines, line))
      fail(path, "truncated OFF header: missing the vertex and face counts");
    splitTokens(line, tok);
    first = 0;
  }
  const std::string hline = "line " + std::to_string(lines.line());
  if (tok.size() < first + 2)
    fail(path, "bad OFF header: expected 'vertices faces edges' counts, " + hline);
  long long nv_ll, nf_ll;
  if (!parseInt(tok[first], nv_ll) || !parseInt(tok[first + 1], nf_ll) || nv_ll < 0 || nf_ll < 0)
    fail(path, "bad OFF header: counts must be non-negative integers, " + hline);
  const auto nv = static_cast<std::uint64_t>(nv_ll), nf = static_cast<std::uint64_t>(nf_ll);
  if (nv > kMaxCount || nf > kMaxCount) fail(path, "OFF counts too large, " + hline);
  // Each vertex line takes at least "x y z" plus a line end (6 bytes), each face line at least
  // two (a bad face then gets its own message); the last line may lack its end. This bounds what
  // is allocated below by a small multiple of the file size.
  if (nv * 6 + nf * 2 > lines.remaining() + 1)
    fail(path, "OFF header counts (" + std::to_string(nv) + " vertices, " + std::to_string(nf) +
                   " faces) are too large for the file size (" + std::to_string(data.size()) +
                   " bytes): truncated file or bad header, " + hline);

  TriangleMesh<S> mesh;
  mesh.vertices.resize(static_cast<std::size_t>(nv));
  for (std::uint64_t i = 0; i < nv; ++i) {
    if (!nextContentLine(lines, line))
      fail(path,
           "truncated: expected " + std::to_string(nv) + " vertices, found " + std::to_string(i));
    splitTokens(line, tok);
    const std::string where =
        "vertex " + std::to_string(i) + ", line " + std::to_string(lines.line());
    if (tok.size() < 3) fail(path, "vertex needs 3 coordinates, " + where);
    for (int k = 0; k < 3; ++k) {
      double v;
      if (!parseDouble(tok[k], v))
        fail(path, "bad vertex coordinate " + quoteTok(tok[k]) + ", " + where);
      mesh.vertices[i][k] = toCoord<S>(path, v, tok[k], where);
    }
  }
  mesh.triangles.reserve(static_cast<std::size_t>(nf));
  std::vector<std::uint32_t> poly;
  for (std::uint64_t f = 0; f < nf; ++f) {
    if (!nextContentLine(lines, line))
      fail(path,
           "truncated: expected " + std::to_string(nf) + " faces, found " + std::to_string(f));
    splitTokens(line, tok);
    const std::string where =
        "face " + std::to_string(f) + ", line " + std::to_string(lines.line());
    long long n;
    if (!parseInt(tok[0], n) || n < 0)
      fail(path, "bad face vertex count " + quoteTok(tok[0]) + ", " + where);
    if (n < 3)
      fail(path, "face with " + std::to_string(n) + " vertices (need at least 3), " + where);
    if (static_cast<unsigned long long>(n) > tok.size() - 1)
      fail(path, "face lists fewer indices than its count " + std::to_string(n) + ", " + where);
    poly.clear();
    for (long long k = 0; k < n; ++k) {
      long long vi;
      const std::string_view t = tok[static_cast<std::size_t>(k) + 1];
      if (!parseInt(t, vi)) fail(path, "bad vertex index " + quoteTok(t) + ", " + where);
      if (vi < 0 || static_cast<unsigned long long>(vi) >= nv)
        fail(path, "vertex index " + std::to_string(vi) + " out of range (" + std::to_string(nv) +
                       " vertices), " + where);
      poly.push_back(static_cast<std::uint32_t>(vi));
    }
    if (mesh.triangles.size() + poly.size() - 2 > kMaxCount) fail(path, "too many triangles");
    fan(mesh.triangles, poly.data(), poly.size());
  }
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// PLY.

enum class PlyType { I8, U8, I16, U16, I32, U32, F32, F64 };

bool parsePlyType(std::string_view s, PlyType& t) {
  struct Name {
    const char* name;
    PlyType type;
  };
  static const Name names[] = {
      {"char", PlyType::I8},    {"int8", PlyType::I8},     {"uchar", PlyType::U8},
      {"uint8", PlyType::U8},   {"short", PlyType::I16},   {"int16", PlyType::I16},
      {"ushort", PlyType::U16}, {"uint16", PlyType::U16},  {"int", PlyType::I32},
      {"int32", PlyType::I32},  {"uint", PlyType::U32},    {"uint32", PlyType::U32},
      {"float", PlyType::F32},  {"float32", PlyType::F32}, {"double", PlyType::F64},
      {"float64", PlyType::F64}};
  for (const Name& n : names)
    if (s == n.name) {
      t = n.type;
      return true;
    }
  return false;
}

std::size_t plySize(PlyType t) {
  switch (t) {
    case PlyType::I8:
    case PlyType::U8:
      return 1;
    case PlyType::I16:
    case PlyType::U16:
      return 2;
    case PlyType::I32:
    case PlyType::U32:
    case PlyType::F32:
      return 4;
    case PlyType::F64:
      return 8;
  }
  return 1;
}

bool plyIsInteger(PlyType t) { return t != PlyType::F32 && t != PlyType::F64; }

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyType type = PlyType::F32;       ///< value type (list entry type for lists)
  PlyType count_type = PlyType::U8;  ///< list count type
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> props;
};

enum class PlyFormat { Ascii, BinaryLE, BinaryBE };

bool hostIsLittleEndian() {
  const std::uint16_t one = 1;
  unsigned char b;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

/// Reads typed values from the binary body; every read is bounds-checked and done by memcpy.
class BinaryCursor {
 public:
  BinaryCursor(const unsigned char* p, const unsigned char* end, bool swap)
      : p_(p), begin_(p), end_(end), swap_(swap) {}
  std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }
  std::size_t offset() const { return static_cast<std::size_t>(p_ - begin_); }
  bool skip(std::size_t n) {
    if (n > remaining()) return false;
    p_ += n;
    return true;
  }
  /// The value of type T stored in the (already byte-order corrected) bytes b.
  template <class T>
  static double loadAs(const unsigned char* b) {
    T v;
    std::memcpy(&v, b, sizeof(T));
    return double(v);
  }
  /// Reads one value as a double (exact for every PLY type).
  bool read(PlyType t, double& out) {
    const std::size_t n = plySize(t);
    if (n > remaining()) return false;
    unsigned char b[8];
    std::memcpy(b, p_, n);
    p_ += n;
    if (swap_) std::reverse(b, b + n);
    switch (t) {
      case PlyType::I8: out = loadAs<std::int8_t>(b); break;
      case PlyType::U8: out = loadAs<std::uint8_t>(b); break;
      case PlyType::I16: out = loadAs<std::int16_t>(b); break;
      case PlyType::U16: out = loadAs<std::uint16_t>(b); break;
      case PlyType::I32: out = loadAs<std::int32_t>(b); break;
      case PlyType::U32: out = loadAs<std::uint32_t>(b); break;
      case PlyType::F32: out = loadAs<float>(b); break;
      case PlyType::F64: out = loadAs<double>(b); break;
    }
    return true;
  }

 private:
  const unsigned char* p_;
  const unsigned char* begin_;
  const unsigned char* end_;
  bool swap_;
};

/// Reads whitespace-separated values from an ASCII body, tracking the line for messages.
class AsciiCursor {
 public:
  AsciiCursor(const char* p, const char* end, std::size_t line) : p_(p), end_(end), line_(line) {}
  std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }
  std::size_t line() const { return line_; }
  bool token(std::string_view& tok) {
    while (p_ < end_ && (isBlank(*p_) || *p_ == '\n' || *p_ == '\r')) {
      if (*p_ == '\n') ++line_;
      ++p_;
    }
    if (p_ >= end_) return false;
    const char* s = p_;
    while (p_ < end_ && !isBlank(*p_) && *p_ != '\n' && *p_ != '\r') ++p_;
    tok = std::string_view(s, static_cast<std::size_t>(p_ - s));
    return true;
  }

 private:
  const char* p_;
  const char* end_;
  std::size_t line_;
};

template <class S>
class PlyReader {
 public:
  PlyReader(const std::string& path, const std::string& data) : path_(path), data_(data) {}

  TriangleMesh<S> read() {
    const std::size_t body = parseHeader();
    const char* begin = data_.data() + body;
    const char* end = data_.data() + data_.size();
    if (format_ == PlyFormat::Ascii) {
      checkNoNulFrom(body);
      AsciiCursor cur(begin, end, header_lines_ + 1);
      for (std::size_t e = 0; e < elements_.size(); ++e) readElement(elements_[e], cur);
    } else {
      const bool file_le = format_ == PlyFormat::BinaryLE;
      BinaryCursor cur(reinterpret_cast<const unsigned char*>(begin),
                       reinterpret_cast<const unsigned char*>(end),
                       file_le != hostIsLittleEndian());
      for (std::size_t e = 0; e < elements_.size(); ++e) readElement(elements_[e], cur);
    }
    // Faces may come before vertices in the file: check the indices once both are known.
    const std::uint64_t nv = mesh_.vertices.size();
    if (have_max_ && max_index_ >= nv)
      fail(path_, "face " + std::to_string(max_index_face_) + " has vertex index " +
                      std::to_string(max_index_) + " out of range (" + std::to_string(nv) +
                      " vertices)");
    return std::move(mesh_);
  }

 private:
  void checkNoNulFrom(std::size_t from) {
    const std::size_t nul = data_.find('\0', from);
    if (nul != std::string::npos)
      fail(path_,
           "unexpected NUL byte in ASCII PLY data (byte offset " + std::to_string(nul) + ")");
  }

  /// Parses the header; returns the byte offset of the body.
  std::size_t parseHeader() {
    const std::size_t kMaxHeader = 1u << 20;
    std::size_t pos = 0, line_no = 0;
    bool have_format = false;
    std::vector<std::string_view> tok;
    for (;;) {
      if (pos >= data_.size()) fail(path_, "truncated PLY header: no 'end_header' line");
      if (pos > kMaxHeader) fail(path_, "PLY header longer than 1 MiB without 'end_header'");
      std::size_t nl = data_.find('\n', pos);
      if (nl == std::string::npos) nl = data_.size();
      std::string_view line(data_.data() + pos, nl - pos);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      pos = nl + 1;
      ++line_no;
      const std::string where = "PLY header line " + std::to_string(line_no);
      if (line_no == 1) {
        if (line != "ply") fail(path_, "not a PLY file: the first line must be 'ply'");
        continue;
      }
      splitTokens(line, tok);
      if (tok.empty()) continue;
      const std::string_view kw = tok[0];
      if (kw == "comment" || kw == "obj_info") continue;
      if (kw == "format") {
        if (tok.size() < 2) fail(path_, "bad format line, " + where);
        if (tok[1] == "ascii")
          format_ = PlyFormat::Ascii;
        else if (tok[1] == "binary_little_endian")
          format_ = PlyFormat::BinaryLE;
        else if (tok[1] == "binary_big_endian")
          format_ = PlyFormat::BinaryBE;
        else
          fail(path_, "unknown PLY format " + quoteTok(tok[1]) + ", " + where);
        have_format = true;
      } else if (kw == "element") {
        long long n;
        if (tok.size() < 3 || !parseInt(tok[2], n) || n < 0)
          fail(path_, "bad element line (expected 'element NAME COUNT'), " + where);
        PlyElement el;
        el.name = std::string(tok[1]);
        el.count = static_cast<std::uint64_t>(n);
        elements_.push_back(std::move(el));
      } else if (kw == "property") {
        if (elements_.empty()) fail(path_, "property before any element, " + where);
        PlyProperty p;
        if (tok.size() >= 2 && tok[1] == "list") {
          if (tok.size() < 5)
            fail(path_,
                 "bad list property (expected 'property list COUNT_TYPE TYPE NAME'), " + where);
          if (!parsePlyType(tok[2], p.count_type) || !plyIsInteger(p.count_type))
            fail(path_, "bad list count type " + quoteTok(tok[2]) + ", " + where);
          if (!parsePlyType(tok[3], p.type))
            fail(path_, "unknown property type " + quoteTok(tok[3]) + ", " + where);
          p.is_list = true;
          p.name = std::string(tok[4]);
        } else {
          if (tok.size() < 3)
            fail(path_, "bad property line (expected 'property TYPE NAME'), " + where);
          if (!parsePlyType(tok[1], p.type))
            fail(path_, "unknown property type " + quoteTok(tok[1]) + ", " + where);
          p.name = std::string(tok[2]);
        }
        elements_.back().props.push_back(std::move(p));
      } else if (kw == "end_header") {
        break;
      } else {
        fail(path_, "unknown PLY header keyword " + quoteTok(kw) + ", " + where);
      }
    }
    if (!have_format) fail(path_, "PLY header has no 'format' line");
    header_lines_ = line_no;
    return std::min(pos, data_.size());
  }

  /// Roles of the properties of the element being read.
  struct Roles {
    int xyz[3] = {-1, -1, -1};
    int indices = -1;
    bool vertex = false, face = false;
  };

  Roles rolesOf(const PlyElement& el) {
    Roles r;
    if (el.name == "vertex") {
      r.vertex = true;
      for (std::size_t i = 0; i < el.props.size(); ++i) {
        const auto& p = el.props[i];
        for (int k = 0; k < 3; ++k)
          if (!p.is_list && p.name == std::string(1, char('x' + k)) && r.xyz[k] < 0)
            r.xyz[k] = int(i);
      }
      for (int k = 0; k < 3; ++k)
        if (r.xyz[k] < 0)
          fail(path_,
               std::string("PLY vertex element has no scalar property '") + char('x' + k) + "'");
      if (el.count > kMaxCount) fail(path_, "too many vertices (" + std::to_string(el.count) + ")");
      if (!mesh_.vertices.empty()) fail(path_, "PLY file has more than one 'vertex' element");
    } else if (el.name == "face") {
      r.face = true;
      for (std::size_t i = 0; i < el.props.size(); ++i) {
        const auto& p = el.props[i];
        if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index") && r.indices < 0)
          r.indices = int(i);
      }
      if (r.indices < 0)
        fail(path_, "PLY face element has no list property 'vertex_indices' or 'vertex_index'");
      if (!plyIsInteger(el.props[static_cast<std::size_t>(r.indices)].type))
        fail(path_, "PLY face indices must have an integer type");
      if (el.count > kMaxCount) fail(path_, "too many faces (" + std::to_string(el.count) + ")");
      if (has_faces_) fail(path_, "PLY file has more than one 'face' element");
      has_faces_ = true;
    }
    return r;
  }

  /// Checks a header count against the bytes left: an element of `count` items each taking at
  /// least `min_bytes` must fit (before anything is allocated for it).
  void checkFits(const PlyElement& el, std::size_t min_bytes, std::size_t remaining, bool last) {
    if (min_bytes == 0) return;
    const std::uint64_t slack = last ? 1 : 0;  // an ASCII body may lack its final line end
    if (el.count > (remaining + slack) / min_bytes)
      fail(path_, "element '" + el.name + "' count " + std::to_string(el.count) +
                      (format_ == PlyFormat::Ascii ? " is too large for the file size"
                                                   : " needs more data than the file holds") +
                      " (truncated file or bad header; " + std::to_string(remaining) +
                      " bytes left)");
  }

  void storeFace(std::uint64_t item, const std::vector<std::uint32_t>& poly) {
    if (poly.size() < 3)
      fail(path_, "face " + std::to_string(item) + " has " + std::to_string(poly.size()) +
                      " vertices (need at least 3)");
    if (mesh_.triangles.size() + poly.size() - 2 > kMaxCount) fail(path_, "too many triangles");
    for (std::uint32_t v : poly)
      if (!have_max_ || v > max_index_) {
        have_max_ = true;
        max_index_ = v;
        max_index_face_ = item;
      }
    fan(mesh_.triangles, poly.data(), poly.size());
  }

  // ---- binary body ----
  void readElement(const PlyElement& el, BinaryCursor& cur) {
    const Roles roles = rolesOf(el);
    std::size_t fixed = 0;
    bool has_list = false;
    for (const auto& p : el.props) {
      fixed += p.is_list ? plySize(p.count_type) : plySize(p.type);
      has_list = has_list || p.is_list;
    }
    checkFits(el, fixed, cur.remaining(), false);
    if (!roles.vertex && !roles.face && !has_list) {
      cur.skip(static_cast<std::size_t>(el.count) * fixed);  // fits: checked above
      return;
    }
    if (roles.vertex) mesh_.vertices.resize(static_cast<std::size_t>(el.count));
    if (roles.face) {
      const auto& ip = el.props[static_cast<std::size_t>(roles.indices)];
      const std::size_t per_tri = plySize(ip.count_type) + 3 * plySize(ip.type);
      mesh_.triangles.reserve(
          std::min<std::size_t>(static_cast<std::size_t>(el.count), cur.remaining() / per_tri + 1));
    }
    std::vector<std::uint32_t> poly;
    for (std::uint64_t item = 0; item < el.count; ++item) {
      for (std::size_t pi = 0; pi < el.props.size(); ++pi) {
        const PlyProperty& p = el.props[pi];
        double v = 0;
        if (!p.is_list) {
          if (!cur.read(p.type, v)) truncated(el, item, cur.offset());
          if (roles.vertex)
            for (int k = 0; k < 3; ++k)
              if (roles.xyz[k] == int(pi))
                mesh_.vertices[static_cast<std::size_t>(item)][k] = static_cast<S>(v);
          continue;
        }
        if (!cur.read(p.count_type, v)) truncated(el, item, cur.offset());
        if (v < 0)
          fail(path_,
               "element '" + el.name + "' item " + std::to_string(item) + ": negative list count");
        const auto n = static_cast<std::uint64_t>(v);
        if (roles.face && int(pi) == roles.indices) {
          if (n > cur.remaining() / plySize(p.type)) truncated(el, item, cur.offset());
          poly.clear();
          for (std::uint64_t k = 0; k < n; ++k) {
            double iv = 0;
            cur.read(p.type, iv);  // fits: checked above
            if (iv < 0)
              fail(path_, "face " + std::to_string(item) + " has negative vertex index " +
                              std::to_string(static_cast<long long>(iv)));
            if (iv > double(kMaxCount))
              fail(path_, "face " + std::to_string(item) + " has vertex index out of range");
            poly.push_back(static_cast<std::uint32_t>(iv));
          }
          storeFace(item, poly);
        } else {
          if (n > cur.remaining() / plySize(p.type) ||
              !cur.skip(static_cast<std::size_t>(n) * plySize(p.type)))
            truncated(el, item, cur.offset());
        }
      }
    }
  }

  [[noreturn]] void truncated(const PlyElement& el, std::uint64_t item, std::size_t offset) {
    fail(path_, "truncated binary PLY data in element '" + el.name + "' item " +
                    std::to_string(item) + " (body byte offset " + std::to_string(offset) + ")");
  }

  // ---- ASCII body ----
  double asciiValue(AsciiCursor& cur, PlyType t, const PlyElement& el, std::uint64_t item) {
    std::string_view tok;
    if (!cur.token(tok))
      fail(path_, "truncated ASCII PLY data in element '" + el.name + "' item " +
                      std::to_string(item) + " (line " + std::to_string(cur.line()) + ")");
    double v;
    if (plyIsInteger(t)) {
      long long iv;
      if (!parseInt(tok, iv)) {
        // Some writers print integers as "3.0": accept integral values.
        if (!parseDouble(tok, v) || !std::isfinite(v) || v != std::floor(v) ||
            std::fabs(v) > 9.0e15)
          fail(path_, "bad integer " + quoteTok(tok) + " in element '" + el.name + "' item " +
                          std::to_string(item) + " (line " + std::to_string(cur.line()) + ")");
        return v;
      }
      if (iv > (1LL << 53) || iv < -(1LL << 53))
        fail(path_, "integer " + quoteTok(tok) + " out of range (line " +
                        std::to_string(cur.line()) + ")");
      return static_cast<double>(iv);
    }
    if (!parseDouble(tok, v))
      fail(path_, "bad number " + quoteTok(tok) + " in element '" + el.name + "' item " +
                      std::to_string(item) + " (line " + std::to_string(cur.line()) + ")");
    return v;
  }

  void readElement(const PlyElement& el, AsciiCursor& cur) {
    const Roles roles = rolesOf(el);
    // Every value takes at least one character and one separator.
    checkFits(el, 2 * el.props.size(), cur.remaining(), true);
    if (el.props.empty()) return;  // no values to read, whatever the count (not a loop over it)
    if (roles.vertex) mesh_.vertices.resize(static_cast<std::size_t>(el.count));
    if (roles.face)
      mesh_.triangles.reserve(
          std::min<std::size_t>(static_cast<std::size_t>(el.count), cur.remaining() / 8 + 1));
    std::vector<std::uint32_t> poly;
    for (std::uint64_t item = 0; item < el.count; ++item) {
      for (std::size_t pi = 0; pi < el.props.size(); ++pi) {
        const PlyProperty& p = el.props[pi];
        if (!p.is_list) {
          const std::size_t line = cur.line();
          const double v = asciiValue(cur, p.type, el, item);
          if (roles.vertex)
            for (int k = 0; k < 3; ++k)
              if (roles.xyz[k] == int(pi)) {
                const S s = static_cast<S>(v);
                if (!std::isfinite(v) || !std::isfinite(s))
                  fail(path_, "vertex " + std::to_string(item) +
                                  " has a non-finite coordinate (line " + std::to_string(line) +
                                  ")");
                mesh_.vertices[static_cast<std::size_t>(item)][k] = s;
              }
          continue;
        }
        const double cnt = asciiValue(cur, p.count_type, el, item);
        if (cnt < 0)
          fail(path_, "element '" + el.name + "' item " + std::to_string(item) +
                          ": negative list count (line " + std::to_string(cur.line()) + ")");
        const auto n = static_cast<std::uint64_t>(cnt);
        if (n > cur.remaining() / 2 + 1)
          fail(path_, "truncated ASCII PLY data: list of " + std::to_string(n) +
                          " values in element '" + el.name + "' item " + std::to_string(item) +
                          " (line " + std::to_string(cur.line()) + ")");
        const bool is_idx = roles.face && int(pi) == roles.indices;
        if (is_idx) poly.clear();
        for (std::uint64_t k = 0; k < n; ++k) {
          const double v = asciiValue(cur, p.type, el, item);
          if (!is_idx) continue;
          if (v < 0)
            fail(path_, "face " + std::to_string(item) + " has negative vertex index (line " +
                            std::to_string(cur.line()) + ")");
          if (v > double(kMaxCount))
            fail(path_, "face " + std::to_string(item) + " has vertex index out of range");
          poly.push_back(static_cast<std::uint32_t>(v));
        }
        if (is_idx) storeFace(item, poly);
      }
    }
  }

  const std::string& path_;
  const std::string& data_;
  PlyFormat format_ = PlyFormat::Ascii;
  std::vector<PlyElement> elements_;
  std::size_t header_lines_ = 0;
  TriangleMesh<S> mesh_;
  bool has_faces_ = false;
  bool have_max_ = false;
  std::uint64_t max_index_ = 0;       ///< largest vertex index over all faces
  std::uint64_t max_index_face_ = 0;  ///< the first face that holds it
};

// ---------------------------------------------------------------------------------------------
// STL. A soup: three new vertices per facet.

template <class S>
TriangleMesh<S> readBinaryStl(const std::string& path, const std::string& data) {
  if (data.size() < 84)
    fail(path, "truncated binary STL header (" + std::to_string(data.size()) + " bytes, need 84)");
  std::uint32_t count;
  std::memcpy(&count, data.data() + 80, 4);
  if (!hostIsLittleEndian()) {
    unsigned char b[4];
    std::memcpy(b, &count, 4);
    std::reverse(b, b + 4);
    std::memcpy(&count, b, 4);
  }
  const std::uint64_t expected = 84 + 50ull * count;
  if (expected != data.size())
    fail(path, "binary STL triangle count " + std::to_string(count) +
                   " disagrees with the file size (" + std::to_string(data.size()) +
                   " bytes, expected " + std::to_string(expected) + ")");
  if (3ull * count > kMaxCount) fail(path, "too many STL triangles");
  TriangleMesh<S> mesh;
  mesh.vertices.resize(3ull * count);
  mesh.triangles.resize(count);
  const bool swap = !hostIsLittleEndian();
  const char* p = data.data() + 84;
  for (std::uint32_t t = 0; t < count; ++t, p += 50) {
    for (int v = 0; v < 3; ++v) {
      for (int k = 0; k < 3; ++k) {
        unsigned char b[4];
        std::memcpy(b, p + 12 + 12 * v + 4 * k, 4);
        if (swap) std::reverse(b, b + 4);
        float f;
        std::memcpy(&f, b, 4);
        mesh.vertices[3ull * t + v][k] = static_cast<S>(f);
      }
    }
    mesh.triangles[t] = {3 * t, 3 * t + 1, 3 * t + 2};
  }
  return mesh;
}

template <class S>
TriangleMesh<S> readAsciiStl(const std::string& path, const std::string& data) {
  checkNoNul(path, data);
  AsciiCursor cur(data.data(), data.data() + data.size(), 1);
  TriangleMesh<S> mesh;
  std::string_view tok;
  std::vector<Vec3<S>> poly;
  std::vector<std::uint32_t> idx;
  const auto where = [&]() { return " (line " + std::to_string(cur.line()) + ")"; };
  const auto expect = [&](std::string_view word) {
    if (!cur.token(tok))
      fail(path,
           "truncated ASCII STL: expected '" + std::string(word) + "' at end of file" + where());
    if (tok != word)
      fail(path,
           "bad ASCII STL: expected '" + std::string(word) + "', found " + quoteTok(tok) + where());
  };
  const auto skipRestOfLine = [&]() {
    // The solid name runs to the end of its line.
    const std::size_t line = cur.line();
    AsciiCursor save = cur;
    while (cur.token(tok)) {
      if (cur.line() != line) {
        cur = save;
        return;
      }
      save = cur;
    }
  };
  std::size_t solids = 0;
  for (;;) {
    if (!cur.token(tok)) break;
    if (tok != "solid")
      fail(path, "bad ASCII STL: expected 'solid', found " + quoteTok(tok) + where());
    ++solids;
    skipRestOfLine();
    for (;;) {
      if (!cur.token(tok)) fail(path, "truncated ASCII STL: missing 'endsolid'" + where());
      if (tok == "endsolid") {
        skipRestOfLine();
        break;
      }
      if (tok != "facet")
        fail(path,
             "bad ASCII STL: expected 'facet' or 'endsolid', found " + quoteTok(tok) + where());
      const std::size_t facet = mesh.triangles.size();
      expect("normal");
      for (int k = 0; k < 3; ++k) {
        double v;
        if (!cur.token(tok)) fail(path, "truncated ASCII STL in a facet normal" + where());
        if (!parseDouble(tok, v))
          fail(path, "bad facet normal component " + quoteTok(tok) + where());
      }
      expect("outer");
      expect("loop");
      poly.clear();
      for (;;) {
        if (!cur.token(tok))
          fail(path, "truncated ASCII STL inside facet " + std::to_string(facet) + where());
        if (tok == "endloop") break;
        if (tok != "vertex")
          fail(path,
               "bad ASCII STL: expected 'vertex' or 'endloop', found " + quoteTok(tok) + where());
        Vec3<S> p;
        for (int k = 0; k < 3; ++k) {
          double v;
          if (!cur.token(tok)) fail(path, "truncated ASCII STL in a vertex" + where());
          if (!parseDouble(tok, v)) fail(path, "bad vertex coordinate " + quoteTok(tok) + where());
          p[k] = toCoord<S>(path, v, tok, "line " + std::to_string(cur.line()));
        }
        poly.push_back(p);
      }
      if (poly.size() < 3)
        fail(path, "facet " + std::to_string(facet) + " has " + std::to_string(poly.size()) +
                       " vertices (need at least 3)" + where());
      expect("endfacet");
      if (mesh.vertices.size() + poly.size() > kMaxCount) fail(path, "too many STL vertices");
      const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
      idx.clear();
      for (std::size_t k = 0; k < poly.size(); ++k) {
        mesh.vertices.push_back(poly[k]);
        idx.push_back(base + static_cast<std::uint32_t>(k));
      }
      fan(mesh.triangles, idx.data(), idx.size());
    }
  }
  if (solids == 0) fail(path, "bad ASCII STL: no 'solid'");
  return mesh;
}

template <class S>
TriangleMesh<S> readStl(const std::string& path, const std::string& data) {
  // Binary when the size matches the count at offset 80 (some binary files start with "solid"
  // too); ASCII when the text starts with "solid"; else binary, whose size check then reports.
  if (data.size() >= 84) {
    std::uint32_t count;
    std::memcpy(&count, data.data() + 80, 4);
    if (!hostIsLittleEndian()) {
      unsigned char b[4];
      std::memcpy(b, &count, 4);
      std::reverse(b, b + 4);
      std::memcpy(&count, b, 4);
    }
    if (84 + 50ull * count == data.size()) return readBinaryStl<S>(path, data);
  }
  std::size_t i = 0;
  while (i < data.size() && (isBlank(data[i]) || data[i] == '\n' || data[i] == '\r')) ++i;
  if (data.compare(i, 5, "solid") == 0 &&
      (i + 5 == data.size() || std::isspace(static_cast<unsigned char>(data[i + 5]))))
    return readAsciiStl<S>(path, data);
  return readBinaryStl<S>(path, data);
}

// ---------------------------------------------------------------------------------------------
// Writers.

template <class S>
void appendNumber(std::string& out, S v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest text that round-trips
  out.append(buf, r.ptr);
}

void appendUint(std::string& out, std::uint64_t v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

/// "x y z\n" with the shortest round-trip text of each coordinate.
template <class S>
void appendPoint(std::string& out, const Vec3<S>& v) {
  appendNumber(out, v.x);
  out += ' ';
  appendNumber(out, v.y);
  out += ' ';
  appendNumber(out, v.z);
  out += '\n';
}

/// "a b c\n" for a triangle's indices plus `base` (1 for OBJ, 0 for OFF).
void appendTriangle(std::string& out, const Triangle& t, std::uint64_t base) {
  appendUint(out, t[0] + base);
  out += ' ';
  appendUint(out, t[1] + base);
  out += ' ';
  appendUint(out, t[2] + base);
  out += '\n';
}

class FileWriter {
 public:
  explicit FileWriter(const std::string& path)
      : path_(path), out_(path, std::ios::binary | std::ios::trunc) {
    if (!out_) fail(path, std::string("cannot open for writing: ") + std::strerror(errno));
  }
  std::string& buffer() { return buf_; }
  void flushIfLarge() {
    if (buf_.size() >= (1u << 20)) flush();
  }
  void flush() {
    out_.write(buf_.data(), static_cast<std::streamsize>(buf_.size()));
    buf_.clear();
    if (!out_) fail(path_, "write failed");
  }
  void close() {
    flush();
    out_.close();
    if (!out_) fail(path_, "write failed on close");
  }

 private:
  const std::string& path_;
  std::ofstream out_;
  std::string buf_;
};

void appendRaw(std::string& out, const void* p, std::size_t n, bool swap) {
  unsigned char b[8];
  std::memcpy(b, p, n);
  if (swap) std::reverse(b, b + n);
  out.append(reinterpret_cast<const char*>(b), n);
}

template <class S>
void writeObj(const TriangleMesh<S>& mesh, FileWriter& w) {
  std::string& b = w.buffer();
  b += "# written by kdet_fcl\n";
  for (const auto& v : mesh.vertices) {
    b += "v ";
    appendPoint(b, v);
    w.flushIfLarge();
  }
  for (const auto& t : mesh.triangles) {
    b += "f ";
    appendTriangle(b, t, 1);
    w.flushIfLarge();
  }
}

template <class S>
void writeOff(const TriangleMesh<S>& mesh, FileWriter& w) {
  std::string& b = w.buffer();
  b += "OFF\n";
  appendUint(b, mesh.vertices.size());
  b += ' ';
  appendUint(b, mesh.triangles.size());
  b += " 0\n";
  for (const auto& v : mesh.vertices) {
    appendPoint(b, v);
    w.flushIfLarge();
  }
  for (const auto& t : mesh.triangles) {
    b += "3 ";
    appendTriangle(b, t, 0);
    w.flushIfLarge();
  }
}

template <class S>
void writePly(const TriangleMesh<S>& mesh, FileWriter& w) {
  const bool swap = !hostIsLittleEndian();
  const char* type = std::is_same<S, float>::value ? "float" : "double";
  const bool signed_idx = mesh.vertices.size() <= 0x7FFFFFFFu;
  std::string& b = w.buffer();
  b += "ply\nformat binary_little_endian 1.0\ncomment written by kdet_fcl\nelement vertex ";
  appendUint(b, mesh.vertices.size());
  b += std::string("\nproperty ") + type + " x\nproperty " + type + " y\nproperty " + type + " z\n";
  b += "element face ";
  appendUint(b, mesh.triangles.size());
  b += std::string("\nproperty list uchar ") + (signed_idx ? "int" : "uint") +
       " vertex_indices\nend_header\n";
  for (const auto& v : mesh.vertices) {
    for (int k = 0; k < 3; ++k) {
      const S s = v[k];
      appendRaw(b, &s, sizeof s, swap);
    }
    w.flushIfLarge();
  }
  for (const auto& t : mesh.triangles) {
    b += '\3';
    for (int k = 0; k < 3; ++k) appendRaw(b, &t[k], 4, swap);
    w.flushIfLarge();
  }
}

// Binary STL stores 32-bit floats: a double coordinate beyond float's range would be written as
// an infinity that no reader accepts back. Checked before the file is opened, so a refused mesh
// leaves no partial file behind.
template <class S>
void checkStlWritable(const TriangleMesh<S>& mesh, const std::string& path) {
  if (mesh.triangles.size() > 0xFFFFFFFFu) fail(path, "too many triangles for binary STL");
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = mesh.triangles[t][c];
      for (int k = 0; k < 3; ++k) {
        if (std::isfinite(static_cast<float>(mesh.vertices[v][k]))) continue;
        std::string num;
        appendNumber(num, mesh.vertices[v][k]);
        fail(path, "vertex " + std::to_string(v) + " (of triangle " + std::to_string(t) +
                       ") has coordinate " + num +
                       ", beyond the range of the 32-bit floats binary STL stores; write .obj, "
                       ".off or .ply to keep it");
      }
    }
}

template <class S>
void writeStl(const TriangleMesh<S>& mesh, FileWriter& w) {  // after checkStlWritable
  const bool swap = !hostIsLittleEndian();
  std::string& b = w.buffer();
  std::string header = "binary STL written by kdet_fcl";
  header.resize(80, ' ');
  b += header;
  const auto count = static_cast<std::uint32_t>(mesh.triangles.size());
  appendRaw(b, &count, 4, swap);
  for (const auto& t : mesh.triangles) {
    const Vec3<S>& a = mesh.vertices[t[0]];
    const Vec3<S>& c1 = mesh.vertices[t[1]];
    const Vec3<S>& c2 = mesh.vertices[t[2]];
    const Vec3<double> e1{double(c1.x) - a.x, double(c1.y) - a.y, double(c1.z) - a.z};
    const Vec3<double> e2{double(c2.x) - a.x, double(c2.y) - a.y, double(c2.z) - a.z};
    Vec3<double> n = cross(e1, e2);
    const double len = std::sqrt(squaredNorm(n));
    n = (len > 0 && std::isfinite(len)) ? n * (1.0 / len) : Vec3<double>{0, 0, 0};
    for (int k = 0; k < 3; ++k) {
      const float f = static_cast<float>(n[k]);
      appendRaw(b, &f, 4, swap);
    }
    for (const Vec3<S>* p : {&a, &c1, &c2})
      for (int k = 0; k < 3; ++k) {
        const float f = static_cast<float>((*p)[k]);
        appendRaw(b, &f, 4, swap);
      }
    b += std::string(2, '\0');
    w.flushIfLarge();
  }
}

}  // namespace

template <class S>
TriangleMesh<S> readMesh(const std::string& path) {
  try {
    const std::string ext = lowerExtension(path);
    if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
      fail(path, "unknown mesh file extension " +
                     (ext.empty() ? std::string("(none)") : quoteTok(ext)) +
                     " (expected .obj, .off, .ply or .stl)");
    const std::string data = readWholeFile(path);
    TriangleMesh<S> mesh;
    if (ext == ".obj")
      mesh = readObj<S>(path, data);
    else if (ext == ".off")
      mesh = readOff<S>(path, data);
    else if (ext == ".ply")
      mesh = PlyReader<S>(path, data).read();
    else
      mesh = readStl<S>(path, data);
    try {
      mesh.validate(false, path);
    } catch (const InvalidInputError& e) {
      const std::string msg = e.what();
      throw MeshFileError(msg.find(path) == std::string::npos ? path + ": " + msg : msg);
    }
    return mesh;
  } catch (const MeshFileError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw MeshFileError(path + ": out of memory while reading the mesh");
  } catch (const std::length_error&) {
    throw MeshFileError(path + ": out of memory while reading the mesh (length error)");
  } catch (const std::exception& e) {
    throw MeshFileError(path + ": " + e.what());
  }
}

template <class S>
void writeMesh(const TriangleMesh<S>& mesh, const std::string& path) {
  const std::string ext = lowerExtension(path);
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    fail(path, "unknown mesh file extension " +
                   (ext.empty() ? std::string("(none)") : quoteTok(ext)) +
                   " (expected .obj, .off, .ply or .stl)");
  // An invalid mesh is the caller's error (InvalidInputError), not the file's.
  mesh.validate(false, path);
  if (ext == ".stl") checkStlWritable(mesh, path);
  try {
    FileWriter w(path);
    if (ext == ".obj")
      writeObj(mesh, w);
    else if (ext == ".off")
      writeOff(mesh, w);
    else if (ext == ".ply")
      writePly(mesh, w);
    else
      writeStl(mesh, w);
    w.close();
  } catch (const MeshFileError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw MeshFileError(path + ": out of memory while writing the mesh");
  } catch (const std::exception& e) {
    throw MeshFileError(path + ": " + e.what());
  }
}

template TriangleMesh<float> readMesh<float>(const std::string&);
template TriangleMesh<double> readMesh<double>(const std::string&);
template void writeMesh<float>(const TriangleMesh<float>&, const std::string&);
template void writeMesh<double>(const TriangleMesh<double>&, const std::string&);

}  // namespace kdet_fcl
