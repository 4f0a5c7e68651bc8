#include "harness/run/group_plan.hpp"

#include "harness/core/registry.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"

namespace bvhbench {

using json = nlohmann::json;

json group_plan_to_json(const GroupPlan& plan) {
  json jobs = json::array();
  for (const GroupPlanJob& g : plan.jobs) {
    const JobSpec& s = g.spec;
    jobs.push_back({{"mesh", s.mesh_path},
                    {"method", s.method.text},
                    {"queries", s.queries_path},
                    {"query", to_string(s.query_type)},
                    {"repeat", s.repeat},
                    {"threads", s.threads},
                    {"truth", s.truth_path},
                    {"out", g.out},
                    {"log", g.log}});
  }
  return {{"build_id", plan.build_id}, {"built", plan.built}, {"jobs", jobs}};
}

namespace {

GroupPlanJob job_from_json(const json& j) {
  GroupPlanJob g;
  g.spec.mesh_path = j.at("mesh").get<std::string>();
  g.spec.method = Registry::global().describe(j.at("method").get<std::string>());
  g.spec.queries_path = j.at("queries").get<std::string>();
  g.spec.query_type = parse_query_type(j.at("query").get<std::string>());
  g.spec.repeat = j.at("repeat").get<int>();
  g.spec.threads = j.at("threads").get<int>();
  g.spec.truth_path = j.value("truth", "");
  g.spec.progress = false;
  g.out = j.at("out").get<std::string>();
  g.log = j.value("log", "");
  if (g.spec.repeat < 1 || g.spec.threads < 1) throw InputError("repeat and threads must be at least 1");
  return g;
}

/// One structure: the same method and structure options (structure_key: query options may
/// differ where the method takes them after its build), mesh, threads and repeat.
bool same_structure(const JobSpec& a, const JobSpec& b) {
  const bool same_method = a.method.resolved() && b.method.resolved()
                               ? a.method.info == b.method.info && structure_key(a.method) == structure_key(b.method)
                               : a.method.text == b.method.text;
  return a.mesh_path == b.mesh_path && same_method && a.threads == b.threads && a.repeat == b.repeat;
}

}  // namespace

GroupPlan group_plan_from_json(const json& j, const std::string& file) {
  GroupPlan plan;
  try {
    plan.build_id = j.value("build_id", "");
    plan.built = j.value("built", "");
    for (const json& job : j.at("jobs")) plan.jobs.push_back(job_from_json(job));
  } catch (const json::exception& e) {
    throw InputError(printable(file) + ": not a group plan: " + e.what());
  } catch (const InputError& e) {
    throw InputError(printable(file) + ": " + e.what());
  }
  if (plan.jobs.empty()) throw InputError(printable(file) + ": a group plan without jobs");
  for (const GroupPlanJob& g : plan.jobs)
    if (!same_structure(g.spec, plan.jobs.front().spec))
      throw InputError(printable(file) + ": its jobs do not share one structure (mesh, method, threads, repeat)");
  return plan;
}

}  // namespace bvhbench
