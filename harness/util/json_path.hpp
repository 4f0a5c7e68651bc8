#pragma once
/// Reading a value at a path of keys in JSON that may lack it (result files written by another
/// version, status rows without blocks): a missing key or a non-object on the way gives null,
/// never an exception.
#include <initializer_list>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// j[k0][k1]... or a null value when any key is missing or a step is not an object; `keys` is any
/// range of things a key can be made of (const char*, std::string).
template <class Keys>
const nlohmann::json& json_at_keys(const nlohmann::json& j, const Keys& keys) {
  static const nlohmann::json null_json;
  const nlohmann::json* p = &j;
  for (const auto& k : keys) {
    if (!p->is_object()) return null_json;
    auto it = p->find(k);
    if (it == p->end()) return null_json;
    p = &*it;
  }
  return *p;
}

/// A path written in code: json_at(r, {"job", "mesh", "name"}).
inline const nlohmann::json& json_at(const nlohmann::json& j, std::initializer_list<const char*> path) {
  return json_at_keys(j, path);
}

/// A path held at run time (a schema's field, split at its dots).
inline const nlohmann::json& json_at(const nlohmann::json& j, const std::vector<std::string>& path) {
  return json_at_keys(j, path);
}

}  // namespace bvhbench
