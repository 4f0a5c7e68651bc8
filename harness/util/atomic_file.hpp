#pragma once
/// Output files that appear whole or not at all: every writer of the harness (results, meshes,
/// .npy/.npz, query-set sidecars, summaries) writes through AtomicOutputFile, so that a reader,
/// a resumed suite or a crash never sees half a file.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

namespace bvhbench {

/// A file written to a temporary in PATH's folder and renamed to PATH by commit(); without
/// commit() (an exception on the way) the temporary is removed and PATH is left as it was.
///
/// The temporary is "PATH.tmp.<random>", created exclusively (O_EXCL), so that two processes
/// writing the same PATH at once (suites on several workers) never write into one temporary:
/// each renames a whole file, and the last rename wins. It is in PATH's folder so that the
/// rename stays on one file system (and is atomic). The file gets the permissions a plain
/// open() would give it (0666 less the umask).
///
/// Errors are std::runtime_error "PATH: cannot write: <why>" (an output problem, not bad input).
class AtomicOutputFile {
 public:
  explicit AtomicOutputFile(const std::string& path);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  void write(const void* data, std::size_t n);
  void write(const std::string& s) { write(s.data(), s.size()); }
  std::uint64_t offset() const { return offset_; }  ///< bytes written so far
  const std::string& path() const { return path_; }
  const std::string& temporary_path() const { return tmp_; }
  /// Flushes, closes and renames the temporary to PATH. Throws if any write failed.
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
  int errno_ = 0;  // of the first failed write
  std::uint64_t offset_ = 0;
};

}  // namespace bvhbench
