#pragma once
/// The triangle mesh every method is built on, read by the one mesh reader (mesh_reader.hpp):
/// PLY (ASCII, binary little and big endian; `face` lists and `tristrips`), OBJ, STL (binary and
/// ASCII, corners welded exactly) and OFF; polygons fan-triangulated (docs/meshes.md says what
/// each format accepts and refuses). Coordinates are kept in double as read; methods convert to
/// what they use.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "geometry.hpp"
#include "mesh_reader.hpp"

namespace bvhbench {

class Progress;

struct Mesh {
  std::string path;                                ///< file it was read from ("" if made in code)
  std::string sha256;                              ///< hex sha256 of the file's bytes
  std::vector<Vec3d> vertices;                     ///< #V positions, as read
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< #F vertex indices, polygons fan-triangulated
  MeshFileInfo file;                               ///< format, faces before triangulation, strips, ...

  std::size_t num_triangles() const { return triangles.size(); }
  Vec3d vertex(std::uint32_t tri, int corner) const { return vertices[triangles[tri][corner]]; }
  Box3d bounds() const;                            ///< box of the vertices referenced or not
  double average_edge_length() const;              ///< mean over the 3 edges of every triangle
  std::size_t bytes() const {
    return vertices.size() * sizeof(Vec3d) + triangles.size() * sizeof(triangles[0]);
  }
};

/// Reads a mesh file (format chosen by extension, case-insensitive; content sniffed if unknown).
/// Throws InputError naming the file and the problem for: a missing or unreadable file, an
/// unknown format, truncated data, element counts that do not match the data, a vertex index out
/// of range, a NaN or infinite coordinate, a face with fewer than 3 vertices, and an empty mesh
/// (no triangle). Degenerate and duplicate triangles are valid and kept.
/// `progress` (optional) is advanced over the file's bytes. The file is streamed, never mapped or
/// read whole: the peak memory is the mesh plus the reader's buffers (≈ 10 MiB; an STL's weld
/// table besides while it is read).
Mesh load_mesh(const std::string& path, Progress* progress = nullptr);

/// The same from bytes in memory (the same code; for fuzzing and tests): `name` names the input
/// in messages (and becomes Mesh::path), `format` is "ply", "obj", "stl", "off", a file name or
/// extension to take it from, or "" to sniff the content (an unknown format is an InputError).
Mesh load_mesh_bytes(std::string_view data, const std::string& name, const std::string& format = "");

/// Reads every vertex and triangle of `reader` into a Mesh (path = the reader's name).
Mesh read_mesh(MeshReader& reader);

/// Writes a binary little-endian PLY (float32 coordinates, int32 indices). For tests and tools.
void write_ply(const std::string& path, const Mesh& mesh, bool ascii = false);

}  // namespace bvhbench
