#pragma once
/// Numbers in text (ASCII meshes, text files of points, the parameters of methods and query
/// kinds): the one parser of each, with std::from_chars, which is exact (correctly rounded, so a
/// value printed with 17 significant digits reads back bit-identical) and independent of the
/// locale.
#include <charconv>
#include <cstdlib>
#include <string>
#include <string_view>
#include <system_error>

namespace bvhbench {

/// Parses all of `tok` as a double (decimal or scientific, an optional sign, "nan", "inf");
/// false for anything else (empty, trailing junk, hexadecimal). Overflow reads as +-inf and
/// underflow as 0 or a subnormal, as strtod does, so that the caller can refuse a non-finite
/// value by name.
inline bool parse_double(std::string_view tok, double& out) {
  const char* b = tok.data();
  const char* end = b + tok.size();
  if (b != end && *b == '+') ++b;
  if (b == end || *b == '+') return false;
  const auto r = std::from_chars(b, end, out, std::chars_format::general);
  if (r.ptr != end) return false;
  if (r.ec == std::errc::result_out_of_range) {  // from_chars reports both as errors
    const std::string copy(tok);
    out = std::strtod(copy.c_str(), nullptr);
    return true;
  }
  return r.ec == std::errc();
}

/// Parses all of `tok` as a (signed) integer; false for anything else, or out of range.
inline bool parse_int(std::string_view tok, long long& out) {
  const char* b = tok.data();
  const char* end = b + tok.size();
  if (b != end && *b == '+') ++b;
  if (b == end || *b == '+') return false;
  auto r = std::from_chars(b, end, out);
  return r.ec == std::errc() && r.ptr == end;
}

}  // namespace bvhbench
