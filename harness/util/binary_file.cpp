#include "harness/util/binary_file.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
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

}  // namespace bvhbench
