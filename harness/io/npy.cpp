// NumPy .npy (format versions 1, 2 and 3) reading and writing.
//
// Query sets and answers reach hundreds of MB, so an array is read straight from its source (a
// file, an .npz entry, bytes in memory) into its final buffer, and written straight from it.
#include "harness/io/npy.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "harness/util/atomic_file.hpp"
#include "harness/util/binary_file.hpp"
#include "harness/util/errors.hpp"

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

/// Checks the header and fills the array's dtype, shape and order; returns the data size in bytes.
std::size_t check_header(const NpyHeader& h, const std::string& name, NpyOrder order, NpyArray& a) {
  char kind = 0;
  const std::size_t isz = dtype_itemsize(h.dtype, &kind);
  if (isz == 0) throw file_error(name, "unsupported dtype '" + h.dtype + "'");
  const bool fortran = h.fortran && h.shape.size() > 1;  // one dimension: the same bytes either way
  if (fortran && order == NpyOrder::c_only)
    throw file_error(name, "fortran_order arrays are not supported (save with C order)");
  std::size_t bytes;
  if (!data_bytes(h.shape, isz, bytes)) throw file_error(name, "shape " + shape_string(h.shape) + " is too large");
  a.shape = h.shape;
  a.dtype = h.dtype;
  a.fortran_order = fortran;
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
  if (a.fortran_order) throw std::invalid_argument("npy: cannot write a Fortran-order array (we write C order)");
  if (isz == 0 || (a.dtype[0] == '>')) throw std::invalid_argument("npy: cannot write dtype '" + a.dtype + "'");
  if (!data_bytes(a.shape, isz, bytes) || bytes != a.data.size())
    throw std::invalid_argument("npy: array of dtype " + a.dtype + " and shape " + shape_string(a.shape) + " has " +
                                std::to_string(a.data.size()) + " bytes of data, expected " + std::to_string(bytes));
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
    if ((cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF) cp = 0xFFFD;  // not encodable in UTF-8
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
NpyArray read_npy_from(const NpyByteSource& read, std::uint64_t size, const std::string& name, NpyOrder order,
                       NpySize size_is) {
  // The header is read in the pieces parse_header asks for: 12 bytes hold the length field of
  // any version, then the whole dict.
  std::string head;
  NpyHeader h;
  for (std::uint64_t want = std::min<std::uint64_t>(size, 12);;) {
    const std::size_t have = head.size();
    head.resize(std::size_t(want));
    read(&head[have], head.size() - have);
    const std::size_t need = parse_header(head.data(), head.size(), name, h);
    if (need == 0) break;
    if (need > size || need <= head.size()) throw file_error(name, "truncated .npy header");
    want = need;
  }
  NpyArray a;
  const std::size_t need = check_header(h, name, order, a);
  const std::uint64_t have = size - h.data_offset;
  if (have != need)
    throw file_error(name, (have < need ? "truncated: " : "") + std::to_string(have) + " bytes of data, but dtype " +
                               h.dtype + " and shape " + shape_string(h.shape) + " need " + std::to_string(need));
  constexpr std::size_t kFirstPiece = std::size_t(64) << 20;
  if (size_is == NpySize::present || need <= kFirstPiece) {
    a.data.resize(need);
    read(a.data.data(), need);
  } else {
    // Each piece as large as what arrived before it: at most one more copy of the data, and a
    // source that ends early throws before the buffer outgrows twice what it delivered.
    for (std::size_t done = 0; done < need;) {
      const std::size_t piece = std::min(need - done, std::max(done, kFirstPiece));
      a.data.resize(done + piece);
      read(a.data.data() + done, piece);
      done += piece;
    }
  }
  normalise_byte_order(a);
  return a;
}

NpyArray parse_npy(const char* bytes, std::size_t n, const std::string& name, NpyOrder order) {
  std::size_t at = 0;
  return read_npy_from(
      [&](void* out, std::size_t k) {
        // read_npy_from never asks for more than n in all; for an empty array it asks for 0
        // bytes into an empty buffer, whose data() may be null (memcpy's arguments may not).
        if (k > 0) std::memcpy(out, bytes + at, k);
        at += k;
      },
      n, name, order);
}

NpyArray read_npy(const std::string& path, NpyOrder order) {
  InputFile f(path);
  std::uint64_t at = 0;
  return read_npy_from(
      [&](void* out, std::size_t k) {
        f.read_at(at, out, k, "the .npy data");
        at += k;
      },
      f.size(), path, order);
}

std::string npy_header(const NpyArray& a) {
  check_writable(a);
  return header_bytes(a);
}

std::string npy_bytes(const NpyArray& a) {
  std::string out = npy_header(a);
  out.append(a.data.data(), a.data.size());
  return out;
}

void write_npy(const std::string& path, const NpyArray& a) {
  const std::string head = npy_header(a);
  AtomicOutputFile w(path);
  w.write(head);
  w.write(a.data.data(), a.data.size());
  w.commit();
}

namespace {
/// Coordinate c of point i of an (N, 3) array of little-endian T in either memory order.
template <class T>
double coordinate(const NpyArray& a, std::size_t i, std::size_t c) {
  const std::size_t n = a.shape[0];
  const std::size_t k = a.fortran_order ? c * n + i : 3 * i + c;
  T v;
  std::memcpy(&v, a.data.data() + k * sizeof(T), sizeof(T));
  if (kBigEndianHost) {
    char* b = reinterpret_cast<char*>(&v);
    std::reverse(b, b + sizeof(T));
  }
  return double(v);
}

template <class T>
std::vector<Vec3d> points_of(const NpyArray& a, const std::string& path) {
  const std::size_t n = a.shape[0];
  std::vector<Vec3d> pts(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double c[3] = {coordinate<T>(a, i, 0), coordinate<T>(a, i, 1), coordinate<T>(a, i, 2)};
    for (double x : c)
      if (!std::isfinite(x))
        throw file_error(path, "point " + std::to_string(i) + " has " +
                                   (std::isnan(x) ? "a NaN coordinate" : "an infinite coordinate"));
    pts[i] = Vec3d(c[0], c[1], c[2]);
  }
  return pts;
}

/// The points of an array read with NpyOrder::c_or_fortran.
std::vector<Vec3d> points_of_array(const NpyArray& a, const std::string& path) {
  const bool f8 = a.dtype == "<f8", f4 = a.dtype == "<f4";
  if (!(f8 || f4) || a.shape.size() != 2 || a.shape[1] != 3)
    throw file_error(path, "expected a float64 or float32 (N, 3) array of points, found dtype " + a.dtype +
                               " and shape " + shape_string(a.shape));
  return f8 ? points_of<double>(a, path) : points_of<float>(a, path);
}
}  // namespace

std::vector<Vec3d> read_points_npy(const std::string& path) {
  return points_of_array(read_npy(path, NpyOrder::c_or_fortran), path);
}

std::vector<Vec3d> parse_points_npy(const char* bytes, std::size_t n, const std::string& name) {
  return points_of_array(parse_npy(bytes, n, name, NpyOrder::c_or_fortran), name);
}

}  // namespace bvhbench
