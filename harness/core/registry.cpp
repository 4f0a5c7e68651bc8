#include "harness/core/registry.hpp"

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
void Method::inside_batch(const std::vector<Vec3d>&, std::vector<std::uint8_t>&) {
  throw UnsupportedError("inside queries in batches are not supported");
}
void Method::distance_batch(const std::vector<Vec3d>&, std::vector<DistanceResult>&) {
  throw UnsupportedError("distance queries in batches are not supported");
}

void Registry::add(MethodInfo info) {
  if (find(info.name)) throw std::logic_error("method registered twice: " + info.name);
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

const Registry& Registry::global() {
  static const Registry r = [] {
    Registry reg;
    register_all_methods(reg);
    return reg;
  }();
  return r;
}

}  // namespace bvhbench
