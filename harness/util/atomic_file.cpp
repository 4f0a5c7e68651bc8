#include "harness/util/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
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

}  // namespace bvhbench
