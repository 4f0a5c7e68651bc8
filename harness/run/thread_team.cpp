#include "harness/run/thread_team.hpp"

#include <chrono>
#include <stdexcept>

namespace bvhbench {

ThreadTeam::ThreadTeam(int threads) : size_(threads) {
  if (threads < 1) throw std::invalid_argument("a thread team needs at least one thread");
  errors_.resize(std::size_t(threads));
  threads_.reserve(std::size_t(threads - 1));
  for (int k = 1; k < threads; ++k) threads_.emplace_back([this, k] { worker(k); });
}

ThreadTeam::~ThreadTeam() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  start_.notify_all();
  for (auto& t : threads_) t.join();
}

void ThreadTeam::worker(int k) {
  std::uint64_t seen = 0;
  for (;;) {
    const std::function<void(int)>* task;
    {
      std::unique_lock<std::mutex> lock(mu_);
      start_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      task = task_;
    }
    try {
      (*task)(k);
    } catch (...) {
      errors_[std::size_t(k)] = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mu_);
    if (--running_ == 0) done_.notify_one();
  }
}

double ThreadTeam::run(const std::function<void(int)>& task) {
  using Clock = std::chrono::steady_clock;
  for (auto& e : errors_) e = nullptr;
  Clock::time_point t0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    task_ = &task;
    running_ = size_ - 1;
    ++generation_;
    t0 = Clock::now();
  }
  start_.notify_all();
  try {
    task(0);
  } catch (...) {
    errors_[0] = std::current_exception();
  }
  {
    std::unique_lock<std::mutex> lock(mu_);
    done_.wait(lock, [&] { return running_ == 0; });
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  for (auto& e : errors_)
    if (e) std::rethrow_exception(e);
  return seconds;
}

}  // namespace bvhbench
