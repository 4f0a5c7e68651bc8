#include "harness/core/params.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "harness/util/errors.hpp"

namespace bvhbench {

const char* to_string(ParamType t) {
  switch (t) {
    case ParamType::integer: return "int";
    case ParamType::real: return "real";
    case ParamType::boolean: return "bool";
    case ParamType::text: return "text";
    case ParamType::choice: return "choice";
  }
  return "?";
}

bool parse_bool(const std::string& s, bool* out) {
  std::string l = s;
  std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return std::tolower(c); });
  if (l == "1" || l == "true" || l == "yes" || l == "on") { *out = true; return true; }
  if (l == "0" || l == "false" || l == "no" || l == "off") { *out = false; return true; }
  return false;
}

namespace {

bool parse_int(const std::string& s, std::int64_t* out) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  long long v = std::strtoll(s.c_str(), &end, 10);
  if (errno != 0 || *end != '\0') return false;
  *out = v;
  return true;
}

bool parse_real(const std::string& s, double* out) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  if (errno != 0 || *end != '\0' || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

// Checks one value against its spec; returns the normalised value or throws.
std::string normalise(const std::string& method, const ParamSpec& p, const std::string& v) {
  auto bad = [&](const std::string& why) {
    return InputError("method " + method + ": parameter " + p.name + "=" + v + ": " + why);
  };
  switch (p.type) {
    case ParamType::integer: {
      std::int64_t i;
      if (!parse_int(v, &i)) throw bad("not an integer");
      if (i < p.min || i > p.max) {
        std::ostringstream os;
        os << "out of range [" << p.min << ", " << p.max << "]";
        throw bad(os.str());
      }
      return std::to_string(i);
    }
    case ParamType::real: {
      double d;
      if (!parse_real(v, &d)) throw bad("not a finite number");
      if (d < p.min || d > p.max) {
        std::ostringstream os;
        os << "out of range [" << p.min << ", " << p.max << "]";
        throw bad(os.str());
      }
      return v;
    }
    case ParamType::boolean: {
      bool b;
      if (!parse_bool(v, &b)) throw bad("not a boolean (true/false, 1/0, yes/no, on/off)");
      return b ? "true" : "false";
    }
    case ParamType::choice: {
      if (std::find(p.choices.begin(), p.choices.end(), v) == p.choices.end()) {
        std::string all;
        for (auto& c : p.choices) all += (all.empty() ? "" : ", ") + c;
        throw bad("not one of: " + all);
      }
      return v;
    }
    case ParamType::text: return v;
  }
  return v;
}

}  // namespace

Params Params::resolve(const std::string& method, const std::vector<ParamSpec>& specs,
                       const std::map<std::string, std::string>& given) {
  Params out;
  for (auto& kv : given) {
    const std::string& k = kv.first;  // a structured binding: a lambda may not capture it (C++17; clang refuses)
    auto it = std::find_if(specs.begin(), specs.end(), [&](const ParamSpec& s) { return s.name == k; });
    if (it == specs.end()) {
      std::string known;
      for (auto& s : specs) known += (known.empty() ? "" : ", ") + s.name;
      throw InputError("method " + method + ": unknown parameter '" + k + "' (known: " +
                       (known.empty() ? "none" : known) + ")");
    }
  }
  for (auto& s : specs) {
    out.defaults_[s.name] = s.default_value.empty() && s.type != ParamType::text
                                ? s.default_value
                                : normalise(method, s, s.default_value);
    auto it = given.find(s.name);
    if (it != given.end()) {
      out.values_[s.name] = normalise(method, s, it->second);
      out.given_[s.name] = it->second;
    } else {
      out.values_[s.name] = out.defaults_[s.name];
    }
  }
  return out;
}

const std::string& Params::get(const std::string& key) const {
  auto it = values_.find(key);
  if (it == values_.end()) throw std::logic_error("parameter not declared: " + key);
  return it->second;
}

std::int64_t Params::get_int(const std::string& key) const {
  std::int64_t v = 0;
  if (!parse_int(get(key), &v)) throw InputError("parameter " + key + " is not an integer");
  return v;
}

double Params::get_real(const std::string& key) const {
  double v = 0;
  if (!parse_real(get(key), &v)) throw InputError("parameter " + key + " is not a number");
  return v;
}

bool Params::get_bool(const std::string& key) const {
  bool b = false;
  if (!parse_bool(get(key), &b)) throw InputError("parameter " + key + " is not a boolean");
  return b;
}

std::string Params::non_default_string() const {
  std::string s;
  for (auto& [k, v] : values_) {
    auto d = defaults_.find(k);
    if (d != defaults_.end() && d->second == v) continue;
    s += (s.empty() ? "" : ",") + k + "=" + v;
  }
  return s;
}

}  // namespace bvhbench
