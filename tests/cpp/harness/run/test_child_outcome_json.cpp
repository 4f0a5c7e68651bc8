// A child's end as JSON (run/child_outcome_json.hpp): what a Dask worker sends back must give the
// job the same status row as if its child had run here.
#include <gtest/gtest.h>
#include <signal.h>

#include <nlohmann/json.hpp>

#include "harness/run/child_outcome_json.hpp"
#include "harness/run/job_status.hpp"

using namespace bvhbench;
using json = nlohmann::json;

TEST(ChildOutcomeJson, RoundTripKeepsEveryMemberAndSoTheStatus) {
  ChildOutcome o;
  o.signal = SIGSEGV;
  o.seconds = 1.25;
  o.stderr_tail = "bvhbench: segfault \xc3\xa9";
  const ChildOutcome back = child_outcome_from_json(json::parse(child_outcome_to_json(o).dump()));
  EXPECT_EQ(back.exited, o.exited);
  EXPECT_EQ(back.exit_code, o.exit_code);
  EXPECT_EQ(back.signal, o.signal);
  EXPECT_EQ(back.timed_out, o.timed_out);
  EXPECT_EQ(back.seconds, o.seconds);
  EXPECT_EQ(back.stderr_tail, o.stderr_tail);
  EXPECT_EQ(child_status(back, 10).code, child_status(o, 10).code);

  ChildOutcome late;
  late.timed_out = true;
  late.signal = SIGKILL;
  EXPECT_EQ(child_status(child_outcome_from_json(child_outcome_to_json(late)), 10).code, "timeout");
}

TEST(ChildOutcomeJson, MissingOrMistypedMembersKeepTheirDefaults) {
  const ChildOutcome none = child_outcome_from_json(json());
  EXPECT_FALSE(none.exited);
  EXPECT_EQ(none.signal, 0);
  EXPECT_EQ(none.stderr_tail, "");
  const ChildOutcome odd = child_outcome_from_json(json{{"exited", "yes"}, {"exit_code", 3}, {"seconds", nullptr}});
  EXPECT_FALSE(odd.exited);
  EXPECT_EQ(odd.exit_code, 3);
  EXPECT_EQ(odd.seconds, 0);
  // An exit without a result, as a worker's run-child reports a job that left none.
  EXPECT_EQ(child_status(child_outcome_from_json(json{{"exited", true}, {"exit_code", 2}}), 10).code, "rejected_input");
}
