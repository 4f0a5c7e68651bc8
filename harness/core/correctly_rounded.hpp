#pragma once
/// Correctly rounded sin, cos and log, for the code whose output must be the same bytes on every
/// machine: query-set generation (docs/architecture.md: "the same seed and parameters give the
/// same bytes on every machine"; the CI gate pairs jobs by the query set's sha256).
///
/// Why not std::sin: glibc picks its libm kernels at run time (FMA variants on processors that
/// have FMA), and its results are within 1 ulp but not always the nearest double, so the same call
/// can return different last bits on two machines (about 0.1 % of sin/cos results differed here
/// between the FMA and the plain kernels). A correctly rounded result has no such freedom: it is
/// the double nearest to the exact value, everywhere. MPFR (already linked through CGAL's exact
/// arithmetic) computes it; at about a microsecond a call it is only for generators, never for
/// a query loop.
namespace bvhbench::correctly_rounded {

double sin(double x);  ///< nearest double to sin(x); NaN for NaN or infinite x
double cos(double x);  ///< nearest double to cos(x); NaN for NaN or infinite x
double log(double x);  ///< nearest double to ln(x); -inf at 0, NaN below 0

}  // namespace bvhbench::correctly_rounded
