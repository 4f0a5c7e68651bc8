#pragma once
/// The ZIP container as NumPy's .npz files use it: reading stored and deflated entries (ZIP64
/// extra fields, data descriptors), and writing stored entries (ZIP64 only when a size or an
/// offset needs it), as np.savez does. Deflate and CRC-32 are zlib's.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "harness/util/atomic_file.hpp"
#include "harness/util/binary_file.hpp"

namespace bvhbench {

/// One member, as the central directory describes it.
struct ZipEntry {
  std::string name;
  std::uint16_t flags = 0, method = 0;  ///< method 0 = stored, 8 = deflate
  std::uint32_t crc = 0;                ///< CRC-32 of the plain bytes
  std::uint64_t csize = 0, usize = 0;   ///< compressed and plain sizes in bytes
  std::uint64_t offset = 0;             ///< of the local header
};

/// A ZIP file opened for reading: its central directory, and readers of its entries. Every
/// error is an InputError naming the file (and the entry, as "FILE (entry 'NAME')").
class ZipReader {
 public:
  /// Reads the end record and the central directory; throws InputError if the file is not a ZIP
  /// (saying so when it is a .npy), is truncated or has a corrupt directory.
  explicit ZipReader(const std::string& path);
  /// The same for a ZIP in memory (not copied: `data` must outlive the reader); `name` names it.
  /// `verify_crc` false skips the entries' CRC-32 check: only for the fuzzer, so that mutated
  /// entries reach the reader of their contents instead of dying at a CRC.
  ZipReader(std::string_view data, std::string name, bool verify_crc = true);
  ZipReader(const ZipReader&) = delete;
  ZipReader& operator=(const ZipReader&) = delete;

  const std::string& path() const { return file_.path(); }
  const std::vector<ZipEntry>& entries() const { return entries_; }

  /// The plain bytes of one entry, read in order. Reads through its ZipReader's file, so it is
  /// valid only while that ZipReader lives.
  class EntryReader {
   public:
    ~EntryReader();
    EntryReader(EntryReader&&) noexcept;
    EntryReader(const EntryReader&) = delete;
    EntryReader& operator=(const EntryReader&) = delete;
    EntryReader& operator=(EntryReader&&) = delete;

    /// "FILE (entry 'NAME')", for messages about the entry's contents.
    const std::string& where() const { return where_; }
    std::uint64_t size() const { return entry_.usize; }  ///< plain bytes
    /// Copies the next `n` plain bytes to `out`. Throws InputError: past the end of the entry,
    /// truncated file or deflate stream, corrupt deflate data (zlib's reason), a stream that
    /// ends before the size the directory gives.
    void read(void* out, std::size_t n);
    /// Checks that the entry ends where the directory says (a deflate stream that inflates to
    /// more bytes is refused) and that its CRC-32 matches. Call after reading size() bytes.
    void finish();

   private:
    friend class ZipReader;
    struct Inflate;  // zlib's stream state, for deflated entries
    EntryReader(InputFile& file, const ZipEntry& entry, std::uint64_t data_start, bool verify_crc);
    std::size_t inflate_into(unsigned char* out, std::size_t n);

    InputFile& file_;
    ZipEntry entry_;
    std::string where_;
    std::uint64_t data_start_;        ///< of the entry's (compressed) data in the file
    std::uint64_t compressed_read_ = 0, plain_read_ = 0;
    std::uint32_t crc_ = 0;
    bool verify_crc_ = true;
    std::unique_ptr<Inflate> inflate_;
  };

  /// A reader of `entry` (one of entries()). Throws InputError for encrypted entries, methods
  /// other than stored and deflate, a corrupt local header, data past the end of the file.
  EntryReader open(const ZipEntry& entry);

 private:
  InputFile file_;
  std::vector<ZipEntry> entries_;
  bool verify_crc_ = true;
};

/// A ZIP file of stored entries, written to a temporary and renamed into place by commit(). The
/// bytes depend on the entries alone (fixed 1980-01-01 timestamps), so equal input gives equal
/// files.
class ZipWriter {
 public:
  explicit ZipWriter(const std::string& path);
  /// Bytes given as pieces, written one after the other without being joined in memory.
  struct Part {
    const void* data;
    std::size_t size;
  };
  /// Appends a stored entry whose bytes are the concatenation of `parts`.
  void add_stored(const std::string& name, const std::vector<Part>& parts);
  /// Writes the central directory and the end records, then renames the file into place.
  /// Errors are std::runtime_error "PATH: cannot write: <why>".
  void commit();

 private:
  AtomicOutputFile out_;
  std::string central_;
  std::uint64_t entries_ = 0;
};

}  // namespace bvhbench
