#include "harness/util/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>

namespace bvhbench {

namespace {

/// Eight random hex digits: with O_EXCL and a few retries, a name no other writer holds.
std::string random_suffix() {
  static thread_local std::mt19937_64 rng{std::random_device{}() ^ (std::uint64_t(::getpid()) << 32)};
  static const char* hex = "0123456789abcdef";
  std::string s(8, '0');
  std::uint64_t v = rng();
  for (char& c : s) {
    c = hex[v & 15];
    v >>= 4;
  }
  return s;
}

}  // namespace

AtomicOutputFile::AtomicOutputFile(const std::string& path) : path_(path) {
  int fd = -1;
  for (int attempt = 0; attempt < 16 && fd < 0; ++attempt) {
    tmp_ = path_ + ".tmp." + random_suffix();
    fd = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) throw std::runtime_error(path_ + ": cannot write: " + std::strerror(errno));
  f_ = ::fdopen(fd, "wb");
  if (!f_) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    std::remove(tmp_.c_str());
    throw std::runtime_error(path_ + ": cannot write: " + why);
  }
}

AtomicOutputFile::~AtomicOutputFile() {
  if (f_) {
    std::fclose(f_);
    std::remove(tmp_.c_str());
  }
}

void AtomicOutputFile::write(const void* data, std::size_t n) {
  if (n && ok_ && std::fwrite(data, 1, n, f_) != n) {
    ok_ = false;
    errno_ = errno;
  }
  offset_ += n;
}

void AtomicOutputFile::commit() {
  const bool closed = std::fclose(f_) == 0;
  const int close_errno = errno;
  f_ = nullptr;
  if (!ok_ || !closed || std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const std::string why = std::strerror(!ok_ ? errno_ : !closed ? close_errno : errno);
    std::remove(tmp_.c_str());
    throw std::runtime_error(path_ + ": cannot write: " + why);
  }
}

void AtomicOutputFile::write_at(std::uint64_t offset, const void* data, std::size_t n) {
  auto fail = [&] { throw std::runtime_error(path_ + ": cannot write: " + std::strerror(errno)); };
  if (std::fflush(f_) != 0) fail();
  if (offset > std::uint64_t(std::numeric_limits<off_t>::max()) || n > std::numeric_limits<off_t>::max() - offset) {
    errno = EFBIG;
    fail();
  }
  const int fd = fileno(f_);
  const auto* p = static_cast<const unsigned char*>(data);
  while (n > 0) {
    const ssize_t w = ::pwrite(fd, p, n, off_t(offset));
    if (w < 0 && errno == EINTR) continue;
    if (w < 0) fail();
    if (w == 0) {  // no progress: a full disk
      errno = ENOSPC;
      fail();
    }
    p += w;
    n -= std::size_t(w);
    offset += std::uint64_t(w);
  }
}

void AtomicOutputFile::resize(std::uint64_t size) {
  if (std::fflush(f_) != 0 || size > std::uint64_t(std::numeric_limits<off_t>::max()) ||
      ::ftruncate(fileno(f_), off_t(size)) != 0)
    throw std::runtime_error(path_ + ": cannot write: " + std::strerror(errno));
}

void AtomicOutputFile::commit_durable() {
  if (ok_ && (std::fflush(f_) != 0 || ::fsync(fileno(f_)) != 0)) {
    ok_ = false;
    errno_ = errno;
  }
  commit();
  const auto slash = path_.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : path_.substr(0, slash);
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    (void)::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace bvhbench
