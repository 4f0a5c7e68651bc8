#pragma once
/// How `compare` writes values and changes, in its JSON verdicts and its Markdown alike.
#include <cstdio>
#include <cstdlib>
#include <string>

#include <nlohmann/json.hpp>

namespace bvhbench::compare_format {

/// A JSON string's text, or the fallback for anything else.
inline std::string str(const nlohmann::json& j, const std::string& fallback = "") {
  return j.is_string() ? j.get<std::string>() : fallback;
}

/// printf-style, for a figure shown to a reader.
inline std::string fmt(double v, const char* f = "%.6g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

/// The shortest decimal that reads back as the same double: exact, and readable.
inline std::string shortest(double v) {
  for (int prec = 6; prec < 17; ++prec) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) return buf;
  }
  return fmt(v, "%.17g");
}

/// A value as shown in a change: "(none)" for null, the shortest exact decimal for a float.
inline std::string show(const nlohmann::json& v) {
  if (v.is_null()) return "(none)";
  if (v.is_number_float()) return shortest(v.get<double>());
  return v.dump();
}

/// "a -> b", and the relative change in percent when both are numbers.
inline std::string change_text(const nlohmann::json& a, const nlohmann::json& b) {
  std::string s = show(a) + " -> " + show(b);
  if (a.is_number() && b.is_number() && a.get<double>() != 0)
    s += " (" + fmt(100.0 * (b.get<double>() / a.get<double>() - 1), "%+.3g") + "%)";
  return s;
}

}  // namespace bvhbench::compare_format
