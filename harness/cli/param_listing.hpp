#pragma once
/// Typed parameters as `bvhbench methods` and `bvhbench kinds` list them (params.hpp): one JSON
/// object or one text line per declared parameter, the same for a method's options and a query
/// kind's generator parameters.
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/params.hpp"

namespace bvhbench {

/// Every parameter of `specs` as JSON: name, type, role, default (canonical, as results record
/// it), help, and choices, min, max (and min_excluded) where declared. `owner` names them in a
/// message should a default not satisfy its own declaration (a programming error).
nlohmann::json params_json(const std::string& owner, const std::vector<ParamSpec>& specs);

/// The same as text, one indented line per parameter: "  name = default (type, role) help".
void print_params(std::ostream& os, const std::string& owner, const std::vector<ParamSpec>& specs);

}  // namespace bvhbench
