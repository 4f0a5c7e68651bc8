#pragma once
/// A team of T threads for a job's query passes: started once, then released together for each
/// pass and waited for together, so that a pass's wall time measures the queries and not thread
/// start-up. The calling thread is the team's thread 0; T = 1 starts no thread at all.
///
/// Idle threads block (a condition variable), they do not spin: with more threads than cores
/// (the oversubscribed point of a scaling curve) a spinning waiter would steal the cores the
/// workers need.
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace bvhbench {

class ThreadTeam {
 public:
  /// Starts `threads` - 1 threads (threads >= 1; std::invalid_argument otherwise).
  explicit ThreadTeam(int threads);
  /// Stops and joins the threads.
  ~ThreadTeam();
  ThreadTeam(const ThreadTeam&) = delete;
  ThreadTeam& operator=(const ThreadTeam&) = delete;

  int size() const { return size_; }

  /// Runs task(k) on thread k for every k in [0, size()) (k = 0 on the calling thread) and returns
  /// when every one has returned: the wall-clock seconds from the threads' release to the end of
  /// the last one. If tasks throw, the first exception (by k) is rethrown once all have ended.
  double run(const std::function<void(int)>& task);

 private:
  void worker(int k);
  int size_;
  std::vector<std::thread> threads_;
  std::mutex mu_;
  std::condition_variable start_, done_;
  const std::function<void(int)>* task_ = nullptr;
  std::uint64_t generation_ = 0;  ///< passes released so far
  int running_ = 0;               ///< workers (k >= 1) still in the current pass
  bool stop_ = false;
  std::vector<std::exception_ptr> errors_;  ///< by k, for the current pass (written once each)
};

}  // namespace bvhbench
