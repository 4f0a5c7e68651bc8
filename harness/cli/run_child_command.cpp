// `bvhbench run-child`: one command under the suite's time and memory limits, its end printed
// as JSON. What a Dask worker runs for each job (run/dask_bridge.py), so that a job on another
// machine is isolated, limited and judged by the same code as a local one (run/child_process.hpp).
#include <signal.h>
#include <sys/prctl.h>

#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "harness/cli/commands.hpp"
#include "harness/run/child_outcome_json.hpp"
#include "harness/run/child_process.hpp"
#include "harness/run/interrupt.hpp"

namespace bvhbench {

// ---------------------------------------------------------------------------------------------
// `bvhbench run-child --timeout S [--memory-limit MB] --log FILE -- PROGRAM ARGS...`
// ---------------------------------------------------------------------------------------------
void add_run_child_command(CLI::App& app) {
  struct Opts {
    ChildLimits limits;
    std::string log;
    long parent_pid = 0;
    std::vector<std::string> command;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = app.add_subcommand(
      "run-child",
      "Run PROGRAM ARGS in a child process under a time and memory limit; print how it ended as JSON "
      "(exited, exit_code, signal, timed_out, seconds, stderr_tail). What a suite's Dask worker runs");
  cmd->add_option("--timeout", o->limits.timeout_s, "Wall-clock limit in seconds")->required()->check(CLI::PositiveNumber);
  cmd->add_option("--memory-limit", o->limits.memory_limit_mb, "Address-space limit in MiB (0 = none)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--log", o->log, "File for the child's stdout and stderr")->required();
  cmd->add_option("--parent-pid", o->parent_pid,
                  "The process that started this one: if it is already gone, exit at once (status 3); "
                  "the job dies with it in any case")
      ->check(CLI::Range(1L, 4194304L));  // Linux's largest pid_max
  cmd->add_option("command", o->command, "PROGRAM (an absolute path) and its arguments, after --")->required();
  cmd->callback([o] {
    // This process dies with whoever started it (a Dask worker killed mid-job must not leave its
    // job running), and its child dies with it (run_child).
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    // The signal only covers a parent that dies from now on; one that died while this program
    // was starting (a worker killed at once) has left us to init: then there is nobody to run
    // the job for. And in case the signal does not come, the job is polled against the parent.
    const pid_t parent = o->parent_pid > 0 ? pid_t(o->parent_pid) : getppid();
    if (getppid() != parent) std::_Exit(3);
    o->limits.outlive_no_longer_than = parent;
    install_interrupt_handler();  // SIGTERM/SIGINT: the child's process group is killed first
    const ChildOutcome outcome = run_child(o->command, o->limits, o->log);
    std::cout << child_outcome_to_json(outcome).dump() << std::endl;
  });
}

}  // namespace bvhbench
