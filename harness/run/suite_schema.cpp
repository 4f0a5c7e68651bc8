// The keys of each level of a suite file, and the check of a map against them (suite_schema.hpp).
#include "harness/run/suite_schema.hpp"

#include <algorithm>

#include "harness/util/errors.hpp"
#include "harness/util/nearest_word.hpp"

namespace bvhbench {

namespace {

struct LevelInfo {
  SuiteLevel level;
  const char* what;  ///< the level in a message: "unknown key 'x' in WHAT"
  std::vector<std::string> keys;
};

const std::vector<LevelInfo>& levels() {
  static const std::vector<LevelInfo> all = {
      {SuiteLevel::top, "the suite's top level", {"name", "repeat", "rounds", "timeout_s", "memory_limit_mb", "truth", "matrices"}},
      {SuiteLevel::matrix, "a matrix", {"meshes", "queries", "query", "methods", "threads"}},
      {SuiteLevel::mesh, "a mesh ({path:, name:})", {"path", "name"}},
      {SuiteLevel::query_set, "a query set ({kind:, n:, seed:, params:})", {"kind", "n", "seed", "params"}},
      {SuiteLevel::points_file, "a points file ({file:, name:})", {"file", "name"}},
      {SuiteLevel::method, "a method ({name:, params:})", {"name", "params"}},
      {SuiteLevel::all_methods, "{all: true, except: [...]}", {"all", "except"}},
  };
  return all;
}

const LevelInfo& info(SuiteLevel level) {
  for (const LevelInfo& l : levels())
    if (l.level == level) return l;
  throw std::logic_error("suite level not declared");
}

std::string listed(const std::vector<std::string>& keys) {
  std::string s;
  for (const std::string& k : keys) s += (s.empty() ? "" : ", ") + k;
  return s;
}

// What `key`, unknown in `level`, probably was: "" when nothing is close.
std::string probably_meant(const std::string& key, SuiteLevel level, const std::vector<ParamSpec>& params_beside) {
  for (const ParamSpec& p : params_beside)
    if (p.name == key) return "did you mean `params: {" + key + ": ...}`?";
  const std::string near = nearest_word(key, info(level).keys);
  if (!near.empty()) return "did you mean '" + near + "'?";
  // Another level's key (a suite's `repeat:` inside a matrix, a matrix's `threads:` at the top).
  for (const LevelInfo& other : {info(SuiteLevel::top), info(SuiteLevel::matrix)})
    if (other.level != level && std::find(other.keys.begin(), other.keys.end(), key) != other.keys.end())
      return "'" + key + "' belongs in " + other.what;
  std::vector<std::string> names;
  for (const ParamSpec& p : params_beside) names.push_back(p.name);
  const std::string param = nearest_word(key, names);
  if (!param.empty()) return "did you mean `params: {" + param + ": ...}`?";
  return "";
}

}  // namespace

void suite_error(const std::string& file, const YAML::Node& node, const std::string& what) {
  std::string where = node.Mark().line >= 0 ? " (line " + std::to_string(node.Mark().line + 1) + ")" : "";
  throw file_error(file, what + where);
}

const std::vector<std::string>& suite_keys(SuiteLevel level) { return info(level).keys; }

void check_suite_keys(const std::string& file, const YAML::Node& node, SuiteLevel level,
                      const std::vector<ParamSpec>& params_beside) {
  if (!node.IsMap()) return;
  const LevelInfo& l = info(level);
  for (auto kv : node) {
    const std::string key = kv.first.as<std::string>();
    if (key.rfind('_', 0) == 0 || std::find(l.keys.begin(), l.keys.end(), key) != l.keys.end()) continue;
    const std::string hint = probably_meant(key, level, params_beside);
    suite_error(file, kv.first,
                "unknown key '" + key + "' in " + l.what + ": " + (hint.empty() ? "" : hint + " ") + "(known: " +
                    listed(l.keys) + ")");
  }
}

}  // namespace bvhbench
