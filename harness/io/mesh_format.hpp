#pragma once
/// Inside the mesh reader (mesh_reader.hpp): the interface each format's parser implements
/// (mesh_ply.cpp, mesh_obj.cpp, mesh_stl.cpp, mesh_off.cpp), the chunked outputs they fill, and
/// the words their messages share, so that a kind of problem reads the same in every format.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "harness/io/mesh_reader.hpp"
#include "harness/util/byte_source.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {

/// Items gathered into chunks of at most kChunk for a chunk callback f(first, items, n). The
/// buffer grows with use (a small input allocates little); once grown it is reused.
template <class T, class Callback>
class ChunkOut {
 public:
  static constexpr std::size_t kChunk = std::size_t(1) << 16;
  explicit ChunkOut(const Callback& f) : f_(f) {}
  void add(const T& x) {
    if (n_ == buf_.size()) grow(n_ + 1);
    buf_[n_++] = x;
    if (n_ == kChunk) flush();
  }
  /// Room left in this chunk (>= 1).
  std::size_t room() const { return kChunk - n_; }
  /// Where to write n <= room() items directly, then commit(n).
  T* tail(std::size_t n) {
    if (n_ + n > buf_.size()) grow(n_ + n);
    return buf_.data() + n_;
  }
  void commit(std::size_t n) {
    n_ += n;
    if (n_ == kChunk) flush();
  }
  void flush() {
    if (n_ == 0) return;
    f_(first_, buf_.data(), n_);
    first_ += n_;
    n_ = 0;
  }
  /// Items added so far.
  std::uint64_t count() const { return first_ + n_; }

 private:
  void grow(std::size_t need) { buf_.resize(std::min(kChunk, std::max({need, 2 * buf_.size(), std::size_t(256)}))); }
  const Callback& f_;
  std::vector<T> buf_;
  std::size_t n_ = 0;
  std::uint64_t first_ = 0;
};

using VertexOut = ChunkOut<Vec3d, MeshReader::VertexChunk>;

/// Triangles gathered into chunks, with the fan triangulation of polygons.
class TriangleOut : public ChunkOut<Triangle, MeshReader::TriangleChunk> {
 public:
  using ChunkOut::ChunkOut;
  using ChunkOut::add;
  void add(std::uint32_t a, std::uint32_t b, std::uint32_t c) { add(Triangle{a, b, c}); }
  /// Fan-triangulates polygon v[0..n) (n >= 3): (v0, v1, v2), (v0, v2, v3), ...
  void add_fan(const std::uint32_t* v, std::size_t n) {
    for (std::size_t j = 1; j + 1 < n; ++j) add(v[0], v[j], v[j + 1]);
  }
};

/// One format's parser over a ByteSource. The reader calls read_header() when it opens the
/// input, read_vertices() once, then read_triangles() once per pass; between passes the parser
/// keeps only what it needs to find the faces again (their offsets; STL: the weld table), never
/// the faces themselves.
class FormatParser {
 public:
  virtual ~FormatParser() = default;
  /// Reads the header (if the format has one) and checks its counts against the input's size.
  /// Sets info.format and info.variant.
  virtual void read_header() = 0;
  /// Delivers every vertex in order.
  virtual void read_vertices(VertexOut& out) = 0;
  /// Delivers every triangle in order. `first`: the first pass, which also reads the input to
  /// its end and rejects what follows the last face when the format says nothing may. Counts
  /// info.polygons, polygons_triangulated, strips and strip_joins_dropped (the same every pass).
  virtual void read_triangles(TriangleOut& out, bool first) = 0;
  /// Vertices and triangles to reserve before the first pass, from the header (bounded by the
  /// input's size; 0: unknown).
  virtual std::uint64_t vertex_hint() const { return 0; }
  virtual std::uint64_t triangle_hint() const { return 0; }
  /// Bytes held between passes besides the ByteSource's buffer.
  virtual std::size_t resident_bytes() const { return 0; }
  /// Why a complete first pass delivered no triangle (ends "no triangles (...)").
  virtual std::string why_no_triangles() const { return "the file has no faces"; }

  MeshFileInfo info;

 protected:
  explicit FormatParser(ByteSource& src) : src_(src) {}
  InputError error(const std::string& problem) const { return file_error(src_.name(), problem); }
  ByteSource& src_;
};

std::unique_ptr<FormatParser> make_ply_parser(ByteSource& src);
std::unique_ptr<FormatParser> make_obj_parser(ByteSource& src);
std::unique_ptr<FormatParser> make_stl_parser(ByteSource& src);
std::unique_ptr<FormatParser> make_off_parser(ByteSource& src);

/// True if the input's size is that of a binary STL whose header declares its facet count:
/// 84 + 50 n bytes, n the uint32 at offset 80 (the only sure sign of a binary STL, since the
/// 80-byte header of many binary STLs starts with "solid" too).
bool stl_binary_size_matches(ByteSource& src);

/// True if the first line of `head` with something before its comment starts with an OFF
/// keyword ("OFF", "COFF", ..., also ModelNet's "OFF490 518 0").
bool looks_like_off(std::string_view head);

// ---- the words of the messages, shared by every format ----

inline bool finite3(double x, double y, double z) { return std::isfinite(x) && std::isfinite(y) && std::isfinite(z); }

/// "a NaN coordinate" or "an infinite coordinate" (for a point that is not finite3).
inline std::string coordinate_problem(double x, double y, double z) {
  for (double v : {x, y, z})
    if (std::isnan(v)) return "a NaN coordinate";
  return "an infinite coordinate";
}

/// "1 vertex", "3 vertices", "2 faces", "4 'edge' elements".
inline std::string count_of(std::uint64_t n, const std::string& what) {
  std::string s = std::to_string(n) + " ";
  if (what == "vertex") return s + (n == 1 ? "vertex" : "vertices");
  if (what == "face") return s + (n == 1 ? "face" : "faces");
  if (what == "facet") return s + (n == 1 ? "facet" : "facets");
  return s + "'" + what + "' element" + (n == 1 ? "" : "s");
}

/// "WHAT has N vertices (a face needs at least 3)", WHAT e.g. "face 7".
inline std::string too_few_vertices(const std::string& what, std::uint64_t n) {
  return what + " has " + count_of(n, "vertex") + " (a face needs at least 3)";
}

/// The largest vertex count the meshes support (indices are 32-bit).
constexpr std::uint64_t kMaxVertices = 0xFFFFFFFFull;

}  // namespace bvhbench
