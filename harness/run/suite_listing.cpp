// A suite's jobs as JSON (suite.hpp: suite_jobs_json), for `bvhbench suite FILE --list --json`.
#include "harness/run/build_groups.hpp"
#include "harness/run/suite.hpp"

namespace bvhbench {

std::vector<std::string> QueryPlan::generator_args() const {
  if (!file.empty()) return {};
  std::vector<std::string> args = {"--kind", kind, "--n", std::to_string(n), "--seed", std::to_string(seed)};
  for (auto& [k, v] : params) args.push_back("--param=" + k + "=" + format_number(v));
  return args;
}

namespace {

nlohmann::json query_set_json(const QueryPlan& q) {
  nlohmann::json j = {{"kind", q.kind}, {"label", q.label()}};
  if (!q.file.empty()) {
    j["file"] = q.file;
    j["name"] = q.name;
    return j;
  }
  j["n"] = q.n;
  j["seed"] = q.seed;
  j["params"] = q.params;  // as given; the kind's defaults fill the rest
  j["generator_args"] = q.generator_args();
  return j;
}

nlohmann::json method_json(const MethodSpec& m) {
  nlohmann::json j = {{"spec", m.text}, {"name", m.name}, {"resolved", m.resolved()}};
  if (!m.resolved()) {
    j["problem"] = m.problem;  // a method this build left out: its jobs are `unsupported` rows
    return j;
  }
  j["params_key"] = m.params_key();
  j["params"] = m.params.values();
  return j;
}

}  // namespace

nlohmann::json suite_jobs_json(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs) {
  nlohmann::json out = {{"suite", cfg.name},       {"file", cfg.file},
                        {"repeat", cfg.repeat},    {"rounds", cfg.rounds},
                        {"timeout_s", cfg.timeout_s}, {"memory_limit_mb", cfg.memory_limit_mb},
                        {"truth", cfg.truth}};
  nlohmann::json list = nlohmann::json::array();
  for (const JobPlan& j : jobs)
    list.push_back({{"id", j.id},
                    {"mesh", {{"name", j.mesh.name}, {"path", j.mesh.path}}},
                    {"queries", query_set_json(j.queries)},
                    {"query", to_string(j.query)},
                    {"method", method_json(j.method)},
                    {"threads", j.threads},
                    {"build_group", build_group_id(j)},
                    {"repeat", cfg.repeat},
                    {"rounds", cfg.rounds}});
  out["jobs"] = list;
  return out;
}

}  // namespace bvhbench
