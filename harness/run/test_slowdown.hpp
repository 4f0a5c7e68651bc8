#pragma once
/// A test-only slowdown: extra work in one method's query loop that changes none of its answers
/// or counters, so that the instruction gate (tools/instr_gate.py) can be shown to catch what
/// the exact gate cannot see (docs/compare.md, "Testing the gate").
///
///   BVHBENCH_TEST_SLOWDOWN=METHOD:UNITS   e.g. ebp_octree:400
///
/// When the variable names the job's method (its registered name, every parameter set), the
/// method is wrapped: each query (each point of a batch call) first runs UNITS rounds of a
/// dependent integer chain the compiler cannot remove (5 instructions a round with GCC 12 -O3,
/// plus 16 for the wrapper's call), then asks
/// the real method. Nothing else changes: answers, counters, path state, structure.
/// It cannot pass unnoticed: the wrapper says so on stderr at build(), and the result's
/// `structure.TEST_SLOWDOWN` records the knob. Unset (always, outside the gate's own tests),
/// the method is not wrapped and no query loop has a branch more.
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "harness/core/method.hpp"

namespace bvhbench {

/// `method` itself, or wrapped as BVHBENCH_TEST_SLOWDOWN asks when it names `name`. A value that
/// is not METHOD:UNITS (UNITS a whole number 1..10^9) throws InputError naming it.
std::unique_ptr<Method> apply_test_slowdown(std::unique_ptr<Method> method, const std::string& name);

}  // namespace bvhbench
