#pragma once
/// SHA-256 (FIPS 180-4) of bytes and files: identifies meshes and query sets in results.
/// Computed by OpenSSL's libcrypto (EVP), which picks the fastest kernel for the processor (the
/// x86 SHA extensions where present); every user in the project goes through this one wrapper.
#include <cstddef>
#include <string>

struct evp_md_ctx_st;  // OpenSSL's EVP_MD_CTX, kept out of this header

namespace bvhbench {

/// An incremental hash: update() any number of times, then hex_digest() once.
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(Sha256&& other) noexcept;
  Sha256& operator=(Sha256&& other) noexcept;
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  void update(const void* data, std::size_t n);
  /// Finalises: 64 lowercase hex characters of the hash of everything given to update(). The
  /// object then starts over, as if new.
  std::string hex_digest();

 private:
  evp_md_ctx_st* ctx_;
};

std::string sha256_hex(const void* data, std::size_t n);
/// Hash of a whole file; throws InputError if it cannot be read.
std::string sha256_file(const std::string& path);

}  // namespace bvhbench
