// run_child (run/child_process.hpp): how a child ended, its output, its limits. The same ends
// are checked through a whole suite (the fault method) in tests/python/harness/test_suite_faults.py.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "harness/run/child_process.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {
ChildOutcome shell(const std::string& script, const TmpDir& d, ChildLimits limits = {30, 0}) {
  return run_child({"/bin/sh", "-c", script}, limits, d.file("child.log"));
}
}  // namespace

TEST(ChildProcess, ExitCodesAndOutput) {
  TmpDir d;
  const ChildOutcome ok = shell("echo to stdout; echo to stderr >&2; exit 0", d);
  EXPECT_TRUE(ok.exited);
  EXPECT_EQ(ok.exit_code, 0);
  EXPECT_EQ(ok.signal, 0);
  EXPECT_FALSE(ok.timed_out);
  EXPECT_EQ(ok.stderr_tail, "to stdout\nto stderr");
  EXPECT_GE(ok.seconds, 0.0);
  const ChildOutcome bad = shell("echo refused >&2; exit 2", d);
  EXPECT_TRUE(bad.exited);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.stderr_tail, "refused");
}

TEST(ChildProcess, OnlyTheTailOfALongOutputIsKept) {
  TmpDir d;
  const ChildOutcome o = shell("i=0; while [ $i -lt 500 ]; do echo line$i; i=$((i+1)); done", d);
  ASSERT_EQ(o.stderr_tail.size(), 2002u);  // "..." and the last 2000 bytes, less the final newline
  EXPECT_EQ(o.stderr_tail.substr(0, 3), "...");
  EXPECT_EQ(o.stderr_tail.substr(o.stderr_tail.size() - 7), "line499");
}

TEST(ChildProcess, ACrashIsItsSignal) {
  TmpDir d;
  const ChildOutcome o = shell("kill -SEGV $$", d);
  EXPECT_FALSE(o.exited);
  EXPECT_EQ(o.signal, SIGSEGV);
  EXPECT_FALSE(o.timed_out);
}

// The whole process group goes: a grandchild the job started does not outlive the limit.
TEST(ChildProcess, TheTimeLimitKillsTheChildAndWhatItStarted) {
  TmpDir d;
  const std::string marker = d.file("grandchild_survived");
  const ChildOutcome o = shell("(sleep 1; touch " + marker + ") & sleep 30", d, {0.3, 0});
  EXPECT_TRUE(o.timed_out);
  EXPECT_FALSE(o.exited);
  EXPECT_EQ(o.signal, SIGKILL);  // killed by the limit: the child's own end (after 30 s) is an exit
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // past the grandchild's touch
  EXPECT_FALSE(std::filesystem::exists(marker)) << "the grandchild outlived the time limit";
}

TEST(ChildProcess, TheMemoryLimitIsTheChildsAddressSpace) {
  TmpDir d;
  const ChildOutcome limited = shell("ulimit -v", d, {30, 64});
  EXPECT_TRUE(limited.exited);
  EXPECT_EQ(limited.stderr_tail, "65536");  // KiB
  const ChildOutcome none = shell("ulimit -v", d, {30, 0});
  EXPECT_EQ(none.stderr_tail, "unlimited");
  // Beyond what rlim_t holds: no limit, rather than an undefined conversion.
  EXPECT_EQ(shell("ulimit -v", d, {30, 1e300}).stderr_tail, "unlimited");
  // A child that needs more does not end normally.
  const ChildOutcome blown = shell("x=$(head -c 200000000 /dev/zero | tr '\\0' a); echo ${#x}", d, {30, 64});
  EXPECT_FALSE(blown.exited && blown.exit_code == 0) << blown.stderr_tail;
}

TEST(ChildProcess, AProgramThatCannotBeStartedIsExitCode127) {
  TmpDir d;
  const ChildOutcome o = run_child({d.file("no_such_program")}, {30, 0}, d.file("child.log"));
  EXPECT_TRUE(o.exited);
  EXPECT_EQ(o.exit_code, 127);
}

TEST(ChildProcess, SelfExeIsThisProgram) {
  EXPECT_EQ(std::filesystem::path(self_exe()).filename(), "bvhbench_tests");
}
