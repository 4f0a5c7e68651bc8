// OBJ: `v` (any extra values, a w or a colour, ignored) and `f` / `fo` with the `v`, `v/vt`,
// `v//vn`, `v/vt/vn` forms, negative (relative) indices and polygons (fan-triangulated);
// comments and `\` line continuations; every other statement ignored.
//
// Vertices and faces may come in any order in an OBJ file, and a face may refer to a vertex
// defined after it. The reader delivers all vertices before any triangle, so it reads the file
// twice: the vertex pass parses the `v` lines (and only counts the faces), each triangle pass
// parses the `f` lines (and only counts the `v` lines, for the relative indices). Neither holds
// the other's data.
#include <algorithm>
#include <string>
#include <string_view>
#include <vector>

#include "harness/io/mesh_format.hpp"
#include "harness/util/printable.hpp"
#include "harness/util/text_scan.hpp"

namespace bvhbench {

namespace {

class ObjParser final : public FormatParser {
 public:
  explicit ObjParser(ByteSource& src) : FormatParser(src) {}

  void read_header() override { info.format = "obj"; }

  void read_vertices(VertexOut& out) override {
    std::string_view ln;
    std::uint64_t line_no = 0;
    while (statement(ln, line_no)) {
      std::string_view rest = ln;
      const std::string_view kw = next_token(rest);
      if (kw.empty()) continue;
      auto where = [&]() { return "line " + std::to_string(line_no) + ": "; };
      if (kw == "v") {
        const std::uint64_t nv = out.count();
        double c[3];
        for (int k = 0; k < 3; ++k) {
          const std::string_view tok = next_token(rest);
          if (tok.empty())
            throw error(where() + "vertex " + std::to_string(nv + 1) + " has " + std::to_string(k) +
                        " coordinates, expected 3");
          if (!parse_double(tok, c[k])) throw error(where() + quoted_excerpt(tok) + " is not a number");
        }
        if (!finite3(c[0], c[1], c[2]))
          throw error(where() + "vertex " + std::to_string(nv + 1) + " has " + coordinate_problem(c[0], c[1], c[2]));
        if (nv >= kMaxVertices) throw error("too many vertices (at most 2^32-1 are supported)");
        out.add(Vec3d(c[0], c[1], c[2]));
      } else if (kw == "f" || kw == "fo") {
        ++faces_;  // parsed by the triangle passes
      } else if (has_control_bytes(kw)) {
        // vt, vn, vp, g, o, s, usemtl, mtllib, l, p and the free-form statements are not ours; a
        // keyword with control bytes means this is not a text OBJ at all.
        throw error(where() + "binary data, not a text OBJ file");
      }
    }
    nv_ = out.count();
  }

  void read_triangles(TriangleOut& out, bool first) override {
    info.polygons = info.polygons_triangulated = 0;
    src_.seek(0, 0);
    std::string_view ln;
    std::uint64_t line_no = 0, defined = 0, face = 0;
    std::vector<long long> raw;
    while (statement(ln, line_no)) {
      std::string_view rest = ln;
      const std::string_view kw = next_token(rest);
      if (kw == "v") {
        ++defined;
        continue;
      }
      if (kw != "f" && kw != "fo") continue;
      ++face;
      auto where = [&]() { return "line " + std::to_string(line_no) + ": face " + std::to_string(face) + " "; };
      raw.clear();
      for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
        const std::string_view head = tok.substr(0, tok.find('/'));
        long long idx;
        if (!parse_int(head, idx))
          throw error("line " + std::to_string(line_no) + ": " + quoted_excerpt(tok) + " is not a vertex reference");
        raw.push_back(idx);
      }
      if (raw.size() < 3)
        throw error("line " + std::to_string(line_no) + ": " + too_few_vertices("face " + std::to_string(face), raw.size()));
      scratch_.resize(raw.size());
      for (std::size_t j = 0; j < raw.size(); ++j) {
        const long long r = raw[j];
        // Relative indices count back from the vertices defined before the face.
        const long long idx = r > 0 ? r - 1 : (long long)defined + r;
        if (r == 0 || idx < 0)
          throw error(where() + "has vertex index " + std::to_string(r) + " out of range (" +
                      (r == 0 ? std::string("OBJ indices start at 1")
                              : count_of(defined, "vertex") + " defined before it") + ")");
        if (std::uint64_t(idx) >= nv_)
          throw error(where() + "has vertex index " + std::to_string(r) + " out of range (the file has " +
                      count_of(nv_, "vertex") + ")");
        scratch_[j] = std::uint32_t(idx);
      }
      ++info.polygons;
      if (raw.size() > 3) ++info.polygons_triangulated;
      out.add_fan(scratch_.data(), scratch_.size());
    }
    (void)first;  // an OBJ file may end anywhere: nothing to check after the last face
  }

  std::uint64_t triangle_hint() const override { return faces_; }

 private:
  /// The next statement: a line joined with its `\` continuations, without its comment.
  /// `line_no` is the number of its first line.
  bool statement(std::string_view& out, std::uint64_t& line_no) {
    if (!src_.line(out)) return false;
    line_no = src_.line_no();
    if (!out.empty() && out.back() == '\\') {
      joined_.assign(out.data(), out.size() - 1);
      std::string_view more;
      while (src_.line(more)) {
        const bool cont = !more.empty() && more.back() == '\\';
        joined_.append(more.data(), more.size() - (cont ? 1 : 0));
        joined_ += ' ';
        if (!cont) break;
      }
      out = joined_;
    }
    out = before_comment(out);
    return true;
  }

  std::uint64_t nv_ = 0, faces_ = 0;
  std::string joined_;
  std::vector<std::uint32_t> scratch_;
};

}  // namespace

std::unique_ptr<FormatParser> make_obj_parser(ByteSource& src) { return std::make_unique<ObjParser>(src); }

}  // namespace bvhbench
