#pragma once
/// SHA-256 (FIPS 180-4) of bytes and files: identifies meshes and query sets in results.
#include <cstddef>
#include <cstdint>
#include <string>

namespace bvhbench {

class Sha256 {
 public:
  Sha256();
  void update(const void* data, std::size_t n);
  std::string hex_digest();  ///< finalises; 64 lowercase hex characters
 private:
  void block(const std::uint8_t* p);
  std::uint32_t h_[8];
  std::uint8_t buf_[64];
  std::size_t buf_len_ = 0;
  std::uint64_t total_ = 0;
};

std::string sha256_hex(const void* data, std::size_t n);
/// Hash of a whole file; throws InputError if it cannot be read.
std::string sha256_file(const std::string& path);

}  // namespace bvhbench
