// Text files of points: the format is described in points_text.hpp. The file is read in large
// pieces and split into lines here (a 30M-point path is about 1.5 GB of text); each line is
// parsed in place, without copies, unless it straddles two pieces.
#include "points_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string_view>

#include "binary_file.hpp"
#include "errors.hpp"
#include "text_number.hpp"

namespace bvhbench {

namespace {

constexpr std::size_t kMaxLine = 64 * 1024;  // longer: not a file of points (or a binary file)

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

/// The fields of a line without its comment: split at commas if it has one (each field
/// trimmed; fields may be empty), else at runs of blanks.
void split_fields(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  if (line.find(',') != std::string_view::npos) {
    for (std::size_t start = 0;;) {
      const std::size_t comma = line.find(',', start);
      out.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
      if (comma == std::string_view::npos) return;
      start = comma + 1;
    }
  }
  for (std::size_t i = 0; i < line.size();) {
    while (i < line.size() && is_blank(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !is_blank(line[j])) ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
}

class PointLines {
 public:
  explicit PointLines(const std::string& path) : path_(path) {}

  /// One line, without its '\n'; `number` counts from 1.
  void take(std::string_view s, std::uint64_t number) {
    if (number == 1 && s.substr(0, 3) == "\xEF\xBB\xBF") s.remove_prefix(3);  // UTF-8 BOM
    s = trim(s.substr(0, s.find('#')));
    if (s.empty()) return;
    split_fields(s, fields_);
    if (!seen_content_) {
      seen_content_ = true;
      double ignored;
      if (std::none_of(fields_.begin(), fields_.end(), [&](std::string_view f) { return parse_double(f, ignored); })) {
        header_ = "line " + std::to_string(number) + ": " + quoted_excerpt(s);
        return;
      }
    }
    if (columns_ == 0) {
      if (fields_.size() < 3)
        fail(number, "expected at least 3 values (x y z), found " + std::to_string(fields_.size()));
      columns_ = fields_.size();
      columns_line_ = number;
    } else if (fields_.size() != columns_) {
      fail(number, std::to_string(fields_.size()) + " values, but the first point (line " +
                       std::to_string(columns_line_) + ") has " + std::to_string(columns_));
    }
    double v[3];
    for (int k = 0; k < 3; ++k) {
      const std::string column = "column " + std::to_string(k + 1);
      if (fields_[k].empty()) fail(number, "no value in " + column);
      if (!parse_double(fields_[k], v[k])) fail(number, quoted_excerpt(fields_[k]) + " in " + column + " is not a number");
    }
    for (double x : v)
      if (!std::isfinite(x))
        fail(number, "point " + std::to_string(points_.size()) + " has " +
                         (std::isnan(x) ? "a NaN coordinate" : "an infinite coordinate"));
    points_.emplace_back(v[0], v[1], v[2]);
  }

  std::vector<Vec3d> finish() {
    if (points_.empty())
      throw file_error(path_, header_.empty() ? "no points (expected one point, x y z, a line)"
                                              : "no points after the header (" + header_ + ")");
    return std::move(points_);
  }

  [[noreturn]] void fail(std::uint64_t number, const std::string& what) const {
    throw file_error(path_, "line " + std::to_string(number) + ": " + what);
  }

 private:
  const std::string& path_;
  bool seen_content_ = false;  // a line that is neither blank nor a comment
  std::string header_;         // where the header was and what it said, for messages
  std::size_t columns_ = 0;
  std::uint64_t columns_line_ = 0;
  std::vector<std::string_view> fields_;
  std::vector<Vec3d> points_;
};

std::vector<Vec3d> read_lines(InputFile& f, std::size_t piece_bytes) {
  PointLines lines(f.path());
  std::vector<char> buf(std::max<std::size_t>(piece_bytes, 1));
  std::string carry;  // the start of a line that continues in the next piece
  std::uint64_t number = 0;
  auto too_long = [&] { lines.fail(number + 1, "longer than " + std::to_string(kMaxLine) + " bytes (not a text file of points?)"); };
  for (std::uint64_t offset = 0; offset < f.size();) {
    const std::size_t n = std::size_t(std::min<std::uint64_t>(buf.size(), f.size() - offset));
    f.read_at(offset, buf.data(), n, "the text");
    offset += n;
    std::string_view piece(buf.data(), n);
    for (;;) {
      const std::size_t nl = piece.find('\n');
      const std::string_view part = piece.substr(0, nl);
      if (carry.size() + part.size() > kMaxLine) too_long();
      if (nl == std::string_view::npos) {
        carry.append(part);
        break;
      }
      if (carry.empty()) {
        lines.take(part, ++number);
      } else {
        carry.append(part);
        lines.take(carry, ++number);
        carry.clear();
      }
      piece.remove_prefix(nl + 1);
    }
  }
  if (!carry.empty()) lines.take(carry, ++number);
  return lines.finish();
}

}  // namespace

std::vector<Vec3d> read_points_text(const std::string& path) {
  InputFile f(path);
  return read_lines(f, std::size_t(1) << 20);
}

std::vector<Vec3d> parse_points_text(std::string_view text, const std::string& name, std::size_t piece_bytes) {
  InputFile f(text, name);
  return read_lines(f, piece_bytes);
}

}  // namespace bvhbench
