#pragma once
#include <cstdint>

namespace bvhbench {

/// Deterministic random source: splitmix64-seeded xoshiro256**, identical on every platform
/// (std::uniform_real_distribution is not), with the few distributions generators need.
class Rng {
 public:
  explicit Rng(std::uint64_t seed);
  std::uint64_t next();
  double uniform();                     ///< [0, 1) with 53 random bits
  double uniform(double lo, double hi);
  double normal();                      ///< standard normal (Box-Muller, deterministic)
  std::uint64_t below(std::uint64_t n);  ///< uniform integer in [0, n)
 private:
  std::uint64_t s_[4];
  bool has_spare_ = false;
  double spare_ = 0;
};

}  // namespace bvhbench
