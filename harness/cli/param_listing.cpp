// Typed parameters listed as JSON or text (param_listing.hpp).
#include "harness/cli/param_listing.hpp"

#include <iomanip>

namespace bvhbench {

nlohmann::json params_json(const std::string& owner, const std::vector<ParamSpec>& specs) {
  const auto defaults = Params::resolve_for(owner, specs, {}).values();
  nlohmann::json ps = nlohmann::json::array();
  for (auto& p : specs) {
    nlohmann::json pj = {{"name", p.name},                  {"type", to_string(p.type)}, {"role", to_string(p.role)},
                         {"default", defaults.at(p.name)}, {"help", p.help}};
    if (!p.choices.empty()) pj["choices"] = p.choices;
    if (p.type == ParamType::integer || p.type == ParamType::real) {
      if (p.min > -1e308) pj["min"] = p.min;
      if (p.max < 1e308) pj["max"] = p.max;
      if (p.min_excluded) pj["min_excluded"] = true;
    }
    ps.push_back(pj);
  }
  return ps;
}

void print_params(std::ostream& os, const std::string& owner, const std::vector<ParamSpec>& specs) {
  if (specs.empty()) os << "  parameters: none\n";
  const auto defaults = Params::resolve_for(owner, specs, {}).values();
  for (auto& p : specs) {
    std::string type = to_string(p.type);
    if (!p.choices.empty()) {
      type.clear();
      for (auto& c : p.choices) type += (type.empty() ? "" : "|") + c;
    }
    os << "  " << std::left << std::setw(18) << p.name << std::setw(22) << ("= " + defaults.at(p.name)) << "("
       << type << ", " << to_string(p.role) << ") " << p.help << "\n";
  }
}

}  // namespace bvhbench
