// Progress lines: what a long command prints on stderr while it works and when it ends.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "harness/util/progress.hpp"

using bvhbench::Progress;

TEST(Progress, UnwindingSaysStoppedNotDone) {
  // A build interrupted by an exception (SIGINT, a bad input, a full disk) must not print
  // "done" just before the error message says what happened.
  Progress::set_global_enabled(true);  // another test in this process may have turned it off
  testing::internal::CaptureStderr();
  try {
    Progress p("building x", 1.0, true);
    p.update(0.5);
    throw std::runtime_error("interrupted");
  } catch (const std::runtime_error&) {
  }
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("building x: stopped at 50.0%"), std::string::npos) << err;
  EXPECT_EQ(err.find("done"), std::string::npos) << err;
}

TEST(Progress, DisabledIsSilentEvenWhenUnwinding) {
  testing::internal::CaptureStderr();
  try {
    Progress p("building y", 1.0, false);
    p.update(0.25);
    throw std::runtime_error("interrupted");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

TEST(Progress, FormatSeconds) {
  EXPECT_EQ(bvhbench::format_seconds(42.2), "42s");
  EXPECT_EQ(bvhbench::format_seconds(185), "3m05s");
  EXPECT_EQ(bvhbench::format_seconds(3720), "1h02m");
  EXPECT_EQ(bvhbench::format_seconds(-1), "?");
}
