#include "harness/util/binary_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>

#include "harness/util/errors.hpp"

namespace bvhbench {

InputFile::InputFile(const std::string& path) : path_(path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw file_error(path, errno == ENOENT ? "file not found" : std::string("cannot open: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw file_error(path, "not a regular file");
  f_ = std::fopen(path.c_str(), "rb");
  if (!f_) throw file_error(path, std::string("cannot open: ") + std::strerror(errno));
  size_ = std::uint64_t(st.st_size);
}

InputFile::InputFile(std::string_view data, std::string name)
    : path_(std::move(name)), data_(data.data()), size_(data.size()) {}

InputFile::~InputFile() {
  if (f_) std::fclose(f_);
}

void InputFile::read_at(std::uint64_t offset, void* out, std::size_t n, const std::string& what) {
  if (offset > size_ || n > size_ - offset)
    throw file_error(path_, "truncated (" + what + " extends past the end of the file)");
  if (n == 0) return;
  if (!f_) {
    std::memcpy(out, data_ + offset, n);
    return;
  }
  if (fseeko(f_, off_t(offset), SEEK_SET) != 0 || std::fread(out, 1, n, f_) != n)
    throw file_error(path_, "read error in " + what);
}

AtomicOutputFile::AtomicOutputFile(const std::string& path) : path_(path), tmp_(path + ".tmp") {
  f_ = std::fopen(tmp_.c_str(), "wb");
  if (!f_) throw std::runtime_error(path_ + ": cannot write: " + std::strerror(errno));
}

AtomicOutputFile::~AtomicOutputFile() {
  if (f_) {
    std::fclose(f_);
    std::remove(tmp_.c_str());
  }
}

void AtomicOutputFile::write(const void* data, std::size_t n) {
  if (n && std::fwrite(data, 1, n, f_) != n) ok_ = false;
  offset_ += n;
}

void AtomicOutputFile::commit() {
  const bool closed = std::fclose(f_) == 0;
  f_ = nullptr;
  if (!ok_ || !closed || std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const std::string why = std::strerror(errno);
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
  if (std::fflush(f_) != 0 || ::fsync(fileno(f_)) != 0) ok_ = false;
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
