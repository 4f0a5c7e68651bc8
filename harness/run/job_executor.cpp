#include "harness/run/job_executor.hpp"

#include <fstream>

namespace bvhbench {

bool read_result_file(const std::string& path, nlohmann::json* out) {
  std::ifstream f(path);
  if (!f) return false;
  try {
    *out = nlohmann::json::parse(f);
    return out->is_object() && out->contains("status");
  } catch (...) {
    return false;
  }
}

std::vector<std::string> run_arguments(const JobSpec& spec) {
  std::vector<std::string> args = {"--quiet", "run", "--mesh", spec.mesh_path, "--method", spec.method.text,
                                   "--queries", spec.queries_path, "--query", to_string(spec.query_type),
                                   "--repeat", std::to_string(spec.repeat)};
  if (!spec.truth_path.empty()) {
    args.push_back("--truth");
    args.push_back(spec.truth_path);
  }
  if (spec.threads != 1) {
    args.push_back("--threads");
    args.push_back(std::to_string(spec.threads));
  }
  return args;
}

std::vector<std::string> run_command_line(const std::string& exe, const JobTask& task) {
  std::vector<std::string> args = {exe};
  for (auto& a : run_arguments(task.spec)) args.push_back(a);
  args.push_back("--out");
  args.push_back(task.child_result_path);
  return args;
}

}  // namespace bvhbench
