#pragma once
/// A command run in a child process with a wall-clock limit and an address-space limit, so that
/// a crash, a hang or a blow-up of what it runs (a job, a query generator, the oracle) ends the
/// child, not the caller. Linux: fork/exec, a process group, PR_SET_PDEATHSIG, RLIMIT_AS.
#include <cstddef>
#include <string>
#include <sys/types.h>
#include <vector>

namespace bvhbench {

struct ChildLimits {
  double timeout_s = 600;         ///< wall clock; the child's process group is SIGKILLed after it
  double memory_limit_mb = 0;     ///< RLIMIT_AS in MiB; 0 (or beyond what rlim_t holds): none
  /// When > 0: the process whose death ends the job (its process group is SIGKILLed and
  /// run_child returns as if killed). The runner's parent-death signal is the first line; this
  /// check, made at every poll, is the one that does not depend on which thread started us.
  pid_t outlive_no_longer_than = 0;
};

/// How a child ended.
struct ChildOutcome {
  bool exited = false;     ///< it called exit(): exit_code holds its code
  int exit_code = 0;
  int signal = 0;          ///< the signal that killed it, when it did not exit
  bool timed_out = false;  ///< killed (SIGKILL) for exceeding the time limit
  double seconds = 0;      ///< wall clock from fork to its end
  std::string stderr_tail; ///< the last 2000 bytes of its output, trailing blanks trimmed
};

/// A child started and not yet waited for, polled by its caller: what run_child() waits with,
/// and what the suite's local executor polls while a child runs several jobs in turn (it reads
/// each job's result as it appears, and gives each job its own time limit: restart_clock()).
/// Same process setup as run_child(). Not copyable; the child is SIGKILLed and reaped if this is
/// destroyed before it ended.
class ChildRun {
 public:
  /// Starts `args` under `limits`, its output to `log_path`. Throws std::runtime_error only if
  /// fork() fails.
  ChildRun(const std::vector<std::string>& args, const ChildLimits& limits, const std::string& log_path);
  ~ChildRun();
  ChildRun(const ChildRun&) = delete;
  ChildRun& operator=(const ChildRun&) = delete;

  /// Looks once without blocking: true when the child has ended (outcome() is then final). Kills
  /// it when the time limit, counted from the start or the last restart_clock(), has passed, or
  /// when limits.outlive_no_longer_than is gone.
  bool poll();
  /// Starts the time limit again from now (the next job of the child gets the whole limit).
  void restart_clock();
  /// Seconds since the start.
  double seconds() const;
  /// How it ended; final once poll() returned true.
  const ChildOutcome& outcome() const { return out_; }

 private:
  void reap(int status);
  pid_t pid_ = -1;
  bool ended_ = false;
  ChildLimits limits_;
  std::string log_path_;
  double started_ = 0, clock_from_ = 0;  // steady-clock seconds
  ChildOutcome out_;
};

/// The last `max_bytes` of a file (a child's log), "..." before a cut, trailing blanks trimmed;
/// "" when it cannot be read.
std::string log_tail(const std::string& path, std::size_t max_bytes = 2000);

/// Runs `args` (args[0] an executable path, no PATH search) and waits for it. The child gets
/// its own process group, so that a timeout or an interrupt kills whatever it started too; it
/// dies with the caller (PR_SET_PDEATHSIG: a SIGKILLed runner must not leave jobs writing
/// results); it writes no core file; its stdout and stderr go to the file `log_path`. Throws
/// std::runtime_error only if fork() fails; an exec that fails is exit code 127.
ChildOutcome run_child(const std::vector<std::string>& args, const ChildLimits& limits,
                       const std::string& log_path);

/// SIGKILLs the process group of the child run_child() is waiting for, if any. Async-signal-safe:
/// it is what an interrupt handler calls (interrupt.hpp).
void kill_running_child() noexcept;

/// The path of this program (/proc/self/exe): the runner starts its children as itself.
std::string self_exe();

}  // namespace bvhbench
