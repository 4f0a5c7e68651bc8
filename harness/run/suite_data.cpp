#include "harness/run/suite_data.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/io/query_set_io.hpp"
#include "harness/util/sha256.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

SuiteData::SuiteData(std::string data, std::string logs, std::string exe, ChildLimits limits, bool truth)
    : data_(std::move(data)), logs_(std::move(logs)), exe_(std::move(exe)), limits_(limits), truth_(truth) {
  fs::create_directories(fs::path(data_) / "queries");
  fs::create_directories(fs::path(data_) / "truth");
}

QuerySetFile SuiteData::queries(const JobPlan& j) {
  if (!j.queries.file.empty()) {
    // Read by each job (a malformed file is its rejected_input); here only what would stop
    // the oracle from hashing it.
    std::error_code ec;
    if (!fs::is_regular_file(j.queries.file, ec)) return {"", j.queries.file + ": points file not found"};
    if (!std::ifstream(j.queries.file)) return {"", j.queries.file + ": points file cannot be read"};
    return {j.queries.file, ""};
  }
  const std::string key = j.mesh.path + "|" + j.queries.label();
  auto it = query_sets_.find(key);
  if (it != query_sets_.end()) return it->second;
  std::string npy = (fs::path(data_) / "queries" / (file_safe(j.mesh.name) + "__" + j.queries.label() + ".npy")).string();
  std::string err;
  bool fresh = false;
  if (fs::exists(npy) && fs::exists(sidecar_path(npy))) {
    // Reuse only if it was made from this very mesh file.
    std::ifstream f(sidecar_path(npy));
    try {
      json meta = json::parse(f);
      fresh = meta.value("mesh_path", "") == j.mesh.path && fs::exists(j.mesh.path) &&
              meta.value("mesh_sha256", "") == sha256_file(j.mesh.path);
    } catch (...) {
      fresh = false;
    }
  }
  if (!fresh) {
    std::vector<std::string> args = {exe_, "--quiet", "queries", "--mesh", j.mesh.path};
    for (const std::string& a : j.queries.generator_args()) args.push_back(a);
    args.insert(args.end(), {"--out", npy});
    std::cerr << "suite: making query set " << fs::path(npy).filename().string() << "\n";
    auto r = run_child(args, limits_, (fs::path(logs_) / ("queries__" + file_safe(j.mesh.name) + "__" + j.queries.label() + ".log")).string());
    if (!(r.exited && r.exit_code == 0)) {
      err = r.stderr_tail.empty() ? "query generation failed" : r.stderr_tail;
      npy.clear();
    }
  }
  return query_sets_[key] = {npy, err};
}

std::string SuiteData::truth(const JobPlan& j, const std::string& npy) {
  if (!truth_ || truth_unavailable_ || npy.empty()) return "";
  const std::string key = j.mesh.path + "|" + npy;
  auto it = truths_.find(key);
  if (it != truths_.end()) return it->second;
  const std::string msha = sha256_file(j.mesh.path), qsha = sha256_file(npy);
  std::string path = (fs::path(data_) / "truth" / (msha.substr(0, 16) + "_" + qsha.substr(0, 16) + ".npz")).string();
  if (!fs::exists(path)) {
    std::cerr << "suite: computing oracle for " << j.mesh.name << " / " << j.queries.label() << "\n";
    const ChildLimits oracle_limits{std::max(limits_.timeout_s, 1800.0), limits_.memory_limit_mb};
    auto r = run_child({exe_, "--quiet", "truth", "--mesh", j.mesh.path, "--queries", npy, "--out", path}, oracle_limits,
                       (fs::path(logs_) / ("truth__" + file_safe(j.mesh.name) + "__" + j.queries.label() + ".log")).string());
    if (!(r.exited && r.exit_code == 0)) {
      if (r.stderr_tail.find("not implemented") != std::string::npos) truth_unavailable_ = true;
      std::cerr << "suite: no oracle for " << j.mesh.name << ": " << r.stderr_tail << "\n";
      path.clear();
    }
  }
  return truths_[key] = path;
}

}  // namespace bvhbench
