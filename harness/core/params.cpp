#include "harness/core/params.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <sstream>

#include "harness/util/errors.hpp"
#include "harness/util/nearest_word.hpp"
#include "harness/util/text_number.hpp"

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

const char* to_string(ParamRole r) { return r == ParamRole::build ? "build" : "query"; }

std::string ParamValue::canonical() const {
  switch (type) {
    case ParamType::integer: return std::to_string(integer);
    case ParamType::real: {
      // The shortest text that reads back to the same double: one configuration, one key.
      std::array<char, 32> buf{};
      auto res = std::to_chars(buf.data(), buf.data() + buf.size(), real);
      return std::string(buf.data(), res.ptr);
    }
    case ParamType::boolean: return boolean ? "true" : "false";
    case ParamType::text:
    case ParamType::choice: return text;
  }
  return text;
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
  long long v = 0;
  if (!bvhbench::parse_int(s, v)) return false;
  *out = v;
  return true;
}

bool parse_real(const std::string& s, double* out) {
  return parse_double(s, *out) && std::isfinite(*out);
}

// What a value out of p's range should have been: "out of range [a, b]", "must be > a", ...
std::string range_text(const ParamSpec& p) {
  const bool has_min = p.min > -1e308, has_max = p.max < 1e308;
  std::ostringstream os;
  if (has_min && has_max)
    os << "out of range " << (p.min_excluded ? "(" : "[") << p.min << ", " << p.max << "]";
  else if (has_min)
    os << "must be " << (p.min_excluded ? "> " : ">= ") << p.min;
  else
    os << "must be <= " << p.max;
  return os.str();
}

// Checks one value against its spec; returns it typed or throws.
ParamValue typed_value(const std::string& owner, const ParamSpec& p, const std::string& v) {
  auto bad = [&](const std::string& why) {
    return InputError(owner + ": parameter " + p.name + "=" + v + ": " + why);
  };
  ParamValue out;
  out.type = p.type;
  auto range = [&](double x) {
    if (x < p.min || x > p.max || (p.min_excluded && x == p.min)) throw bad(range_text(p));
  };
  // A number may be declared with choices too (e.g. 1, 3 or 5 rays): its canonical text must be one.
  auto one_of = [&](const ParamValue& x) {
    if (!p.choices.empty() && std::find(p.choices.begin(), p.choices.end(), x.canonical()) == p.choices.end()) {
      std::string all;
      for (auto& c : p.choices) all += (all.empty() ? "" : ", ") + c;
      throw bad("not one of: " + all);
    }
  };
  switch (p.type) {
    case ParamType::integer:
      if (!parse_int(v, &out.integer)) throw bad("not an integer");
      range(double(out.integer));
      one_of(out);
      return out;
    case ParamType::real:
      if (!parse_real(v, &out.real)) throw bad("not a finite number");
      range(out.real);
      one_of(out);
      return out;
    case ParamType::boolean:
      if (!parse_bool(v, &out.boolean)) throw bad("not a boolean (true/false, 1/0, yes/no, on/off)");
      return out;
    case ParamType::choice:
      if (std::find(p.choices.begin(), p.choices.end(), v) == p.choices.end()) {
        std::string all;
        for (auto& c : p.choices) all += (all.empty() ? "" : ", ") + c;
        throw bad("not one of: " + all);
      }
      out.text = v;
      return out;
    case ParamType::text: out.text = v; return out;
  }
  return out;
}

}  // namespace

namespace {

// An unknown key: the declared ones and, when one is close, the one probably meant.
InputError unknown_parameter(const std::string& owner, const std::vector<ParamSpec>& specs, const std::string& key) {
  std::string known;
  std::vector<std::string> names;
  for (auto& s : specs) {
    known += (known.empty() ? "" : ", ") + s.name;
    names.push_back(s.name);
  }
  const std::string nearest = nearest_word(key, names);
  return InputError(owner + ": unknown parameter '" + key + "' (" +
                    (nearest.empty() ? "" : "did you mean '" + nearest + "'? ") + "known: " +
                    (known.empty() ? "none" : known) + ")");
}

}  // namespace

Params Params::resolve_for(const std::string& owner, const std::vector<ParamSpec>& specs,
                           const std::map<std::string, std::string>& given) {
  Params out;
  for (auto& kv : given) {
    const std::string& k = kv.first;  // a structured binding: a lambda may not capture it (C++17; clang refuses)
    auto it = std::find_if(specs.begin(), specs.end(), [&](const ParamSpec& s) { return s.name == k; });
    if (it == specs.end()) throw unknown_parameter(owner, specs, k);
  }
  for (auto& s : specs) {
    out.defaults_[s.name] = typed_value(owner, s, s.default_value);
    auto it = given.find(s.name);
    if (it != given.end()) {
      out.values_[s.name] = typed_value(owner, s, it->second);
      out.given_[s.name] = it->second;
    } else {
      out.values_[s.name] = out.defaults_[s.name];
    }
  }
  return out;
}

Params Params::with_values(const std::string& method, const std::vector<ParamSpec>& specs,
                           const std::map<std::string, std::string>& read) const {
  Params out = *this;
  for (const auto& [k, text] : read) {
    auto it = std::find_if(specs.begin(), specs.end(), [&](const ParamSpec& s) { return s.name == k; });
    if (it == specs.end()) throw std::logic_error("method " + method + " read an undeclared option " + k);
    out.values_[k] = typed_value("method " + method, *it, text);
  }
  return out;
}

const ParamValue& Params::value(const std::string& key) const {
  auto it = values_.find(key);
  if (it == values_.end()) throw std::logic_error("parameter not declared: " + key);
  return it->second;
}

namespace {
const ParamValue& typed(const ParamValue& v, ParamType want, const std::string& key) {
  if (v.type != want) throw std::logic_error("parameter " + key + " is declared " + to_string(v.type) +
                                             ", read as " + to_string(want));
  return v;
}
}  // namespace

const std::string& Params::get(const std::string& key) const {
  const ParamValue& v = value(key);
  if (v.type != ParamType::text && v.type != ParamType::choice)
    throw std::logic_error("parameter " + key + " is declared " + to_string(v.type) + ", read as text");
  return v.text;
}

std::int64_t Params::get_int(const std::string& key) const {
  return typed(value(key), ParamType::integer, key).integer;
}

double Params::get_real(const std::string& key) const { return typed(value(key), ParamType::real, key).real; }

bool Params::get_bool(const std::string& key) const {
  return typed(value(key), ParamType::boolean, key).boolean;
}

std::map<std::string, std::string> Params::values() const {
  std::map<std::string, std::string> out;
  for (const auto& [k, v] : values_) out[k] = v.canonical();
  return out;
}

std::string Params::non_default_string() const {
  return non_default_where([](const std::string&) { return true; });
}

std::string Params::non_default_string(const std::set<std::string>& only) const {
  return non_default_where([&](const std::string& key) { return only.count(key) != 0; });
}

template <class Keep>
std::string Params::non_default_where(Keep keep) const {
  std::string s;
  for (auto& [k, v] : values_) {
    if (!keep(k)) continue;
    auto d = defaults_.find(k);
    if (d != defaults_.end() && d->second == v) continue;
    s += (s.empty() ? "" : ",") + k + "=" + v.canonical();
  }
  return s;
}

}  // namespace bvhbench
