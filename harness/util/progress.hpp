#pragma once
/// Progress for long work (mesh loading, builds, suites): a line on stderr with the fraction
/// done and an estimate of the time left. Redraws in place on a terminal, otherwise prints at
/// most one line every few seconds so that logs stay short. Silent when disabled.
#include <chrono>
#include <cstdint>
#include <string>

namespace bvhbench {

class Progress {
 public:
  Progress(std::string what, double total, bool enabled = true);
  ~Progress();
  void update(double done);  ///< cheap to call often
  void add(double delta) { update(done_ + delta); }
  void finish();             ///< prints the final line (with elapsed time)
  static void set_global_enabled(bool on);  ///< --quiet turns all progress off
 private:
  enum class Line { running, done, stopped };
  void print(Line kind);
  std::string what_;
  double total_, done_ = 0;
  bool enabled_, finished_ = false, tty_;
  int uncaught_;  ///< std::uncaught_exceptions() at construction: more at destruction = unwinding
  std::chrono::steady_clock::time_point start_, last_;
};

std::string format_seconds(double s);  ///< "42s", "3m05s", "1h02m"

}  // namespace bvhbench
