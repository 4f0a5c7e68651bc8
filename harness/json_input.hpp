#pragma once
/// JSON text read from a file that may come from elsewhere (a query set's sidecar, a result file
/// of `bvhbench compare`).
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// Deepest nesting of arrays and objects accepted: our files nest 5 levels deep.
inline constexpr int kMaxJsonDepth = 64;

/// Parses `text`; `name` (the file) names it in messages. Throws InputError "NAME: malformed
/// JSON: <nlohmann's reason>" (syntax, invalid UTF-8, a number too large for a double), or
/// "NAME: JSON nested deeper than 64 levels": nlohmann::json parses iteratively but copies,
/// compares and prints recursively, as does the code that walks a result, so a file of a few
/// hundred KB of '[' would otherwise overflow the stack.
nlohmann::json parse_json_input(std::string_view text, const std::string& name);

}  // namespace bvhbench
