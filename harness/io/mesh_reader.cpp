// The mesh reader: picks the format (extension, else content), runs its parser's passes and
// checks what every format shares (vertex and triangle counts, an empty mesh, the hash).
#include "harness/io/mesh_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>

#include "harness/io/mesh_format.hpp"
#include "harness/util/byte_source.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"
#include "harness/util/text_scan.hpp"

namespace bvhbench {

namespace {

const char* const kKnownFormats = "expected a PLY, OBJ, STL or OFF file";

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// "ply" from "ply", ".PLY", "dir/m.ply"; "" when there is no extension.
std::string format_name(const std::string& format_or_path) {
  const std::size_t slash = format_or_path.find_last_of('/');
  const std::size_t dot = format_or_path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash))
    return slash == std::string::npos ? lower(format_or_path) : "";
  return lower(format_or_path.substr(dot + 1));
}

bool known(const std::string& f) { return f == "ply" || f == "obj" || f == "stl" || f == "off"; }

/// The format of an input whose name says nothing: PLY has a magic line; a binary STL has the
/// size its header declares, an ASCII STL starts with "solid"; OFF starts with its keyword
/// (after comments); OBJ is text starting with a known statement or a comment.
std::string sniff(ByteSource& src) {
  src.fill(std::size_t(std::min<std::uint64_t>(src.size(), 4096)));
  std::string_view head(src.p, src.avail());
  if (head.substr(0, 4) == "ply\n" || head.substr(0, 4) == "ply\r") return "ply";
  if (stl_binary_size_matches(src)) return "stl";
  head = std::string_view(src.p, src.avail());  // fill() may have moved the bytes
  std::string_view rest = head;
  const std::string_view kw = next_token(rest);
  if (kw == "solid") return "stl";
  if (looks_like_off(head)) return "off";
  const bool text = head.find('\0') == std::string_view::npos;
  if (text && (kw == "v" || kw == "vt" || kw == "vn" || kw == "f" || kw == "o" || kw == "g" || kw == "mtllib" ||
               kw == "usemtl" || kw == "s" || (!kw.empty() && kw[0] == '#')))
    return "obj";
  return "";
}

}  // namespace

MeshReader::MeshReader(std::unique_ptr<ByteSource> src, std::string format) : src_(std::move(src)) {
  if (src_->size() == 0) throw file_error(src_->name(), "the file is empty: no triangles");
  if (!known(format)) format = sniff(*src_);
  if (format.empty()) throw file_error(src_->name(), std::string("unknown mesh format (") + kKnownFormats + ")");
  if (format == "ply")
    parser_ = make_ply_parser(*src_);
  else if (format == "stl")
    parser_ = make_stl_parser(*src_);
  else if (format == "off")
    parser_ = make_off_parser(*src_);
  else
    parser_ = make_obj_parser(*src_);
  parser_->read_header();
}

MeshReader::~MeshReader() = default;

std::unique_ptr<MeshReader> MeshReader::open(const std::string& path, Progress* progress) {
  auto src = std::make_unique<ByteSource>(path, progress);
  return std::unique_ptr<MeshReader>(new MeshReader(std::move(src), format_name(path)));
}

std::unique_ptr<MeshReader> MeshReader::open_bytes(std::string_view data, const std::string& name,
                                                   const std::string& format) {
  const std::string f = format_name(format);
  if (!format.empty() && !known(f))
    throw file_error(name, "unknown mesh format " + quoted_excerpt(format) + " (" + kKnownFormats + ")");
  auto src = std::make_unique<ByteSource>(data, name);
  return std::unique_ptr<MeshReader>(new MeshReader(std::move(src), f));
}

void MeshReader::read_vertices(const VertexChunk& f) {
  if (vertices_read_) throw std::logic_error("MeshReader::read_vertices called twice");
  VertexOut out(f);
  parser_->read_vertices(out);
  out.flush();
  num_vertices_ = out.count();
  vertices_read_ = true;
}

void MeshReader::read_triangles(const TriangleChunk& f) {
  if (!vertices_read_) throw std::logic_error("MeshReader::read_triangles before read_vertices");
  TriangleOut out(f);
  parser_->read_triangles(out, !triangles_read_);
  out.flush();
  if (!triangles_read_) {
    if (out.count() == 0) throw file_error(src_->name(), "no triangles (" + parser_->why_no_triangles() + ")");
    num_triangles_ = out.count();
    sha256_ = src_->finish_hash();
    triangles_read_ = true;
  } else if (out.count() != num_triangles_) {
    throw file_error(src_->name(), "the file changed while it was being read (" + std::to_string(out.count()) +
                                       " triangles, " + std::to_string(num_triangles_) + " before)");
  }
}

std::uint64_t MeshReader::num_vertices() const { return vertices_read_ ? num_vertices_ : parser_->vertex_hint(); }

std::uint64_t MeshReader::num_triangles() const { return triangles_read_ ? num_triangles_ : parser_->triangle_hint(); }

const MeshFileInfo& MeshReader::info() const { return parser_->info; }

const std::string& MeshReader::name() const { return src_->name(); }

std::size_t MeshReader::resident_bytes() const { return src_->buffer_bytes() + parser_->resident_bytes(); }

}  // namespace bvhbench
