#include "harness/run/result_schema.hpp"

#include <algorithm>
#include <functional>
#include <stdexcept>

#include "harness/util/errors.hpp"
#include "result_schema_text.hpp"  // generated: kResultSchemaText, the text of result_schema.json

using json = nlohmann::json;

namespace bvhbench {

std::vector<std::string> split_field_path(const std::string& path) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t dot = path.find('.', start);
    out.push_back(path.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (dot == std::string::npos) return out;
    start = dot + 1;
  }
}

namespace {

std::vector<std::string> split_path(const std::string& path) { return split_field_path(path); }

std::string join_path(const std::vector<std::string>& keys) {
  std::string s;
  for (const std::string& k : keys) s += (s.empty() ? "" : ".") + k;
  return s;
}

bool matches(const std::vector<std::string>& pattern, const std::vector<std::string>& path) {
  if (pattern.size() != path.size()) return false;
  for (std::size_t i = 0; i < path.size(); ++i)
    if (pattern[i] != "*" && pattern[i] != path[i]) return false;
  return true;
}

bool nullable(const std::string& type) { return type.size() > 5 && type.compare(type.size() - 5, 5, "|null") == 0; }

std::string base_type(const std::string& type) { return nullable(type) ? type.substr(0, type.size() - 5) : type; }

bool has_type(const json& v, const std::string& type) {
  if (v.is_null()) return nullable(type) || base_type(type) == "any";
  const std::string t = base_type(type);
  if (t == "any") return true;
  if (t == "string") return v.is_string();
  if (t == "integer") return v.is_number_integer();
  if (t == "number") return v.is_number();
  if (t == "boolean") return v.is_boolean();
  if (t == "object") return v.is_object();
  if (t.rfind("array<", 0) == 0 && t.back() == '>') {
    if (!v.is_array()) return false;
    const std::string item = t.substr(6, t.size() - 7);
    for (const json& x : v)
      if (x.is_null() || !has_type(x, item)) return false;
    return true;
  }
  return false;
}

std::string a_type(const std::string& type) {
  std::string t = base_type(type);
  std::string article = (t == "integer" || t == "object" || t.rfind("array", 0) == 0) ? "an " : "a ";
  if (t.rfind("array<", 0) == 0) t = "array of " + t.substr(6, t.size() - 7) + "s";
  return article + t + (nullable(type) ? " or null" : "");
}

}  // namespace

ResultSchema ResultSchema::parse(std::string_view text) {
  ResultSchema s;
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::exception& e) {
    throw std::invalid_argument(std::string("result schema: malformed JSON: ") + e.what());
  }
  try {
    s.version_ = doc.at("schema").get<std::string>();
    for (auto& [path, f] : doc.at("fields").items())
      s.fields_.push_back({path, f.at("type").get<std::string>(), f.at("required").get<std::string>(),
                           f.value("doc", std::string()), f.value("enum", std::vector<std::string>())});
    for (const json& c : doc.at("summary_csv")) {
      SummaryColumn col;
      col.column = c.at("column").get<std::string>();
      col.field = c.value("field", std::string());
      col.or_stem_of = c.value("or_stem_of", std::string());
      if (c.contains("ratio")) for (int i = 0; i < 2; ++i) col.ratio_of[i] = c["ratio"].at(i).get<std::string>();
      if (c.contains("share")) for (int i = 0; i < 2; ++i) col.share_of[i] = c["share"].at(i).get<std::string>();
      s.columns_.push_back(col);
    }
  } catch (const json::exception& e) {
    throw std::invalid_argument(std::string("result schema: ") + e.what());
  }
  return s;
}

const ResultSchema& ResultSchema::get() {
  static const ResultSchema s = parse(kResultSchemaText);
  return s;
}

const std::vector<std::string>& ResultSchema::statuses() const {
  for (const ResultField& f : fields_)
    if (f.path == "status") return f.values;
  throw std::logic_error("result schema without a status field");
}

const ResultField* ResultSchema::describe(const std::vector<std::string>& path) const {
  if (path.empty()) return nullptr;  // the result itself is not a field
  const ResultField* wildcard = nullptr;
  for (const ResultField& f : fields_) {
    const std::vector<std::string> p = split_path(f.path);
    if (p == path) return &f;
    if (!wildcard && matches(p, path)) wildcard = &f;
  }
  if (wildcard) return wildcard;
  // Below a free-form value ("structure.*": any) everything is described by it.
  for (std::size_t n = path.size() - 1; n > 0; --n) {
    const std::vector<std::string> prefix(path.begin(), path.begin() + long(n));
    for (const ResultField& f : fields_)
      if (base_type(f.type) == "any" && matches(split_path(f.path), prefix)) return &f;
  }
  return nullptr;
}

void ResultSchema::validate(const json& r, const std::string& file) const {
  if (!r.is_object()) throw file_error(file, "not a bvhbench result (a JSON object is expected)");
  const json& schema = r.contains("schema") ? r["schema"] : json();
  if (!schema.is_string() || schema.get<std::string>().rfind("bvhbench.result/", 0) != 0)
    throw file_error(file, "not a bvhbench result (no \"schema\": \"" + version_ + "\")");
  if (schema.get<std::string>() != version_)
    throw file_error(file, "unknown result schema '" + schema.get<std::string>() + "' (this build reads " + version_ + ")");
  const bool ok = r.contains("status") && r["status"] == "ok";
  for (const ResultField& f : fields_) {
    const std::vector<std::string> p = split_path(f.path);
    // Walk to the parent; every concrete prefix must be an object for the field to apply.
    const json* parent = &r;
    bool applies = true;
    for (std::size_t i = 0; i + 1 < p.size() && applies; ++i) {
      if (p[i] == "*") { applies = false; break; }  // wildcard parents: checked below, per key
      auto it = parent->find(p[i]);
      if (it == parent->end() || !it->is_object()) applies = false;
      else parent = &*it;
    }
    if (!applies) continue;
    const std::string& key = p.back();
    if (key == "*") {
      for (auto& [k, v] : parent->items()) {
        std::vector<std::string> concrete(p.begin(), p.end() - 1);
        concrete.push_back(k);
        if (describe(concrete) == &f && !has_type(v, f.type))
          throw file_error(file, join_path(concrete) + " must be " + a_type(f.type));
      }
      continue;
    }
    auto it = parent->find(key);
    if (it == parent->end()) {
      if (f.required == "always" || (f.required == "ok" && ok))
        throw file_error(file, "result without " + f.path + (f.required == "ok" ? " (status ok)" : ""));
      continue;
    }
    if (!has_type(*it, f.type)) throw file_error(file, f.path + " must be " + a_type(f.type));
    if (!f.values.empty() && it->is_string() &&
        std::find(f.values.begin(), f.values.end(), it->get<std::string>()) == f.values.end()) {
      std::string all;
      for (const std::string& v : f.values) all += (all.empty() ? "" : ", ") + v;
      throw file_error(file, f.path + " '" + it->get<std::string>() + "' is none of: " + all);
    }
  }
}

std::vector<std::string> ResultSchema::undescribed(const json& result) const {
  std::vector<std::string> out;
  std::vector<std::string> path;
  std::function<void(const json&)> walk = [&](const json& v) {
    if (!path.empty()) {
      const ResultField* f = describe(path);
      if (!f) { out.push_back(join_path(path)); return; }
      if (base_type(f->type) == "any") return;
    }
    if (!v.is_object()) return;
    for (auto& [k, x] : v.items()) {
      path.push_back(k);
      walk(x);
      path.pop_back();
    }
  };
  walk(result);
  return out;
}

}  // namespace bvhbench
