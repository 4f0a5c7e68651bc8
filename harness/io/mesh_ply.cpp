// PLY (ASCII, binary little and big endian): any elements and properties, triangles from a
// `face` element (polygons fan-triangulated) and/or a `tristrips` element (strips with -1
// restarts, as the Stanford scans store them), in element order.
//
// Binary PLY in the common layout (scalar vertex properties, faces as a uchar count + int32
// indices) is parsed in tight batches; any other layout goes through a generic per-item path that
// is slower but complete. A strip's index list is streamed in pieces (one strip can hold every
// triangle of the model). The first pass reads the header and the elements up to the vertex
// element; the triangle passes read the face and strip elements again from their recorded
// offsets.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string_view>
#include <type_traits>
#include <vector>

#include "harness/io/mesh_format.hpp"
#include "harness/util/printable.hpp"
#include "harness/util/text_scan.hpp"

namespace bvhbench {

namespace {

constexpr bool kBigEndianHost = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;

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

bool is_unsigned(PlyType t) { return t == PlyType::u8 || t == PlyType::u16 || t == PlyType::u32 || t == PlyType::u64; }

const char* type_name(PlyType t) {
  static const char* const kNames[] = {"int8", "uint8", "int16", "uint16", "int32", "uint32",
                                       "int64", "uint64", "float32", "float64"};
  return kNames[static_cast<int>(t)];
}

/// Whether `d`, a number read as double, is a value of integer type `t`: whole and within its
/// range. The bounds are powers of two, exact in double; a 64-bit type's largest value rounds up
/// to its bound when read as double (as a binary value of it does), so that bound is allowed.
bool integer_value_of(PlyType t, double d) {
  if (d != std::floor(d)) return false;
  const int bits = int(8 * type_size(t));
  const double lo = is_unsigned(t) ? 0.0 : -std::ldexp(1.0, bits - 1);
  const double hi = std::ldexp(1.0, is_unsigned(t) ? bits : bits - 1);
  return d >= lo && (bits == 64 ? d <= hi : d < hi);
}

/// The largest value of an unsigned type (for u64, clamped as load_int clamps).
long long unsigned_max(PlyType t) {
  switch (t) {
    case PlyType::u8: return 0xFF;
    case PlyType::u16: return 0xFFFF;
    case PlyType::u32: return 0xFFFFFFFFll;
    default: return std::numeric_limits<long long>::max();
  }
}

template <class T>
inline T load(const char* q, bool swap) {
  char b[sizeof(T)];
  std::memcpy(b, q, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

/// The value of type `t` at q as R: double (any type) or long long (integer types; uint64 values
/// beyond int64 are clamped: they are out of range anyway).
template <class R>
R load_as(PlyType t, const char* q, bool swap) {
  switch (t) {
    case PlyType::i8: return R(load<std::int8_t>(q, swap));
    case PlyType::u8: return R(load<std::uint8_t>(q, swap));
    case PlyType::i16: return R(load<std::int16_t>(q, swap));
    case PlyType::u16: return R(load<std::uint16_t>(q, swap));
    case PlyType::i32: return R(load<std::int32_t>(q, swap));
    case PlyType::u32: return R(load<std::uint32_t>(q, swap));
    case PlyType::i64: return R(load<std::int64_t>(q, swap));
    case PlyType::u64: {
      const std::uint64_t v = load<std::uint64_t>(q, swap);
      if (std::is_floating_point<R>::value) return R(v);
      return v > std::uint64_t(std::numeric_limits<long long>::max()) ? R(std::numeric_limits<long long>::max()) : R(v);
    }
    case PlyType::f32: return std::is_floating_point<R>::value ? R(load<float>(q, swap)) : R(0);
    case PlyType::f64: return std::is_floating_point<R>::value ? R(load<double>(q, swap)) : R(0);
  }
  return R(0);  // not reached; list counts and indices are checked to be integers
}

double load_double(PlyType t, const char* q, bool swap) { return load_as<double>(t, q, swap); }
long long load_int(PlyType t, const char* q, bool swap) { return load_as<long long>(t, q, swap); }

/// A strip restart in binary: -1, i.e. every bit set, in any integer type (so an unsigned index
/// type restarts at its largest value: the same bits).
inline bool all_ones(const char* q, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    if (static_cast<unsigned char>(q[i]) != 0xFF) return false;
  return true;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::f32;   // scalar type, or list item type
  bool list = false;
  PlyType count_type = PlyType::u8;
};

enum class Role { other, vertex, faces, strips };

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> props;
  Role role = Role::other;
  int coord[3] = {-1, -1, -1};  // vertex: property index of x, y, z
  int indices = -1;             // faces, strips: property index of the vertex index list
  std::uint64_t start = 0, start_line = 0;  // where its first item begins (once reached)

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
  bool has_triangles() const { return role == Role::faces || role == Role::strips; }
};

enum class PlyFormat { ascii, binary_le, binary_be };

/// A strip being decoded: its last two vertices and how many it has had since its start.
/// Triangle k of a strip v0 v1 v2 ... is (v[k], v[k+1], v[k+2]) for even k and
/// (v[k+1], v[k], v[k+2]) for odd k, so that every triangle keeps the strip's orientation (the
/// OpenGL convention; VCG/MeshLab read igea.ply's strips so; trimesh's
/// triangle_strips_to_faces writes the odd ones (v[k+2], v[k+1], v[k]): the same triangles, each
/// started at another corner).
struct StripState {
  std::uint32_t a = 0, b = 0;
  std::uint64_t k = 0;
};

class PlyParser final : public FormatParser {
 public:
  explicit PlyParser(ByteSource& src) : FormatParser(src) {}

  void read_header() override {
    parse_header();
    check_sizes();
    info.format = "ply";
    info.variant = format_ == PlyFormat::ascii ? "ascii"
                   : format_ == PlyFormat::binary_le ? "binary_little_endian" : "binary_big_endian";
  }

  void read_vertices(VertexOut& out) override {
    for (std::size_t i = 0; i < elements_.size(); ++i) {
      PlyElement& el = elements_[i];
      el.start = src_.offset();
      el.start_line = src_.line_no();
      if (el.role == Role::vertex) {
        read_element(el, &out, nullptr);
        after_vertex_ = i + 1;
        break;
      }
      read_element(el, nullptr, nullptr);  // faces before the vertices: read in the triangle passes
    }
    resume_ = src_.offset();
    resume_line_ = src_.line_no();
  }

  void read_triangles(TriangleOut& out, bool first) override {
    info.polygons = info.polygons_triangulated = info.strips = info.strip_joins_dropped = 0;
    for (std::size_t i = 0; i < after_vertex_; ++i) {
      const PlyElement& el = elements_[i];
      if (!el.has_triangles()) continue;
      src_.seek(el.start, el.start_line);
      read_element(el, nullptr, &out);
    }
    if (first) {
      src_.seek(resume_, resume_line_);
      for (std::size_t i = after_vertex_; i < elements_.size(); ++i) {
        PlyElement& el = elements_[i];
        el.start = src_.offset();
        el.start_line = src_.line_no();
        read_element(el, nullptr, el.has_triangles() ? &out : nullptr);
      }
      if (format_ == PlyFormat::ascii) {
        std::string_view ln;
        while (src_.line(ln))
          if (!strip(ln).empty())
            throw error("line " + std::to_string(src_.line_no()) +
                        ": more data after the last element than the header declares "
                        "(counts do not match the data)");
      }
      return;
    }
    for (std::size_t i = after_vertex_; i < elements_.size(); ++i) {
      const PlyElement& el = elements_[i];
      if (!el.has_triangles()) continue;
      src_.seek(el.start, el.start_line);
      read_element(el, nullptr, &out);
    }
  }

  std::uint64_t vertex_hint() const override { return nverts_; }

  std::uint64_t triangle_hint() const override {
    for (const auto& el : elements_)
      if (el.role == Role::faces) return el.count;
    return 0;
  }

  std::string why_no_triangles() const override {
    return "every strip triangle repeats a vertex: " + std::to_string(info.strip_joins_dropped) + " joins, dropped";
  }

 private:
  /// The header: its lines (format, elements and their properties), then what each element is.
  void parse_header() {
    read_header_lines();
    assign_element_roles();
  }

  /// The header's lines up to 'end_header': the format, the elements and their properties.
  void read_header_lines() {
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
        format_ = parse_format(next_token(rest), where());
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
        elements_.back().props.push_back(parse_property(rest, ln, where()));
      } else {
        throw error(where() + "unexpected header line " + quoted_excerpt(ln));
      }
    }
    if (!have_format) throw error("PLY header has no 'format' line");
  }

  PlyFormat parse_format(std::string_view f, const std::string& where) const {
    if (f == "ascii") return PlyFormat::ascii;
    if (f == "binary_little_endian") return PlyFormat::binary_le;
    if (f == "binary_big_endian") return PlyFormat::binary_be;
    throw error(where + "unknown PLY format " + quoted_excerpt(f));
  }

  /// A 'property' line's rest: `[list COUNT_TYPE] TYPE NAME`.
  PlyProperty parse_property(std::string_view rest, std::string_view ln, const std::string& where) const {
    PlyProperty prop;
    std::string_view t = next_token(rest);
    if (t == "list") {
      prop.list = true;
      if (!ply_type(next_token(rest), prop.count_type) || !is_integer(prop.count_type))
        throw error(where + "bad list count type in " + quoted_excerpt(ln));
      t = next_token(rest);
    }
    if (!ply_type(t, prop.type)) throw error(where + "unknown property type " + quoted_excerpt(t));
    prop.name = std::string(next_token(rest));
    if (prop.name.empty()) throw error(where + "property without a name");
    return prop;
  }

  /// Which element holds the vertices, the faces and the triangle strips, with their properties
  /// checked; the vertex count.
  void assign_element_roles() {
    const PlyElement* vertex = nullptr;
    const PlyElement* faces = nullptr;
    const PlyElement* strips = nullptr;
    for (auto& el : elements_) {
      if (el.props.empty() && el.count > 0) throw error("element '" + el.name + "' has no properties");
      if (el.name == "vertex") {
        if (vertex) throw error("more than one 'vertex' element");
        vertex = &el;
        el.role = Role::vertex;
        const char* names[3] = {"x", "y", "z"};
        for (int k = 0; k < 3; ++k) {
          for (std::size_t i = 0; i < el.props.size(); ++i)
            if (el.props[i].name == names[k]) el.coord[k] = int(i);
          if (el.coord[k] < 0) throw error(std::string("the vertex element has no '") + names[k] + "' property");
          if (el.props[el.coord[k]].list) throw error(std::string("vertex property '") + names[k] + "' is a list");
        }
      } else if (el.name == "face" || el.name == "tristrips") {
        const bool is_face = el.name == "face";
        if ((is_face ? faces : strips) != nullptr) throw error("more than one '" + el.name + "' element");
        (is_face ? faces : strips) = &el;
        el.role = is_face ? Role::faces : Role::strips;
        for (std::size_t i = 0; i < el.props.size(); ++i)
          if (el.props[i].list && (el.props[i].name == "vertex_indices" || el.props[i].name == "vertex_index"))
            el.indices = int(i);
        if (el.indices < 0) throw error("the " + el.name + " element has no 'vertex_indices' list property");
        if (!is_integer(el.props[el.indices].type))
          throw error(std::string(is_face ? "face" : "strip") + " vertex indices have a floating-point type");
      }
    }
    if ((!faces || faces->count == 0) && (!strips || strips->count == 0))
      throw error("no triangles (the file has no faces)");
    if (!vertex) throw error("no 'vertex' element");
    if (vertex->count > kMaxVertices)
      throw error("too many vertices (" + std::to_string(vertex->count) + "; at most 2^32-1 are supported)");
    nverts_ = vertex->count;
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
  }

  [[noreturn]] void truncated(const PlyElement& el, std::uint64_t i) const {
    throw error("truncated: the file ends in " + el.name + " " + std::to_string(i) + " of " +
                std::to_string(el.count) + " declared in the header");
  }

  [[noreturn]] void bad_vertex(std::uint64_t i, const Vec3d& v) const {
    throw error("vertex " + std::to_string(i) + " has " + coordinate_problem(v.x, v.y, v.z));
  }

  [[noreturn]] void bad_index(const PlyElement& el, std::uint64_t item, long long index) const {
    throw error(el.name + " " + std::to_string(item) + " has vertex index " + std::to_string(index) +
                " out of range (the header declares " + count_of(nverts_, "vertex") + ")");
  }

  /// Fan-triangulates one polygon of `scratch_` indices (already range-checked).
  void add_polygon(std::uint64_t face, TriangleOut& out) {
    const std::size_t n = scratch_.size();
    if (n < 3) throw error(too_few_vertices("face " + std::to_string(face), n));
    ++info.polygons;
    if (n > 3) ++info.polygons_triangulated;
    out.add_fan(scratch_.data(), n);
  }

  /// One vertex `v` (range-checked) of the strip in `strip_`.
  void strip_vertex(std::uint32_t v, TriangleOut& out) {
    StripState& s = strip_;
    if (s.k >= 2) {
      if (s.a == s.b || s.b == v || s.a == v)
        ++info.strip_joins_dropped;  // zero area by its indices: a join between strips, not surface
      else if ((s.k - 2) % 2 == 0)
        out.add(s.a, s.b, v);
      else
        out.add(s.b, s.a, v);
    }
    if (s.k == 0) ++info.strips;
    s.a = s.b;
    s.b = v;
    ++s.k;
  }

  /// Reads one element: vertices to `vout`, triangles to `tout`; a null output reads past it.
  void read_element(const PlyElement& el, VertexOut* vout, TriangleOut* tout) {
    if (format_ == PlyFormat::ascii)
      read_ascii(el, vout, tout);
    else
      read_binary(el, vout, tout);
  }

  // ---- binary ----

  template <class T, bool Swap>
  void vertex_batch(const char* q, std::size_t stride, const int off[3], std::uint64_t first, std::size_t n, Vec3d* out) {
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
                      std::size_t n, Vec3d* out) {
    if (swap)
      vertex_batch<T, true>(q, stride, off, first, n, out);
    else
      vertex_batch<T, false>(q, stride, off, first, n, out);
  }

  void read_binary(const PlyElement& el, VertexOut* vout, TriangleOut* tout) {
    const bool swap = (format_ == PlyFormat::binary_be) != (kBigEndianHost);
    if (vout && el.role == Role::vertex && !el.has_list()) {
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
        const std::size_t n = std::size_t(std::min<std::uint64_t>({el.count - i, src_.avail() / stride, vout->room()}));
        Vec3d* dst = vout->tail(n);
        if (same && t == PlyType::f32) {
          vertex_batch_t<float>(swap, src_.p, stride, off, i, n, dst);
        } else if (same && t == PlyType::f64) {
          vertex_batch_t<double>(swap, src_.p, stride, off, i, n, dst);
        } else {
          const char* q = src_.p;
          for (std::size_t j = 0; j < n; ++j, q += stride) {
            Vec3d v;
            for (int k = 0; k < 3; ++k) v[k] = load_double(el.props[el.coord[k]].type, q + off[k], swap);
            dst[j] = v;
            if (!finite3(v.x, v.y, v.z)) bad_vertex(i + j, v);
          }
        }
        vout->commit(n);
        src_.p += n * stride;
        i += n;
      }
      return;
    }
    if (tout && el.role == Role::faces && el.props.size() == 1 && el.props[0].count_type == PlyType::u8 &&
        (el.props[0].type == PlyType::i32 || el.props[0].type == PlyType::u32)) {
      read_binary_faces_fast(el, swap, *tout);
      return;
    }
    if (!el.has_list()) {
      // Read past an element of fixed size.
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
    for (std::uint64_t i = 0; i < el.count; ++i) read_binary_item(el, i, swap, vout, tout);
  }

  /// The common layout: one `list uchar int` property. Triangles go straight from the buffer;
  /// anything else (a polygon, the end of the buffer) through the generic item reader.
  void read_binary_faces_fast(const PlyElement& el, bool swap, TriangleOut& out) {
    const std::uint32_t nv = std::uint32_t(nverts_);
    const bool is_signed = el.props[0].type == PlyType::i32;
    for (std::uint64_t i = 0; i < el.count;) {
      if (!src_.fill(13)) {
        read_binary_item(el, i, swap, nullptr, &out);  // reports the truncation precisely, or reads a short face
        ++i;
        continue;
      }
      const char* q = src_.p;
      const char* end = src_.e - 12;
      const std::uint64_t i0 = i;
      const std::size_t room = std::size_t(std::min<std::uint64_t>(el.count - i, out.room()));
      Triangle* dst = out.tail(room);
      std::size_t w = 0;
      while (w < room && q < end && static_cast<unsigned char>(*q) == 3) {
        std::uint32_t v[3];
        std::memcpy(v, q + 1, 12);
        if (swap)
          for (auto& x : v) x = __builtin_bswap32(x);
        for (int k = 0; k < 3; ++k)
          if (v[k] >= nv) {
            src_.p = q;
            bad_index(el, i + w, is_signed ? (long long)std::int32_t(v[k]) : (long long)v[k]);
          }
        dst[w++] = {v[0], v[1], v[2]};
        q += 13;
      }
      out.commit(w);
      i += w;
      info.polygons += i - i0;
      src_.p = q;
      if (i == i0 && i < el.count) {
        read_binary_item(el, i, swap, nullptr, &out);
        ++i;
      }
    }
  }

  void read_binary_item(const PlyElement& el, std::uint64_t i, bool swap, VertexOut* vout, TriangleOut* tout) {
    const bool is_vertex = vout && el.role == Role::vertex;
    const bool wants_indices = tout && el.has_triangles();
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
      if (wants_indices && int(k) == el.indices && el.role == Role::strips) {
        read_binary_strip(el, i, prop.type, std::uint64_t(n), swap, *tout);
        continue;
      }
      const std::size_t bytes = std::size_t(n) * isz;
      if (!src_.fill(bytes)) truncated(el, i);
      if (wants_indices && int(k) == el.indices) {
        scratch_.resize(std::size_t(n));
        for (long long j = 0; j < n; ++j) {
          const long long idx = load_int(prop.type, src_.p + j * isz, swap);
          if (idx < 0 || std::uint64_t(idx) >= nverts_) bad_index(el, i, idx);
          scratch_[std::size_t(j)] = std::uint32_t(idx);
        }
        src_.p += bytes;
        add_polygon(i, *tout);
      } else {
        src_.p += bytes;
      }
    }
    if (is_vertex) {
      if (!finite3(v.x, v.y, v.z)) bad_vertex(i, v);
      vout->add(v);
    }
  }

  /// One strip list of `n` indices of type `t`, streamed through the buffer in pieces.
  void read_binary_strip(const PlyElement& el, std::uint64_t item, PlyType t, std::uint64_t n, bool swap,
                         TriangleOut& out) {
    const std::size_t isz = type_size(t);
    constexpr std::size_t kPiece = std::size_t(1) << 20;  // bytes per fill: the buffer never grows
    strip_ = StripState{};
    for (std::uint64_t left = n; left > 0;) {
      const std::size_t want = std::size_t(std::min<std::uint64_t>(left * isz, kPiece));
      if (!src_.fill(want)) truncated(el, item);
      const std::size_t m = want / isz;
      const char* q = src_.p;
      for (std::size_t j = 0; j < m; ++j, q += isz) {
        if (all_ones(q, isz)) {
          strip_.k = 0;
          continue;
        }
        const long long idx = load_int(t, q, swap);
        if (idx < 0 || std::uint64_t(idx) >= nverts_) bad_index(el, item, idx);
        strip_vertex(std::uint32_t(idx), out);
      }
      src_.p = q;
      left -= m;
    }
  }

  // ---- ASCII ----

  void read_ascii(const PlyElement& el, VertexOut* vout, TriangleOut* tout) {
    const bool is_vertex = vout && el.role == Role::vertex;
    const bool wants_indices = tout && el.has_triangles();
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
          // read the same coordinates: a float32 is rounded to float, and an integer coordinate
          // must be one of its type (binary cannot hold 1.5 or 300 in a uint8).
          if (prop.type == PlyType::f32) d = double(float(d));
          if (is_vertex)
            for (int c = 0; c < 3; ++c)
              if (el.coord[c] == int(k)) {
                if (is_integer(prop.type) && std::isfinite(d) && !integer_value_of(prop.type, d))
                  throw error(where() + quoted_excerpt(tok) + " is not a value of type " + type_name(prop.type) +
                              " (property '" + prop.name + "')");
                v[c] = d;
              }
          continue;
        }
        std::string_view tok = next_token(ln);
        if (tok.empty()) throw too_few();
        long long n;
        if (!parse_int(tok, n) || n < 0) throw error(where() + quoted_excerpt(tok) + " is not a list length");
        const bool wanted = wants_indices && int(k) == el.indices;
        const bool strips = wanted && el.role == Role::strips;
        const long long restart_alt = is_unsigned(prop.type) ? unsigned_max(prop.type) : -1;
        if (wanted) scratch_.clear();
        if (strips) strip_ = StripState{};
        for (long long j = 0; j < n; ++j) {
          tok = next_token(ln);
          if (tok.empty()) throw too_few();
          if (wanted) {
            long long idx;
            if (!parse_int(tok, idx)) throw error(where() + quoted_excerpt(tok) + " is not a vertex index");
            if (strips && (idx == -1 || idx == restart_alt)) {
              strip_.k = 0;
              continue;
            }
            if (idx < 0 || std::uint64_t(idx) >= nverts_) bad_index(el, i, idx);
            if (strips)
              strip_vertex(std::uint32_t(idx), *tout);
            else
              scratch_.push_back(std::uint32_t(idx));
          } else {
            double d;
            if (!parse_double(tok, d)) throw error(where() + quoted_excerpt(tok) + " is not a number");
          }
        }
        if (wanted && !strips) add_polygon(i, *tout);
      }
      if (!strip(ln).empty())
        throw error(where() + "more values than the header declares (" + quoted_excerpt(strip(ln)) + " left over)");
      if (is_vertex) {
        if (!finite3(v.x, v.y, v.z)) bad_vertex(i, v);
        vout->add(v);
      }
    }
  }

  PlyFormat format_ = PlyFormat::ascii;
  std::vector<PlyElement> elements_;
  std::size_t after_vertex_ = 0;  ///< index of the first element after the vertex element
  std::uint64_t resume_ = 0, resume_line_ = 0;  ///< where the vertex element ends
  std::uint64_t nverts_ = 0;
  std::vector<std::uint32_t> scratch_;
  StripState strip_;
};

}  // namespace

std::unique_ptr<FormatParser> make_ply_parser(ByteSource& src) { return std::make_unique<PlyParser>(src); }

}  // namespace bvhbench
