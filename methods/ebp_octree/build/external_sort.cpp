// The external sort's run files (external_sort.hpp).
#include "methods/ebp_octree/build/external_sort.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "methods/ebp_octree/store/posix_io.hpp"

namespace ebp::detail {

RunReader::RunReader(const RunFile& rf, std::size_t buf_records)
    : path_(rf.path), left_(rf.records), buf_(std::max<std::size_t>(buf_records, 16)) {
  fd_ = ::open(rf.path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) io::fail(rf.path, "cannot open a sorted run");
  ::posix_fadvise(fd_, 0, 0, POSIX_FADV_SEQUENTIAL);
}

RunReader::~RunReader() {
  if (fd_ >= 0) ::close(fd_);
}

bool RunReader::fill() {
  if (left_ == 0) return false;
  const std::size_t n = std::size_t(std::min<std::uint64_t>(left_, buf_.size()));
  switch (io::pread_full(fd_, buf_.data(), n * sizeof(Rec), off_)) {
    case io::ReadEnd::complete: break;
    case io::ReadEnd::error: io::fail(path_, "read failed");
    case io::ReadEnd::end_of_file: errno = EIO; io::fail(path_, "sorted run shorter than written");
  }
  off_ += n * sizeof(Rec);
  left_ -= n;
  n_ = n;
  pos_ = 0;
  return true;
}

void write_run(const std::string& path, const std::vector<Rec>& run) {
  const int fd = ::open(path.c_str(), O_CREAT | O_TRUNC | O_WRONLY | O_CLOEXEC, 0600);
  if (fd < 0) io::fail(path, "cannot create a temporary file");
  try {
    io::pwrite_all(fd, path, run.data(), run.size() * sizeof(Rec), 0);
  } catch (...) {
    ::close(fd);
    throw;
  }
  if (::close(fd) != 0) io::fail(path, "close failed");
}

}  // namespace ebp::detail
