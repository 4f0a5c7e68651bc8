// OFF (Geomview's Object File Format, the format of the Princeton Shape Benchmark and ModelNet):
//
//   [ST][C][N][4][n]OFF        keyword: texture coordinates, colours, normals per vertex,
//                                       homogeneous coordinates, a dimension line
//   NV NF [NE]                 counts, on the keyword line or the next (NE, edges, ignored)
//   x y z [extras]             NV vertex lines: normal, colour, texture coordinates ignored
//   n i1 ... in [colour]       NF faces (0-based indices), polygons fan-triangulated
//
// `#` starts a comment anywhere; blank lines are skipped anywhere. ModelNet's files that glue the
// counts to the keyword ("OFF490 518 0") are read. Refused, each with its reason in the message
// (docs/meshes.md): `4OFF` (homogeneous x y z w: the reader would have to divide by w, and w = 0
// is a point at infinity, not a surface vertex), `nOFF` of a dimension other than 3 (not 3D
// points), and `OFF BINARY` (Geomview's binary variant: no collection we know of ships it, and a
// format we cannot test against a real writer is better refused than misread).
//
// Vertex lines may carry up to 9 values after x y z (3 normal, 4 colour, 2 texture), face lines
// up to 4 after the indices (a colour or a colour-map index), whatever the keyword says: writers
// that add colours to a plain `OFF` are common. More than that means the counts or the lines are
// wrong, and is refused.
#include <string>
#include <string_view>
#include <vector>

#include "harness/io/mesh_format.hpp"
#include "harness/util/printable.hpp"
#include "harness/util/text_scan.hpp"

namespace bvhbench {

namespace {

constexpr int kMaxVertexExtras = 9, kMaxFaceExtras = 4;

/// The keyword's prefix letters, if `tok` starts with an OFF keyword; `tail` gets what follows
/// "OFF" in the token (ModelNet's glued counts), `keyword` the keyword itself.
struct OffKeyword {
  bool homogeneous = false, dimension = false;
  std::string_view keyword, tail;
};

bool parse_keyword(std::string_view tok, OffKeyword& k) {
  std::size_t i = 0;
  if (tok.substr(i, 2) == "ST") i += 2;
  if (tok.substr(i, 1) == "C") ++i;
  if (tok.substr(i, 1) == "N") ++i;
  if (tok.substr(i, 1) == "4") {
    k.homogeneous = true;
    ++i;
  }
  if (tok.substr(i, 1) == "n") {
    k.dimension = true;
    ++i;
  }
  if (tok.substr(i, 3) != "OFF") return false;
  i += 3;
  k.keyword = tok.substr(0, i);
  k.tail = tok.substr(i);
  for (char c : k.tail)
    if (c < '0' || c > '9') return false;
  return true;
}

class OffParser final : public FormatParser {
 public:
  explicit OffParser(ByteSource& src) : FormatParser(src) {}

  void read_header() override {
    info.format = "off";
    std::string_view ln;
    if (!data_line(ln)) throw error("not an OFF file: it has no keyword line");
    std::string_view rest = ln;
    const std::string_view tok = next_token(rest);
    OffKeyword kw;
    if (!parse_keyword(tok, kw))
      throw error("line " + std::to_string(src_.line_no()) + ": not an OFF file: " + quoted_excerpt(tok) +
                  " is not an OFF keyword (OFF, COFF, NOFF, CNOFF, STOFF, ...)");
    info.variant = std::string(kw.keyword);
    if (kw.homogeneous)
      throw error("line " + std::to_string(src_.line_no()) + ": " + quoted_excerpt(kw.keyword) +
                  " has homogeneous coordinates (x y z w), which are not read: divide by w and write OFF");
    std::string counts = std::string(kw.tail) + " " + std::string(rest);
    std::string_view c = strip(counts);
    if (c.substr(0, 6) == "BINARY")
      throw error("line " + std::to_string(src_.line_no()) +
                  ": binary OFF ('OFF BINARY') is not read: write the mesh as ASCII OFF, PLY or STL");
    if (kw.dimension) {
      if (c.empty()) c = next_data_line("the dimension of nOFF");
      std::string_view t = c;
      long long dim;
      if (!parse_int(next_token(t), dim) || dim != 3)
        throw error("line " + std::to_string(src_.line_no()) + ": " + quoted_excerpt(kw.keyword) +
                    " of dimension " + quoted_excerpt(strip(c)) + ": only 3D vertices are read");
      counts = std::string(t);
      c = strip(counts);
    }
    if (c.empty()) {
      c = next_data_line("the counts");
      counts = std::string(c);
      c = counts;
    }
    long long v[3] = {0, 0, 0};
    int n = 0;
    std::string_view t = c;
    for (std::string_view x = next_token(t); !x.empty(); x = next_token(t)) {
      if (n == 3 || !parse_int(x, v[n]) || v[n] < 0)
        throw error("line " + std::to_string(src_.line_no()) + ": bad counts line " + quoted_excerpt(c) +
                    " (expected: vertices faces [edges])");
      ++n;
    }
    if (n < 2)
      throw error("line " + std::to_string(src_.line_no()) + ": bad counts line " + quoted_excerpt(c) +
                  " (expected: vertices faces [edges])");
    nv_ = std::uint64_t(v[0]);
    nf_ = std::uint64_t(v[1]);
    if (nf_ == 0) throw error("no triangles (the file has no faces)");
    if (nv_ > kMaxVertices)
      throw error("too many vertices (" + std::to_string(nv_) + "; at most 2^32-1 are supported)");
    // Every vertex and face line holds at least one character and a line end (a line too short
    // for what it must hold is reported where it is).
    const long double need = (long double)(nv_ + nf_) * 2 - 1;
    if (need > (long double)src_.remaining())
      throw error("truncated: the header declares " + count_of(nv_, "vertex") + " and " + count_of(nf_, "face") +
                  " (at least " + std::to_string((unsigned long long)need) + " bytes of data) but only " +
                  std::to_string(src_.remaining()) + " bytes follow the header");
  }

  void read_vertices(VertexOut& out) override {
    std::string_view ln;
    for (std::uint64_t i = 0; i < nv_; ++i) {
      if (!data_line(ln)) truncated("vertex", i, nv_);
      auto where = [&] { return "line " + std::to_string(src_.line_no()) + " (vertex " + std::to_string(i) + "): "; };
      double c[3];
      for (int k = 0; k < 3; ++k) {
        const std::string_view tok = next_token(ln);
        if (tok.empty()) throw error(where() + "too few values (x y z expected)");
        if (!parse_double(tok, c[k])) throw error(where() + quoted_excerpt(tok) + " is not a number");
      }
      extras(ln, kMaxVertexExtras, where, "x y z and a normal, a colour and texture coordinates");
      if (!finite3(c[0], c[1], c[2]))
        throw error("vertex " + std::to_string(i) + " has " + coordinate_problem(c[0], c[1], c[2]));
      out.add(Vec3d(c[0], c[1], c[2]));
    }
    faces_ = src_.offset();
    faces_line_ = src_.line_no();
  }

  void read_triangles(TriangleOut& out, bool first) override {
    info.polygons = info.polygons_triangulated = 0;
    src_.seek(faces_, faces_line_);
    std::string_view ln;
    for (std::uint64_t f = 0; f < nf_; ++f) {
      if (!data_line(ln)) truncated("face", f, nf_);
      auto where = [&] { return "line " + std::to_string(src_.line_no()) + " (face " + std::to_string(f) + "): "; };
      auto line = [&] { return "line " + std::to_string(src_.line_no()) + ": "; };
      std::string_view tok = next_token(ln);
      long long n;
      if (!parse_int(tok, n) || n < 0) throw error(where() + quoted_excerpt(tok) + " is not a vertex count");
      if (n < 3) throw error(line() + too_few_vertices("face " + std::to_string(f), std::uint64_t(n)));
      scratch_.clear();
      for (long long j = 0; j < n; ++j) {
        tok = next_token(ln);
        if (tok.empty())
          throw error(where() + "too few values (the face has " + count_of(std::uint64_t(n), "vertex") + ")");
        long long idx;
        if (!parse_int(tok, idx)) throw error(where() + quoted_excerpt(tok) + " is not a vertex index");
        if (idx < 0 || std::uint64_t(idx) >= nv_)
          throw error(line() + "face " + std::to_string(f) + " has vertex index " + std::to_string(idx) +
                      " out of range (the header declares " + count_of(nv_, "vertex") + ")");
        scratch_.push_back(std::uint32_t(idx));
      }
      extras(ln, kMaxFaceExtras, where, "the indices and a colour");
      ++info.polygons;
      if (n > 3) ++info.polygons_triangulated;
      out.add_fan(scratch_.data(), scratch_.size());
    }
    if (first && data_line(ln))
      throw error("line " + std::to_string(src_.line_no()) +
                  ": more data after the last face than the header declares (counts do not match the data)");
  }

  std::uint64_t vertex_hint() const override { return nv_; }
  std::uint64_t triangle_hint() const override { return nf_; }

 private:
  /// The next line with something before its comment (that part, stripped); false at the end.
  bool data_line(std::string_view& out) {
    while (src_.line(out)) {
      out = strip(before_comment(out));
      if (!out.empty()) return true;
    }
    return false;
  }

  std::string_view next_data_line(const char* what) {
    std::string_view ln;
    if (!data_line(ln)) throw error(std::string("truncated: the file ends before ") + what);
    return ln;
  }

  [[noreturn]] void truncated(const char* what, std::uint64_t i, std::uint64_t n) const {
    throw error(std::string("truncated: the file ends in ") + what + " " + std::to_string(i) + " of " +
                std::to_string(n) + " declared in the header (counts do not match the data)");
  }

  /// The values after what a line must hold: at most `max`, all numbers.
  template <class Where>
  void extras(std::string_view rest, int max, const Where& where, const char* allowed) const {
    const char* end = rest.data() + rest.size();
    int n = 0;
    for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest), ++n) {
      if (n == max) {
        const std::string_view left(tok.data(), std::size_t(end - tok.data()));
        throw error(where() + "more values than " + allowed + " (" + quoted_excerpt(left) + " left over)");
      }
      double d;
      if (!parse_double(tok, d)) throw error(where() + quoted_excerpt(tok) + " is not a number");
    }
  }

  std::uint64_t nv_ = 0, nf_ = 0;
  std::uint64_t faces_ = 0, faces_line_ = 0;  ///< where the first face line may start
  std::vector<std::uint32_t> scratch_;
};

}  // namespace

bool looks_like_off(std::string_view head) {
  std::string_view ln;
  while (!head.empty()) {
    const std::size_t nl = head.find('\n');
    ln = strip(before_comment(head.substr(0, nl)));
    head = nl == std::string_view::npos ? std::string_view() : head.substr(nl + 1);
    if (ln.empty()) continue;
    OffKeyword kw;
    return parse_keyword(next_token(ln), kw);
  }
  return false;
}

std::unique_ptr<FormatParser> make_off_parser(ByteSource& src) { return std::make_unique<OffParser>(src); }

}  // namespace bvhbench
