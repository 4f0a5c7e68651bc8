#pragma once
/// One loop over [0, n) on a thread budget, for the structure's build steps (the builder's per-leaf
/// passes, the face sides): TBB in an arena of `threads`, or a plain loop where one thread is
/// asked for or the range is too short to share.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstddef>

namespace ebp {

/// f(i) for i in [0, n), in parallel when threads > 1 and n >= 64, in chunks of `grain`.
template <class F>
void par_for(int threads, std::size_t n, F&& f, std::size_t grain = 16) {
  if (threads <= 1 || n < 64) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
    });
  });
}

}  // namespace ebp
