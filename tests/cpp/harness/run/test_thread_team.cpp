// ThreadTeam (harness/run/thread_team.hpp): every thread runs its task once per pass, thread 0 is
// the caller, the same threads serve every pass (started once), 64 threads work on any machine,
// and a task's exception comes back to the caller after the pass.
#include <gtest/gtest.h>

#include <atomic>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "harness/run/thread_team.hpp"

using bvhbench::ThreadTeam;

TEST(ThreadTeam, EachThreadRunsItsTaskOncePerPassOnTheSameThreads) {
  for (int threads : {1, 2, 4, 64}) {
    ThreadTeam team(threads);
    ASSERT_EQ(team.size(), threads);
    std::vector<std::thread::id> first(static_cast<std::size_t>(threads));
    for (int pass = 0; pass < 3; ++pass) {
      std::vector<int> runs(static_cast<std::size_t>(threads), 0);
      std::vector<std::thread::id> ids(static_cast<std::size_t>(threads));
      const double seconds = team.run([&](int k) {
        ++runs[static_cast<std::size_t>(k)];
        ids[static_cast<std::size_t>(k)] = std::this_thread::get_id();
      });
      EXPECT_GE(seconds, 0.0);
      EXPECT_EQ(runs, std::vector<int>(static_cast<std::size_t>(threads), 1));
      EXPECT_EQ(ids[0], std::this_thread::get_id()) << "thread 0 is the caller";
      EXPECT_EQ(std::set<std::thread::id>(ids.begin(), ids.end()).size(), static_cast<std::size_t>(threads));
      if (pass == 0) first = ids;
      EXPECT_EQ(ids, first) << "a pass started new threads";
    }
  }
}

TEST(ThreadTeam, APassEndsWhenItsLastThreadDoes) {
  ThreadTeam team(4);
  std::atomic<int> done{0};
  team.run([&](int k) {
    if (k == 3) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ++done;
  });
  EXPECT_EQ(done.load(), 4);
}

TEST(ThreadTeam, ATaskExceptionComesBackAfterThePass) {
  ThreadTeam team(3);
  std::atomic<int> ran{0};
  EXPECT_THROW(team.run([&](int k) {
    ++ran;
    if (k == 2) throw std::runtime_error("thread 2 fails");
  }),
               std::runtime_error);
  EXPECT_EQ(ran.load(), 3);
  // The team still works afterwards.
  ran = 0;
  team.run([&](int) { ++ran; });
  EXPECT_EQ(ran.load(), 3);
}

TEST(ThreadTeam, NeedsAThread) { EXPECT_THROW(ThreadTeam(0), std::invalid_argument); }
