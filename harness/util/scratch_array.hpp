#pragma once
/// An array too large for the memory a command may use: written once, in order, to a temporary
/// file, then read by index through a fixed cache of pages. The file is unlinked as soon as it is
/// made, so nothing is left behind however the process ends. The cache is a clock: a page read
/// since the hand last passed gets a second chance, so the pages of the region a loop works in
/// stay while the rest come and go. Reads change the cache: one thread at a time.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace bvhbench {

/// The untyped file and cache under ScratchArray: records of a fixed size.
class ScratchFile {
 public:
  /// Records per page: a page is one read (Vec3d: 48 KiB).
  static constexpr std::size_t kPageRecords = 2048;

  /// A temporary file in `dir` for records of `record_bytes`, read back through a cache of at
  /// most `cache_bytes` (never fewer than two pages). `what` names it in messages. Throws
  /// InputError naming `dir` when the file cannot be made there.
  ScratchFile(const std::string& dir, const std::string& what, std::size_t record_bytes, std::size_t cache_bytes);
  ~ScratchFile();
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  /// Appends n records (before finish). Throws InputError naming the file on a full disk.
  void append(const void* records, std::size_t n);
  /// Flushes what is left to write; the records can be read from now on.
  void finish();
  /// Record i (< size(), after finish): valid until the next call.
  const unsigned char* record(std::uint64_t i) const;

  std::uint64_t size() const { return records_; }
  /// The cache, the write buffer and the page table.
  std::size_t resident_bytes() const;
  std::uint64_t reads() const { return reads_; }
  std::uint64_t misses() const { return misses_; }

 private:
  const unsigned char* page(std::uint64_t p) const;
  void flush();

  std::string name_;  ///< "DIR/WHAT (temporary)", for messages
  int fd_ = -1;
  std::size_t record_bytes_, page_bytes_, cache_bytes_;
  std::uint64_t records_ = 0, flushed_bytes_ = 0;
  bool finished_ = false;
  std::vector<unsigned char> wbuf_;  ///< one page being written
  mutable std::vector<unsigned char> slots_;         ///< the cache, page_bytes_ per slot
  mutable std::vector<std::int32_t> slot_of_;        ///< page -> slot, -1 when not cached
  mutable std::vector<std::uint64_t> page_in_;       ///< slot -> page (UINT64_MAX when free)
  mutable std::vector<std::uint8_t> referenced_;     ///< slot -> the clock's second chance
  mutable std::size_t hand_ = 0;
  mutable std::uint64_t last_page_ = UINT64_MAX;
  mutable const unsigned char* last_ = nullptr;
  mutable std::uint64_t reads_ = 0, misses_ = 0;
};

/// ScratchFile with records of a trivially copyable T.
template <class T>
class ScratchArray {
  static_assert(std::is_trivially_copyable_v<T>, "a ScratchArray holds plain bytes");

 public:
  ScratchArray(const std::string& dir, const std::string& what, std::size_t cache_bytes)
      : file_(dir, what, sizeof(T), cache_bytes) {}
  void append(const T* values, std::size_t n) { file_.append(values, n); }
  void push_back(const T& value) { file_.append(&value, 1); }
  void finish() { file_.finish(); }
  T operator[](std::uint64_t i) const {
    T v;
    std::memcpy(&v, file_.record(i), sizeof(T));
    return v;
  }
  std::uint64_t size() const { return file_.size(); }
  std::size_t resident_bytes() const { return file_.resident_bytes(); }
  const ScratchFile& file() const { return file_; }

 private:
  ScratchFile file_;
};

}  // namespace bvhbench
