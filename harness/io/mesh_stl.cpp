// STL, binary and ASCII. An STL file is a list of facets, each with its own three corner
// positions: there are no vertex indices, so the reader welds the corners exactly (equal
// coordinates are one vertex) and a closed STL becomes a closed indexed mesh. docs/meshes.md
// says what is accepted and why.
//
// - Binary or ASCII is decided by the size: a file of exactly 84 + 50 n bytes, n the uint32 at
//   offset 80, is binary, even when its 80-byte header starts with "solid" (many binary
//   writers put "solid" there); anything else must be ASCII, starting with "solid".
// - Coordinates are float32 (binary STL stores them so; ASCII STL's numbers are rounded to
//   float32, so that an ASCII and a binary STL of the same mesh read the same vertices).
// - Welding compares values: -0.0 and 0.0 are one vertex (they are the same point, and a writer
//   that negated a zero coordinate must not open a closed mesh); the vertex keeps the first
//   corner's coordinates. NaN never reaches the table (it is rejected).
// - Vertices are numbered in the order of their first corner; the facet normal is ignored
//   (the methods derive normals from the winding), whatever it holds (even NaN).
// - ASCII: keywords in any case, tokens split across lines in any way; several
//   `solid ... endsolid` blocks are read as one mesh (welded together); a loop of more than 3
//   vertices is fan-triangulated, fewer than 3 is refused.
//
// The weld table (coordinates + an open-addressing index) is kept between passes: each triangle
// pass reads the facets again and looks their corners up. Its size is what resident_bytes()
// reports.
#include <algorithm>
#include <cctype>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "harness/core/weld_table.hpp"
#include "harness/io/mesh_format.hpp"
#include "harness/util/printable.hpp"
#include "harness/util/text_scan.hpp"

namespace bvhbench {

namespace {

constexpr bool kBigEndianHost = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;
constexpr std::size_t kHeader = 84, kFacet = 50;

inline float le_float(const char* q) {
  std::uint32_t u;
  std::memcpy(&u, q, 4);
  if (kBigEndianHost) u = __builtin_bswap32(u);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

inline std::uint32_t le_u32(const char* q) {
  std::uint32_t u;
  std::memcpy(&u, q, 4);
  return kBigEndianHost ? __builtin_bswap32(u) : u;
}

inline bool iequals(std::string_view a, const char* b) {
  const std::size_t n = std::strlen(b);
  if (a.size() != n) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (char(std::tolower(static_cast<unsigned char>(a[i]))) != b[i]) return false;
  return true;
}

class StlParser final : public FormatParser {
 public:
  explicit StlParser(ByteSource& src) : FormatParser(src) {}

  void read_header() override {
    info.format = "stl";
    const bool binary = stl_binary_size_matches(src_);
    if (src_.size() >= kHeader) header_facets_ = le_u32(src_.p + 80);
    if (binary) {
      binary_ = true;
      info.variant = "binary";
      facets_ = header_facets_;
      weld_ = WeldTable(facets_);  // a closed mesh has about half as many vertices as facets
      return;
    }
    info.variant = "ascii";
    src_.fill(std::size_t(std::min<std::uint64_t>(src_.size(), 512)));
    std::string_view head(src_.p, src_.avail());
    while (!head.empty() && (is_space(head.front()) || head.front() == '\n')) head.remove_prefix(1);
    if (iequals(head.substr(0, 5), "solid")) return;
    if (src_.size() < kHeader)
      throw error("truncated: " + std::to_string(src_.size()) +
                  " bytes, less than the 84-byte header of a binary STL (and not an ASCII STL: it does not "
                  "start with 'solid')");
    throw error(binary_size_problem() + " (and not an ASCII STL: it does not start with 'solid')");
  }

  void read_vertices(VertexOut& out) override {
    if (binary_) {
      scan_binary(&out, nullptr);
    } else {
      src_.seek(0, 0);
      scan_ascii(&out, nullptr);
    }
  }

  void read_triangles(TriangleOut& out, bool first) override {
    info.polygons = info.polygons_triangulated = info.solids = 0;
    if (binary_)
      scan_binary(nullptr, &out);
    else
      scan_ascii(nullptr, &out);
    (void)first;  // both variants are read to their end by the parse itself
  }

  std::uint64_t vertex_hint() const override { return binary_ ? facets_ / 2 + 3 : 0; }
  std::uint64_t triangle_hint() const override { return facets_; }
  std::size_t resident_bytes() const override { return weld_.bytes(); }
  std::string why_no_triangles() const override { return "the file has no facets"; }

 private:
  std::string binary_size_problem() const {
    const std::uint64_t n = header_facets_;
    const std::uint64_t want = kHeader + kFacet * n;
    const std::string declared = "the binary STL header declares " + count_of(n, "facet") + " (84 + 50 x " +
                                 std::to_string(n) + " = " + std::to_string(want) + " bytes) but the file has " +
                                 std::to_string(src_.size()) + " bytes";
    return src_.size() < want ? "truncated: " + declared : declared + " (counts do not match the data)";
  }

  /// One corner: welded (vertex pass: new vertices to `vout`) or looked up (triangle pass).
  std::uint32_t corner(const float* p, std::uint64_t facet, int k, VertexOut* vout) {
    if (vout) {
      if (!finite3(p[0], p[1], p[2]))
        throw error("facet " + std::to_string(facet) + " vertex " + std::to_string(k) + " has " +
                    coordinate_problem(p[0], p[1], p[2]));
      bool added;
      const std::uint32_t id = weld_.insert(p, added);
      if (added) {
        if (weld_.size() > kMaxVertices) throw error("too many vertices (at most 2^32-1 are supported)");
        vout->add(Vec3d(p[0], p[1], p[2]));
      }
      return id;
    }
    const std::uint32_t id = weld_.find(p);
    if (id == WeldTable::kAbsent)
      throw error("the file changed while it was being read (facet " + std::to_string(facet) +
                  " has a corner that was not there before)");
    return id;
  }

  void scan_binary(VertexOut* vout, TriangleOut* tout) {
    src_.seek(kHeader, 0);
    if (vout) info.corners = 3 * facets_;
    for (std::uint64_t i = 0; i < facets_;) {
      if (!src_.fill(kFacet)) throw error("truncated: the file ends in facet " + std::to_string(i));
      const std::size_t n = std::size_t(std::min<std::uint64_t>(facets_ - i, src_.avail() / kFacet));
      for (std::size_t j = 0; j < n; ++j, ++i) {
        const char* q = src_.p + j * kFacet + 12;  // the normal (12 bytes) is ignored
        std::uint32_t id[3];
        for (int k = 0; k < 3; ++k) {
          const float p[3] = {le_float(q + 12 * k), le_float(q + 12 * k + 4), le_float(q + 12 * k + 8)};
          id[k] = corner(p, i, k, vout);
        }
        if (tout) tout->add(id[0], id[1], id[2]);
      }
      src_.p += n * kFacet;
    }
    if (tout) info.polygons = facets_;
  }

  // ---- ASCII ----

  /// The next token, across lines; false at the end of the file.
  bool token(std::string_view& tok) {
    for (;;) {
      tok = next_token(rest_);
      if (!tok.empty()) {
        if (has_control_bytes(tok)) binary_data();
        return true;
      }
      if (!src_.line(rest_)) return false;
    }
  }

  std::string where() const { return "line " + std::to_string(src_.line_no()) + ": "; }

  [[noreturn]] void binary_data() const {
    throw error(where() + "binary data in an ASCII STL" +
                (src_.size() >= kHeader ? " (if this is a binary STL: " + binary_size_problem() + ")" : ""));
  }

  /// Skips the name after `solid` / `endsolid`: the rest of the line, any text.
  void skip_name() {
    if (has_control_bytes(rest_)) binary_data();
    rest_ = {};
  }

  [[noreturn]] void unexpected(std::string_view tok, const char* expected) const {
    throw error(where() + "unexpected " + quoted_excerpt(tok) + " (expected " + expected + ")");
  }

  void expect(const char* kw, std::uint64_t facet) {
    std::string_view tok;
    if (!token(tok)) throw error("truncated: the file ends in facet " + std::to_string(facet));
    if (!iequals(tok, kw)) unexpected(tok, (std::string("'") + kw + "'").c_str());
  }

  void scan_ascii(VertexOut* vout, TriangleOut* tout) {
    src_.seek(0, 0);
    rest_ = {};
    std::string_view tok;
    std::uint64_t facet = 0;
    std::vector<std::uint32_t> loop;
    token(tok);
    if (!iequals(tok, "solid")) unexpected(tok, "'solid'");
    skip_name();
    bool in_solid = true;
    for (;;) {
      if (!token(tok)) {
        if (in_solid)
          throw error("truncated: the file ends in solid " + std::to_string(info.solids) + " after " +
                      count_of(facet, "facet") + " (no 'endsolid')");
        break;
      }
      if (!in_solid) {
        if (!iequals(tok, "solid")) unexpected(tok, "'solid' or the end of the file");
        skip_name();
        in_solid = true;
        continue;
      }
      if (iequals(tok, "endsolid")) {
        skip_name();
        ++info.solids;
        in_solid = false;
        continue;
      }
      if (!iequals(tok, "facet")) unexpected(tok, "'facet' or 'endsolid'");
      if (!token(tok)) throw error("truncated: the file ends in facet " + std::to_string(facet));
      if (iequals(tok, "normal")) {
        for (int k = 0; k < 3; ++k)  // ignored, whatever it holds
          if (!token(tok)) throw error("truncated: the file ends in facet " + std::to_string(facet));
        expect("outer", facet);
      } else if (!iequals(tok, "outer")) {
        unexpected(tok, "'normal' or 'outer'");
      }
      expect("loop", facet);
      loop.clear();
      for (;;) {
        if (!token(tok)) throw error("truncated: the file ends in facet " + std::to_string(facet));
        if (iequals(tok, "endloop")) break;
        if (!iequals(tok, "vertex")) unexpected(tok, "'vertex' or 'endloop'");
        float p[3];
        for (int k = 0; k < 3; ++k) {
          if (!token(tok)) throw error("truncated: the file ends in facet " + std::to_string(facet));
          double d;
          if (!parse_double(tok, d)) throw error(where() + quoted_excerpt(tok) + " is not a number");
          p[k] = float(d);
        }
        loop.push_back(corner(p, facet, int(loop.size()), vout));
      }
      expect("endfacet", facet);
      if (loop.size() < 3) throw error(where() + too_few_vertices("facet " + std::to_string(facet), loop.size()));
      if (vout) info.corners += loop.size();
      if (tout) {
        ++info.polygons;
        if (loop.size() > 3) ++info.polygons_triangulated;
        tout->add_fan(loop.data(), loop.size());
      }
      ++facet;
    }
    facets_ = facet;
  }

  bool binary_ = false;
  std::uint64_t facets_ = 0;
  std::uint64_t header_facets_ = 0;  ///< the uint32 at offset 80, whatever the variant
  WeldTable weld_;
  std::string_view rest_;  ///< ASCII: what is left of the current line
};

}  // namespace

bool stl_binary_size_matches(ByteSource& src) {
  if (src.size() < kHeader || !src.fill(kHeader)) return false;
  return src.size() == kHeader + kFacet * std::uint64_t(le_u32(src.p + 80));
}

std::unique_ptr<FormatParser> make_stl_parser(ByteSource& src) { return std::make_unique<StlParser>(src); }

}  // namespace bvhbench
