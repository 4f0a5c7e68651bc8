#pragma once
/// Tokens and numbers of the text mesh formats (ASCII PLY, OBJ, ASCII STL, OFF), parsed with
/// from_chars: exact, locale-independent, and strict (a token is a number only if all of it is).
/// parse_double and parse_int are text_number.hpp's, shared with the text files of points and
/// the parameters of methods and query kinds.
#include <charconv>
#include <string_view>
#include <system_error>

#include "harness/util/text_number.hpp"

namespace bvhbench {

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

/// `s` without leading and trailing whitespace.
inline std::string_view strip(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

/// `s` up to its first '#' (a comment to the end of the line in OBJ and OFF).
inline std::string_view before_comment(std::string_view s) { return s.substr(0, s.find('#')); }

/// True if `s` holds a byte that no text mesh file has (a control character other than tab,
/// CR, LF, FF, VT): binary data.
inline bool has_control_bytes(std::string_view s) {
  for (char c : s) {
    const unsigned char u = static_cast<unsigned char>(c);
    if ((u < 32 && !is_space(c) && c != '\n') || u == 127) return true;
  }
  return false;
}

}  // namespace bvhbench
