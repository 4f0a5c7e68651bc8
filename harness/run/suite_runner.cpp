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

#include "harness/run/interrupt.hpp"
#include "harness/run/job_status.hpp"
#include "harness/run/suite_data.hpp"
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

}  // namespace

SuiteRunSummary run_suite(const SuiteConfig& cfg, const std::vector<JobPlan>& jobs, const SuiteRunOptions& options,
                          JobExecutor& executor) {
  const fs::path out = options.out;
  const fs::path runs = out / "runs", logs = out / "logs";
  const fs::path data = options.data_dir.empty() ? out / "data" : fs::path(options.data_dir);
  fs::create_directories(out);
  const FolderLock lock(out.string());  // one writer per results folder, until this returns
  fs::create_directories(runs);
  fs::create_directories(logs);
  const ChildLimits limits{cfg.timeout_s, cfg.memory_limit_mb};
  SuiteData shared(data.string(), logs.string(), self_exe(), limits, cfg.truth);
  copy_suite_file(cfg.file, out / "suite.yml");
  install_interrupt_handler();

  auto result_path = [&](const JobPlan& j) { return (runs / (j.id + ".json")).string(); };
  auto child_path = [&](const JobPlan& j) { return (runs / (j.id + ".json.child")).string(); };

  std::vector<json> done;
  SuiteRunSummary summary;
  std::map<std::string, json> summary_rows;
  for (auto& j : cfg.jobs) {
    json r;
    if (read_result_file(result_path(j), &r)) summary_rows[j.id] = r;
  }
  auto write_summary = [&] {
    std::vector<json> rows;
    for (auto& j : cfg.jobs) {
      auto it = summary_rows.find(j.id);
      if (it != summary_rows.end()) rows.push_back(it->second);
    }
    write_summary_csv((out / "summary.csv").string(), rows);
  };
  // Jobs this invocation will actually run (for the time-left estimate): --resume skips the rest.
  std::size_t to_run = jobs.size();
  if (options.resume)
    for (auto& j : jobs)
      if (fs::exists(result_path(j)) || fs::exists(child_path(j))) --to_run;
  double spent = 0;
  std::size_t finished = 0;
  const auto t_start = Clock::now();
  std::map<std::size_t, Clock::time_point> started;

  // Writes a job's result with its identity, and reports it.
  auto record = [&](std::size_t i, json result) {
    const JobPlan& j = jobs[i];
    result["job"]["id"] = j.id;
    result["job"]["mesh"]["name"] = j.mesh.name;
    result["job"]["suite"] = cfg.name;
    write_json_atomic(result_path(j), result);
    std::remove(child_path(j).c_str());
    done.push_back(result);
    summary_rows[j.id] = result;
    write_summary();
    ++finished;
    spent += seconds_since(started[i]);
    started.erase(i);
    // Jobs that run side by side (on several workers) overlap: then the rate is the wall clock's.
    const double per_job = executor.slots() > 1 ? seconds_since(t_start) / double(finished) : spent / double(finished);
    double left = per_job * double(to_run > finished ? to_run - finished : 0);
    std::cerr << "[" << (i + 1) << "/" << jobs.size() << "] " << j.id << ": " << short_result(result)
              << "  (elapsed " << format_seconds(seconds_since(t_start)) << ", left ~" << format_seconds(left) << ")\n";
  };
  // Records a job the executor finished; false when an interrupt stopped it.
  auto record_finished = [&](JobFinished& f) {
    if (!f.kept) {
      std::remove(f.task.child_result_path.c_str());
      return false;
    }
    record(f.task.index, std::move(f.result));
    return true;
  };
  auto collect_one = [&] {
    std::optional<JobFinished> f = executor.collect();
    return f ? record_finished(*f) : true;
  };
  // Records, without waiting, the jobs that ended while this one was prepared.
  auto collect_ended = [&] {
    bool kept = true;
    while (std::optional<JobFinished> f = executor.collect_ready()) kept = record_finished(*f) && kept;
    return kept;
  };

  bool stopped = false;
  for (std::size_t i = 0; i < jobs.size() && !interrupted() && !stopped; ++i) {
    const JobPlan& j = jobs[i];
    json existing;
    if (options.resume && read_result_file(result_path(j), &existing)) {
      done.push_back(existing);
      ++summary.resumed;
      continue;
    }
    if (options.resume && read_result_file(child_path(j), &existing)) {
      // The job finished but the runner was killed before recording it: adopt the result.
      existing["job"]["id"] = j.id;
      existing["job"]["mesh"]["name"] = j.mesh.name;
      existing["job"]["suite"] = cfg.name;
      write_json_atomic(result_path(j), existing);
      std::remove(child_path(j).c_str());
      summary_rows[j.id] = existing;
      done.push_back(existing);
      ++summary.resumed;
      continue;
    }
    started[i] = Clock::now();
    JobTask task;
    task.index = i;
    task.plan = j;
    task.spec.mesh_path = j.mesh.path;
    task.spec.method = j.method;
    task.spec.query_type = j.query;
    task.spec.repeat = cfg.repeat;
    task.spec.threads = j.threads;
    if (!j.method.resolved()) {  // left out of this build (suite.cpp): nothing to run
      record(i, job_failure_row(task.spec, j, status::unsupported, j.method.problem));
      continue;
    }
    const QuerySetFile qs = shared.queries(j);
    if (interrupted()) break;  // the query set was cut short: not this job's failure
    task.spec.queries_path = qs.path;
    if (qs.path.empty()) {
      record(i, query_set_failure_row(task.spec, j, qs.error));
      continue;
    }
    task.spec.truth_path = shared.truth(j, qs.path);
    if (interrupted()) break;
    task.limits = limits;
    task.child_result_path = child_path(j);
    task.log_path = (logs / (j.id + ".log")).string();
    std::remove(result_path(j).c_str());
    std::remove(task.child_result_path.c_str());
    executor.submit(std::move(task));
    stopped = !collect_ended();
    while (!stopped && executor.pending() >= executor.slots()) stopped = !collect_one();
  }
  // What is still running: recorded as it ends (an interrupt drops what it stopped).
  while (executor.pending() > 0) collect_one();
  write_summary();

  summary.recorded = done.size();
  summary.not_ok = std::size_t(std::count_if(done.begin(), done.end(), [](const json& r) { return r.value("status", "") != "ok"; }));
  summary.interrupted = interrupted();
  if (summary.interrupted)
    std::cerr << "suite: interrupted; " << done.size() << " job(s) kept. Run again with --resume to finish.\n";
  else
    std::cerr << "suite " << cfg.name << ": " << done.size() << " job(s) (" << summary.resumed << " resumed), "
              << summary.not_ok << " not ok; results in " << out.string() << "\n";
  return summary;
}

}  // namespace bvhbench
