#pragma once
/// Text that is safe to show and to store: whatever a reader quotes from a file (a header line, a
/// token) may hold any bytes, but a message goes to a terminal and into a result JSON, which must
/// be valid UTF-8. These helpers keep valid UTF-8 as it is and write everything else as `\xNN`.
#include <cstddef>
#include <string>
#include <string_view>

namespace bvhbench {

/// `s` with each byte that is not part of a valid UTF-8 sequence (stray continuation bytes,
/// overlong forms, surrogates, code points above U+10FFFF, truncated sequences) and each ASCII
/// control character but tab and newline written as `\xNN` (two upper-case hex digits). Valid
/// UTF-8 without control characters comes back unchanged, so applying it twice changes nothing.
std::string printable(std::string_view s);

/// A token or line quoted from a file for a message: `'...'`, printable, at most `max_chars`
/// bytes of `s` (then `...`), never cutting a UTF-8 sequence in two.
std::string quoted_excerpt(std::string_view s, std::size_t max_chars = 40);

}  // namespace bvhbench
