#include "harness/util/printable.hpp"

namespace bvhbench {

namespace {

/// Length of the valid UTF-8 sequence that starts at s[i] (1 to 4), or 0 if none starts there
/// (RFC 3629: no overlong forms, no surrogates, nothing above U+10FFFF).
std::size_t utf8_sequence_length(std::string_view s, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char b0 = byte(i);
  if (b0 < 0x80) return 1;
  std::size_t n;
  unsigned char lo = 0x80, hi = 0xBF;  // allowed range of the second byte
  if (b0 >= 0xC2 && b0 <= 0xDF) n = 2;
  else if (b0 == 0xE0) { n = 3; lo = 0xA0; }
  else if (b0 == 0xED) { n = 3; hi = 0x9F; }
  else if (b0 >= 0xE1 && b0 <= 0xEF) n = 3;
  else if (b0 == 0xF0) { n = 4; lo = 0x90; }
  else if (b0 == 0xF4) { n = 4; hi = 0x8F; }
  else if (b0 >= 0xF1 && b0 <= 0xF3) n = 4;
  else return 0;
  if (i + n > s.size()) return 0;
  if (byte(i + 1) < lo || byte(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  return n;
}

void append_escaped(std::string& out, unsigned char b) {
  static const char hex[] = "0123456789ABCDEF";
  out += "\\x";
  out += hex[b >> 4];
  out += hex[b & 15];
}

std::string escape(std::string_view s, bool keep_tab_and_newline) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char b = static_cast<unsigned char>(s[i]);
    const std::size_t n = utf8_sequence_length(s, i);
    if (n == 0 || (n == 1 && ((b < 0x20 && !(keep_tab_and_newline && (b == '\t' || b == '\n'))) || b == 0x7F))) {
      append_escaped(out, b);
      ++i;
    } else {
      out.append(s, i, n);
      i += n;
    }
  }
  return out;
}

}  // namespace

std::string printable(std::string_view s) { return escape(s, true); }

std::string quoted_excerpt(std::string_view s, std::size_t max_chars) {
  std::size_t cut = 0;
  while (cut < s.size() && cut < max_chars) {
    const std::size_t n = utf8_sequence_length(s, cut);
    if (n > 1 && cut + n > max_chars) break;
    cut += n ? n : 1;
  }
  std::string out = "'" + escape(s.substr(0, cut), false);
  if (cut < s.size()) out += "...";
  return out + "'";
}

}  // namespace bvhbench
