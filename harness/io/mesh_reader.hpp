#pragma once
/// The one streamed mesh reader: PLY (ASCII, binary little and big endian; `face` lists and
/// `tristrips`), OBJ, STL (binary and ASCII, vertices welded exactly) and OFF, from a file or from
/// bytes in memory. `load_mesh` (mesh_io.hpp) and the EBP-Octree's external-memory build both read
/// through it; docs/meshes.md says what each format accepts and refuses, and why.
///
/// A reader delivers the vertex positions (all of them, in order), then the triangles (in
/// order), in chunks, and hashes the input's bytes (SHA-256) on the way. The triangles can be
/// read again, any number of times, for a consumer that scans them several times: each pass
/// re-reads the faces from the input (nothing of them is kept in between), and delivers the
/// same triangles in the same chunks.
///
/// Every problem of the input is an InputError "NAME: problem" (exit 2), with the same words
/// in every format: file not found, unknown mesh format, truncated, counts that do not match the
/// data, a vertex index out of range, a NaN or infinite coordinate, a face with fewer than 3
/// vertices, no triangles. Every count read from the input is checked against the bytes left
/// before anything is reserved, so a lying header cannot make the reader allocate or loop long.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "harness/core/geometry.hpp"
#include "harness/core/mesh.hpp"

namespace bvhbench {

class Progress;
class ByteSource;
class FormatParser;


class MeshReader {
 public:
  /// f(first, v, n): vertices first .. first + n - 1 (positions as read, double).
  using VertexChunk = std::function<void(std::uint64_t first, const Vec3d* v, std::size_t n)>;
  /// f(first, t, n): triangles first .. first + n - 1 (vertex indices < num_vertices()).
  using TriangleChunk = std::function<void(std::uint64_t first, const Triangle* t, std::size_t n)>;

  /// Opens the file at `path` and reads its header; the format is chosen by the extension (.ply .obj .stl .off, any
  /// case), sniffed from the content otherwise. `progress` is advanced over the file's bytes.
  static std::unique_ptr<MeshReader> open(const std::string& path, Progress* progress = nullptr);
  /// Reads `data` (not copied: it must outlive the reader) by the same code. `name` names it in
  /// messages; `format` is "ply", "obj", "stl", "off", a file name or extension to take it
  /// from ("m.STL", ".off"), or "" to sniff the content.
  static std::unique_ptr<MeshReader> open_bytes(std::string_view data, const std::string& name,
                                                const std::string& format = "");
  ~MeshReader();
  MeshReader(const MeshReader&) = delete;
  MeshReader& operator=(const MeshReader&) = delete;

  /// Delivers every vertex, in order, in chunks. Call it once, first.
  void read_vertices(const VertexChunk& f);
  /// Delivers every triangle, in order, in chunks (after read_vertices; any number of times,
  /// the same triangles each time). The first pass reads the input to its end, checks it holds
  /// nothing more, and completes the hash.
  void read_triangles(const TriangleChunk& f);

  /// Vertices: exact after read_vertices; before it, a count for reserving memory (what the
  /// header declares, checked against the input's size; 0 if unknown).
  std::uint64_t num_vertices() const;
  /// Triangles: exact after the first read_triangles; before it, a count for reserving memory
  /// (the faces the header declares, checked against the input's size; 0 if unknown).
  std::uint64_t num_triangles() const;
  const MeshFileInfo& info() const;
  /// Hex SHA-256 of the input's bytes (after the first read_triangles).
  const std::string& sha256() const { return sha256_; }
  /// The input's name (its path, or the name given with the bytes).
  const std::string& name() const;
  /// Bytes the reader holds between passes (its read buffer; STL: the weld table).
  std::size_t resident_bytes() const;

 private:
  MeshReader(std::unique_ptr<ByteSource> src, std::string format);
  std::unique_ptr<ByteSource> src_;
  std::unique_ptr<FormatParser> parser_;
  std::uint64_t num_vertices_ = 0, num_triangles_ = 0;
  bool vertices_read_ = false, triangles_read_ = false;
  std::string sha256_;
};

}  // namespace bvhbench
