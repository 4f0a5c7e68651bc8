#include "harness/core/inside_definition.hpp"

#include <array>
#include <sstream>
#include <utility>

#include "harness/core/params.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {

namespace {

constexpr std::array<std::pair<InsideRule, const char*>, 5> kRules{{
    {InsideRule::undeclared, "undeclared"},
    {InsideRule::ray_parity, "ray_parity"},
    {InsideRule::winding_number, "winding_number"},
    {InsideRule::nonzero_winding, "nonzero_winding"},
    {InsideRule::generalized_winding_number, "generalized_winding_number"},
}};

constexpr std::array<std::pair<InputContract, const char*>, 6> kContracts{{
    {InputContract::undeclared, "undeclared"},
    {InputContract::any, "any"},
    {InputContract::closed, "closed"},
    {InputContract::closed_oriented, "closed_oriented"},
    {InputContract::closed_oriented_manifold, "closed_oriented_manifold"},
    {InputContract::embedded, "embedded"},
}};

template <class E, std::size_t N>
E parse_name(const std::array<std::pair<E, const char*>, N>& names, const std::string& s, const std::string& what) {
  std::string known;
  for (const auto& [e, name] : names) {
    if (s == name) return e;
    known += (known.empty() ? "" : ", ") + std::string(name);
  }
  throw InputError(what + ": '" + s + "' is not one of " + known);
}

const char* rule_words(InsideRule r) {
  switch (r) {
    case InsideRule::ray_parity: return "ray parity";
    case InsideRule::winding_number: return "winding number > 1/2";
    case InsideRule::nonzero_winding: return "nonzero winding number";
    case InsideRule::generalized_winding_number: return "generalized winding number";
    default: return "not declared";
  }
}

const char* contract_words(InputContract c) {
  switch (c) {
    case InputContract::any: return "any triangle soup";
    case InputContract::closed: return "closed";
    case InputContract::closed_oriented: return "closed, consistently oriented";
    case InputContract::closed_oriented_manifold: return "closed, consistently oriented, manifold";
    case InputContract::embedded: return "closed, outward, manifold, not self-intersecting";
    default: return "not declared";
  }
}

}  // namespace

const char* to_string(InsideRule r) {
  for (const auto& [e, name] : kRules)
    if (e == r) return name;
  return "undeclared";
}

const char* to_string(InputContract c) {
  for (const auto& [e, name] : kContracts)
    if (e == c) return name;
  return "undeclared";
}

InsideRule parse_inside_rule(const std::string& s, const std::string& what) { return parse_name(kRules, s, what); }

InputContract parse_input_contract(const std::string& s, const std::string& what) {
  return parse_name(kContracts, s, what);
}

nlohmann::json InsideDefinition::to_json() const {
  return {{"definition", to_string(rule)},
          {"approximate", approximate},
          {"threshold", rule == InsideRule::generalized_winding_number ? nlohmann::json(threshold) : nlohmann::json(nullptr)},
          {"contract", to_string(contract)}};
}

std::string InsideDefinition::text() const {
  std::ostringstream o;
  o << rule_words(rule);
  if (rule == InsideRule::generalized_winding_number) o << " > " << threshold;
  if (approximate) o << " (approximate)";
  o << "; input: " << contract_words(contract);
  return o.str();
}

InsideDefinition resolve_inside(const std::vector<InsideVariant>& declaration, const Params& params) {
  const auto values = params.values();
  for (const InsideVariant& v : declaration) {
    bool match = true;
    for (const auto& [key, value] : v.when) {
      auto it = values.find(key);
      match = match && it != values.end() && it->second == value;
    }
    if (!match) continue;
    InsideDefinition d = v.definition;
    if (!v.threshold_option.empty()) d.threshold = params.get_real(v.threshold_option);
    return d;
  }
  return {};
}

nlohmann::json declaration_json(const std::vector<InsideVariant>& declaration) {
  nlohmann::json out = nlohmann::json::array();
  for (const InsideVariant& v : declaration) {
    nlohmann::json j = v.definition.to_json();
    j["when"] = v.when;
    if (!v.threshold_option.empty()) j["threshold"] = "the option " + v.threshold_option;
    out.push_back(j);
  }
  return out;
}

}  // namespace bvhbench
