#pragma once
/// The external sort of the external build: (leaf cell, triangle) records, sorted in runs that
/// fit the memory budget, spilled to temporary files and read back for the k-way merge.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ebp::detail {

struct Rec {
  std::uint64_t m;     // leaf Morton code
  std::uint32_t t;     // triangle
  std::uint32_t v[3];  // its vertices (coordinates: TriangleSource::float_vertices())
};
static_assert(sizeof(Rec) == 24, "Rec is 24 bytes");
struct RecLess {
  bool operator()(const Rec& a, const Rec& b) const { return a.m < b.m || (a.m == b.m && a.t < b.t); }
};

struct RunFile {
  std::string path;
  std::uint64_t records = 0;
};

/// Reads a run back in buffers of `buf_records` records (at least 16), in order.
class RunReader {
 public:
  RunReader(const RunFile& rf, std::size_t buf_records);
  ~RunReader();
  RunReader(const RunReader&) = delete;
  RunReader& operator=(const RunReader&) = delete;
  const Rec* peek() {
    if (pos_ == n_ && !fill()) return nullptr;
    return &buf_[pos_];
  }
  void pop() { ++pos_; }

 private:
  bool fill();
  std::string path_;
  int fd_ = -1;
  std::uint64_t left_, off_ = 0;
  std::vector<Rec> buf_;
  std::size_t pos_ = 0, n_ = 0;
};

/// Writes `run` (sorted) as the run file `path` (mode 0600). Throws std::runtime_error naming it.
void write_run(const std::string& path, const std::vector<Rec>& run);

/// Removes its files on scope exit.
struct TempFiles {
  std::vector<std::string> paths;
  ~TempFiles() {
    for (const std::string& p : paths) ::unlink(p.c_str());
  }
};

}  // namespace ebp::detail
