// SHA-256 through OpenSSL's EVP interface. libcrypto dispatches at run time to the SHA extensions
// or AVX2 kernels of the processor; meshes of several hundred MB are hashed on every load.
#include "harness/util/sha256.hpp"

#include <openssl/err.h>
#include <openssl/evp.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>
#include <utility>
#include <vector>

#include "harness/util/errors.hpp"

namespace bvhbench {
namespace {

/// A libcrypto failure is not bad input: it means an allocation failed or the library is broken.
[[noreturn]] void crypto_failure(const char* what) {
  const unsigned long code = ERR_get_error();
  char reason[256] = "unknown error";
  if (code) ERR_error_string_n(code, reason, sizeof reason);
  throw std::runtime_error(std::string("OpenSSL SHA-256: ") + what + " failed (" + reason + ")");
}

void start(EVP_MD_CTX* ctx) {
  if (EVP_DigestInit_ex(ctx, EVP_sha256(), nullptr) != 1) crypto_failure("EVP_DigestInit_ex");
}

}  // namespace

Sha256::Sha256() : ctx_(EVP_MD_CTX_new()) {
  if (!ctx_) throw std::bad_alloc();
  try {
    start(ctx_);
  } catch (...) {
    EVP_MD_CTX_free(ctx_);
    throw;
  }
}

Sha256::~Sha256() { EVP_MD_CTX_free(ctx_); }  // accepts nullptr (a moved-from object)

Sha256::Sha256(Sha256&& other) noexcept : ctx_(std::exchange(other.ctx_, nullptr)) {}

Sha256& Sha256::operator=(Sha256&& other) noexcept {
  std::swap(ctx_, other.ctx_);
  return *this;
}

void Sha256::update(const void* data, std::size_t n) {
  if (n > 0 && EVP_DigestUpdate(ctx_, data, n) != 1) crypto_failure("EVP_DigestUpdate");
}

std::string Sha256::hex_digest() {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  if (EVP_DigestFinal_ex(ctx_, digest, &len) != 1 || len != 32) crypto_failure("EVP_DigestFinal_ex");
  start(ctx_);
  static const char* digits = "0123456789abcdef";
  std::string out(64, '0');
  for (unsigned i = 0; i < 32; ++i) {
    out[2 * i] = digits[digest[i] >> 4];
    out[2 * i + 1] = digits[digest[i] & 0xf];
  }
  return out;
}

std::string sha256_hex(const void* data, std::size_t n) {
  Sha256 s;
  s.update(data, n);
  return s.hex_digest();
}

std::string sha256_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw file_error(path, std::string("cannot open: ") + std::strerror(errno));
  Sha256 s;
  std::vector<char> buf(1 << 20);
  for (;;) {
    const std::size_t got = std::fread(buf.data(), 1, buf.size(), f);
    if (got > 0) s.update(buf.data(), got);
    if (got < buf.size()) break;
  }
  const bool bad = std::ferror(f);
  std::fclose(f);
  if (bad) throw file_error(path, "read error");
  return s.hex_digest();
}

}  // namespace bvhbench
