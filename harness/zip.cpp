// ZIP reading and writing for .npz files. The reader takes our files and NumPy's (ZIP64 extra
// fields, data descriptors, deflated entries of np.savez_compressed); an entry is read in order,
// straight into the caller's buffer, inflated by zlib as it goes. The writer produces what
// np.savez does: stored entries, CRC-32, ZIP64 only when a size or an offset needs it.
#include "zip.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <new>
#include <stdexcept>
#include <utility>

#include "errors.hpp"

namespace bvhbench {

namespace {

inline std::uint16_t le16(const unsigned char* p) { return std::uint16_t(p[0] | p[1] << 8); }
inline std::uint32_t le32(const unsigned char* p) {
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24;
}
inline std::uint64_t le64(const unsigned char* p) { return le32(p) | std::uint64_t(le32(p + 4)) << 32; }

void put16(std::string& s, std::uint32_t v) {
  s += char(v & 0xff);
  s += char((v >> 8) & 0xff);
}
void put32(std::string& s, std::uint32_t v) {
  put16(s, v & 0xffff);
  put16(s, v >> 16);
}
void put64(std::string& s, std::uint64_t v) {
  put32(s, std::uint32_t(v));
  put32(s, std::uint32_t(v >> 32));
}

constexpr std::uint32_t kLocalSig = 0x04034b50, kCentralSig = 0x02014b50, kEndSig = 0x06054b50,
                        kEnd64Sig = 0x06064b50, kLocator64Sig = 0x07064b50;
constexpr std::uint32_t kMax32 = 0xffffffffu;
constexpr std::uint16_t kDosDate = (0 << 9) | (1 << 5) | 1;  // 1980-01-01: reproducible bytes

/// zlib counts in 32-bit units: larger buffers go through in pieces of this size.
constexpr std::size_t kZlibChunk = std::size_t(1) << 30;

/// CRC-32 of `n` more bytes. (zlib's crc32_z returns the initial value for a null buffer, which
/// an empty vector's data() may be.)
std::uint32_t crc32_of(std::uint32_t crc, const void* data, std::size_t n) {
  if (n == 0) return crc;
  return std::uint32_t(crc32_z(crc, static_cast<const Bytef*>(data), n));
}

std::vector<ZipEntry> read_central_directory(InputFile& f) {
  const std::string& path = f.path();
  if (f.size() < 22) throw file_error(path, "not a ZIP/.npz file (too short)");
  // The end record sits in the last 22 bytes plus at most a 65535-byte comment.
  const std::size_t tail_len = std::size_t(std::min<std::uint64_t>(f.size(), 22 + 65535));
  std::vector<unsigned char> tail(tail_len);
  f.read_at(f.size() - tail_len, tail.data(), tail_len, "the end of central directory");
  std::size_t eocd = std::string::npos;
  for (std::size_t i = tail_len - 22 + 1; i-- > 0;)
    if (le32(&tail[i]) == kEndSig) {
      eocd = i;
      break;
    }
  if (eocd == std::string::npos) {
    if (f.size() >= 6) {
      unsigned char head[6];
      f.read_at(0, head, 6, "the file header");
      if (std::memcmp(head, "\x93NUMPY", 6) == 0) throw file_error(path, "is a .npy file, not an .npz archive");
    }
    throw file_error(path, "not a ZIP/.npz file (no end of central directory record; truncated?)");
  }
  const unsigned char* e = &tail[eocd];
  std::uint64_t count = le16(e + 10), cd_size = le32(e + 12), cd_offset = le32(e + 16);
  const std::uint64_t eocd_pos = f.size() - tail_len + eocd;
  if (count == 0xffff || cd_size == kMax32 || cd_offset == kMax32) {
    if (eocd_pos < 20) throw file_error(path, "bad ZIP64 end record");
    unsigned char loc[20];
    f.read_at(eocd_pos - 20, loc, 20, "the ZIP64 locator");
    if (le32(loc) != kLocator64Sig) throw file_error(path, "bad ZIP64 locator");
    const std::uint64_t rec_pos = le64(loc + 8);
    unsigned char rec[56];
    f.read_at(rec_pos, rec, 56, "the ZIP64 end record");
    if (le32(rec) != kEnd64Sig) throw file_error(path, "bad ZIP64 end record");
    count = le64(rec + 32);
    cd_size = le64(rec + 40);
    cd_offset = le64(rec + 48);
  }
  if (cd_offset > f.size() || cd_size > f.size() - cd_offset) throw file_error(path, "truncated (central directory past the end)");
  if (count > cd_size / 46) throw file_error(path, "corrupt central directory (entry count does not fit)");
  std::vector<unsigned char> cd(std::size_t(cd_size) + 1);
  f.read_at(cd_offset, cd.data(), std::size_t(cd_size), "the central directory");
  std::vector<ZipEntry> entries;
  std::size_t p = 0;
  for (std::uint64_t i = 0; i < count; ++i) {
    if (p + 46 > cd_size || le32(&cd[p]) != kCentralSig) throw file_error(path, "corrupt central directory");
    const unsigned char* c = &cd[p];
    ZipEntry z;
    z.flags = le16(c + 8);
    z.method = le16(c + 10);
    z.crc = le32(c + 16);
    z.csize = le32(c + 20);
    z.usize = le32(c + 24);
    const std::size_t nlen = le16(c + 28), xlen = le16(c + 30), clen = le16(c + 32);
    z.offset = le32(c + 42);
    if (p + 46 + nlen + xlen + clen > cd_size) throw file_error(path, "corrupt central directory");
    z.name.assign(reinterpret_cast<const char*>(c + 46), nlen);
    for (std::size_t x = 0; x + 4 <= xlen;) {
      const unsigned char* xf = c + 46 + nlen + x;
      const std::size_t id = le16(xf), sz = le16(xf + 2);
      if (x + 4 + sz > xlen) break;
      if (id == 1) {  // ZIP64: the 8-byte values of the fields that overflowed, in this order
        std::size_t q = 4;
        auto take = [&](std::uint64_t& v) {
          if (v != kMax32) return;
          if (q + 8 > 4 + sz) throw file_error(path, "corrupt ZIP64 extra field");
          v = le64(xf + q);
          q += 8;
        };
        take(z.usize);
        take(z.csize);
        take(z.offset);
      }
      x += 4 + sz;
    }
    p += 46 + nlen + xlen + clen;
    entries.push_back(std::move(z));
  }
  return entries;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------------
ZipReader::ZipReader(const std::string& path) : file_(path), entries_(read_central_directory(file_)) {}
ZipReader::ZipReader(std::string_view data, std::string name, bool verify_crc)
    : file_(data, std::move(name)), entries_(read_central_directory(file_)), verify_crc_(verify_crc) {}

struct ZipReader::EntryReader::Inflate {
  z_stream z{};
  std::vector<unsigned char> in = std::vector<unsigned char>(std::size_t(1) << 18);
  bool ended = false;

  Inflate() {
    const int rc = inflateInit2(&z, -MAX_WBITS);  // raw deflate, as ZIP stores it
    if (rc == Z_MEM_ERROR) throw std::bad_alloc();
    if (rc != Z_OK) throw std::runtime_error(std::string("zlib inflateInit2 failed: ") + zError(rc));
  }
  ~Inflate() { inflateEnd(&z); }
  Inflate(const Inflate&) = delete;
  Inflate& operator=(const Inflate&) = delete;
};

ZipReader::EntryReader::EntryReader(InputFile& file, const ZipEntry& entry, std::uint64_t data_start,
                                    bool verify_crc)
    : file_(file),
      entry_(entry),
      where_(file.path() + " (entry " + quoted_excerpt(entry.name, 100) + ")"),
      data_start_(data_start),
      verify_crc_(verify_crc) {
  if (entry_.method == 8) inflate_ = std::make_unique<Inflate>();
}

ZipReader::EntryReader::~EntryReader() = default;
ZipReader::EntryReader::EntryReader(EntryReader&&) noexcept = default;

std::size_t ZipReader::EntryReader::inflate_into(unsigned char* out, std::size_t n) {
  Inflate& s = *inflate_;
  std::size_t produced = 0;
  while (produced < n && !s.ended) {
    if (s.z.avail_in == 0) {
      const std::uint64_t left = entry_.csize - compressed_read_;
      if (left == 0) throw file_error(where_, "truncated compressed data (the deflate stream ends early)");
      const std::size_t take = std::size_t(std::min<std::uint64_t>(left, s.in.size()));
      file_.read_at(data_start_ + compressed_read_, s.in.data(), take, "the data of " + where_);
      compressed_read_ += take;
      s.z.next_in = s.in.data();
      s.z.avail_in = uInt(take);
    }
    const std::size_t chunk = std::min(n - produced, kZlibChunk);
    s.z.next_out = out + produced;
    s.z.avail_out = uInt(chunk);
    const int rc = ::inflate(&s.z, Z_NO_FLUSH);
    produced += chunk - s.z.avail_out;
    if (rc == Z_STREAM_END) {
      s.ended = true;
    } else if (rc == Z_DATA_ERROR || rc == Z_NEED_DICT) {
      throw file_error(where_, std::string("corrupt compressed data (zlib: ") +
                                   (s.z.msg ? s.z.msg : "invalid deflate data") + ")");
    } else if (rc == Z_MEM_ERROR) {
      throw std::bad_alloc();
    } else if (rc != Z_OK && rc != Z_BUF_ERROR) {  // Z_BUF_ERROR: no input left, refilled above
      throw std::runtime_error(where_ + ": zlib inflate failed: " + zError(rc));
    }
  }
  return produced;
}

void ZipReader::EntryReader::read(void* out, std::size_t n) {
  if (n > entry_.usize - plain_read_)
    throw file_error(where_, "read past the end of the entry (" + std::to_string(plain_read_ + n) + " of " +
                                 std::to_string(entry_.usize) + " bytes)");
  if (inflate_) {
    const std::size_t got = inflate_into(static_cast<unsigned char*>(out), n);
    if (got < n)
      throw file_error(where_, "the deflate stream inflates to " + std::to_string(plain_read_ + got) +
                                   " bytes, fewer than the " + std::to_string(entry_.usize) +
                                   " the directory says");
  } else {
    file_.read_at(data_start_ + plain_read_, out, n, "the data of " + where_);
  }
  crc_ = crc32_of(crc_, out, n);
  plain_read_ += n;
}

void ZipReader::EntryReader::finish() {
  if (plain_read_ != entry_.usize)
    throw file_error(where_, "only " + std::to_string(plain_read_) + " of its " + std::to_string(entry_.usize) +
                                 " bytes were read");
  if (inflate_ && !inflate_->ended) {
    unsigned char extra;
    if (inflate_into(&extra, 1) > 0)
      throw file_error(where_, "the deflate stream inflates to more than the " + std::to_string(entry_.usize) +
                                   " bytes the directory says");
  }
  if (verify_crc_ && crc_ != entry_.crc) throw file_error(where_, "CRC-32 mismatch (the file is corrupt)");
}

ZipReader::EntryReader ZipReader::open(const ZipEntry& z) {
  const std::string where = file_.path() + " (entry " + quoted_excerpt(z.name, 100) + ")";
  if (z.flags & 1) throw file_error(where, "encrypted entries are not supported");
  if (z.method != 0 && z.method != 8)
    throw file_error(where, "unsupported compression method " + std::to_string(z.method) +
                                " (only stored and deflate entries are read)");
  if (z.method == 0 && z.csize != z.usize)
    throw file_error(where, "stored entry with different compressed and plain sizes");
  unsigned char lh[30];
  file_.read_at(z.offset, lh, 30, "the local header of " + quoted_excerpt(z.name, 100));
  if (le32(lh) != kLocalSig) throw file_error(file_.path(), "corrupt local header of " + quoted_excerpt(z.name, 100));
  const std::uint64_t start = z.offset + 30 + le16(lh + 26) + le16(lh + 28);
  if (start > file_.size() || z.csize > file_.size() - start)
    throw file_error(file_.path(), "truncated (entry " + quoted_excerpt(z.name, 100) + " extends past the end of the file)");
  // Deflate expands at most ~1032:1; a directory that claims more is lying (and would make the
  // reader allocate for it).
  if (z.method == 8 && z.usize > z.csize * 1032 + 1024) throw file_error(where, "corrupt sizes in the central directory");
  return EntryReader(file_, z, start, verify_crc_);
}

// ---------------------------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------------------------
ZipWriter::ZipWriter(const std::string& path) : out_(path) {}

void ZipWriter::add_stored(const std::string& name, const std::vector<Part>& parts) {
  std::uint64_t size = 0;
  std::uint32_t crc = 0;
  for (const Part& p : parts) {
    size += p.size;
    crc = crc32_of(crc, p.data, p.size);
  }
  const std::uint64_t offset = out_.offset();
  const bool zip64 = size >= kMax32 || offset >= kMax32;

  std::string local;
  put32(local, kLocalSig);
  put16(local, zip64 ? 45 : 20);
  put16(local, 0);  // flags
  put16(local, 0);  // stored
  put16(local, 0);  // time
  put16(local, kDosDate);
  put32(local, crc);
  put32(local, zip64 ? kMax32 : std::uint32_t(size));
  put32(local, zip64 ? kMax32 : std::uint32_t(size));
  put16(local, std::uint32_t(name.size()));
  put16(local, zip64 ? 20 : 0);
  local += name;
  if (zip64) {
    put16(local, 1);
    put16(local, 16);
    put64(local, size);
    put64(local, size);
  }
  out_.write(local);
  for (const Part& p : parts) out_.write(p.data, p.size);

  std::string extra;
  if (zip64) {
    put16(extra, 1);
    put16(extra, 24);
    put64(extra, size);
    put64(extra, size);
    put64(extra, offset);
  }
  put32(central_, kCentralSig);
  put16(central_, (3 << 8) | (zip64 ? 45 : 20));  // made by: Unix
  put16(central_, zip64 ? 45 : 20);
  put16(central_, 0);
  put16(central_, 0);
  put16(central_, 0);
  put16(central_, kDosDate);
  put32(central_, crc);
  put32(central_, zip64 ? kMax32 : std::uint32_t(size));
  put32(central_, zip64 ? kMax32 : std::uint32_t(size));
  put16(central_, std::uint32_t(name.size()));
  put16(central_, std::uint32_t(extra.size()));
  put16(central_, 0);  // comment
  put16(central_, 0);  // disk
  put16(central_, 0);  // internal attributes
  put32(central_, 0100644u << 16);
  put32(central_, zip64 ? kMax32 : std::uint32_t(offset));
  central_ += name;
  central_ += extra;
  ++entries_;
}

void ZipWriter::commit() {
  const std::uint64_t cd_offset = out_.offset();
  out_.write(central_);
  const std::uint64_t cd_size = central_.size();
  std::string end;
  const bool zip64 = entries_ >= 0xffff || cd_offset >= kMax32 || cd_size >= kMax32;
  if (zip64) {
    const std::uint64_t rec = out_.offset();
    put32(end, kEnd64Sig);
    put64(end, 44);
    put16(end, (3 << 8) | 45);
    put16(end, 45);
    put32(end, 0);
    put32(end, 0);
    put64(end, entries_);
    put64(end, entries_);
    put64(end, cd_size);
    put64(end, cd_offset);
    put32(end, kLocator64Sig);
    put32(end, 0);
    put64(end, rec);
    put32(end, 1);
  }
  put32(end, kEndSig);
  put16(end, 0);
  put16(end, 0);
  put16(end, zip64 ? 0xffff : std::uint32_t(entries_));
  put16(end, zip64 ? 0xffff : std::uint32_t(entries_));
  put32(end, zip64 ? kMax32 : std::uint32_t(cd_size));
  put32(end, zip64 ? kMax32 : std::uint32_t(cd_offset));
  put16(end, 0);
  out_.write(end);
  out_.commit();
}

}  // namespace bvhbench
