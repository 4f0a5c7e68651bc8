#pragma once
/// Binary files read at offsets and written atomically: the plumbing under the .npy and ZIP
/// (.npz) readers and writers, which move arrays of hundreds of MB straight between a file and
/// their final buffer.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace bvhbench {

/// A regular file opened for reading, or bytes in memory read as if they were one (fuzzing,
/// tests): the readers above it cannot tell the two apart. Errors are InputError naming the file.
class InputFile {
 public:
  /// Throws InputError: "file not found", "not a regular file", "cannot open: <why>".
  explicit InputFile(const std::string& path);
  /// Bytes in memory, not copied: `data` must outlive the InputFile. `name` names it in messages.
  InputFile(std::string_view data, std::string name);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  const std::string& path() const { return path_; }  ///< or the name given for bytes in memory
  std::uint64_t size() const { return size_; }  ///< bytes, when opened

  /// Reads exactly `n` bytes at `offset`; throws InputError "truncated (`what` extends past the
  /// end of the file)" if they are not all there, or "read error in `what`".
  void read_at(std::uint64_t offset, void* out, std::size_t n, const std::string& what);

 private:
  std::string path_;
  std::FILE* f_ = nullptr;       // null for bytes in memory
  const char* data_ = nullptr;   // bytes in memory
  std::uint64_t size_ = 0;
};

/// A file written to PATH.tmp and renamed to PATH by commit(); without commit() (an exception
/// on the way) the temporary file is removed and PATH is left as it was. Errors are
/// std::runtime_error "PATH: cannot write: <why>" (an output problem, not bad input).
class AtomicOutputFile {
 public:
  explicit AtomicOutputFile(const std::string& path);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  void write(const void* data, std::size_t n);
  void write(const std::string& s) { write(s.data(), s.size()); }
  std::uint64_t offset() const { return offset_; }  ///< bytes written so far
  void commit();

  // For files written out of order (the EBP-Octree's `.ebp` stores: pages first, the header
  // that points at them last) and that must survive a crash once they have their name.
  /// Writes `n` bytes at byte `offset` of the file (after any sequential writes still buffered),
  /// whatever the short transfers and EINTR; offset() is not moved. Throws the class's error.
  void write_at(std::uint64_t offset, const void* data, std::size_t n);
  /// Makes the file exactly `size` bytes long (cut, or extended with zeros). Throws likewise.
  void resize(std::uint64_t size);
  /// commit() with durability: the file's bytes reach the disk (fsync) before the rename, and the
  /// rename itself (fsync of the directory, best effort) after it.
  void commit_durable();

 private:
  std::string path_, tmp_;
  std::FILE* f_ = nullptr;
  bool ok_ = true;
  std::uint64_t offset_ = 0;
};

}  // namespace bvhbench
