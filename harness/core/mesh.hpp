#pragma once
/// The triangle mesh every method is built on. It is read by the one mesh reader
/// (io/mesh_reader.hpp; loaded whole by io/mesh_io.hpp): PLY (ASCII, binary little and big
/// endian; `face` lists and `tristrips`), OBJ, STL (binary and ASCII, corners welded exactly) and
/// OFF; polygons fan-triangulated (docs/meshes.md says what each format accepts and refuses).
/// Coordinates are kept in double as read; methods convert to what they use.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "harness/core/geometry.hpp"

namespace bvhbench {

/// What the reader saw in the input, beyond the vertices and triangles.
struct MeshFileInfo {
  std::string format;   ///< "ply", "obj", "stl", "off" ("" for a mesh made in code)
  /// PLY: "ascii", "binary_little_endian", "binary_big_endian"; STL: "binary", "ascii";
  /// OFF: the keyword as written ("OFF", "COFF", "NOFF", "STCNOFF", ...); OBJ: "".
  std::string variant;
  std::uint64_t polygons = 0;               ///< faces in the input (PLY faces, OBJ `f`, OFF faces, STL facets)
  std::uint64_t polygons_triangulated = 0;  ///< of them, faces of more than 3 vertices (fan-triangulated)
  std::uint64_t strips = 0;                 ///< PLY `tristrips`: strips (non-empty runs between -1 restarts)
  std::uint64_t strip_joins_dropped = 0;    ///< strip triangles with a repeated vertex index: joins, dropped
  std::uint64_t corners = 0;                ///< STL: facet corners (3 per facet) before welding
  std::uint64_t solids = 0;                 ///< ASCII STL: `solid ... endsolid` blocks (all read as one mesh)
};

using Triangle = std::array<std::uint32_t, 3>;

/// What a job records about its mesh, without the geometry: made from a loaded Mesh
/// (Mesh::summary) or by one streamed pass over the file (mesh_io.hpp: summarize_mesh), so that
/// a method that reads its structure from a file (a store) and a query kind that needs only the
/// box run without the mesh in memory (a 128M-triangle model is 3 GB of it).
struct MeshSummary {
  std::string path;    ///< file it was read from
  std::string sha256;  ///< hex sha256 of the file's bytes
  std::uint64_t triangles = 0, vertices = 0;
  Box3d bounds;  ///< box of the vertices referenced or not (Mesh::bounds)
};

struct Mesh {
  std::string path;                                ///< file it was read from ("" if made in code)
  std::string sha256;                              ///< hex sha256 of the file's bytes
  std::vector<Vec3d> vertices;                     ///< #V positions, as read
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< #F vertex indices, polygons fan-triangulated
  MeshFileInfo file;                               ///< format, faces before triangulation, strips, ...

  std::size_t num_triangles() const { return triangles.size(); }
  Vec3d vertex(std::uint32_t tri, int corner) const { return vertices[triangles[tri][corner]]; }
  Box3d bounds() const;                            ///< box of the vertices referenced or not
  MeshSummary summary() const;
  double average_edge_length() const;              ///< mean over the 3 edges of every triangle
  std::size_t bytes() const {
    return vertices.size() * sizeof(Vec3d) + triangles.size() * sizeof(triangles[0]);
  }
};

}  // namespace bvhbench
