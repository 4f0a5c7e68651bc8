// Mesh readers (PLY ASCII / binary little and big endian, OBJ) and a PLY writer.
//
// Meshes reach 30M+ triangles (~600 MB of binary PLY), so the reader streams the file through one
// buffer (8 MB, grown only for a longer line or list): it never maps or copies the whole file,
// which would add the file's size to the job's peak RSS. Every byte is hashed as it is read, so
// the SHA-256 costs no second pass. Binary PLY in the common layout (scalar vertex properties,
// faces as a uchar count + int32 indices) is parsed in tight batches; any other layout goes
// through a generic per-item path that is slower but complete. Text is parsed with from_chars.
//
// Every count read from the file is checked against the bytes left in it before anything is
// reserved, so a lying header cannot make the reader allocate, loop or wait for long.
#include "mesh.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string_view>
#include <system_error>
#include <vector>

#include "errors.hpp"
#include "printable.hpp"
#include "progress.hpp"
#include "sha256.hpp"

namespace bvhbench {

Box3d Mesh::bounds() const {
  Box3d b;
  for (const Vec3d& v : vertices) b.add(v);
  return b;
}

double Mesh::average_edge_length() const {
  if (triangles.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& t : triangles) {
    const Vec3d& a = vertices[t[0]];
    const Vec3d& b = vertices[t[1]];
    const Vec3d& c = vertices[t[2]];
    sum += norm(b - a) + norm(c - b) + norm(a - c);
  }
  return sum / (3.0 * double(triangles.size()));
}

namespace {

constexpr std::size_t kChunk = std::size_t(8) << 20;
constexpr std::size_t kMaxLine = std::size_t(64) << 20;
constexpr bool kBigEndianHost = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;

// ---------------------------------------------------------------------------------------------
// The file, read through one buffer and hashed on the way.
// ---------------------------------------------------------------------------------------------
class Source {
 public:
  Source(const std::string& path, Progress* progress) : path_(path), progress_(progress) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
      const int err = errno;
      throw file_error(path, err == ENOENT ? "file not found"
                                           : std::string("cannot open: ") + std::strerror(err));
    }
    if (S_ISDIR(st.st_mode)) throw file_error(path, "is a directory, not a mesh file");
    if (!S_ISREG(st.st_mode)) throw file_error(path, "not a regular file");
    f_ = std::fopen(path.c_str(), "rb");
    if (!f_) throw file_error(path, std::string("cannot open: ") + std::strerror(errno));
    std::setvbuf(f_, nullptr, _IONBF, 0);
    size_ = std::uint64_t(st.st_size);
    buf_.resize(std::size_t(std::min<std::uint64_t>(kChunk, size_ + 1)));
    p = e = buf_.data();
  }
  ~Source() {
    if (f_) std::fclose(f_);
  }
  Source(const Source&) = delete;
  Source& operator=(const Source&) = delete;

  const std::string& path() const { return path_; }
  std::uint64_t size() const { return size_; }
  /// File offset of `p`.
  std::uint64_t offset() const { return read_ - std::uint64_t(e - p); }
  /// Bytes of the file after `p` (as stat saw it).
  std::uint64_t remaining() const { return size_ > offset() ? size_ - offset() : 0; }
  std::size_t avail() const { return std::size_t(e - p); }
  std::uint64_t line_no() const { return line_no_; }
  bool at_eof() { return !fill(1); }

  /// Makes at least `need` bytes available at `p`; false if the file ends first.
  bool fill(std::size_t need) {
    if (avail() >= need) return true;
    if (eof_) return false;
    const std::size_t have = avail();
    if (need > buf_.size()) {
      std::vector<char> bigger(std::max(need, 2 * buf_.size()));
      std::memcpy(bigger.data(), p, have);
      buf_.swap(bigger);
    } else if (p != buf_.data()) {
      std::memmove(buf_.data(), p, have);
    }
    p = buf_.data();
    e = p + have;
    while (!eof_ && avail() < need) {
      const std::size_t room = buf_.size() - avail();
      const std::size_t got = std::fread(const_cast<char*>(e), 1, room, f_);
      if (got < room) {
        if (std::ferror(f_)) throw file_error(path_, std::string("read error: ") + std::strerror(errno));
        eof_ = true;
      }
      sha_.update(e, got);
      read_ += got;
      e += got;
      if (progress_) progress_->update(double(read_));
    }
    return avail() >= need;
  }

  /// The next line without its terminator (nor a trailing '\r'); false at the end of the file.
  bool line(std::string_view& out) {
    std::size_t scanned = 0;
    for (;;) {
      const char* nl = static_cast<const char*>(std::memchr(p + scanned, '\n', avail() - scanned));
      if (nl) {
        out = std::string_view(p, std::size_t(nl - p));
        p = nl + 1;
        break;
      }
      scanned = avail();
      if (eof_ || !fill(avail() + 1)) {
        if (avail() == 0) return false;
        out = std::string_view(p, avail());
        p = e;
        break;
      }
      if (avail() > kMaxLine)
        throw file_error(path_, "line " + std::to_string(line_no_ + 1) +
                                    " is longer than 64 MB (binary data in a text file?)");
    }
    ++line_no_;
    if (!out.empty() && out.back() == '\r') out.remove_suffix(1);
    return true;
  }

  /// Reads (and hashes) whatever the parser did not consume; returns the file's hex SHA-256.
  std::string finish_hash() {
    while (!eof_) {
      p = e;
      fill(buf_.size());
    }
    p = e;
    return sha_.hex_digest();
  }

  const char* p = nullptr;  ///< next unread byte
  const char* e = nullptr;  ///< end of the bytes read so far

 private:
  std::string path_;
  Progress* progress_;
  std::FILE* f_ = nullptr;
  std::uint64_t size_ = 0, read_ = 0, line_no_ = 0;
  std::vector<char> buf_;
  bool eof_ = false;
  Sha256 sha_;
};

// ---------------------------------------------------------------------------------------------
// Text numbers.
// ---------------------------------------------------------------------------------------------
inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

/// Next whitespace-separated token of `s` (advanced past it); empty at the end.
inline std::string_view next_token(std::string_view& s) {
  std::size_t i = 0;
  while (i < s.size() && is_space(s[i])) ++i;
  std::size_t j = i;
  while (j < s.size() && !is_space(s[j])) ++j;
  std::string_view tok = s.substr(i, j - i);
  s.remove_prefix(j);
  return tok;
}

inline std::string_view strip(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

/// Parses all of `tok` as a double; false for anything else (empty, trailing junk, overflow).
inline bool parse_double(std::string_view tok, double& out) {
  const char* b = tok.data();
  const char* end = b + tok.size();
  if (b != end && *b == '+') ++b;
  if (b == end || *b == '+') return false;
  auto r = std::from_chars(b, end, out, std::chars_format::general);
  if (r.ptr != end) return false;
  if (r.ec == std::errc::result_out_of_range) {
    // Overflow reads as +-inf (then rejected as an infinite coordinate), underflow as 0 or a
    // subnormal, as strtod does; from_chars reports both as errors.
    const std::string copy(tok);
    out = std::strtod(copy.c_str(), nullptr);
    return true;
  }
  return r.ec == std::errc();
}

/// Parses all of `tok` as a (signed) integer.
inline bool parse_int(std::string_view tok, long long& out) {
  const char* b = tok.data();
  const char* end = b + tok.size();
  if (b != end && *b == '+') ++b;
  if (b == end || *b == '+') return false;
  auto r = std::from_chars(b, end, out);
  return r.ec == std::errc() && r.ptr == end;
}

std::string coordinate_problem(double x, double y, double z) {
  for (double v : {x, y, z})
    if (std::isnan(v)) return "a NaN coordinate";
  return "an infinite coordinate";
}

inline bool finite3(double x, double y, double z) {
  return std::isfinite(x) && std::isfinite(y) && std::isfinite(z);
}

/// "1 vertex", "3 vertices", "2 faces", "4 'edge' elements".
std::string count_of(std::uint64_t n, const std::string& what) {
  std::string s = std::to_string(n) + " ";
  if (what == "vertex") return s + (n == 1 ? "vertex" : "vertices");
  if (what == "face") return s + (n == 1 ? "face" : "faces");
  return s + "'" + what + "' element" + (n == 1 ? "" : "s");
}

// ---------------------------------------------------------------------------------------------
// PLY.
// ---------------------------------------------------------------------------------------------
enum class PlyType : std::uint8_t { i8, u8, i16, u16, i32, u32, i64, u64, f32, f64 };

bool ply_type(std::string_view s, PlyType& t) {
  static const struct { const char* name; PlyType type; } kTypes[] = {
      {"char", PlyType::i8},     {"int8", PlyType::i8},     {"uchar", PlyType::u8},
      {"uint8", PlyType::u8},    {"short", PlyType::i16},   {"int16", PlyType::i16},
      {"ushort", PlyType::u16},  {"uint16", PlyType::u16},  {"int", PlyType::i32},
      {"int32", PlyType::i32},   {"uint", PlyType::u32},    {"uint32", PlyType::u32},
      {"int64", PlyType::i64},   {"uint64", PlyType::u64},  {"float", PlyType::f32},
      {"float32", PlyType::f32}, {"double", PlyType::f64},  {"float64", PlyType::f64}};
  for (const auto& k : kTypes)
    if (s == k.name) {
      t = k.type;
      return true;
    }
  return false;
}

std::size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::i8: case PlyType::u8: return 1;
    case PlyType::i16: case PlyType::u16: return 2;
    case PlyType::i32: case PlyType::u32: case PlyType::f32: return 4;
    default: return 8;
  }
}

bool is_integer(PlyType t) { return t != PlyType::f32 && t != PlyType::f64; }

template <class T>
inline T load(const char* q, bool swap) {
  char b[sizeof(T)];
  std::memcpy(b, q, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

double load_double(PlyType t, const char* q, bool swap) {
  switch (t) {
    case PlyType::i8: return load<std::int8_t>(q, swap);
    case PlyType::u8: return load<std::uint8_t>(q, swap);
    case PlyType::i16: return load<std::int16_t>(q, swap);
    case PlyType::u16: return load<std::uint16_t>(q, swap);
    case PlyType::i32: return load<std::int32_t>(q, swap);
    case PlyType::u32: return load<std::uint32_t>(q, swap);
    case PlyType::i64: return double(load<std::int64_t>(q, swap));
    case PlyType::u64: return double(load<std::uint64_t>(q, swap));
    case PlyType::f32: return load<float>(q, swap);
    case PlyType::f64: return load<double>(q, swap);
  }
  return 0;
}

/// Integer value; uint64 values beyond int64 are clamped (they are out of range anyway).
long long load_int(PlyType t, const char* q, bool swap) {
  switch (t) {
    case PlyType::i8: return load<std::int8_t>(q, swap);
    case PlyType::u8: return load<std::uint8_t>(q, swap);
    case PlyType::i16: return load<std::int16_t>(q, swap);
    case PlyType::u16: return load<std::uint16_t>(q, swap);
    case PlyType::i32: return load<std::int32_t>(q, swap);
    case PlyType::u32: return load<std::uint32_t>(q, swap);
    case PlyType::i64: return load<std::int64_t>(q, swap);
    case PlyType::u64: {
      std::uint64_t v = load<std::uint64_t>(q, swap);
      return v > std::uint64_t(std::numeric_limits<long long>::max()) ? std::numeric_limits<long long>::max()
                                                                       : (long long)v;
    }
    default: return 0;  // not reached: list counts and indices are checked to be integers
  }
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::f32;   // scalar type, or list item type
  bool list = false;
  PlyType count_type = PlyType::u8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> props;
  int coord[3] = {-1, -1, -1};  // vertex: property index of x, y, z
  int indices = -1;             // face: property index of the vertex index list

  bool has_list() const {
    for (const auto& p : props)
      if (p.list) return true;
    return false;
  }
  /// Bytes of the smallest binary item (lists empty).
  std::size_t min_bytes() const {
    std::size_t n = 0;
    for (const auto& p : props) n += p.list ? type_size(p.count_type) : type_size(p.type);
    return n;
  }
};

enum class PlyFormat { ascii, binary_le, binary_be };

class PlyReader {
 public:
  PlyReader(Source& src, Mesh& mesh) : src_(src), mesh_(mesh), path_(src.path()) {}

  void read() {
    read_header();
    check_sizes();
    for (auto& el : elements_) {
      if (format_ == PlyFormat::ascii)
        read_ascii(el);
      else
        read_binary(el);
    }
    if (format_ == PlyFormat::ascii) {
      std::string_view ln;
      while (src_.line(ln))
        if (!strip(ln).empty())
          throw error("line " + std::to_string(src_.line_no()) +
                      ": more data after the last element than the header declares "
                      "(counts do not match the data)");
    }
  }

 private:
  InputError error(const std::string& problem) const { return file_error(path_, problem); }

  void read_header() {
    if (!src_.fill(4) || std::memcmp(src_.p, "ply", 3) != 0 || (src_.p[3] != '\n' && src_.p[3] != '\r'))
      throw error("not a PLY file: bad magic (the first line is not 'ply')");
    std::string_view ln;
    src_.line(ln);
    bool have_format = false, ended = false;
    while (!ended) {
      if (src_.offset() > (std::uint64_t(1) << 20))
        throw error("PLY header longer than 1 MB without 'end_header'");
      if (!src_.line(ln)) throw error("truncated: the PLY header has no 'end_header'");
      auto where = [&]() { return "header line " + std::to_string(src_.line_no()) + ": "; };
      std::string_view rest = ln;
      const std::string_view kw = next_token(rest);
      if (kw.empty() || kw == "comment" || kw == "obj_info") continue;
      if (kw == "end_header") {
        ended = true;
      } else if (kw == "format") {
        const std::string_view f = next_token(rest);
        if (f == "ascii")
          format_ = PlyFormat::ascii;
        else if (f == "binary_little_endian")
          format_ = PlyFormat::binary_le;
        else if (f == "binary_big_endian")
          format_ = PlyFormat::binary_be;
        else
          throw error(where() + "unknown PLY format " + quoted_excerpt(f));
        have_format = true;
      } else if (kw == "element") {
        PlyElement el;
        el.name = std::string(next_token(rest));
        long long count = -1;
        if (el.name.empty() || !parse_int(next_token(rest), count) || count < 0)
          throw error(where() + "bad element line " + quoted_excerpt(ln));
        el.count = std::uint64_t(count);
        elements_.push_back(std::move(el));
      } else if (kw == "property") {
        if (elements_.empty()) throw error(where() + "property before any element");
        PlyProperty prop;
        std::string_view t = next_token(rest);
        if (t == "list") {
          prop.list = true;
          if (!ply_type(next_token(rest), prop.count_type) || !is_integer(prop.count_type))
            throw error(where() + "bad list count type in " + quoted_excerpt(ln));
          t = next_token(rest);
        }
        if (!ply_type(t, prop.type)) throw error(where() + "unknown property type " + quoted_excerpt(t));
        prop.name = std::string(next_token(rest));
        if (prop.name.empty()) throw error(where() + "property without a name");
        elements_.back().props.push_back(std::move(prop));
      } else {
        throw error(where() + "unexpected header line " + quoted_excerpt(ln));
      }
    }
    if (!have_format) throw error("PLY header has no 'format' line");

    for (auto& el : elements_) {
      if (el.props.empty() && el.count > 0) throw error("element '" + el.name + "' has no properties");
      if (el.name == "vertex") {
        if (vertex_) throw error("more than one 'vertex' element");
        vertex_ = &el;
        const char* names[3] = {"x", "y", "z"};
        for (int k = 0; k < 3; ++k) {
          for (std::size_t i = 0; i < el.props.size(); ++i)
            if (el.props[i].name == names[k]) el.coord[k] = int(i);
          if (el.coord[k] < 0) throw error(std::string("the vertex element has no '") + names[k] + "' property");
          if (el.props[el.coord[k]].list) throw error(std::string("vertex property '") + names[k] + "' is a list");
        }
      } else if (el.name == "face") {
        if (face_) throw error("more than one 'face' element");
        face_ = &el;
        for (std::size_t i = 0; i < el.props.size(); ++i)
          if (el.props[i].list && (el.props[i].name == "vertex_indices" || el.props[i].name == "vertex_index"))
            el.indices = int(i);
        if (el.indices < 0) throw error("the face element has no 'vertex_indices' list property");
        if (!is_integer(el.props[el.indices].type))
          throw error("face vertex indices have a floating-point type");
      }
    }
    if (!face_ || face_->count == 0) throw error("no triangles (the file has no faces)");
    if (!vertex_) throw error("no 'vertex' element");
    if (vertex_->count > std::numeric_limits<std::uint32_t>::max())
      throw error("too many vertices (" + std::to_string(vertex_->count) + "; at most 2^32-1 are supported)");
    nverts_ = vertex_->count;
  }

  /// Rejects headers whose counts cannot fit in the bytes that follow, before any reservation.
  void check_sizes() {
    long double need = 0;
    std::string declared;
    for (const auto& el : elements_) {
      if (el.count == 0) continue;
      // An ASCII item needs at least one character and one separator per value.
      const std::size_t per = format_ == PlyFormat::ascii ? 2 * el.props.size() : el.min_bytes();
      need += (long double)el.count * per;
      if (!declared.empty()) declared += ", ";
      declared += count_of(el.count, el.name);
    }
    if (format_ == PlyFormat::ascii) need -= 1;  // the last value needs no separator
    const std::uint64_t have = src_.remaining();
    if (need > (long double)have)
      throw error("truncated: the header declares " + declared + " (at least " +
                  std::to_string((unsigned long long)need) + " bytes of data) but only " +
                  std::to_string(have) + " bytes follow the header");
    mesh_.vertices.resize(std::size_t(nverts_));
    mesh_.triangles.reserve(std::size_t(face_->count));
    mesh_.input_polygons = std::size_t(face_->count);
  }

  [[noreturn]] void truncated(const PlyElement& el, std::uint64_t i) const {
    throw error("truncated: the file ends in " + el.name + " " + std::to_string(i) + " of " +
                std::to_string(el.count) + " declared in the header");
  }

  [[noreturn]] void bad_vertex(std::uint64_t i, const Vec3d& v) const {
    throw error("vertex " + std::to_string(i) + " has " + coordinate_problem(v.x, v.y, v.z));
  }

  [[noreturn]] void bad_index(std::uint64_t face, long long index) const {
    throw error("face " + std::to_string(face) + " has vertex index " + std::to_string(index) +
                " out of range (the header declares " + count_of(nverts_, "vertex") + ")");
  }

  /// Fan-triangulates one polygon of `scratch_` indices (already range-checked).
  void add_polygon(std::uint64_t face) {
    const std::size_t n = scratch_.size();
    if (n < 3)
      throw error("face " + std::to_string(face) + " has " + count_of(n, "vertex") + " (a face needs at least 3)");
    for (std::size_t j = 1; j + 1 < n; ++j) mesh_.triangles.push_back({scratch_[0], scratch_[j], scratch_[j + 1]});
  }

  // ---- binary ----

  template <class T, bool Swap>
  void vertex_batch(const char* q, std::size_t stride, const int off[3], std::uint64_t first, std::size_t n) {
    Vec3d* out = mesh_.vertices.data() + first;
    for (std::size_t i = 0; i < n; ++i, q += stride) {
      const double x = double(load<T>(q + off[0], Swap));
      const double y = double(load<T>(q + off[1], Swap));
      const double z = double(load<T>(q + off[2], Swap));
      out[i] = Vec3d(x, y, z);
      if (!finite3(x, y, z)) bad_vertex(first + i, out[i]);
    }
  }

  template <class T>
  void vertex_batch_t(bool swap, const char* q, std::size_t stride, const int off[3], std::uint64_t first,
                      std::size_t n) {
    if (swap)
      vertex_batch<T, true>(q, stride, off, first, n);
    else
      vertex_batch<T, false>(q, stride, off, first, n);
  }

  void read_binary(const PlyElement& el) {
    const bool swap = (format_ == PlyFormat::binary_be) != (kBigEndianHost);
    if (&el == vertex_ && !el.has_list()) {
      // Fixed stride: whole batches straight from the buffer.
      const std::size_t stride = el.min_bytes();
      int off[3] = {0, 0, 0};
      std::size_t o = 0;
      for (std::size_t i = 0; i < el.props.size(); ++i) {
        for (int k = 0; k < 3; ++k)
          if (el.coord[k] == int(i)) off[k] = int(o);
        o += type_size(el.props[i].type);
      }
      const PlyType t = el.props[el.coord[0]].type;
      const bool same = el.props[el.coord[1]].type == t && el.props[el.coord[2]].type == t;
      for (std::uint64_t i = 0; i < el.count;) {
        if (!src_.fill(stride)) truncated(el, i);
        const std::size_t n = std::size_t(std::min<std::uint64_t>(el.count - i, src_.avail() / stride));
        if (same && t == PlyType::f32) {
          vertex_batch_t<float>(swap, src_.p, stride, off, i, n);
        } else if (same && t == PlyType::f64) {
          vertex_batch_t<double>(swap, src_.p, stride, off, i, n);
        } else {
          const char* q = src_.p;
          for (std::size_t j = 0; j < n; ++j, q += stride) {
            Vec3d v;
            for (int k = 0; k < 3; ++k) v[k] = load_double(el.props[el.coord[k]].type, q + off[k], swap);
            mesh_.vertices[i + j] = v;
            if (!finite3(v.x, v.y, v.z)) bad_vertex(i + j, v);
          }
        }
        src_.p += n * stride;
        i += n;
      }
      return;
    }
    if (&el == face_ && el.props.size() == 1 && el.props[0].count_type == PlyType::u8 &&
        (el.props[0].type == PlyType::i32 || el.props[0].type == PlyType::u32)) {
      read_binary_faces_fast(el, swap);
      return;
    }
    if (&el != vertex_ && &el != face_ && !el.has_list()) {
      // Skipped element of fixed size.
      const std::uint64_t bytes = el.count * el.min_bytes();
      if (bytes > src_.remaining()) truncated(el, src_.remaining() / el.min_bytes());
      for (std::uint64_t left = bytes; left > 0;) {
        if (!src_.fill(1)) truncated(el, (bytes - left) / el.min_bytes());
        const std::size_t n = std::size_t(std::min<std::uint64_t>(left, src_.avail()));
        src_.p += n;
        left -= n;
      }
      return;
    }
    for (std::uint64_t i = 0; i < el.count; ++i) read_binary_item(el, i, swap);
  }

  /// The common layout: one `list uchar int` property. Triangles go straight from the buffer;
  /// anything else (a polygon, the end of the buffer) through the generic item reader.
  void read_binary_faces_fast(const PlyElement& el, bool swap) {
    const std::uint32_t nv = std::uint32_t(nverts_);
    const bool is_signed = el.props[0].type == PlyType::i32;
    for (std::uint64_t i = 0; i < el.count;) {
      if (!src_.fill(13)) {
        read_binary_item(el, i, swap);  // reports the truncation precisely, or reads a short face
        ++i;
        continue;
      }
      const char* q = src_.p;
      const char* end = src_.e - 12;
      std::uint64_t i0 = i;
      while (i < el.count && q < end && static_cast<unsigned char>(*q) == 3) {
        std::uint32_t v[3];
        std::memcpy(v, q + 1, 12);
        if (swap)
          for (auto& x : v) x = __builtin_bswap32(x);
        for (int k = 0; k < 3; ++k)
          if (v[k] >= nv) {
            src_.p = q;
            bad_index(i, is_signed ? (long long)std::int32_t(v[k]) : (long long)v[k]);
          }
        mesh_.triangles.push_back({v[0], v[1], v[2]});
        q += 13;
        ++i;
      }
      src_.p = q;
      if (i == i0 && i < el.count) {
        read_binary_item(el, i, swap);
        ++i;
      }
    }
  }

  void read_binary_item(const PlyElement& el, std::uint64_t i, bool swap) {
    const bool is_vertex = &el == vertex_, is_face = &el == face_;
    Vec3d v;
    for (std::size_t k = 0; k < el.props.size(); ++k) {
      const PlyProperty& prop = el.props[k];
      if (!prop.list) {
        const std::size_t sz = type_size(prop.type);
        if (!src_.fill(sz)) truncated(el, i);
        if (is_vertex)
          for (int c = 0; c < 3; ++c)
            if (el.coord[c] == int(k)) v[c] = load_double(prop.type, src_.p, swap);
        src_.p += sz;
        continue;
      }
      const std::size_t csz = type_size(prop.count_type), isz = type_size(prop.type);
      if (!src_.fill(csz)) truncated(el, i);
      const long long n = load_int(prop.count_type, src_.p, swap);
      src_.p += csz;
      if (n < 0) throw error(el.name + " " + std::to_string(i) + " has a negative list length " + std::to_string(n));
      if ((long double)n * isz > (long double)src_.remaining()) truncated(el, i);
      const std::size_t bytes = std::size_t(n) * isz;
      if (!src_.fill(bytes)) truncated(el, i);
      if (is_face && int(k) == el.indices) {
        scratch_.resize(std::size_t(n));
        for (long long j = 0; j < n; ++j) {
          const long long idx = load_int(prop.type, src_.p + j * isz, swap);
          if (idx < 0 || std::uint64_t(idx) >= nverts_) bad_index(i, idx);
          scratch_[std::size_t(j)] = std::uint32_t(idx);
        }
        src_.p += bytes;
        add_polygon(i);
      } else {
        src_.p += bytes;
      }
    }
    if (is_vertex) {
      mesh_.vertices[std::size_t(i)] = v;
      if (!finite3(v.x, v.y, v.z)) bad_vertex(i, v);
    }
  }

  // ---- ASCII ----

  void read_ascii(const PlyElement& el) {
    const bool is_vertex = &el == vertex_, is_face = &el == face_;
    std::string_view ln;
    for (std::uint64_t i = 0; i < el.count; ++i) {
      do {
        if (!src_.line(ln))
          throw error("truncated: the file ends in " + el.name + " " + std::to_string(i) + " of " +
                      std::to_string(el.count) + " declared in the header (counts do not match the data)");
      } while (strip(ln).empty());
      auto where = [&]() {
        return "line " + std::to_string(src_.line_no()) + " (" + el.name + " " + std::to_string(i) + "): ";
      };
      auto too_few = [&]() {
        return error(where() + "too few values (the header declares more properties or list items)");
      };
      Vec3d v;
      for (std::size_t k = 0; k < el.props.size(); ++k) {
        const PlyProperty& prop = el.props[k];
        if (!prop.list) {
          const std::string_view tok = next_token(ln);
          if (tok.empty()) throw too_few();
          double d;
          if (!parse_double(tok, d)) throw error(where() + quoted_excerpt(tok) + " is not a number");
          // Values take their declared type, so that ASCII and binary files of the same mesh
          // read the same coordinates.
          if (prop.type == PlyType::f32) d = double(float(d));
          if (is_vertex)
            for (int c = 0; c < 3; ++c)
              if (el.coord[c] == int(k)) v[c] = d;
          continue;
        }
        std::string_view tok = next_token(ln);
        if (tok.empty()) throw too_few();
        long long n;
        if (!parse_int(tok, n) || n < 0) throw error(where() + quoted_excerpt(tok) + " is not a list length");
        const bool wanted = is_face && int(k) == el.indices;
        if (wanted) scratch_.clear();
        for (long long j = 0; j < n; ++j) {
          tok = next_token(ln);
          if (tok.empty()) throw too_few();
          if (wanted) {
            long long idx;
            if (!parse_int(tok, idx)) throw error(where() + quoted_excerpt(tok) + " is not a vertex index");
            if (idx < 0 || std::uint64_t(idx) >= nverts_) bad_index(i, idx);
            scratch_.push_back(std::uint32_t(idx));
          } else {
            double d;
            if (!parse_double(tok, d)) throw error(where() + quoted_excerpt(tok) + " is not a number");
          }
        }
        if (wanted) add_polygon(i);
      }
      if (!strip(ln).empty())
        throw error(where() + "more values than the header declares (" + quoted_excerpt(strip(ln)) + " left over)");
      if (is_vertex) {
        mesh_.vertices[std::size_t(i)] = v;
        if (!finite3(v.x, v.y, v.z)) bad_vertex(i, v);
      }
    }
  }

  Source& src_;
  Mesh& mesh_;
  const std::string& path_;
  PlyFormat format_ = PlyFormat::ascii;
  std::vector<PlyElement> elements_;
  const PlyElement* vertex_ = nullptr;
  const PlyElement* face_ = nullptr;
  std::uint64_t nverts_ = 0;
  std::vector<std::uint32_t> scratch_;
};

// ---------------------------------------------------------------------------------------------
// OBJ.
// ---------------------------------------------------------------------------------------------
class ObjReader {
 public:
  ObjReader(Source& src, Mesh& mesh) : src_(src), mesh_(mesh), path_(src.path()) {}

  void read() {
    std::string_view ln;
    std::string joined;
    std::vector<long long> raw;
    std::uint64_t faces = 0;
    while (src_.line(ln)) {
      const std::uint64_t line_no = src_.line_no();
      if (!ln.empty() && ln.back() == '\\') {  // line continuation
        joined.assign(ln.data(), ln.size() - 1);
        std::string_view more;
        while (src_.line(more)) {
          const bool cont = !more.empty() && more.back() == '\\';
          joined.append(more.data(), more.size() - (cont ? 1 : 0));
          joined += ' ';
          if (!cont) break;
        }
        ln = joined;
      }
      const std::size_t hash = ln.find('#');  // comments, also after a statement
      if (hash != std::string_view::npos) ln = ln.substr(0, hash);
      std::string_view rest = ln;
      const std::string_view kw = next_token(rest);
      if (kw.empty()) continue;
      auto where = [&]() { return "line " + std::to_string(line_no) + ": "; };
      if (kw == "v") {
        double c[3];
        for (int k = 0; k < 3; ++k) {
          const std::string_view tok = next_token(rest);
          if (tok.empty())
            throw error(where() + "vertex " + std::to_string(mesh_.vertices.size() + 1) + " has " +
                        std::to_string(k) + " coordinates, expected 3");
          if (!parse_double(tok, c[k])) throw error(where() + quoted_excerpt(tok) + " is not a number");
        }
        if (!finite3(c[0], c[1], c[2]))
          throw error(where() + "vertex " + std::to_string(mesh_.vertices.size() + 1) + " has " +
                      coordinate_problem(c[0], c[1], c[2]));
        if (mesh_.vertices.size() >= std::numeric_limits<std::uint32_t>::max())
          throw error("too many vertices (at most 2^32-1 are supported)");
        mesh_.vertices.emplace_back(c[0], c[1], c[2]);
      } else if (kw == "f" || kw == "fo") {
        ++faces;
        raw.clear();
        for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
          const std::string_view head = tok.substr(0, tok.find('/'));
          long long idx;
          if (!parse_int(head, idx)) throw error(where() + quoted_excerpt(tok) + " is not a vertex reference");
          raw.push_back(idx);
        }
        if (raw.size() < 3)
          throw error(where() + "face " + std::to_string(faces) + " has " + std::to_string(raw.size()) +
                      (raw.size() == 1 ? " vertex" : " vertices") + " (a face needs at least 3)");
        scratch_.resize(raw.size());
        const long long nv = (long long)mesh_.vertices.size();
        for (std::size_t j = 0; j < raw.size(); ++j) {
          const long long r = raw[j];
          long long idx = r > 0 ? r - 1 : nv + r;
          if (r == 0 || idx < 0)
            throw error(where() + "face " + std::to_string(faces) + " has vertex index " + std::to_string(r) +
                        " out of range (" + (r == 0 ? std::string("OBJ indices start at 1") :
                        count_of(std::uint64_t(nv), "vertex") + " defined before it") + ")");
          if (idx >= nv) {  // a forward reference: checked once every vertex is known
            if (idx > (long long)std::numeric_limits<std::uint32_t>::max())
              throw error(where() + "face " + std::to_string(faces) + " has vertex index " + std::to_string(r) +
                          " out of range");
            if (!forward_ || idx > forward_->idx) forward_ = Forward{faces, line_no, r, idx};
          }
          scratch_[j] = std::uint32_t(idx);
        }
        for (std::size_t j = 1; j + 1 < scratch_.size(); ++j)
          mesh_.triangles.push_back({scratch_[0], scratch_[j], scratch_[j + 1]});
        max_index_ = std::max<std::uint64_t>(max_index_, *std::max_element(scratch_.begin(), scratch_.end()));
      } else {
        // vt, vn, vp, g, o, s, usemtl, mtllib, l, p, and the free-form statements: not ours.
        // A keyword with control bytes means this is not a text OBJ at all.
        for (char c : kw)
          if (static_cast<unsigned char>(c) < 32 || c == 127)
            throw error(where() + "binary data, not a text OBJ file");
      }
    }
    mesh_.input_polygons = std::size_t(faces);
    const std::uint64_t nv = mesh_.vertices.size();
    if (!mesh_.triangles.empty() && max_index_ >= nv) {
      // Only a forward reference can reach past the end; the largest one is recorded.
      throw error("line " + std::to_string(forward_->line) + ": face " + std::to_string(forward_->face) +
                  " has vertex index " + std::to_string(forward_->raw) + " out of range (the file has " +
                  count_of(nv, "vertex") + ")");
    }
    if (mesh_.triangles.empty()) throw error("no triangles (the file has no faces)");
  }

 private:
  InputError error(const std::string& problem) const { return file_error(path_, problem); }

  struct Forward {
    std::uint64_t face, line;
    long long raw, idx;
  };
  Source& src_;
  Mesh& mesh_;
  const std::string& path_;
  std::vector<std::uint32_t> scratch_;
  std::uint64_t max_index_ = 0;
  std::optional<Forward> forward_;
};

std::string lower_extension(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

Mesh load_mesh(const std::string& path, Progress* progress) {
  Source src(path, progress);
  Mesh mesh;
  mesh.path = path;
  if (src.size() == 0) throw file_error(path, "the file is empty: no triangles");
  std::string ext = lower_extension(path);
  if (ext != "ply" && ext != "obj") {
    // Sniff: PLY has a magic line; OBJ is text starting with a known statement or a comment.
    src.fill(std::size_t(std::min<std::uint64_t>(src.size(), 256)));
    const std::string_view head(src.p, src.avail());
    if (head.substr(0, 4) == "ply\n" || head.substr(0, 4) == "ply\r") {
      ext = "ply";
    } else {
      std::string_view rest = head;
      const std::string_view kw = next_token(rest);
      const bool text = head.find('\0') == std::string_view::npos;
      if (text && (kw == "v" || kw == "vt" || kw == "vn" || kw == "f" || kw == "o" || kw == "g" ||
                   kw == "mtllib" || kw == "usemtl" || kw == "s" || (!kw.empty() && kw[0] == '#')))
        ext = "obj";
      else
        throw file_error(path, "unknown mesh format (expected a PLY or OBJ file)");
    }
  }
  if (ext == "ply")
    PlyReader(src, mesh).read();
  else
    ObjReader(src, mesh).read();
  mesh.sha256 = src.finish_hash();
  if (progress) progress->update(double(src.size()));
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// Writer.
// ---------------------------------------------------------------------------------------------
void write_ply(const std::string& path, const Mesh& mesh, bool ascii) {
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw std::runtime_error(path + ": cannot write: " + std::strerror(errno));
  std::string buf;
  buf.reserve(kChunk + 256);
  bool ok = true;
  auto flush = [&](bool force) {
    if (buf.size() >= kChunk || (force && !buf.empty())) {
      ok = ok && std::fwrite(buf.data(), 1, buf.size(), f) == buf.size();
      buf.clear();
    }
  };
  buf += "ply\nformat ";
  buf += ascii ? "ascii" : "binary_little_endian";
  buf += " 1.0\ncomment written by bvhbench\nelement vertex " + std::to_string(mesh.vertices.size()) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(mesh.triangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  char tmpc[64];
  for (const Vec3d& v : mesh.vertices) {
    const float c[3] = {float(v.x), float(v.y), float(v.z)};
    if (ascii) {
      for (int k = 0; k < 3; ++k) {
        auto r = std::to_chars(tmpc, tmpc + sizeof tmpc, c[k]);
        buf.append(tmpc, r.ptr);
        buf += k < 2 ? ' ' : '\n';
      }
    } else {
      char b[12];
      for (int k = 0; k < 3; ++k) {
        std::uint32_t u;
        std::memcpy(&u, &c[k], 4);
        if (kBigEndianHost) u = __builtin_bswap32(u);
        std::memcpy(b + 4 * k, &u, 4);
      }
      buf.append(b, 12);
    }
    flush(false);
  }
  for (const auto& t : mesh.triangles) {
    if (ascii) {
      buf += "3";
      for (int k = 0; k < 3; ++k) {
        buf += ' ';
        auto r = std::to_chars(tmpc, tmpc + sizeof tmpc, t[k]);
        buf.append(tmpc, r.ptr);
      }
      buf += '\n';
    } else {
      char b[13];
      b[0] = 3;
      for (int k = 0; k < 3; ++k) {
        std::uint32_t u = t[k];
        if (kBigEndianHost) u = __builtin_bswap32(u);
        std::memcpy(b + 1 + 4 * k, &u, 4);
      }
      buf.append(b, 13);
    }
    flush(false);
  }
  flush(true);
  ok = (std::fclose(f) == 0) && ok;
  if (!ok || std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot write: " + why);
  }
}

}  // namespace bvhbench
