// NumPy .npy (format versions 1, 2 and 3) and .npz (a ZIP of .npy entries) reading and writing.
//
// Query sets and answers reach hundreds of MB, so arrays are read straight from the file into
// their final buffer (no whole-file copy) and written straight from it. The .npz writer produces
// what np.savez does: stored entries, CRC-32, ZIP64 only when a size or an offset needs it. The
// reader takes our files and NumPy's (ZIP64 extra fields, data descriptors, and deflated entries
// of np.savez_compressed through a small built-in inflate, so that no zlib is needed).
#include "npy.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

#include "errors.hpp"

namespace bvhbench {

namespace {

constexpr bool kBigEndianHost = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;

// ---------------------------------------------------------------------------------------------
// dtypes
// ---------------------------------------------------------------------------------------------

/// Bytes per element of a dtype descr we support ("<f8", "|b1", "<U14", ...), 0 if unsupported.
/// `kind` receives the type character (f, i, u, b, U).
std::size_t dtype_itemsize(const std::string& d, char* kind = nullptr) {
  if (d.size() < 3) return 0;
  const char order = d[0], k = d[1];
  if (order != '<' && order != '>' && order != '|' && order != '=') return 0;
  std::size_t n = 0;
  for (std::size_t i = 2; i < d.size(); ++i) {
    if (d[i] < '0' || d[i] > '9' || n > 1000000000) return 0;
    n = n * 10 + std::size_t(d[i] - '0');
  }
  if (kind) *kind = k;
  switch (k) {
    case 'f': return (n == 4 || n == 8) ? n : 0;
    case 'i': case 'u': return (n == 1 || n == 2 || n == 4 || n == 8) ? n : 0;
    case 'b': return n == 1 ? 1 : 0;
    case 'U': return n >= 1 ? 4 * n : 0;  // UTF-32 code units
    default: return 0;
  }
}

/// Size of the data of an array, or false on overflow.
bool data_bytes(const std::vector<std::size_t>& shape, std::size_t itemsize, std::size_t& out) {
  std::size_t n = itemsize;
  for (std::size_t s : shape) {
    if (s != 0 && n > std::numeric_limits<std::size_t>::max() / s) return false;
    n *= s;
  }
  out = n;
  return true;
}

std::string shape_string(const std::vector<std::size_t>& shape) {
  std::string s = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) {
    if (i) s += ", ";
    s += std::to_string(shape[i]);
  }
  if (shape.size() == 1) s += ",";
  return s + ")";
}

// ---------------------------------------------------------------------------------------------
// The .npy header: a Python dict literal.
// ---------------------------------------------------------------------------------------------
struct NpyHeader {
  std::string dtype;  // as written in the file
  std::vector<std::size_t> shape;
  bool fortran = false;
  std::size_t data_offset = 0;  // header length including magic
};

class DictParser {
 public:
  DictParser(const std::string& text, const std::string& name) : s_(text), name_(name) {}

  NpyHeader parse() {
    NpyHeader h;
    bool have_descr = false, have_shape = false, have_fortran = false;
    expect('{');
    for (;;) {
      skip();
      if (peek() == '}') break;
      const std::string key = string_literal();
      expect(':');
      skip();
      if (key == "descr") {
        if (peek() == '[') fail("structured dtypes are not supported");
        h.dtype = string_literal();
        have_descr = true;
      } else if (key == "fortran_order") {
        h.fortran = boolean();
        have_fortran = true;
      } else if (key == "shape") {
        h.shape = tuple();
        have_shape = true;
      } else {
        fail("unexpected header key '" + key + "'");
      }
      skip();
      if (peek() == ',') {
        ++i_;
        continue;
      }
      skip();
      if (peek() != '}') fail("expected ',' or '}'");
    }
    if (!have_descr || !have_shape || !have_fortran)
      fail("the header lacks 'descr', 'fortran_order' or 'shape'");
    return h;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw file_error(name_, "bad .npy header (" + what + "): " + s_.substr(0, 200));
  }
  void skip() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t' || s_[i_] == '\n' || s_[i_] == '\r')) ++i_;
  }
  char peek() const { return i_ < s_.size() ? s_[i_] : '\0'; }
  void expect(char c) {
    skip();
    if (peek() != c) fail(std::string("expected '") + c + "'");
    ++i_;
  }
  std::string string_literal() {
    skip();
    const char q = peek();
    if (q != '\'' && q != '"') fail("expected a string");
    const std::size_t end = s_.find(q, i_ + 1);
    if (end == std::string::npos) fail("unterminated string");
    std::string out = s_.substr(i_ + 1, end - i_ - 1);
    i_ = end + 1;
    return out;
  }
  bool boolean() {
    if (s_.compare(i_, 4, "True") == 0) {
      i_ += 4;
      return true;
    }
    if (s_.compare(i_, 5, "False") == 0) {
      i_ += 5;
      return false;
    }
    fail("expected True or False");
  }
  std::vector<std::size_t> tuple() {
    std::vector<std::size_t> out;
    expect('(');
    for (;;) {
      skip();
      if (peek() == ')') {
        ++i_;
        return out;
      }
      if (peek() < '0' || peek() > '9') fail("expected a dimension");
      std::size_t v = 0;
      while (peek() >= '0' && peek() <= '9') {
        if (v > (std::numeric_limits<std::size_t>::max() - 9) / 10) fail("dimension too large");
        v = v * 10 + std::size_t(s_[i_++] - '0');
      }
      if (peek() == 'L') ++i_;  // Python 2 longs
      out.push_back(v);
      skip();
      if (peek() == ',') ++i_;
      else if (peek() != ')') fail("expected ',' or ')'");
      if (out.size() > 32) fail("too many dimensions");
    }
  }

  const std::string& s_;
  const std::string& name_;
  std::size_t i_ = 0;
};

/// Parses the magic, version and header dict from the first `n` bytes; on success sets
/// `h.data_offset`. Returns the total header length needed if `n` is too short (so that a caller
/// reading a file can fetch more), else 0.
std::size_t parse_header(const char* b, std::size_t n, const std::string& name, NpyHeader& h) {
  if (n < 10) {
    if (n >= 1 && std::memcmp(b, "\x93NUMPY", std::min<std::size_t>(n, 6)) != 0)
      throw file_error(name, "not a .npy file (bad magic)");
    return 12;  // enough for the length field of any version
  }
  if (std::memcmp(b, "\x93NUMPY", 6) != 0) throw file_error(name, "not a .npy file (bad magic)");
  const unsigned major = static_cast<unsigned char>(b[6]);
  std::size_t hlen, start;
  if (major == 1) {
    hlen = std::size_t(static_cast<unsigned char>(b[8])) | std::size_t(static_cast<unsigned char>(b[9])) << 8;
    start = 10;
  } else if (major == 2 || major == 3) {
    if (n < 12) return 12;
    hlen = 0;
    for (int i = 3; i >= 0; --i) hlen = hlen << 8 | static_cast<unsigned char>(b[8 + i]);
    start = 12;
  } else {
    throw file_error(name, "unsupported .npy format version " + std::to_string(major));
  }
  if (hlen > (std::size_t(1) << 24)) throw file_error(name, "bad .npy header (longer than 16 MB)");
  if (n < start + hlen) return start + hlen;
  h = DictParser(std::string(b + start, hlen), name).parse();
  h.data_offset = start + hlen;
  return 0;
}

/// Checks the header and fills the array's dtype and shape; returns the data size in bytes.
std::size_t check_header(const NpyHeader& h, const std::string& name, NpyArray& a) {
  char kind = 0;
  const std::size_t isz = dtype_itemsize(h.dtype, &kind);
  if (isz == 0) throw file_error(name, "unsupported dtype '" + h.dtype + "'");
  if (h.fortran && h.shape.size() > 1)
    throw file_error(name, "fortran_order arrays are not supported (save with C order)");
  std::size_t bytes;
  if (!data_bytes(h.shape, isz, bytes)) throw file_error(name, "shape " + shape_string(h.shape) + " is too large");
  a.shape = h.shape;
  a.dtype = h.dtype;
  return bytes;
}

/// Turns a big-endian (or native '=') array into the little-endian form we keep.
void normalise_byte_order(NpyArray& a) {
  char kind = 0;
  const std::size_t isz = dtype_itemsize(a.dtype, &kind);
  const std::size_t unit = kind == 'U' ? 4 : isz;
  const bool big = a.dtype[0] == '>' || (a.dtype[0] == '=' && kBigEndianHost);
  if (big && unit > 1)
    for (std::size_t i = 0; i + unit <= a.data.size(); i += unit) std::reverse(&a.data[i], &a.data[i] + unit);
  a.dtype[0] = unit == 1 ? '|' : '<';
}

std::string header_bytes(const NpyArray& a) {
  std::string dict = "{'descr': '" + a.dtype + "', 'fortran_order': False, 'shape': " + shape_string(a.shape) + ", }";
  // NumPy pads the header with spaces and a newline so that the data is 64-byte aligned.
  std::size_t start = 10;
  std::size_t total = start + dict.size() + 1;
  if ((total + 63) / 64 * 64 - start > 65535) start = 12;
  total = start + dict.size() + 1;
  const std::size_t padded = (total + 63) / 64 * 64;
  dict.append(padded - total, ' ');
  dict += '\n';
  const std::size_t hlen = dict.size();
  std::string out = "\x93NUMPY";
  out += start == 10 ? '\x01' : '\x02';
  out += '\0';
  out += char(hlen & 0xff);
  out += char((hlen >> 8) & 0xff);
  if (start == 12) {
    out += char((hlen >> 16) & 0xff);
    out += char((hlen >> 24) & 0xff);
  }
  return out + dict;
}

void check_writable(const NpyArray& a) {
  const std::size_t isz = dtype_itemsize(a.dtype);
  std::size_t bytes = 0;
  if (isz == 0 || (a.dtype[0] == '>')) throw std::invalid_argument("npy: cannot write dtype '" + a.dtype + "'");
  if (!data_bytes(a.shape, isz, bytes) || bytes != a.data.size())
    throw std::invalid_argument("npy: array of dtype " + a.dtype + " and shape " + shape_string(a.shape) + " has " +
                                std::to_string(a.data.size()) + " bytes of data, expected " + std::to_string(bytes));
}

// ---------------------------------------------------------------------------------------------
// Files
// ---------------------------------------------------------------------------------------------
struct File {
  std::FILE* f = nullptr;
  std::string path;
  std::uint64_t size = 0;

  explicit File(const std::string& p) : path(p) {
    struct stat st {};
    if (::stat(p.c_str(), &st) != 0)
      throw file_error(p, errno == ENOENT ? "file not found" : std::string("cannot open: ") + std::strerror(errno));
    if (!S_ISREG(st.st_mode)) throw file_error(p, "not a regular file");
    f = std::fopen(p.c_str(), "rb");
    if (!f) throw file_error(p, std::string("cannot open: ") + std::strerror(errno));
    size = std::uint64_t(st.st_size);
  }
  ~File() {
    if (f) std::fclose(f);
  }
  File(const File&) = delete;
  File& operator=(const File&) = delete;

  /// Reads exactly n bytes at `offset`; throws "truncated" otherwise.
  void read_at(std::uint64_t offset, void* out, std::size_t n, const char* what) {
    if (offset > size || n > size - offset)
      throw file_error(path, std::string("truncated (") + what + " extends past the end of the file)");
    if (fseeko(f, off_t(offset), SEEK_SET) != 0 || std::fread(out, 1, n, f) != n)
      throw file_error(path, std::string("read error in ") + what);
  }
};

class AtomicWriter {
 public:
  explicit AtomicWriter(const std::string& path) : path_(path), tmp_(path + ".tmp") {
    f_ = std::fopen(tmp_.c_str(), "wb");
    if (!f_) throw std::runtime_error(path_ + ": cannot write: " + std::strerror(errno));
  }
  ~AtomicWriter() {
    if (f_) {
      std::fclose(f_);
      std::remove(tmp_.c_str());
    }
  }
  AtomicWriter(const AtomicWriter&) = delete;
  AtomicWriter& operator=(const AtomicWriter&) = delete;

  void write(const void* p, std::size_t n) {
    if (n && std::fwrite(p, 1, n, f_) != n) ok_ = false;
    offset_ += n;
  }
  void write(const std::string& s) { write(s.data(), s.size()); }
  std::uint64_t offset() const { return offset_; }

  void commit() {
    const bool closed = std::fclose(f_) == 0;
    f_ = nullptr;
    if (!ok_ || !closed || std::rename(tmp_.c_str(), path_.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      std::remove(tmp_.c_str());
      throw std::runtime_error(path_ + ": cannot write: " + why);
    }
  }

 private:
  std::string path_, tmp_;
  std::FILE* f_ = nullptr;
  bool ok_ = true;
  std::uint64_t offset_ = 0;
};

// ---------------------------------------------------------------------------------------------
// CRC-32 (ZIP polynomial), slicing by 8.
// ---------------------------------------------------------------------------------------------
struct CrcTables {
  std::uint32_t t[8][256];
  CrcTables() {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (int s = 1; s < 8; ++s)
      for (int i = 0; i < 256; ++i) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xff];
  }
};
const CrcTables kCrc;

std::uint32_t crc32_update(std::uint32_t crc, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  crc = ~crc;
  if (!kBigEndianHost) {
    while (n >= 8) {
      std::uint32_t lo, hi;
      std::memcpy(&lo, p, 4);
      std::memcpy(&hi, p + 4, 4);
      lo ^= crc;
      crc = kCrc.t[7][lo & 0xff] ^ kCrc.t[6][(lo >> 8) & 0xff] ^ kCrc.t[5][(lo >> 16) & 0xff] ^ kCrc.t[4][lo >> 24] ^
            kCrc.t[3][hi & 0xff] ^ kCrc.t[2][(hi >> 8) & 0xff] ^ kCrc.t[1][(hi >> 16) & 0xff] ^ kCrc.t[0][hi >> 24];
      p += 8;
      n -= 8;
    }
  }
  while (n--) crc = kCrc.t[0][(crc ^ *p++) & 0xff] ^ (crc >> 8);
  return ~crc;
}

// ---------------------------------------------------------------------------------------------
// Inflate (RFC 1951), after Mark Adler's puff.c: small and strict, for np.savez_compressed.
// ---------------------------------------------------------------------------------------------
class Inflater {
 public:
  Inflater(const unsigned char* in, std::size_t inlen, unsigned char* out, std::size_t outlen)
      : in_(in), inlen_(inlen), out_(out), outlen_(outlen) {}

  /// Decompresses the whole stream; returns nullptr on success, else what went wrong.
  const char* run() {
    try {
      int last;
      do {
        last = bits(1);
        const int type = bits(2);
        if (type == 0) stored();
        else if (type == 1) fixed();
        else if (type == 2) dynamic();
        else throw "invalid block type";
      } while (!last);
      if (outcnt_ != outlen_) throw "decompressed size does not match the directory";
    } catch (const char* why) {
      return why;
    }
    return nullptr;
  }

 private:
  static constexpr int kMaxBits = 15, kMaxLCodes = 286, kMaxDCodes = 30, kFixLCodes = 288;
  struct Huffman {
    short count[kMaxBits + 1];
    short symbol[kFixLCodes];
  };

  int bits(int need) {
    long val = bitbuf_;
    while (bitcnt_ < need) {
      if (incnt_ == inlen_) throw "compressed data ends early";
      val |= long(in_[incnt_++]) << bitcnt_;
      bitcnt_ += 8;
    }
    bitbuf_ = int(val >> need);
    bitcnt_ -= need;
    return int(val & ((1L << need) - 1));
  }

  void put(unsigned char c) {
    if (outcnt_ == outlen_) throw "decompressed data larger than the directory says";
    out_[outcnt_++] = c;
  }

  void stored() {
    bitbuf_ = 0;
    bitcnt_ = 0;
    if (incnt_ + 4 > inlen_) throw "compressed data ends early";
    unsigned len = in_[incnt_] | unsigned(in_[incnt_ + 1]) << 8;
    const unsigned nlen = in_[incnt_ + 2] | unsigned(in_[incnt_ + 3]) << 8;
    incnt_ += 4;
    if (len != (~nlen & 0xffffu)) throw "stored block length check failed";
    if (incnt_ + len > inlen_) throw "compressed data ends early";
    if (outcnt_ + len > outlen_) throw "decompressed data larger than the directory says";
    std::memcpy(out_ + outcnt_, in_ + incnt_, len);
    incnt_ += len;
    outcnt_ += len;
  }

  int decode(const Huffman& h) {
    int code = 0, first = 0, index = 0;
    for (int len = 1; len <= kMaxBits; ++len) {
      code |= bits(1);
      const int count = h.count[len];
      if (code - count < first) return h.symbol[index + (code - first)];
      index += count;
      first += count;
      first <<= 1;
      code <<= 1;
    }
    throw "invalid Huffman code";
  }

  static int construct(Huffman& h, const short* length, int n) {
    for (int len = 0; len <= kMaxBits; ++len) h.count[len] = 0;
    for (int s = 0; s < n; ++s) h.count[length[s]]++;
    if (h.count[0] == n) return 0;
    int left = 1;
    for (int len = 1; len <= kMaxBits; ++len) {
      left <<= 1;
      left -= h.count[len];
      if (left < 0) return left;
    }
    short offs[kMaxBits + 1];
    offs[1] = 0;
    for (int len = 1; len < kMaxBits; ++len) offs[len + 1] = short(offs[len] + h.count[len]);
    for (int s = 0; s < n; ++s)
      if (length[s] != 0) h.symbol[offs[length[s]]++] = short(s);
    return left;
  }

  void codes(const Huffman& lencode, const Huffman& distcode) {
    static const short lens[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                   31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
    static const short lext[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
    static const short dists[30] = {1,   2,   3,   4,   5,   7,    9,    13,   17,   25,   33,   49,   65,    97,    129,
                                    193, 257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
    static const short dext[30] = {0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};
    for (;;) {
      int symbol = decode(lencode);
      if (symbol < 256) {
        put(static_cast<unsigned char>(symbol));
      } else if (symbol == 256) {
        return;
      } else {
        symbol -= 257;
        if (symbol >= 29) throw "invalid length code";
        const std::size_t len = std::size_t(lens[symbol] + bits(lext[symbol]));
        symbol = decode(distcode);
        if (symbol >= 30) throw "invalid distance code";
        const std::size_t dist = std::size_t(dists[symbol] + bits(dext[symbol]));
        if (dist > outcnt_) throw "distance too far back";
        if (len > outlen_ - outcnt_) throw "decompressed data larger than the directory says";
        for (std::size_t k = 0; k < len; ++k, ++outcnt_) out_[outcnt_] = out_[outcnt_ - dist];
      }
    }
  }

  void fixed() {
    if (!fixed_built_) {
      short lengths[kFixLCodes];
      int s = 0;
      for (; s < 144; ++s) lengths[s] = 8;
      for (; s < 256; ++s) lengths[s] = 9;
      for (; s < 280; ++s) lengths[s] = 7;
      for (; s < kFixLCodes; ++s) lengths[s] = 8;
      construct(fixed_len_, lengths, kFixLCodes);
      for (s = 0; s < kMaxDCodes; ++s) lengths[s] = 5;
      construct(fixed_dist_, lengths, kMaxDCodes);
      fixed_built_ = true;
    }
    codes(fixed_len_, fixed_dist_);
  }

  void dynamic() {
    static const short order[19] = {16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15};
    short lengths[kMaxLCodes + kMaxDCodes];
    const int nlen = bits(5) + 257, ndist = bits(5) + 1, ncode = bits(4) + 4;
    if (nlen > kMaxLCodes || ndist > kMaxDCodes) throw "bad counts in a dynamic block";
    int index = 0;
    for (; index < ncode; ++index) lengths[order[index]] = short(bits(3));
    for (; index < 19; ++index) lengths[order[index]] = 0;
    Huffman lencode{}, distcode{};
    if (construct(lencode, lengths, 19) != 0) throw "incomplete code-length code";
    index = 0;
    while (index < nlen + ndist) {
      int symbol = decode(lencode);
      if (symbol < 16) {
        lengths[index++] = short(symbol);
      } else {
        short len = 0;
        if (symbol == 16) {
          if (index == 0) throw "repeat with no first length";
          len = lengths[index - 1];
          symbol = 3 + bits(2);
        } else if (symbol == 17) {
          symbol = 3 + bits(3);
        } else {
          symbol = 11 + bits(7);
        }
        if (index + symbol > nlen + ndist) throw "too many lengths";
        while (symbol--) lengths[index++] = len;
      }
    }
    if (lengths[256] == 0) throw "no end-of-block code";
    int err = construct(lencode, lengths, nlen);
    if (err && (err < 0 || nlen != lencode.count[0] + lencode.count[1])) throw "incomplete literal/length code";
    err = construct(distcode, lengths + nlen, ndist);
    if (err && (err < 0 || ndist != distcode.count[0] + distcode.count[1])) throw "incomplete distance code";
    codes(lencode, distcode);
  }

  const unsigned char* in_;
  std::size_t inlen_, incnt_ = 0;
  unsigned char* out_;
  std::size_t outlen_, outcnt_ = 0;
  int bitbuf_ = 0, bitcnt_ = 0;
  bool fixed_built_ = false;
  Huffman fixed_len_{}, fixed_dist_{};
};

// ---------------------------------------------------------------------------------------------
// ZIP
// ---------------------------------------------------------------------------------------------
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

struct ZipEntry {
  std::string name;
  std::uint16_t flags = 0, method = 0;
  std::uint32_t crc = 0;
  std::uint64_t csize = 0, usize = 0, offset = 0;
};

std::vector<ZipEntry> read_central_directory(File& f) {
  const std::string& path = f.path;
  if (f.size < 22) throw file_error(path, "not a ZIP/.npz file (too short)");
  // The end record sits in the last 22 bytes plus at most a 65535-byte comment.
  const std::size_t tail_len = std::size_t(std::min<std::uint64_t>(f.size, 22 + 65535));
  std::vector<unsigned char> tail(tail_len);
  f.read_at(f.size - tail_len, tail.data(), tail_len, "the end of central directory");
  std::size_t eocd = std::string::npos;
  for (std::size_t i = tail_len - 22 + 1; i-- > 0;)
    if (le32(&tail[i]) == kEndSig) {
      eocd = i;
      break;
    }
  if (eocd == std::string::npos) {
    if (f.size >= 6) {
      unsigned char head[6];
      f.read_at(0, head, 6, "the file header");
      if (std::memcmp(head, "\x93NUMPY", 6) == 0) throw file_error(path, "is a .npy file, not an .npz archive");
    }
    throw file_error(path, "not a ZIP/.npz file (no end of central directory record; truncated?)");
  }
  const unsigned char* e = &tail[eocd];
  std::uint64_t count = le16(e + 10), cd_size = le32(e + 12), cd_offset = le32(e + 16);
  const std::uint64_t eocd_pos = f.size - tail_len + eocd;
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
  if (cd_offset > f.size || cd_size > f.size - cd_offset) throw file_error(path, "truncated (central directory past the end)");
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

/// Where an entry's data starts (after its local header).
std::uint64_t entry_data_offset(File& f, const ZipEntry& z) {
  unsigned char lh[30];
  f.read_at(z.offset, lh, 30, ("the local header of '" + z.name + "'").c_str());
  if (le32(lh) != kLocalSig) throw file_error(f.path, "corrupt local header of '" + z.name + "'");
  const std::uint64_t start = z.offset + 30 + le16(lh + 26) + le16(lh + 28);
  if (start > f.size || z.csize > f.size - start)
    throw file_error(f.path, "truncated (entry '" + z.name + "' extends past the end of the file)");
  return start;
}

NpyArray read_entry(File& f, const ZipEntry& z) {
  const std::string where = f.path + " (entry '" + z.name + "')";
  if (z.flags & 1) throw file_error(where, "encrypted entries are not supported");
  const std::uint64_t start = entry_data_offset(f, z);
  NpyArray a;
  if (z.method == 0) {
    if (z.csize != z.usize) throw file_error(where, "stored entry with different compressed and plain sizes");
    // Header first, then the data straight into the array.
    std::vector<char> head(std::size_t(std::min<std::uint64_t>(z.usize, 4096)));
    f.read_at(start, head.data(), head.size(), "an entry");
    NpyHeader h;
    std::size_t need = parse_header(head.data(), head.size(), where, h);
    if (need) {
      if (need > z.usize) throw file_error(where, "truncated .npy header");
      head.resize(need);
      f.read_at(start, head.data(), need, "an entry");
      if (parse_header(head.data(), need, where, h)) throw file_error(where, "bad .npy header");
    }
    const std::size_t bytes = check_header(h, where, a);
    if (h.data_offset + bytes != z.usize)
      throw file_error(where, "holds " + std::to_string(z.usize - h.data_offset) + " bytes of data, but dtype " + h.dtype +
                                  " and shape " + shape_string(h.shape) + " need " + std::to_string(bytes));
    a.data.resize(bytes);
    f.read_at(start + h.data_offset, a.data.data(), bytes, "an entry");
    const std::uint32_t crc = crc32_update(crc32_update(0, head.data(), h.data_offset), a.data.data(), bytes);
    if (crc != z.crc) throw file_error(where, "CRC-32 mismatch (the file is corrupt)");
  } else if (z.method == 8) {
    // Deflate expands at most ~1032:1; a directory that claims more is lying.
    if (z.usize > z.csize * 1032 + 1024) throw file_error(where, "corrupt sizes in the central directory");
    std::vector<unsigned char> comp(std::size_t(z.csize));
    f.read_at(start, comp.data(), comp.size(), "an entry");
    std::vector<char> plain(std::size_t(z.usize));
    if (const char* why = Inflater(comp.data(), comp.size(), reinterpret_cast<unsigned char*>(plain.data()),
                                   plain.size()).run())
      throw file_error(where, std::string("bad compressed data: ") + why);
    if (crc32_update(0, plain.data(), plain.size()) != z.crc) throw file_error(where, "CRC-32 mismatch (the file is corrupt)");
    return parse_npy(plain.data(), plain.size(), where);
  } else {
    throw file_error(where, "unsupported compression method " + std::to_string(z.method) +
                                " (only stored and deflate entries are read)");
  }
  normalise_byte_order(a);
  return a;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// NpyArray
// ---------------------------------------------------------------------------------------------
std::size_t NpyArray::size() const {
  std::size_t n = 1;
  for (std::size_t s : shape) n *= s;
  return n;
}

std::size_t NpyArray::itemsize() const { return dtype_itemsize(dtype); }

namespace {
template <class T>
NpyArray make(const char* dtype, const std::vector<T>& v, std::vector<std::size_t> shape) {
  NpyArray a;
  a.dtype = dtype;
  a.shape = std::move(shape);
  a.data.resize(v.size() * sizeof(T));
  if (!v.empty()) std::memcpy(a.data.data(), v.data(), a.data.size());
  if (kBigEndianHost && sizeof(T) > 1)
    for (std::size_t i = 0; i < a.data.size(); i += sizeof(T)) std::reverse(&a.data[i], &a.data[i] + sizeof(T));
  return a;
}
}  // namespace

NpyArray NpyArray::f8(const std::vector<double>& v) { return make("<f8", v, {v.size()}); }

NpyArray NpyArray::f8_n3(const std::vector<Vec3d>& v) {
  std::vector<double> flat;
  flat.reserve(3 * v.size());
  for (const Vec3d& p : v) {
    flat.push_back(p.x);
    flat.push_back(p.y);
    flat.push_back(p.z);
  }
  return make("<f8", flat, {v.size(), 3});
}

NpyArray NpyArray::i8(const std::vector<std::int64_t>& v) { return make("<i8", v, {v.size()}); }

NpyArray NpyArray::b1(const std::vector<std::uint8_t>& v) {
  NpyArray a = make("|b1", v, {v.size()});
  for (char& c : a.data) c = c ? 1 : 0;
  return a;
}

NpyArray NpyArray::unicode(const std::string& s) {
  // UTF-8 to UTF-32LE code points; invalid bytes are taken as Latin-1.
  std::vector<std::uint32_t> cps;
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    const int extra = c < 0x80 ? 0 : c < 0xC0 ? -1 : c < 0xE0 ? 1 : c < 0xF0 ? 2 : c < 0xF8 ? 3 : -1;
    std::uint32_t cp = extra <= 0 ? c : c & (0x3Fu >> extra);
    bool ok = extra >= 0 && i + std::size_t(extra) < s.size();
    for (int k = 1; ok && k <= extra; ++k) {
      const unsigned char cc = static_cast<unsigned char>(s[i + std::size_t(k)]);
      if ((cc & 0xC0) != 0x80) ok = false;
      cp = cp << 6 | (cc & 0x3F);
    }
    if (!ok) {  // not UTF-8: the byte as Latin-1
      cps.push_back(c);
      ++i;
      continue;
    }
    cps.push_back(cp);
    i += std::size_t(extra) + 1;
  }
  const std::size_t len = std::max<std::size_t>(1, cps.size());
  NpyArray a;
  a.dtype = "<U" + std::to_string(len);
  a.shape = {1};
  a.data.assign(4 * len, 0);
  for (std::size_t i = 0; i < cps.size(); ++i)
    for (int k = 0; k < 4; ++k) a.data[4 * i + k] = char((cps[i] >> (8 * k)) & 0xff);
  return a;
}

std::string NpyArray::unicode_value(std::size_t i) const {
  char kind = 0;
  const std::size_t isz = dtype_itemsize(dtype, &kind);
  if (kind != 'U' || (i + 1) * isz > data.size()) return {};
  std::string out;
  for (std::size_t j = i * isz; j < (i + 1) * isz; j += 4) {
    std::uint32_t cp = 0;
    for (int k = 3; k >= 0; --k) cp = cp << 8 | static_cast<unsigned char>(data[j + k]);
    if (cp == 0) break;  // NumPy pads with NULs
    if (cp < 0x80) {
      out += char(cp);
    } else if (cp < 0x800) {
      out += char(0xC0 | (cp >> 6));
      out += char(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
      out += char(0xE0 | (cp >> 12));
      out += char(0x80 | ((cp >> 6) & 0x3F));
      out += char(0x80 | (cp & 0x3F));
    } else {
      out += char(0xF0 | ((cp >> 18) & 0x07));
      out += char(0x80 | ((cp >> 12) & 0x3F));
      out += char(0x80 | ((cp >> 6) & 0x3F));
      out += char(0x80 | (cp & 0x3F));
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// .npy
// ---------------------------------------------------------------------------------------------
NpyArray parse_npy(const char* bytes, std::size_t n, const std::string& name) {
  NpyHeader h;
  if (parse_header(bytes, n, name, h)) throw file_error(name, "truncated .npy header");
  NpyArray a;
  const std::size_t need = check_header(h, name, a);
  const std::size_t have = n - h.data_offset;
  if (have != need)
    throw file_error(name, (have < need ? "truncated: " : "") + std::to_string(have) + " bytes of data, but dtype " +
                               h.dtype + " and shape " + shape_string(h.shape) + " need " + std::to_string(need));
  a.data.assign(bytes + h.data_offset, bytes + n);
  normalise_byte_order(a);
  return a;
}

NpyArray read_npy(const std::string& path) {
  File f(path);
  std::vector<char> head(std::size_t(std::min<std::uint64_t>(f.size, 4096)));
  f.read_at(0, head.data(), head.size(), "the header");
  NpyHeader h;
  if (const std::size_t need = parse_header(head.data(), head.size(), path, h)) {
    if (need > f.size) throw file_error(path, "truncated .npy header");
    head.resize(need);
    f.read_at(0, head.data(), need, "the header");
    if (parse_header(head.data(), need, path, h)) throw file_error(path, "bad .npy header");
  }
  NpyArray a;
  const std::size_t need = check_header(h, path, a);
  const std::uint64_t have = f.size - h.data_offset;
  if (have != need)
    throw file_error(path, (have < need ? "truncated: " : "") + std::to_string(have) + " bytes of data, but dtype " +
                               h.dtype + " and shape " + shape_string(h.shape) + " need " + std::to_string(need));
  a.data.resize(need);
  f.read_at(h.data_offset, a.data.data(), need, "the data");
  normalise_byte_order(a);
  return a;
}

std::string npy_bytes(const NpyArray& a) {
  check_writable(a);
  std::string out = header_bytes(a);
  out.append(a.data.data(), a.data.size());
  return out;
}

void write_npy(const std::string& path, const NpyArray& a) {
  check_writable(a);
  AtomicWriter w(path);
  w.write(header_bytes(a));
  w.write(a.data.data(), a.data.size());
  w.commit();
}

std::vector<Vec3d> read_points_npy(const std::string& path) {
  const NpyArray a = read_npy(path);
  if (a.dtype != "<f8" || a.shape.size() != 2 || a.shape[1] != 3)
    throw file_error(path, "expected a float64 (N, 3) array of points, found dtype " + a.dtype + " and shape " +
                               shape_string(a.shape));
  const std::size_t n = a.shape[0];
  std::vector<Vec3d> pts(n);
  const char* d = a.data.data();
  for (std::size_t i = 0; i < n; ++i) {
    double c[3];
    std::memcpy(c, d + 24 * i, 24);
    if (kBigEndianHost)
      for (double& x : c) {
        char* b = reinterpret_cast<char*>(&x);
        std::reverse(b, b + 8);
      }
    for (double x : c)
      if (!std::isfinite(x))
        throw file_error(path, "point " + std::to_string(i) + " has " +
                                   (std::isnan(x) ? "a NaN coordinate" : "an infinite coordinate"));
    pts[i] = Vec3d(c[0], c[1], c[2]);
  }
  return pts;
}

// ---------------------------------------------------------------------------------------------
// .npz
// ---------------------------------------------------------------------------------------------
std::map<std::string, NpyArray> read_npz(const std::string& path) {
  File f(path);
  std::map<std::string, NpyArray> out;
  for (const ZipEntry& z : read_central_directory(f)) {
    if (!z.name.empty() && z.name.back() == '/') continue;  // a directory
    std::string key = z.name;
    if (key.size() > 4 && key.compare(key.size() - 4, 4, ".npy") == 0) key.resize(key.size() - 4);
    else continue;  // np.load only exposes .npy members as arrays
    if (out.count(key)) throw file_error(path, "duplicate entry '" + z.name + "'");
    out.emplace(key, read_entry(f, z));
  }
  return out;
}

void write_npz(const std::string& path, const std::map<std::string, NpyArray>& arrays) {
  for (const auto& kv : arrays) check_writable(kv.second);
  AtomicWriter w(path);
  std::string central;
  std::uint64_t entries = 0;
  for (const auto& kv : arrays) {
    const NpyArray& a = kv.second;
    const std::string name = kv.first + ".npy";
    const std::string head = header_bytes(a);
    const std::uint64_t size = head.size() + a.data.size();
    const std::uint32_t crc = crc32_update(crc32_update(0, head.data(), head.size()), a.data.data(), a.data.size());
    const std::uint64_t offset = w.offset();
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
    w.write(local);
    w.write(head);
    w.write(a.data.data(), a.data.size());

    std::string extra;
    if (zip64) {
      put16(extra, 1);
      put16(extra, 24);
      put64(extra, size);
      put64(extra, size);
      put64(extra, offset);
    }
    put32(central, kCentralSig);
    put16(central, (3 << 8) | (zip64 ? 45 : 20));  // made by: Unix
    put16(central, zip64 ? 45 : 20);
    put16(central, 0);
    put16(central, 0);
    put16(central, 0);
    put16(central, kDosDate);
    put32(central, crc);
    put32(central, zip64 ? kMax32 : std::uint32_t(size));
    put32(central, zip64 ? kMax32 : std::uint32_t(size));
    put16(central, std::uint32_t(name.size()));
    put16(central, std::uint32_t(extra.size()));
    put16(central, 0);  // comment
    put16(central, 0);  // disk
    put16(central, 0);  // internal attributes
    put32(central, 0100644u << 16);
    put32(central, zip64 ? kMax32 : std::uint32_t(offset));
    central += name;
    central += extra;
    ++entries;
  }
  const std::uint64_t cd_offset = w.offset();
  w.write(central);
  const std::uint64_t cd_size = central.size();
  std::string end;
  const bool zip64 = entries >= 0xffff || cd_offset >= kMax32 || cd_size >= kMax32;
  if (zip64) {
    const std::uint64_t rec = w.offset();
    put32(end, kEnd64Sig);
    put64(end, 44);
    put16(end, (3 << 8) | 45);
    put16(end, 45);
    put32(end, 0);
    put32(end, 0);
    put64(end, entries);
    put64(end, entries);
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
  put16(end, zip64 ? 0xffff : std::uint32_t(entries));
  put16(end, zip64 ? 0xffff : std::uint32_t(entries));
  put32(end, zip64 ? kMax32 : std::uint32_t(cd_size));
  put32(end, zip64 ? kMax32 : std::uint32_t(cd_offset));
  put16(end, 0);
  w.write(end);
  w.commit();
}

}  // namespace bvhbench
