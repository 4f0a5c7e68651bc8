#pragma once
/// Directed rounding of a double to float, on the float's bits (the libm call, nextafterf, was
/// ~60 instructions, and the distance search rounds a ball's box outwards on every search).
/// Inline: the coherent searches call them a dozen times per query.
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

}  // namespace ebp
