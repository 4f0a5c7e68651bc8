// Rounds of a suite: their files, --resume's view of them, a round's order, the book of each
// job's rounds (suite_rounds.hpp).
#include "harness/run/suite_rounds.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "harness/run/job_executor.hpp"
#include "harness/run/round_merge.hpp"
#include "harness/run/run_job.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

namespace {

std::string round_suffix(int round, int rounds) { return rounds == 1 ? "" : ".round" + std::to_string(round); }

}  // namespace

RoundFiles round_files(const std::string& out, const JobPlan& job, int round, int rounds) {
  const std::string suffix = round_suffix(round, rounds);
  RoundFiles f;
  f.result = (fs::path(out) / (rounds == 1 ? "runs" : "rounds") / (job.id + suffix + ".json")).string();
  f.child = f.result + ".child";
  f.log = (fs::path(out) / "logs" / (job.id + suffix + ".log")).string();
  return f;
}

GroupRoundFiles group_round_files(const std::string& out, const std::string& group_id, int round, int rounds) {
  const fs::path stem = fs::path(out) / "logs" / (group_id + round_suffix(round, rounds));
  return {stem.string() + ".plan.json", stem.string() + ".built.json"};
}

bool round_done(const std::string& out, const JobPlan& job, int round, int rounds) {
  const RoundFiles f = round_files(out, job, round, rounds);
  json r;
  if (read_result_file(f.result, &r)) return r.value("status", "") != status::not_run;
  return read_result_file(f.child, &r);
}

std::vector<BuildGroup> round_order(const std::vector<BuildGroup>& groups, const std::vector<JobPlan>& jobs,
                                    int round) {
  std::map<std::string, std::size_t> mesh_rank;  // mesh path -> place of its first group
  std::vector<std::vector<BuildGroup>> by_mesh;
  for (const BuildGroup& g : groups) {
    const std::string& mesh = jobs.at(g.jobs.front()).mesh.path;
    auto [it, fresh] = mesh_rank.emplace(mesh, by_mesh.size());
    if (fresh) by_mesh.emplace_back();
    by_mesh[it->second].push_back(g);
  }
  std::vector<BuildGroup> ordered;
  for (std::vector<BuildGroup>& mesh_groups : by_mesh) {
    if (round % 2 == 0) std::reverse(mesh_groups.begin(), mesh_groups.end());
    ordered.insert(ordered.end(), mesh_groups.begin(), mesh_groups.end());
  }
  return ordered;
}

std::optional<RoundBook::Complete> RoundBook::add(std::size_t job, int round, json result, bool ran_now) {
  if (round < 1 || round > rounds_) throw std::logic_error("RoundBook: round out of range");
  if (jobs_.size() <= job) jobs_.resize(job + 1);
  JobRounds& j = jobs_[job];
  if (j.results.empty()) j.results.assign(std::size_t(rounds_), json());
  json& slot = j.results[std::size_t(round - 1)];
  if (slot.is_null()) ++j.recorded;
  slot = std::move(result);
  j.ran_now = j.ran_now || ran_now;
  if (j.recorded < j.results.size()) return std::nullopt;
  Complete done;
  done.result = rounds_ == 1 ? j.results.front() : merge_rounds(j.results);
  done.resumed = !j.ran_now;
  return done;
}

}  // namespace bvhbench
