#pragma once
/// Whole-buffer POSIX reads and writes for the `.ebp` store and the external build: one place for
/// the loops over short transfers and EINTR. Writes throw (the store's writers turn any failure
/// into "nothing written"); reads report how they ended, so that each reader keeps its own
/// message (a truncated store, a truncated mesh and a short sort run are different problems).
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

namespace ebp::io {

/// Throws "PATH: WHAT: strerror(errno)".
[[noreturn]] inline void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": " + what + ": " + std::strerror(errno));
}

/// Writes n bytes at `off` (a write of 0 bytes counts as a full disk), or throws via fail().
inline void pwrite_all(int fd, const std::string& path, const void* data, std::size_t n, std::uint64_t off) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  while (n > 0) {
    const ssize_t w = ::pwrite(fd, p, n, off_t(off));
    if (w < 0) {
      if (errno == EINTR) continue;
      fail(path, "write failed");
    }
    if (w == 0) {
      errno = ENOSPC;
      fail(path, "write failed");
    }
    p += w;
    n -= std::size_t(w);
    off += std::uint64_t(w);
  }
}

enum class ReadEnd { complete, end_of_file, error };

/// Reads n bytes at `off`. `error` leaves errno set; `end_of_file` means the file ended first.
inline ReadEnd pread_full(int fd, void* dst, std::size_t n, std::uint64_t off) {
  auto* p = static_cast<std::uint8_t*>(dst);
  while (n > 0) {
    const ssize_t r = ::pread(fd, p, n, off_t(off));
    if (r < 0) {
      if (errno == EINTR) continue;
      return ReadEnd::error;
    }
    if (r == 0) return ReadEnd::end_of_file;
    p += r;
    n -= std::size_t(r);
    off += std::uint64_t(r);
  }
  return ReadEnd::complete;
}

}  // namespace ebp::io
