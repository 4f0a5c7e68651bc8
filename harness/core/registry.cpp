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

bool Method::inside(const Vec3d&) { throw UnsupportedError("inside queries are not supported"); }
DistanceResult Method::distance(const Vec3d&) {
  throw UnsupportedError("distance queries are not supported");
}

void Registry::add(MethodInfo info) {
  if (find(info.name)) throw std::logic_error("method registered twice: " + info.name);
  methods_.push_back(std::move(info));
}

void Registry::add_command(CommandInfo cmd) { commands_.push_back(std::move(cmd)); }

const MethodInfo* Registry::find(const std::string& name) const {
  for (auto& m : methods_)
    if (m.name == name) return &m;
  return nullptr;
}

std::unique_ptr<Method> Registry::create(const std::string& spec, const MethodInfo** info,
                                         Params* resolved) const {
  std::string name;
  std::map<std::string, std::string> given;
  parse_method_spec(spec, &name, &given);
  const MethodInfo* m = find(name);
  if (!m) {
    std::string known;
    for (auto& k : methods_)
      if (!k.testing_only) known += (known.empty() ? "" : ", ") + k.name;
    throw InputError("unknown method '" + name + "' (known: " + known + ")");
  }
  Params p = Params::resolve(name, m->params, given);
  auto method = m->create(p);
  if (info) *info = m;
  if (resolved) *resolved = p;
  return method;
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
