// printable() and quoted_excerpt(): what a message may quote from a file is valid UTF-8 afterwards.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"

using bvhbench::printable;
using bvhbench::quoted_excerpt;

TEST(Printable, ValidUtf8IsUnchanged) {
  EXPECT_EQ(printable("plain ascii"), "plain ascii");
  EXPECT_EQ(printable("caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x90\x87"), "caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x90\x87");
  EXPECT_EQ(printable("tab\tand\nnewline"), "tab\tand\nnewline");
}

TEST(Printable, InvalidBytesAreEscaped) {
  EXPECT_EQ(printable("x\xFFy"), "x\\xFFy");
  EXPECT_EQ(printable("\x80"), "\\x80");                  // stray continuation byte
  EXPECT_EQ(printable("\xC0\xAF"), "\\xC0\\xAF");         // overlong '/'
  EXPECT_EQ(printable("\xED\xA0\x80"), "\\xED\\xA0\\x80");  // UTF-16 surrogate
  EXPECT_EQ(printable("\xF4\x90\x80\x80"), "\\xF4\\x90\\x80\\x80");  // above U+10FFFF
  EXPECT_EQ(printable("end\xE2\x82"), "end\\xE2\\x82");   // truncated sequence
  EXPECT_EQ(printable(std::string("nul\0bell\a", 9)), "nul\\x00bell\\x07");
  EXPECT_EQ(printable("\x7F"), "\\x7F");
}

TEST(Printable, IsIdempotentAndMakesJsonSafe) {
  std::string all;
  for (int b = 0; b < 256; ++b) all += char(b);
  const std::string once = printable(all);
  EXPECT_EQ(printable(once), once);
  nlohmann::json j = {{"message", once}};
  EXPECT_NO_THROW((void)j.dump());
}

TEST(Printable, QuotedExcerptCutsLongTokensWithoutSplittingASequence) {
  EXPECT_EQ(quoted_excerpt("abc"), "'abc'");
  EXPECT_EQ(quoted_excerpt("a\tb\nc"), "'a\\x09b\\x0Ac'");  // a quoted token stays on one line
  EXPECT_EQ(quoted_excerpt(std::string(50, 'x')), "'" + std::string(40, 'x') + "...'");
  // 39 ASCII bytes and a 2-byte character: the character does not fit in 40 bytes whole.
  EXPECT_EQ(quoted_excerpt(std::string(39, 'x') + "\xC3\xA9"), "'" + std::string(39, 'x') + "...'");
  EXPECT_EQ(quoted_excerpt("\xFF\xFE"), "'\\xFF\\xFE'");
}

TEST(Printable, FileErrorsArePrintable) {
  const bvhbench::InputError e = bvhbench::file_error("m\xFF.ply", "bad token 'x\xFE'");
  EXPECT_STREQ(e.what(), "m\\xFF.ply: bad token 'x\\xFE'");
}
