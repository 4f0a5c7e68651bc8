#include "harness/run/suite_runner.hpp"

#include "harness/run/folder_lock.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>

#include "harness/run/build_groups.hpp"
#include "harness/run/calibration.hpp"
#include "harness/run/interrupt.hpp"
#include "harness/run/job_status.hpp"
#include "harness/run/suite_data.hpp"
#include "harness/run/suite_estimate.hpp"
#include "harness/run/suite_rounds.hpp"
#include "harness/run/summary_csv.hpp"
#include "harness/util/atomic_file.hpp"
#include "harness/util/json_path.hpp"
#include "harness/util/progress.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace bvhbench {

namespace {

std::string short_result(const json& r) {
  std::string s = r.value("status", "?");
  json q = json_at(r, {"queries", "throughput_qps", "median"});
  if (s == "ok" && q.is_number()) {
    char buf[64];
    std::snprintf(buf, sizeof buf, " %.3g q/s", q.get<double>());
    s += buf;
  } else if (s != "ok") {
    std::string m = r.value("message", "");
    if (m.size() > 80) m = m.substr(0, 77) + "...";
    if (!m.empty()) s += " (" + m + ")";
  }
  return s;
}

/// OUT/suite.yml: the suite file as it was run. Read whole before it is written, so that a suite
/// run from its own copy (OUT/suite.yml) keeps it.
void copy_suite_file(const std::string& from, const fs::path& to) {
  std::ifstream src(from, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(src)), std::istreambuf_iterator<char>());
  AtomicOutputFile dst(to.string());
  dst.write(text);
  dst.commit();
}

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

fs::path data_folder(const SuiteRunOptions& options) {
  return options.data_dir.empty() ? fs::path(options.out) / "data" : fs::path(options.data_dir);
}

}  // namespace

std::string result_path(const SuiteRunOptions& options, const JobPlan& j) {
  return (fs::path(options.out) / "runs" / (j.id + ".json")).string();
}

SuitePrice estimate_suite(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs, const SuiteRunOptions& options,
                          bool shared_builds) {
  // By round: the jobs whose round is still to run.
  std::vector<std::vector<bool>> to_run(std::size_t(cfg.rounds), std::vector<bool>(jobs.size(), true));
  if (options.resume)
    for (int r = 1; r <= cfg.rounds; ++r)
      for (std::size_t i = 0; i < jobs.size(); ++i) to_run[r - 1][i] = !round_done(options.out, jobs[i], r, cfg.rounds);
  // The kernel timed here now, as each result timed it beside its job.
  const double kernel_here = measure_calibration(3).value("median_seconds", 0.0);
  const SuiteEstimator estimator(SuiteEstimator::default_folders(options.out), kernel_here);
  return estimator.price(cfg, jobs, to_run, group_by_structure(jobs), shared_builds, data_folder(options).string());
}

namespace {

/// One invocation of `bvhbench suite`: the jobs, grouped by structure, each group's jobs made
/// ready (query set, oracle) and handed to the executor, each result recorded as it ends; with
/// rounds, the whole suite once per round (suite_rounds.hpp), each job's result merged from its
/// rounds once it has them all.
class SuiteRun {
 public:
  SuiteRun(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs, const SuiteRunOptions& options,
           JobExecutor& executor)
      : cfg_(cfg), jobs_(jobs), options_(options), executor_(executor), out_(options.out),
        limits_{cfg.timeout_s, cfg.memory_limit_mb},
        data_(data_folder(options).string(), (out_ / "logs").string(), self_exe(), limits_, cfg.truth),
        book_(cfg.rounds) {
    for (auto& j : cfg_.jobs) {
      json r;
      if (read_result_file(result_path(options_, j), &r)) summary_rows_[j.id] = r;
    }
  }

  SuiteRunSummary run() {
    announce();
    const std::vector<BuildGroup> groups = group_by_structure(jobs_);
    for (int round = 1; round <= cfg_.rounds && !interrupted() && !stopped_; ++round) run_round(groups, round);
    // What is still running: recorded as it ends (an interrupt drops what it stopped).
    while (executor_.pending() > 0) collect_one();
    write_summary();
    return finish();
  }

 private:
  /// The expected time, said first.
  void announce() {
    price_ = estimate_suite(cfg_, jobs_, options_, executor_.shares_builds());
    expected_left_ = price_.total();
    std::cerr << "suite " << cfg_.name << ": " << price_.describe() << ". The ETA after each job corrects it.\n";
  }

  /// Every group once. One round keeps the groups' own order, as a suite always ran; rounds run
  /// mesh after mesh (round_order says why). A round ends before the next starts, so that on an
  /// executor of several slots too each round is a pass over the whole suite.
  void run_round(const std::vector<BuildGroup>& groups, int round) {
    for (const BuildGroup& g : cfg_.rounds == 1 ? groups : round_order(groups, jobs_, round)) {
      if (interrupted() || stopped_) break;
      submit_group(g, round);
      stopped_ = !collect_ended();
      while (!stopped_ && executor_.pending() >= executor_.slots()) stopped_ = !collect_one();
    }
    while (!stopped_ && executor_.pending() > 0) stopped_ = !collect_one();
  }

  /// The group's jobs whose round is not done, made ready and submitted together.
  void submit_group(const BuildGroup& g, int round) {
    GroupTask group;
    group.id = g.id;
    const GroupRoundFiles files = group_round_files(out_.string(), g.id, round, cfg_.rounds);
    group.plan_path = files.plan;
    group.built_path = files.built;
    for (std::size_t i : g.jobs) {
      if (interrupted()) return;  // a query set or oracle cut short: not this job's failure
      if (std::optional<JobTask> t = prepare(i, round)) group.jobs.push_back(std::move(*t));
    }
    if (interrupted() || group.jobs.empty()) return;
    for (const JobTask& t : group.jobs) started_[t.index] = Clock::now();
    executor_.submit_group(std::move(group));
  }

  /// Round `round` of a job made ready to run; nullopt when it needs no run: resumed, or
  /// recorded at once (a method this build left out, a query set that could not be made).
  std::optional<JobTask> prepare(std::size_t i, int round) {
    const JobPlan& j = jobs_[i];
    if (options_.resume && resume(i, round)) return std::nullopt;
    started_[i] = Clock::now();
    JobTask task;
    task.index = i;
    task.round = round;
    task.plan = j;
    task.spec.mesh_path = j.mesh.path;
    task.spec.method = j.method;
    task.spec.query_type = j.query;
    task.spec.repeat = cfg_.repeat;
    task.spec.threads = j.threads;
    if (!j.method.resolved()) {  // left out of this build (suite.cpp): nothing to run
      record(i, round, job_failure_row(task.spec, j, status::unsupported, j.method.problem));
      return std::nullopt;
    }
    const QuerySetFile qs = data_.queries(j);
    if (interrupted()) return std::nullopt;
    task.spec.queries_path = qs.path;
    if (qs.path.empty()) {
      record(i, round, query_set_failure_row(task.spec, j, qs.error));
      return std::nullopt;
    }
    task.spec.truth_path = data_.truth(j, qs.path);
    if (interrupted()) return std::nullopt;
    task.limits = limits_;
    const RoundFiles files = round_files(out_.string(), j, round, cfg_.rounds);
    task.child_result_path = files.child;
    task.log_path = files.log;
    forget(j, files);
    return task;
  }

  /// Before a round of job j runs: its earlier files, and the job's result they made, removed,
  /// so that none is taken for this run's (summary.csv lists only the jobs with a result).
  void forget(const JobPlan& j, const RoundFiles& files) {
    std::remove(files.result.c_str());
    std::remove(files.child.c_str());
    std::remove(result_path(options_, j).c_str());
    summary_rows_.erase(j.id);
  }

  /// --resume: true when round `round` of job i is done (its result kept, or a finished child's
  /// adopted). A `not_run` result is not done: the round runs again.
  bool resume(std::size_t i, int round) {
    const JobPlan& j = jobs_[i];
    const RoundFiles files = round_files(out_.string(), j, round, cfg_.rounds);
    json existing;
    if (read_result_file(files.result, &existing) && existing.value("status", "") != status::not_run) {
      keep(i, round, std::move(existing), false);
      return true;
    }
    if (!read_result_file(files.child, &existing)) return false;
    // The round finished but the runner was killed before recording it: adopt the result.
    stamp(j, existing);
    write_json_atomic(files.result, existing);
    std::remove(files.child.c_str());
    keep(i, round, std::move(existing), false);
    return true;
  }

  void stamp(const JobPlan& j, json& result) const {
    result["job"]["id"] = j.id;
    result["job"]["mesh"]["name"] = j.mesh.name;
    result["job"]["suite"] = cfg_.name;
  }

  /// Round `round` of job i has its result (written): once the job has every round, its result
  /// (merged from them: round_merge.hpp) is written to runs/ID.json. Returns it then.
  std::optional<json> keep(std::size_t i, int round, json result, bool ran_now) {
    std::optional<RoundBook::Complete> done = book_.add(i, round, std::move(result), ran_now);
    if (!done) return std::nullopt;
    const JobPlan& j = jobs_[i];
    if (cfg_.rounds > 1) write_json_atomic(result_path(options_, j), done->result);
    summary_rows_[j.id] = done->result;
    done_.push_back(done->result);
    summary_.resumed += done->resumed ? 1 : 0;
    return std::move(done->result);
  }

  /// Writes a round's result with its job's identity, and reports it with the time left.
  void record(std::size_t i, int round, json result) {
    const JobPlan& j = jobs_[i];
    const RoundFiles files = round_files(out_.string(), j, round, cfg_.rounds);
    stamp(j, result);
    write_json_atomic(files.result, result);
    std::remove(files.child.c_str());
    const double took = started_.count(i) ? seconds_since(started_[i]) : 0.0;
    const double own = result.value("elapsed_seconds", took);
    started_.erase(i);
    std::string line = short_result(result);
    const std::optional<json> job_result = keep(i, round, std::move(result), true);
    if (job_result) write_summary();
    ++runs_recorded_;
    if (cfg_.rounds > 1) {
      line = "round " + std::to_string(round) + "/" + std::to_string(cfg_.rounds) + " " + j.id + ": " + line;
      if (job_result) line += "; kept round " + json_at(*job_result, {"rounds", "kept"}).dump() + ": " + short_result(*job_result);
    } else {
      line = j.id + ": " + line;
    }
    report_progress(price_.run_seconds(i), own, line);
  }

  /// "[k/N] LINE  (elapsed .., left ~..)": a run took `own` seconds of its expected `expected`.
  void report_progress(double expected, double own, const std::string& line) {
    expected_done_ += expected;
    expected_left_ = std::max(0.0, expected_left_ - expected);
    actual_done_ += own;
    // Jobs that run side by side (on several workers) overlap: then the rate is the wall clock's.
    const double actual = executor_.slots() > 1 ? seconds_since(t_start_) : actual_done_;
    const double left = time_left(expected_left_, expected_done_, actual);
    std::cerr << "[" << runs_recorded_ << "/" << price_.runs << "] " << line << "  (elapsed "
              << format_seconds(seconds_since(t_start_)) << ", left ~" << format_seconds(left) << ")\n";
  }

  /// Records a job the executor finished; false when an interrupt stopped it.
  bool record_finished(JobFinished& f) {
    if (!f.kept) {
      std::remove(f.task.child_result_path.c_str());
      return false;
    }
    record(f.task.index, f.task.round, std::move(f.result));
    return true;
  }
  bool collect_one() {
    std::optional<JobFinished> f = executor_.collect();
    return f ? record_finished(*f) : true;
  }
  /// Records, without waiting, the jobs that ended while this one was prepared.
  bool collect_ended() {
    bool kept = true;
    while (std::optional<JobFinished> f = executor_.collect_ready()) kept = record_finished(*f) && kept;
    return kept;
  }

  void write_summary() {
    std::vector<json> rows;
    for (auto& j : cfg_.jobs) {
      auto it = summary_rows_.find(j.id);
      if (it != summary_rows_.end()) rows.push_back(it->second);
    }
    write_summary_csv((out_ / "summary.csv").string(), rows);
  }

  SuiteRunSummary finish() {
    summary_.recorded = done_.size();
    summary_.not_ok = std::size_t(
        std::count_if(done_.begin(), done_.end(), [](const json& r) { return r.value("status", "") != "ok"; }));
    summary_.interrupted = interrupted();
    const std::string in_rounds = cfg_.rounds > 1 ? " in " + std::to_string(cfg_.rounds) + " rounds" : "";
    if (summary_.interrupted)
      std::cerr << "suite: interrupted; " << done_.size() << " job(s) kept"
                << (cfg_.rounds > 1 ? ", with the finished rounds of the others" : "")
                << ". Run again with --resume to finish.\n";
    else
      std::cerr << "suite " << cfg_.name << ": " << done_.size() << " job(s)" << in_rounds << " (" << summary_.resumed
                << " resumed), " << summary_.not_ok << " not ok in " << format_seconds(seconds_since(t_start_))
                << " (expected ~" << format_seconds(price_.total()) << "); results in " << out_.string() << "\n";
    return summary_;
  }

  const SuiteConfig& cfg_;
  const std::vector<JobPlan>& jobs_;
  const SuiteRunOptions& options_;
  JobExecutor& executor_;
  const fs::path out_;
  const ChildLimits limits_;
  SuiteData data_;
  RoundBook book_;
  SuitePrice price_;
  double expected_left_ = 0, expected_done_ = 0, actual_done_ = 0;
  const Clock::time_point t_start_ = Clock::now();
  std::map<std::size_t, Clock::time_point> started_;
  std::map<std::string, json> summary_rows_;
  std::vector<json> done_;
  std::size_t runs_recorded_ = 0;  // rounds of jobs run (or recorded at once) by this invocation
  SuiteRunSummary summary_;
  bool stopped_ = false;
};

}  // namespace

SuiteRunSummary run_suite(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs, const SuiteRunOptions& options,
                          JobExecutor& executor) {
  const fs::path out = options.out;
  fs::create_directories(out);
  const FolderLock lock(out.string());  // one writer per results folder, until this returns
  fs::create_directories(out / "runs");
  fs::create_directories(out / "logs");
  if (cfg.rounds > 1) fs::create_directories(out / "rounds");
  copy_suite_file(cfg.file, out / "suite.yml");
  install_interrupt_handler();
  SuiteRun run(cfg, jobs, options, executor);
  return run.run();
}

}  // namespace bvhbench
