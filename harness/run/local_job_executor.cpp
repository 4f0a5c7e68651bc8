#include "harness/run/local_job_executor.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "harness/run/child_process.hpp"
#include "harness/run/group_plan.hpp"
#include "harness/run/interrupt.hpp"
#include "harness/run/job_status.hpp"

namespace fs = std::filesystem;

namespace bvhbench {

/// The group whose child runs now.
struct LocalJobExecutor::Running {
  GroupTask group;
  std::unique_ptr<ChildRun> child;
  std::vector<bool> reported;  // by job: handed to ready_
  double last_end = 0;         // child seconds when the last job's result appeared
};

LocalJobExecutor::LocalJobExecutor(std::string exe) : exe_(std::move(exe)) {}
LocalJobExecutor::~LocalJobExecutor() = default;

void LocalJobExecutor::submit(JobTask task) {
  GroupTask g;
  g.id = task.plan.id;
  g.plan_path = task.log_path + ".plan.json";
  g.built_path = task.log_path + ".built.json";
  g.jobs.push_back(std::move(task));
  submit_group(std::move(g));
}

std::size_t LocalJobExecutor::pending() const {
  std::size_t n = ready_.size();
  for (const GroupTask& g : queue_) n += g.jobs.size();
  if (running_)
    for (bool r : running_->reported) n += r ? 0 : 1;
  return n;
}

void LocalJobExecutor::start_next() {
  auto r = std::make_unique<Running>();
  r->group = std::move(queue_.front());
  queue_.pop_front();
  const GroupTask& g = r->group;
  GroupPlan plan;
  plan.build_id = g.id;
  plan.built = g.built_path;
  for (const JobTask& t : g.jobs) plan.jobs.push_back({t.spec, t.child_result_path, t.log_path});
  write_json_atomic(g.plan_path, group_plan_to_json(plan));
  std::remove(g.built_path.c_str());
  r->reported.assign(g.jobs.size(), false);
  const std::vector<std::string> args = {exe_, "--quiet", "run-group", "--plan", g.plan_path};
  // The child's output goes to the first job's log (the build's output with it) until the
  // child moves each later job's to its own.
  r->child = std::make_unique<ChildRun>(args, g.jobs.front().limits, g.jobs.front().log_path);
  running_ = std::move(r);
}

void LocalJobExecutor::harvest() {
  Running& r = *running_;
  for (std::size_t k = 0; k < r.group.jobs.size(); ++k) {
    if (r.reported[k]) continue;
    const JobTask& t = r.group.jobs[k];
    std::error_code ec;
    JobFinished f{t, nlohmann::json(), true};
    if (!fs::exists(t.child_result_path, ec) || !read_result_file(t.child_result_path, &f.result)) continue;
    const double now = r.child->seconds();
    f.result["elapsed_seconds"] = now - r.last_end;
    r.last_end = now;
    r.child->restart_clock();  // the next job has the whole time limit
    r.reported[k] = true;
    ready_.push_back(std::move(f));
  }
}

namespace {

/// The row of a job that its group's child never reached: `not_run`, naming the job that ended it.
nlohmann::json not_run_row(const JobTask& t, const std::string& build_id, const JobTask& ended_in,
                           const ChildStatus& how) {
  return job_failure_row(t.spec, t.plan, status::not_run,
                         "not run: the child of its structure (build " + build_id + ") ended in job " +
                             ended_in.plan.id + " (" + how.code + "); --resume runs it again");
}

}  // namespace

void LocalJobExecutor::settle() {
  Running& r = *running_;
  harvest();
  const ChildOutcome& end = r.child->outcome();
  std::error_code ec;
  const bool built = fs::exists(r.group.built_path, ec);
  const JobTask* ended_in = nullptr;
  ChildStatus how;
  for (std::size_t k = 0; k < r.group.jobs.size(); ++k) {
    if (r.reported[k]) continue;
    const JobTask& t = r.group.jobs[k];
    JobFinished f{t, nlohmann::json(), true};
    r.reported[k] = true;
    if (interrupted()) {  // an interrupt killed it: not done, --resume runs it
      std::remove(t.child_result_path.c_str());
      f.kept = false;
    } else if (ended_in == nullptr || !built) {
      // The job that was running (or, before the build was done, every job: the build was theirs).
      ChildOutcome own = end;
      if (fs::exists(t.log_path, ec)) own.stderr_tail = log_tail(t.log_path);
      how = child_status(own, t.limits.timeout_s);
      f.result = job_failure_row(t.spec, t.plan, how.code,
                                 (!built && r.group.jobs.size() > 1 ? "in the build shared by " +
                                                                          std::to_string(r.group.jobs.size()) + " jobs: "
                                                                    : std::string()) +
                                     how.message);
      f.result["elapsed_seconds"] = ended_in == nullptr ? end.seconds - r.last_end : 0.0;
      if (ended_in == nullptr) ended_in = &t;
    } else {
      f.result = not_run_row(t, r.group.id, *ended_in, how);
      f.result["elapsed_seconds"] = 0.0;
    }
    // Which structure it belonged to, as the rows of its group's finished jobs say.
    if (f.kept) f.result["build"] = {{"id", r.group.id}, {"jobs", r.group.jobs.size()}};
    ready_.push_back(std::move(f));
  }
  running_.reset();
}

std::optional<JobFinished> LocalJobExecutor::collect() {
  for (;;) {
    if (!ready_.empty()) {
      JobFinished f = std::move(ready_.front());
      ready_.pop_front();
      return f;
    }
    if (!running_) {
      if (queue_.empty()) return std::nullopt;
      start_next();
    }
    if (running_->child->poll()) {
      settle();
      continue;
    }
    harvest();
    if (ready_.empty())
      std::this_thread::sleep_for(std::chrono::milliseconds(running_->child->seconds() < 2 ? 5 : 50));
  }
}

}  // namespace bvhbench
