#pragma once
/// The bytes of one input (a file, or bytes in memory) as the mesh parsers read them: a window
/// `[p, e)` that `fill()` extends, lines, and `seek()` for a parser that reads a part again. The
/// SHA-256 of the input is computed on the way: every byte is hashed once, in order, the first
/// time it is read, so re-reading a part (a second scan of the faces) costs no second hash and
/// the hash needs no pass of its own.
///
/// A file is read through one buffer (8 MiB, grown only for a longer line or list): it is never
/// mapped or read whole, which would add its size to the process's peak RSS.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "harness/util/sha256.hpp"

namespace bvhbench {

class Progress;

class ByteSource {
 public:
  /// Opens the file at `path` (InputError: not found, a directory, not a regular file, cannot
  /// open). `progress` (optional) is advanced over the bytes read the first time.
  ByteSource(const std::string& path, Progress* progress);
  /// Bytes in memory, not copied: `data` must outlive the source. `name` names it in messages.
  ByteSource(std::string_view data, std::string name);
  ~ByteSource();
  ByteSource(const ByteSource&) = delete;
  ByteSource& operator=(const ByteSource&) = delete;

  /// The file's path, or the name given for bytes in memory: what messages name.
  const std::string& name() const { return name_; }
  /// Bytes of the input (the file's size as stat saw it).
  std::uint64_t size() const { return size_; }
  /// Offset of `p` in the input.
  std::uint64_t offset() const { return read_ - std::uint64_t(e - p); }
  /// Bytes of the input after `p`.
  std::uint64_t remaining() const { return size_ > offset() ? size_ - offset() : 0; }
  std::size_t avail() const { return std::size_t(e - p); }
  /// Number of the last line returned by line() (1-based; as set by seek()).
  std::uint64_t line_no() const { return line_no_; }

  /// Makes at least `need` bytes available at `p`; false if the input ends first.
  bool fill(std::size_t need);
  /// The next line without its terminator (nor a trailing '\r'); false at the end of the input.
  /// A line longer than 64 MiB is an InputError (binary data in a text file).
  bool line(std::string_view& out);
  /// Moves `p` to `offset` (at most size()); `line_no` is the number of the line before it.
  /// Bytes before `offset` that were never read are read (and hashed) on the way.
  void seek(std::uint64_t offset, std::uint64_t line_no);
  /// Hashes whatever was never read and returns the input's hex SHA-256 (the same on every call).
  /// `p` is left where it was.
  std::string finish_hash();
  /// Bytes of the read buffer (0 for bytes in memory).
  std::size_t buffer_bytes() const { return buf_.capacity(); }

  const char* p = nullptr;  ///< next unread byte
  const char* e = nullptr;  ///< end of the bytes available

 private:
  void hash_new_bytes(std::uint64_t at, const char* bytes, std::size_t n);

  std::string name_;
  Progress* progress_ = nullptr;
  std::FILE* f_ = nullptr;  ///< null for bytes in memory
  std::uint64_t size_ = 0;
  std::uint64_t read_ = 0;     ///< input offset of `e`
  std::uint64_t hashed_ = 0;   ///< bytes [0, hashed_) are hashed
  std::uint64_t line_no_ = 0;
  std::vector<char> buf_;
  bool eof_ = false;
  Sha256 sha_;
  std::string digest_;
};

}  // namespace bvhbench
