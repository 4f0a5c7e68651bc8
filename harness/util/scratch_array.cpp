// Arrays in temporary files behind a page cache (scratch_array.hpp).
#include "harness/util/scratch_array.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <stdexcept>

#include "harness/util/errors.hpp"

namespace bvhbench {

namespace {
[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw InputError(name + ": " + what + ": " + std::strerror(errno));
}
}  // namespace

ScratchFile::ScratchFile(const std::string& dir, const std::string& what, std::size_t record_bytes,
                         std::size_t cache_bytes)
    : name_((dir.empty() ? std::string(".") : dir) + "/" + what + " (temporary)"),
      record_bytes_(record_bytes),
      page_bytes_(kPageRecords * record_bytes),
      cache_bytes_(cache_bytes) {
  std::string pattern = (dir.empty() ? std::string(".") : dir) + "/bvhbench-scratch-XXXXXX";
  std::vector<char> buf(pattern.begin(), pattern.end());
  buf.push_back('\0');
  fd_ = ::mkstemp(buf.data());
  if (fd_ < 0) fail(dir.empty() ? std::string(".") : dir, "cannot create a temporary file for " + what);
  // Unlinked at once: the file lives as long as the descriptor, whatever ends the process.
  ::unlink(buf.data());
  wbuf_.reserve(page_bytes_);
}

ScratchFile::~ScratchFile() {
  if (fd_ >= 0) ::close(fd_);
}

std::size_t ScratchFile::resident_bytes() const {
  return slots_.capacity() + wbuf_.capacity() + slot_of_.capacity() * sizeof(std::int32_t) +
         page_in_.capacity() * (sizeof(std::uint64_t) + 1);
}

void ScratchFile::flush() {
  const unsigned char* p = wbuf_.data();
  std::size_t n = wbuf_.size();
  std::uint64_t off = flushed_bytes_;
  while (n > 0) {
    const ssize_t w = ::pwrite(fd_, p, n, off_t(off));
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      if (w == 0) errno = ENOSPC;
      fail(name_, "write failed");
    }
    p += w;
    n -= std::size_t(w);
    off += std::uint64_t(w);
  }
  flushed_bytes_ = off;
  wbuf_.clear();
}

void ScratchFile::append(const void* records, std::size_t n) {
  if (finished_) throw std::logic_error("ScratchFile: append after finish");
  const auto* src = static_cast<const unsigned char*>(records);
  std::size_t bytes = n * record_bytes_;
  records_ += n;
  while (bytes > 0) {
    const std::size_t take = std::min(bytes, page_bytes_ - wbuf_.size());
    wbuf_.insert(wbuf_.end(), src, src + take);
    src += take;
    bytes -= take;
    if (wbuf_.size() == page_bytes_) flush();
  }
}

void ScratchFile::finish() {
  if (finished_) return;
  if (!wbuf_.empty()) flush();
  std::vector<unsigned char>().swap(wbuf_);  // its page is not needed again
  finished_ = true;
  const std::uint64_t pages = (records_ + kPageRecords - 1) / kPageRecords;
  std::size_t slots = std::max<std::size_t>(2, cache_bytes_ / page_bytes_);
  slots = std::size_t(std::min<std::uint64_t>(slots, std::max<std::uint64_t>(pages, 1)));
  slots_.assign(slots * page_bytes_, 0);
  slot_of_.assign(pages, -1);
  page_in_.assign(slots, UINT64_MAX);
  referenced_.assign(slots, 0);
}

const unsigned char* ScratchFile::page(std::uint64_t p) const {
  ++reads_;
  if (p == last_page_) return last_;
  std::int32_t s = slot_of_[p];
  if (s < 0) {
    ++misses_;
    while (referenced_[hand_]) {
      referenced_[hand_] = 0;
      hand_ = (hand_ + 1) % page_in_.size();
    }
    s = std::int32_t(hand_);
    hand_ = (hand_ + 1) % page_in_.size();
    if (page_in_[std::size_t(s)] != UINT64_MAX) slot_of_[page_in_[std::size_t(s)]] = -1;
    unsigned char* dst = &slots_[std::size_t(s) * page_bytes_];
    std::uint64_t off = p * page_bytes_;
    std::size_t n = std::size_t(std::min<std::uint64_t>(page_bytes_, records_ * record_bytes_ - off));
    while (n > 0) {
      const ssize_t r = ::pread(fd_, dst, n, off_t(off));
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) {
        if (r == 0) errno = EIO;  // shorter than written: someone else changed the file
        fail(name_, "read failed");
      }
      dst += r;
      n -= std::size_t(r);
      off += std::uint64_t(r);
    }
    page_in_[std::size_t(s)] = p;
    slot_of_[p] = s;
  }
  referenced_[std::size_t(s)] = 1;
  last_page_ = p;
  last_ = &slots_[std::size_t(s) * page_bytes_];
  return last_;
}

const unsigned char* ScratchFile::record(std::uint64_t i) const {
  if (!finished_ || i >= records_) throw std::logic_error("ScratchFile: record read out of range or before finish");
  return page(i / kPageRecords) + (i % kPageRecords) * record_bytes_;
}

}  // namespace bvhbench
