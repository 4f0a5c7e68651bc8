#pragma once
/// NumPy .npy and .npz (uncompressed, as np.savez writes) reading and writing.
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "geometry.hpp"

namespace bvhbench {

/// One array: dtype descr as NumPy writes it ("<f8", "<i8", "|b1", "<f4", "<u4", ...), C order.
struct NpyArray {
  std::string dtype;
  std::vector<std::size_t> shape;
  std::vector<char> data;  ///< raw little-endian bytes, product(shape) * itemsize
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
  std::string unicode_value(std::size_t i = 0) const;
};

/// Parses .npy bytes; `name` is used in error messages. Throws InputError.
NpyArray parse_npy(const char* bytes, std::size_t n, const std::string& name);
NpyArray read_npy(const std::string& path);
std::string npy_bytes(const NpyArray& a);
/// Writes atomically (to PATH.tmp, then rename).
void write_npy(const std::string& path, const NpyArray& a);

/// Reads an .npz written by np.savez (stored entries; ZIP64 supported) or np.savez_compressed
/// (deflate). Keys drop ".npy". Throws InputError for anything else, naming the file.
std::map<std::string, NpyArray> read_npz(const std::string& path);
/// Writes an uncompressed .npz that np.load reads; atomically.
void write_npz(const std::string& path, const std::map<std::string, NpyArray>& arrays);

/// Reads a float64 (N, 3) array as points; throws InputError naming the file if it is not one,
/// or if a value is NaN or infinite.
std::vector<Vec3d> read_points_npy(const std::string& path);

}  // namespace bvhbench
