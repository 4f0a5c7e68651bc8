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
#if defined(__has_include)
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define BVHBENCH_HAVE_CALLGRIND_REQUESTS 1
#endif
#endif

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

}  // namespace bvhbench
