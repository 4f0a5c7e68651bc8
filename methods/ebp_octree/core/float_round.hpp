#pragma once
/// Directed rounding of a double to float, on the float's bits (the libm call, nextafterf, was
/// ~60 instructions, and the distance search rounds a ball's box outwards on every search).
/// Inline: the coherent searches call them a dozen times per query.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace ebp {

/// The next float above f (f not NaN; +infinity stays).
inline float next_float_up(float f) {
  if (f == 0) return std::numeric_limits<float>::denorm_min();
  if (f == std::numeric_limits<float>::infinity()) return f;
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  u = f > 0 ? u + 1 : u - 1;
  std::memcpy(&f, &u, 4);
  return f;
}
/// The next float below f (f not NaN; -infinity stays).
inline float next_float_down(float f) { return -next_float_up(-f); }

/// x rounded to float towards -infinity (lo) and +infinity (hi).
inline void float_bounds(double x, float* lo, float* hi) {
  const float f = float(x);  // to nearest; then one step outwards where it went the other way
  *lo = double(f) > x ? next_float_down(f) : f;
  *hi = double(f) < x ? next_float_up(f) : f;
}
/// The largest float <= x and the smallest float >= x.
inline float float_down(double x) {
  const float f = float(x);
  return double(f) > x ? next_float_down(f) : f;
}
inline float float_up(double x) {
  const float f = float(x);
  return double(f) < x ? next_float_up(f) : f;
}

// Floats below and above x (x not NaN), each at most three floats beyond float_down / float_up's
// tightest ones, without a branch: x is moved outwards by more than half a float ulp (|x| 2^-23,
// and three quarters of the least subnormal near 0) before rounding to nearest, which then cannot
// cross x. For the searches' boxes about the query point, where the tightest floats are not
// needed: the tight rounding's comparison with x goes either way at random, a branch mispredicted
// half the time, and costs three times the instructions.

/// The margin. (|x| capped beyond the floats, so that an infinite x does not give inf - inf.)
inline double float_near_margin(double x) { return std::min(std::fabs(x), 0x1p130) * 0x1p-23 + 0x1.8p-150; }
/// A float <= x near it. (x beyond the floats: the float beside it.)
inline float float_down_near(double x) {
  return std::min(float(x - float_near_margin(x)), std::numeric_limits<float>::max());
}
/// A float >= x near it.
inline float float_up_near(double x) {
  return std::max(float(x + float_near_margin(x)), -std::numeric_limits<float>::max());
}
/// Both.
inline void float_bounds_near(double x, float* lo, float* hi) {
  *lo = float_down_near(x);
  *hi = float_up_near(x);
}

}  // namespace ebp
