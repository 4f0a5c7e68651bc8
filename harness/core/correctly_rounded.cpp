#include "harness/core/correctly_rounded.hpp"

#include <mpfr.h>

namespace bvhbench::correctly_rounded {

namespace {

/// Two MPFR numbers of double precision (53 bits), made once per thread: with a 53-bit target
/// and round-to-nearest, MPFR's result is the correctly rounded double, and mpfr_get_d returns it
/// exactly (the values here are never subnormal, where MPFR's wider exponent range would round
/// twice).
struct Scratch {
  mpfr_t in, out;
  Scratch() {
    mpfr_init2(in, 53);
    mpfr_init2(out, 53);
  }
  ~Scratch() {
    mpfr_clear(in);
    mpfr_clear(out);
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
};

template <int (*F)(mpfr_ptr, mpfr_srcptr, mpfr_rnd_t)>
double apply(double x) {
  thread_local Scratch s;
  mpfr_set_d(s.in, x, MPFR_RNDN);  // exact: 53 bits hold any double
  F(s.out, s.in, MPFR_RNDN);
  return mpfr_get_d(s.out, MPFR_RNDN);
}

}  // namespace

double sin(double x) { return apply<mpfr_sin>(x); }
double cos(double x) { return apply<mpfr_cos>(x); }
double log(double x) { return apply<mpfr_log>(x); }

}  // namespace bvhbench::correctly_rounded
