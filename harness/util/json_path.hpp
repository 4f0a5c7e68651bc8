#pragma once
/// Reading a value at a path of keys in JSON that may lack it (result files written by another
/// version, status rows without blocks): a missing key or a non-object on the way gives null,
/// never an exception.
#include <initializer_list>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// j[k0][k1]... or a null value when any key is missing or a step is not an object.
inline const nlohmann::json& json_at(const nlohmann::json& j, std::initializer_list<const char*> path) {
  static const nlohmann::json null_json;
  const nlohmann::json* p = &j;
  for (const char* k : path) {
    if (!p->is_object()) return null_json;
    auto it = p->find(k);
    if (it == p->end()) return null_json;
    p = &*it;
  }
  return *p;
}

/// The same for a path held at run time (a schema's field, split at its dots).
inline const nlohmann::json& json_at(const nlohmann::json& j, const std::vector<std::string>& path) {
  static const nlohmann::json null_json;
  const nlohmann::json* p = &j;
  for (const std::string& k : path) {
    if (!p->is_object()) return null_json;
    auto it = p->find(k);
    if (it == p->end()) return null_json;
    p = &*it;
  }
  return *p;
}

}  // namespace bvhbench
