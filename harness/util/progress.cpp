#include "harness/util/progress.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <exception>

namespace bvhbench {

namespace {
bool g_enabled = true;
}

void Progress::set_global_enabled(bool on) { g_enabled = on; }

std::string format_seconds(double s) {
  char buf[32];
  if (!std::isfinite(s) || s < 0) return "?";
  if (s < 60) std::snprintf(buf, sizeof buf, "%.0fs", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
  else std::snprintf(buf, sizeof buf, "%dh%02dm", int(s) / 3600, (int(s) % 3600) / 60);
  return buf;
}

Progress::Progress(std::string what, double total, bool enabled)
    : what_(std::move(what)), total_(total), enabled_(enabled && g_enabled),
      tty_(isatty(STDERR_FILENO)), uncaught_(std::uncaught_exceptions()),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

Progress::~Progress() {
  if (!enabled_ || finished_ || done_ <= 0) return;
  // Unwinding (an interrupt, a bad input, a full disk): the work did not finish, and the line
  // must not say "done" just before the error message says what happened.
  if (std::uncaught_exceptions() > uncaught_) {
    finished_ = true;
    print(Line::stopped);
    return;
  }
  finish();
}

void Progress::update(double done) {
  done_ = done;
  if (!enabled_) return;
  auto now = std::chrono::steady_clock::now();
  double since = std::chrono::duration<double>(now - last_).count();
  // A terminal redraws often; a log gets a line every 5 s at most.
  if (since < (tty_ ? 0.25 : 5.0)) return;
  last_ = now;
  print(Line::running);
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (!enabled_) return;
  double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (elapsed < 1.0 && !tty_) return;  // short work: no noise in logs
  print(Line::done);
}

void Progress::print(Line kind) {
  const bool final = kind != Line::running;
  double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  double frac = total_ > 0 ? std::min(1.0, done_ / total_) : 0.0;
  char line[256];
  if (kind == Line::stopped) {
    std::snprintf(line, sizeof line, "%s: stopped at %.1f%% after %s", what_.c_str(), 100 * frac,
                  format_seconds(elapsed).c_str());
  } else if (final) {
    std::snprintf(line, sizeof line, "%s: done in %s", what_.c_str(), format_seconds(elapsed).c_str());
  } else {
    double left = frac > 0 ? elapsed * (1 - frac) / frac : NAN;
    std::snprintf(line, sizeof line, "%s: %5.1f%%  elapsed %s  left ~%s", what_.c_str(), 100 * frac,
                  format_seconds(elapsed).c_str(), format_seconds(left).c_str());
  }
  if (tty_) std::fprintf(stderr, "\r\033[K%s%s", line, final ? "\n" : "");
  else std::fprintf(stderr, "%s\n", line);
  std::fflush(stderr);
}

}  // namespace bvhbench
