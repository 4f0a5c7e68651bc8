#pragma once
/// The triangle mesh every method is built on, and its readers (PLY ASCII / binary little and
/// big endian, OBJ). Coordinates are kept in double as read; methods convert to what they use.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry.hpp"

namespace bvhbench {

class Progress;

struct Mesh {
  std::string path;                                ///< file it was read from ("" if made in code)
  std::string sha256;                              ///< hex sha256 of the file's bytes
  std::vector<Vec3d> vertices;                     ///< #V positions, as read
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< #F vertex indices, polygons fan-triangulated
  std::size_t input_polygons = 0;                  ///< faces in the file before triangulation

  std::size_t num_triangles() const { return triangles.size(); }
  Vec3d vertex(std::uint32_t tri, int corner) const { return vertices[triangles[tri][corner]]; }
  Box3d bounds() const;                            ///< box of the vertices referenced or not
  double average_edge_length() const;              ///< mean over the 3 edges of every triangle
  std::size_t bytes() const {
    return vertices.size() * sizeof(Vec3d) + triangles.size() * sizeof(triangles[0]);
  }
};

/// Reads a PLY or OBJ file (chosen by extension, case-insensitive; content sniffed if unknown).
/// Throws InputError naming the file and the problem for: a missing or unreadable file, an
/// unknown format, truncated data, element counts that do not match the data, a vertex index out
/// of range, a NaN or infinite coordinate, a face with fewer than 3 vertices, and an empty mesh
/// (no triangle). Degenerate and duplicate triangles are valid and kept.
/// `progress` (optional) is advanced over the file's bytes.
Mesh load_mesh(const std::string& path, Progress* progress = nullptr);

/// Writes a binary little-endian PLY (float32 coordinates, int32 indices). For tests and tools.
void write_ply(const std::string& path, const Mesh& mesh, bool ascii = false);

}  // namespace bvhbench
