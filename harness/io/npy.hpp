#pragma once
/// The NumPy .npy format (versions 1, 2 and 3): one array per file, read and written. The .npz
/// archives of several arrays are in npz.hpp.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "harness/core/geometry.hpp"

namespace bvhbench {

/// One array: dtype descr as NumPy writes it ("<f8", "<i8", "|b1", "<f4", "<u4", ...), C order
/// unless `fortran_order` says otherwise.
struct NpyArray {
  std::string dtype;
  std::vector<std::size_t> shape;
  std::vector<char> data;  ///< raw little-endian bytes, product(shape) * itemsize
  /// True only for an array of two or more dimensions read with NpyOrder::c_or_fortran from a
  /// file in Fortran order: then the first index varies fastest (element (i, j) of an (N, M)
  /// array is element j * N + i of `data`).
  bool fortran_order = false;
  std::size_t size() const;      ///< number of elements
  std::size_t itemsize() const;  ///< bytes per element from dtype

  template <class T> const T* as() const { return reinterpret_cast<const T*>(data.data()); }
  template <class T> T* as() { return reinterpret_cast<T*>(data.data()); }

  static NpyArray f8(const std::vector<double>& v);
  static NpyArray f8_n3(const std::vector<Vec3d>& v);  ///< shape (N, 3)
  static NpyArray i8(const std::vector<std::int64_t>& v);
  static NpyArray b1(const std::vector<std::uint8_t>& v);  ///< bool
  /// A one-element NumPy unicode array ("<U{k}", k = code points, at least 1; shape (1,))
  /// holding the UTF-8 string `s` as UTF-32LE, as NumPy stores str values.
  static NpyArray unicode(const std::string& s);
  /// Element i of a "<U*" array as UTF-8, trailing NUL padding dropped ("" if not unicode).
  /// Always valid UTF-8 (it may go into a result JSON): a code unit that is no Unicode scalar
  /// value (a surrogate, or above U+10FFFF) reads as U+FFFD, the replacement character.
  std::string unicode_value(std::size_t i = 0) const;
};

/// Which memory orders a reader accepts. Our own arrays are C order; Fortran order is accepted
/// where a caller indexes by `NpyArray::fortran_order` (points made by other tools).
enum class NpyOrder { c_only, c_or_fortran };

/// A sequential source of bytes: must copy exactly the next `n` bytes to `out`, or throw.
using NpyByteSource = std::function<void(void* out, std::size_t n)>;

/// Whether the `size` given to read_npy_from is known to be there (a file's size, a stored ZIP
/// entry's, bytes in memory) or only claimed by a header (the plain size of a deflated ZIP entry,
/// which a corrupt directory can make about 1000 times what the entry really inflates to).
enum class NpySize { present, claimed };

/// Reads one .npy of `size` bytes from `read`; `name` is used in error messages. The data goes
/// straight into the array's buffer; for a claimed size, the buffer grows as the bytes arrive
/// (from 64 MiB, doubling), so that a lying header cannot make the reader allocate much more than
/// the source delivers. Throws InputError (bad magic, bad header, unsupported dtype, size that
/// does not match the shape, ...).
NpyArray read_npy_from(const NpyByteSource& read, std::uint64_t size, const std::string& name,
                       NpyOrder order = NpyOrder::c_only, NpySize size_is = NpySize::present);
/// Parses .npy bytes; `name` is used in error messages. Throws InputError.
NpyArray parse_npy(const char* bytes, std::size_t n, const std::string& name,
                   NpyOrder order = NpyOrder::c_only);
NpyArray read_npy(const std::string& path, NpyOrder order = NpyOrder::c_only);

/// The header that a .npy of `a` starts with (magic, version, dict, padding to 64 bytes), as
/// np.save writes it. Throws std::invalid_argument if `a` cannot be written (big-endian dtype,
/// data size that does not match dtype and shape).
std::string npy_header(const NpyArray& a);
std::string npy_bytes(const NpyArray& a);  ///< npy_header(a) followed by the data
/// Writes atomically (AtomicOutputFile: a temporary beside PATH, then rename).
void write_npy(const std::string& path, const NpyArray& a);

/// Reads an (N, 3) array of points: float64 or float32 (widened exactly), either byte order,
/// C or Fortran order, in the file's row order. Throws InputError naming the file if it is not
/// one, or if a value is NaN or infinite (naming the point).
std::vector<Vec3d> read_points_npy(const std::string& path);
/// The same for .npy bytes in memory; `name` names them in messages.
std::vector<Vec3d> parse_points_npy(const char* bytes, std::size_t n, const std::string& name);

}  // namespace bvhbench
