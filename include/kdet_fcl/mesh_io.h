#pragma once
/// \file
/// Reading and writing triangle meshes: OBJ, OFF, PLY (ASCII, binary little- and big-endian,
/// float and double properties) and STL (ASCII and binary). Polygons with more than three
/// vertices are fan-triangulated; faces with fewer than three vertices are an error.

#include <string>

#include "kdet_fcl/triangle_mesh.h"

namespace kdet_fcl {

/// Reads a mesh, choosing the format from the extension (case-insensitive: .obj .off .ply .stl).
/// Throws MeshFileError naming the file and the problem (missing file, unknown extension, bad
/// header, truncated data, bad indices, NaN/Inf coordinates, fewer than three vertices in a face).
template <class S>
TriangleMesh<S> readMesh(const std::string& path);

/// Writes a mesh; format from the extension (.obj, .off, .ply = binary little-endian, .stl =
/// binary, 32-bit floats). Throws MeshFileError if the file cannot be written, or, for STL, if
/// a coordinate of a written triangle is beyond float's range (nothing is written then); throws
/// InvalidInputError for an invalid mesh.
template <class S>
void writeMesh(const TriangleMesh<S>& mesh, const std::string& path);

}  // namespace kdet_fcl
