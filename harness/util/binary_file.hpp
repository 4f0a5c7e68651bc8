#pragma once
/// Binary files read at offsets: the plumbing under the .npy and ZIP (.npz) readers, which move
/// arrays of hundreds of MB straight from a file into their final buffer. (Their writers use
/// atomic_file.hpp.)
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

}  // namespace bvhbench
