// SHA-256 against the FIPS 180-4 / NIST example vectors, in one piece and in odd-sized chunks.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <utility>

#include "harness/util/errors.hpp"
#include "harness/util/sha256.hpp"

using namespace bvhbench;

namespace {
const char* kMsg448 = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
const char* kMsg896 =
    "abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklmnoijklmnopjklmnopqklmnopqrlmnopqrs"
    "mnopqrstnopqrstu";
}  // namespace

TEST(Sha256, Empty) {
  EXPECT_EQ(sha256_hex("", 0), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST(Sha256, Abc) {
  EXPECT_EQ(sha256_hex("abc", 3), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Sha256, Message448Bits) {
  EXPECT_EQ(sha256_hex(kMsg448, 56), "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Sha256, Message896Bits) {
  EXPECT_EQ(sha256_hex(kMsg896, 112), "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1");
}

TEST(Sha256, OneMillionA) {
  const std::string m(1000000, 'a');
  EXPECT_EQ(sha256_hex(m.data(), m.size()),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, IncrementalUpdatesMatchOneShot) {
  const std::string m(1000000, 'a');
  for (std::size_t chunk : {1u, 7u, 63u, 64u, 65u, 4096u}) {
    Sha256 s;
    for (std::size_t i = 0; i < m.size(); i += chunk) s.update(m.data() + i, std::min(chunk, m.size() - i));
    EXPECT_EQ(s.hex_digest(), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0")
        << "chunk " << chunk;
  }
}

TEST(Sha256, PaddingBoundaries) {
  // Lengths around the 55/56/64-byte padding edges must agree between one-shot and byte-wise.
  for (std::size_t n = 50; n <= 130; ++n) {
    const std::string m(n, 'q');
    Sha256 s;
    for (char c : m) s.update(&c, 1);
    EXPECT_EQ(s.hex_digest(), sha256_hex(m.data(), m.size())) << n;
  }
}

TEST(Sha256, File) {
  const std::string path = testing::TempDir() + "bvhbench_sha256_test.txt";
  { std::ofstream(path, std::ios::binary) << "abc"; }
  EXPECT_EQ(sha256_file(path), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  std::remove(path.c_str());
}

TEST(Sha256, MissingFileIsInputError) {
  try {
    sha256_file("/nonexistent/dir/file.ply");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/file.ply"), std::string::npos);
  }
}

TEST(Sha256, DigestStartsOver) {
  Sha256 s;
  s.update("xyz", 3);
  s.hex_digest();
  s.update("abc", 3);
  EXPECT_EQ(s.hex_digest(), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(s.hex_digest(), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST(Sha256, MovedHashKeepsItsState) {
  Sha256 a;
  a.update("ab", 2);
  Sha256 b(std::move(a));
  b.update("c", 1);
  EXPECT_EQ(b.hex_digest(), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  Sha256 c;
  c.update("junk", 4);
  c = std::move(b);
  c.update(kMsg448, 56);
  EXPECT_EQ(c.hex_digest(), "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}
