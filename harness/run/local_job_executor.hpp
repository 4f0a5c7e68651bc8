#pragma once
/// The executor of `bvhbench suite`: each job in a child process of this one, one at a time
/// (timings are the point of the suite: jobs must not share the machine).
#include <deque>
#include <string>

#include "harness/run/job_executor.hpp"

namespace bvhbench {

class LocalJobExecutor : public JobExecutor {
 public:
  /// `exe`: the bvhbench to run (self_exe()).
  explicit LocalJobExecutor(std::string exe) : exe_(std::move(exe)) {}
  std::size_t slots() const override { return 1; }
  void submit(JobTask task) override { queue_.push_back(std::move(task)); }
  /// Runs the next queued job to its end (run_child) and reads the result it left at
  /// child_result_path; its status row when it left none. After an interrupt, a job is kept only
  /// if it ended on its own with a result; otherwise its .child file is removed.
  std::optional<JobFinished> collect() override;
  std::size_t pending() const override { return queue_.size(); }

 private:
  std::string exe_;
  std::deque<JobTask> queue_;
};

}  // namespace bvhbench
