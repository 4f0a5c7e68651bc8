// correctly_rounded::sin/cos/log: the double nearest to the exact value (checked against long
// double, which carries 11 more bits: an error above half an ulp plus that slack fails).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "harness/core/correctly_rounded.hpp"

namespace cr = bvhbench::correctly_rounded;

namespace {

/// |computed - reference| in ulps of the double result.
long double ulp_error(double computed, long double reference) {
  const double ulp = std::nextafter(std::fabs(computed), INFINITY) - std::fabs(computed);
  return std::fabs(static_cast<long double>(computed) - reference) / ulp;
}

}  // namespace

TEST(CorrectlyRounded, WithinHalfAnUlpOverManyArguments) {
  std::uint64_t s = 12345;
  for (int i = 0; i < 20000; ++i) {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    const double u = double(s >> 11) * 0x1.0p-53;   // [0, 1)
    const double x = (u - 0.5) * 40.0;              // [-20, 20): the generators' phases
    const double l = u + 1e-300;                    // (0, 1]: Box-Muller's log argument
    EXPECT_LE(ulp_error(cr::sin(x), sinl(x)), 0.5L + 0x1.0p-10L) << x;
    EXPECT_LE(ulp_error(cr::cos(x), cosl(x)), 0.5L + 0x1.0p-10L) << x;
    EXPECT_LE(ulp_error(cr::log(l), logl(l)), 0.5L + 0x1.0p-10L) << l;
  }
}

TEST(CorrectlyRounded, ExactAndSpecialValues) {
  EXPECT_EQ(cr::sin(0.0), 0.0);
  EXPECT_EQ(cr::cos(0.0), 1.0);
  EXPECT_EQ(cr::log(1.0), 0.0);
  EXPECT_EQ(cr::log(0.0), -INFINITY);
  EXPECT_TRUE(std::isnan(cr::log(-1.0)));
  EXPECT_TRUE(std::isnan(cr::sin(INFINITY)));
  EXPECT_TRUE(std::isnan(cr::cos(NAN)));
  EXPECT_EQ(cr::sin(1e-300), 1e-300);  // sin x = x below half an ulp of x^3/6
}
