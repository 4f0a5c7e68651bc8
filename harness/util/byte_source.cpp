#include "harness/util/byte_source.hpp"

#include <sys/stat.h>
#include <sys/types.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "harness/util/errors.hpp"
#include "harness/util/progress.hpp"

namespace bvhbench {

namespace {
constexpr std::size_t kBuffer = std::size_t(8) << 20;
constexpr std::size_t kMaxLine = std::size_t(64) << 20;
}  // namespace

ByteSource::ByteSource(const std::string& path, Progress* progress) : name_(path), progress_(progress) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    throw file_error(path, err == ENOENT ? "file not found" : std::string("cannot open: ") + std::strerror(err));
  }
  if (S_ISDIR(st.st_mode)) throw file_error(path, "is a directory, not a mesh file");
  if (!S_ISREG(st.st_mode)) throw file_error(path, "not a regular file");
  f_ = std::fopen(path.c_str(), "rb");
  if (!f_) throw file_error(path, std::string("cannot open: ") + std::strerror(errno));
  std::setvbuf(f_, nullptr, _IONBF, 0);
  size_ = std::uint64_t(st.st_size);
  buf_.resize(std::size_t(std::min<std::uint64_t>(kBuffer, size_ + 1)));
  p = e = buf_.data();
}

ByteSource::ByteSource(std::string_view data, std::string name) : name_(std::move(name)) {
  size_ = data.size();
  p = data.data();
  e = p + data.size();
  read_ = size_;
  eof_ = true;
  hash_new_bytes(0, p, data.size());
}

ByteSource::~ByteSource() {
  if (f_) std::fclose(f_);
}

void ByteSource::hash_new_bytes(std::uint64_t at, const char* bytes, std::size_t n) {
  // Reads are sequential from wherever seek() put them, and seek() never skips unhashed bytes,
  // so a read starts at or before hashed_: only its tail past hashed_ is new.
  if (at + n <= hashed_) return;
  const std::size_t skip = std::size_t(hashed_ - at);
  sha_.update(bytes + skip, n - skip);
  hashed_ = at + n;
  if (progress_) progress_->update(double(hashed_));
}

bool ByteSource::fill(std::size_t need) {
  if (avail() >= need) return true;
  if (eof_) return false;
  const std::size_t have = avail();
  if (need > buf_.size()) {
    std::vector<char> bigger(std::max(need, 2 * buf_.size()));
    std::memcpy(bigger.data(), p, have);
    buf_.swap(bigger);
  } else if (p != buf_.data()) {
    std::memmove(buf_.data(), p, have);
  }
  p = buf_.data();
  e = p + have;
  while (!eof_ && avail() < need) {
    char* end = buf_.data() + avail();
    const std::size_t room = buf_.size() - avail();
    const std::size_t got = std::fread(end, 1, room, f_);
    if (got < room) {
      if (std::ferror(f_)) throw file_error(name_, std::string("read error: ") + std::strerror(errno));
      eof_ = true;
    }
    hash_new_bytes(read_, end, got);
    read_ += got;
    e += got;
  }
  return avail() >= need;
}

bool ByteSource::line(std::string_view& out) {
  std::size_t scanned = 0;
  for (;;) {
    const char* nl = static_cast<const char*>(std::memchr(p + scanned, '\n', avail() - scanned));
    if (nl) {
      out = std::string_view(p, std::size_t(nl - p));
      p = nl + 1;
      break;
    }
    scanned = avail();
    if (eof_ || !fill(avail() + 1)) {
      if (avail() == 0) return false;
      out = std::string_view(p, avail());
      p = e;
      break;
    }
    if (avail() > kMaxLine)
      throw file_error(name_, "line " + std::to_string(line_no_ + 1) +
                                  " is longer than 64 MB (binary data in a text file?)");
  }
  ++line_no_;
  if (!out.empty() && out.back() == '\r') out.remove_suffix(1);
  return true;
}

void ByteSource::seek(std::uint64_t offset, std::uint64_t line_no) {
  offset = std::min(offset, size_);
  if (offset > hashed_) {
    // Never skip bytes that were not hashed: read through them.
    seek(hashed_, 0);
    while (this->offset() < offset && fill(1)) p += std::min<std::uint64_t>(avail(), offset - this->offset());
    line_no_ = line_no;
    return;
  }
  // The bytes at hand are [read_ - (e - first), read_): all of them for bytes in memory.
  const char* first = f_ ? buf_.data() : e - std::size_t(size_);
  if (offset >= read_ - std::uint64_t(e - first) && offset <= read_) {
    p = e - std::size_t(read_ - offset);
  } else {
    if (::fseeko(f_, off_t(offset), SEEK_SET) != 0)
      throw file_error(name_, std::string("cannot seek: ") + std::strerror(errno));
    std::clearerr(f_);
    read_ = offset;
    p = e = buf_.data();
    eof_ = false;
  }
  line_no_ = line_no;
}

std::string ByteSource::finish_hash() {
  if (!digest_.empty()) return digest_;
  if (f_) {
    seek(hashed_, line_no_);
    while (fill(1)) p = e;
  }
  digest_ = sha_.hex_digest();
  return digest_;
}

}  // namespace bvhbench
