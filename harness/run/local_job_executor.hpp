#pragma once
/// The executor of `bvhbench suite`: on this machine, one child process at a time (timings are
/// the point of the suite: jobs must not share the machine). A group of jobs that share one
/// structure runs in one child (`bvhbench run-group`): one build, then each job's queries in
/// turn; the child writes each job's result as it ends, and this side hands it back at once.
///
/// Time limit: per job. The first job of a group has the limit for the shared build and its own
/// queries, as a job alone has; each later job has the whole limit again from the moment the
/// previous job's result appeared.
///
/// When a group's child dies (a crash, the time limit, the memory limit): the jobs it finished
/// keep their results; the job that was running gets the status of the child's end
/// (job_status.hpp: child_status, with the tail of that job's own log); the jobs after it
/// `not_run`, saying which job ended the child (--resume runs them again). When it died in the
/// build (it never said the build was done), every unfinished job gets the build's status.
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "harness/run/job_executor.hpp"

namespace bvhbench {

class ChildRun;

class LocalJobExecutor : public JobExecutor {
 public:
  /// `exe`: the bvhbench to run (self_exe()).
  explicit LocalJobExecutor(std::string exe);
  ~LocalJobExecutor() override;
  std::size_t slots() const override { return 1; }
  /// A group of one.
  void submit(JobTask task) override;
  void submit_group(GroupTask group) override { queue_.push_back(std::move(group)); }
  bool shares_builds() const override { return true; }
  /// The next job that ends: runs the queued groups, one child at a time, and returns each job
  /// as its result appears (or its status row when the child died first). After an interrupt, a
  /// job is kept only if its result was written; the others come back with kept = false and
  /// their .child files removed.
  std::optional<JobFinished> collect() override;
  std::size_t pending() const override;

 private:
  struct Running;
  void start_next();
  /// The jobs whose results appeared since the last look, into ready_.
  void harvest();
  /// The child has ended: every job it left without a result, into ready_.
  void settle();

  std::string exe_;
  std::deque<GroupTask> queue_;
  std::unique_ptr<Running> running_;
  std::deque<JobFinished> ready_;
};

}  // namespace bvhbench
