#include "harness/core/registry.hpp"

#include <algorithm>
#include <set>
#include <stdexcept>

#include "harness/util/errors.hpp"

namespace bvhbench {

const char* to_string(QueryType q) { return q == QueryType::inside ? "inside" : "distance"; }

QueryType parse_query_type(const std::string& s) {
  if (s == "inside") return QueryType::inside;
  if (s == "distance") return QueryType::distance;
  throw InputError("query type '" + s + "': expected 'inside' or 'distance'");
}

bool QueryState::inside(const Vec3d&) { throw UnsupportedError("inside queries are not supported"); }
DistanceResult QueryState::distance(const Vec3d&) {
  throw UnsupportedError("distance queries are not supported");
}

void Method::set_query_options(const Params&) {
  throw std::logic_error("set_query_options on a method that does not declare query_options_after_build");
}

void Method::open(const MeshSummary&, const BuildContext&) {
  throw std::logic_error("open on a method that does not read its structure from a file");
}

std::string structure_key(const MethodSpec& spec) {
  if (!spec.resolved()) return std::string();
  if (!spec.info->caps.query_options_after_build) return spec.params_key();
  std::set<std::string> build_options;
  for (const ParamSpec& p : spec.info->params)
    if (p.role == ParamRole::build) build_options.insert(p.name);
  return spec.params.non_default_string(build_options);
}

bool answers(const MethodInfo& info, const Method& method, QueryType q) {
  return (q == QueryType::inside ? info.caps.inside : info.caps.distance) && method.supports(q);
}

std::string sweep_problem(const MethodInfo& m) {
  for (const std::string& entry : m.sweep) {
    try {
      const MethodSpec spec = parse_method_spec(entry.empty() ? m.name : m.name + ":" + entry);
      const Params p = Params::resolve(m.name, m.params, spec.given);
      if (m.check) m.check(p);
    } catch (const InputError& e) {
      return "'" + entry + "': " + e.what();
    }
  }
  return "";
}

// Path coherence is one concept with one spelling (its variant is a row of its own,
// docs/architecture.md, "Path coherence").
std::string inside_declaration_problem(const MethodInfo& m) {
  auto declared = [&](const std::string& name) -> const ParamSpec* {
    for (const ParamSpec& p : m.params)
      if (p.name == name) return &p;
    return nullptr;
  };
  for (const InsideVariant& v : m.inside) {
    for (const auto& [key, value] : v.when)
      if (!declared(key)) return "inside declaration: '" + key + "' is not an option of " + m.name;
    if (v.threshold_option.empty()) continue;
    const ParamSpec* t = declared(v.threshold_option);
    if (!t || t->type != ParamType::real)
      return "inside declaration: threshold option '" + v.threshold_option + "' is not a real option of " + m.name;
  }
  return "";
}

std::string coherence_problem(const MethodInfo& m) {
  const auto it = std::find_if(m.params.begin(), m.params.end(), [](const ParamSpec& p) { return p.name == "coherent"; });
  const bool declared = it != m.params.end();
  if (m.caps.coherence && !declared) return "has the coherence capability but no `coherent` option";
  if (!m.caps.coherence && declared) return "declares `coherent` without the coherence capability";
  if (declared && (it->type != ParamType::boolean || it->role != ParamRole::query || it->default_value != "false"))
    return "declares `coherent` other than as a boolean query option, false by default";
  return "";
}

void Registry::add(MethodInfo info) {
  if (find(info.name)) throw std::logic_error("method registered twice: " + info.name);
  if (const std::string bad = coherence_problem(info); !bad.empty())
    throw std::logic_error("method " + info.name + " " + bad);
  if (const std::string bad = sweep_problem(info); !bad.empty())
    throw std::logic_error("method " + info.name + ": sweep entry " + bad);
  if (const std::string bad = inside_declaration_problem(info); !bad.empty())
    throw std::logic_error("method " + info.name + ": " + bad);
  methods_.push_back(std::move(info));
}

void Registry::add_command(CommandInfo cmd) { commands_.push_back(std::move(cmd)); }

void Registry::add_left_out(const std::string& name, const std::string& why) {
  left_out_.emplace_back(name, why);
}

const MethodInfo* Registry::find(const std::string& name) const {
  for (auto& m : methods_)
    if (m.name == name) return &m;
  return nullptr;
}

bool Registry::is_left_out(const std::string& name) const {
  for (const auto& entry : left_out_)
    if (entry.first == name) return true;
  return false;
}

MethodSpec Registry::describe(const std::string& text) const {
  MethodSpec spec;
  try {
    spec = parse_method_spec(text);
  } catch (const InputError& e) {
    spec.text = spec.name = text;
    spec.problem = e.what();
    return spec;
  }
  const MethodInfo* m = find(spec.name);
  if (!m) {
    for (const auto& [name, why] : left_out_)
      if (name == spec.name) {
        spec.problem = "method '" + name + "' is not available in this build: " + why;
        return spec;
      }
    std::string known;
    for (auto& k : methods_)
      if (!k.testing_only) known += (known.empty() ? "" : ", ") + k.name;
    spec.problem = "unknown method '" + spec.name + "' (known: " + known + ")";
    return spec;
  }
  try {
    spec.params = Params::resolve(spec.name, m->params, spec.given);
    if (m->check) m->check(spec.params);
  } catch (const InputError& e) {
    spec.problem = e.what();
    return spec;
  }
  spec.info = m;
  return spec;
}

MethodSpec Registry::resolve(const std::string& text) const {
  MethodSpec spec = describe(text);
  if (!spec.resolved()) throw InputError(spec.problem);
  return spec;
}

std::unique_ptr<Method> Registry::create(const MethodSpec& spec) const {
  if (!spec.resolved()) throw InputError(spec.problem.empty() ? "method spec '" + spec.text + "' is not resolved" : spec.problem);
  return spec.info->create(spec.params);
}

std::unique_ptr<Method> Registry::create(const std::string& text) const { return create(resolve(text)); }

std::vector<std::string> Registry::all_method_specs(const std::vector<std::string>& except) const {
  std::vector<std::string> out;
  for (const MethodInfo& m : methods_) {
    if (m.testing_only || std::find(except.begin(), except.end(), m.name) != except.end()) continue;
    for (const std::string& entry : m.sweep) out.push_back(entry.empty() ? m.name : m.name + ":" + entry);
  }
  return out;
}

const Registry& Registry::global() {
  static const Registry r = [] {
    Registry reg;
    register_all_methods(reg);
    return reg;
  }();
  return r;
}

}  // namespace bvhbench
