// The float vertices in a temporary file behind a page cache (vertex_pages.hpp).
#include "methods/ebp_octree/build/vertex_pages.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "methods/ebp_octree/store/posix_io.hpp"

namespace ebp {

namespace {
constexpr std::size_t kPageFloats = 3 * VertexPages::kPageVertices;
constexpr std::size_t kPageBytes = kPageFloats * sizeof(float);
}  // namespace

VertexPages::VertexPages(const std::string& dir, std::uint64_t vertices, std::size_t cache_bytes)
    : dir_(dir), vertices_(vertices), num_pages_((vertices + kPageVertices - 1) / kPageVertices) {
  std::string name = dir + "/vertices-XXXXXX";
  std::vector<char> buf(name.begin(), name.end());
  buf.push_back('\0');
  fd_ = ::mkstemp(buf.data());
  if (fd_ < 0) io::fail(dir, "cannot create the temporary vertex file");
  // Unlinked at once: the file lives as long as the descriptor, whatever ends the build.
  ::unlink(buf.data());
  wbuf_.reserve(kPageFloats);
  std::size_t slots = std::max<std::size_t>(2, cache_bytes / kPageBytes);
  slots = std::size_t(std::min<std::uint64_t>(slots, std::max<std::uint64_t>(num_pages_, 1)));
  slots_.assign(slots * kPageFloats, 0.0f);
  slot_of_.assign(num_pages_, -1);
  page_in_.assign(slots, UINT64_MAX);
  referenced_.assign(slots, 0);
}

VertexPages::~VertexPages() {
  if (fd_ >= 0) ::close(fd_);
}

std::size_t VertexPages::resident_bytes() const {
  return slots_.capacity() * sizeof(float) + wbuf_.capacity() * sizeof(float) +
         slot_of_.capacity() * sizeof(std::int32_t) + page_in_.capacity() * (sizeof(std::uint64_t) + 1);
}

void VertexPages::flush() {
  io::pwrite_all(fd_, dir_ + "/vertices (temporary)", wbuf_.data(), wbuf_.size() * sizeof(float),
                 flushed_ * sizeof(float));
  flushed_ += wbuf_.size();
  wbuf_.clear();
}

void VertexPages::append(const float* xyz, std::size_t n) {
  // Written a page at a time, through wbuf_.
  written_ += n;
  const float* end = xyz + 3 * n;
  while (xyz < end) {
    const std::size_t take = std::min<std::size_t>(std::size_t(end - xyz), kPageFloats - wbuf_.size());
    wbuf_.insert(wbuf_.end(), xyz, xyz + take);
    xyz += take;
    if (wbuf_.size() == kPageFloats) flush();
  }
}

void VertexPages::rewind() {
  wbuf_.clear();
  written_ = flushed_ = 0;
  std::fill(slot_of_.begin(), slot_of_.end(), -1);
  std::fill(page_in_.begin(), page_in_.end(), UINT64_MAX);
  last_page_ = UINT64_MAX;
  last_ = nullptr;
}

void VertexPages::finish() {
  if (written_ != vertices_)
    throw std::logic_error("VertexPages: " + std::to_string(written_) + " vertices written, " +
                           std::to_string(vertices_) + " announced");
  if (!wbuf_.empty()) flush();
  wbuf_.shrink_to_fit();
}

const float* VertexPages::page(std::uint64_t p) {
  ++reads_;
  if (p == last_page_) return last_;
  std::int32_t s = slot_of_[p];
  if (s < 0) {
    ++misses_;
    // The clock: a slot read since the hand last passed gets a second chance.
    while (referenced_[hand_]) {
      referenced_[hand_] = 0;
      hand_ = (hand_ + 1) % page_in_.size();
    }
    s = std::int32_t(hand_);
    hand_ = (hand_ + 1) % page_in_.size();
    if (page_in_[std::size_t(s)] != UINT64_MAX) slot_of_[page_in_[std::size_t(s)]] = -1;
    const std::uint64_t first = p * kPageVertices;
    const std::size_t n = std::size_t(std::min<std::uint64_t>(kPageVertices, vertices_ - first));
    float* dst = &slots_[std::size_t(s) * kPageFloats];
    switch (io::pread_full(fd_, dst, 3 * n * sizeof(float), first * 3 * sizeof(float))) {
      case io::ReadEnd::complete: break;
      case io::ReadEnd::error: io::fail(dir_ + "/vertices (temporary)", "read failed");
      case io::ReadEnd::end_of_file: errno = EIO; io::fail(dir_ + "/vertices (temporary)", "shorter than written");
    }
    page_in_[std::size_t(s)] = p;
    slot_of_[p] = s;
  }
  referenced_[std::size_t(s)] = 1;
  last_page_ = p;
  last_ = &slots_[std::size_t(s) * kPageFloats];
  return last_;
}

void VertexPages::gather(const std::uint32_t* idx, std::size_t n, float* xyz) {
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint64_t v = idx[k];
    const float* pg = page(v / kPageVertices);
    std::memcpy(xyz + 3 * k, pg + 3 * (v % kPageVertices), 3 * sizeof(float));
  }
}

}  // namespace ebp
