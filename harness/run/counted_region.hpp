#pragma once
/// The timed query passes, marked for an instruction count under valgrind's callgrind.
///
/// A timed pass on a shared machine is noise; the instructions it executes are not: for a given
/// binary, input and (valgrind-emulated) processor they are the same on every run. The
/// instruction gate (tools/instr_gate.py, docs/compare.md) runs `bvhbench run` under
///   valgrind --tool=callgrind --instr-atstart=no --collect-atstart=no
/// and this region switches instrumentation and collection on for exactly the timed passes (the
/// build, the calibration kernel, the counted and latency passes run uninstrumented, several
/// times faster). Outside valgrind each macro is a few instructions that valgrind alone
/// recognises: nothing is timed differently. Without valgrind's header the region is empty, and
/// the gate says "nothing was collected" rather than reporting zero instructions.
/// Collection is per thread in callgrind: the region is opened on the thread that runs stream 0
/// (ThreadTeam runs task 0 on its caller), which is every query when threads == 1, as the gate runs.
///
/// The jobs of one build group run in one process (`bvhbench run-group`); where there are several,
/// each job's timed passes are dumped on their own when the job ends (end_counted_job), so that
/// callgrind writes one part file per job (OUT.1, OUT.2, ...) labelled "bvhbench job K", K the
/// job's index in its group, and a measurement counts a 32M model's twenty jobs with one build
/// under valgrind rather than twenty (tools/instr_gate.py measure --groups). A lone job (`bvhbench
/// run`) dumps nothing: its counts are in OUT, as every callgrind reader expects.
#if defined(__has_include)
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define BVHBENCH_HAVE_CALLGRIND_REQUESTS 1
#endif
#endif

#include <cstddef>
#include <string>

namespace bvhbench {

class CountedRegion {
 public:
  CountedRegion() {
#ifdef BVHBENCH_HAVE_CALLGRIND_REQUESTS
    CALLGRIND_START_INSTRUMENTATION;
    CALLGRIND_TOGGLE_COLLECT;
#endif
  }
  ~CountedRegion() {
#ifdef BVHBENCH_HAVE_CALLGRIND_REQUESTS
    CALLGRIND_TOGGLE_COLLECT;
    CALLGRIND_STOP_INSTRUMENTATION;
#endif
  }
  CountedRegion(const CountedRegion&) = delete;
  CountedRegion& operator=(const CountedRegion&) = delete;
};

/// Writes what the counted regions of the group's job `index` collected to a callgrind part file
/// labelled "bvhbench job INDEX", and zeroes the counts for the next job. Outside callgrind it does
/// nothing.
inline void end_counted_job(std::size_t index) {
#ifdef BVHBENCH_HAVE_CALLGRIND_REQUESTS
  const std::string label = "bvhbench job " + std::to_string(index);
  CALLGRIND_DUMP_STATS_AT(label.c_str());
#else
  (void)index;
#endif
}

}  // namespace bvhbench
