#pragma once
/// What an accepted .npy array promises (fuzz_npy.cpp, fuzz_npz.cpp): data of product(shape) *
/// itemsize bytes, kept little-endian, and unicode strings that are valid UTF-8 (an oracle's
/// `definition` and hashes end up in result JSON: nlohmann::json refuses to print invalid UTF-8).
#include <algorithm>
#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

#include "fuzz_contract.hpp"
#include "harness/io/npy.hpp"

namespace bvhbench::fuzz {

/// `what` names the array in a violation.
inline void check_array(const NpyArray& a, const std::string& what) {
  check(a.data.size() == a.size() * a.itemsize(), what + ": data size is not product(shape) * itemsize");
  check(a.dtype[0] == '<' || a.dtype[0] == '|', what + ": dtype " + a.dtype + " is not in our byte order");
  if (a.dtype[1] == 'U')
    for (std::size_t i = 0; i < std::min<std::size_t>(a.size(), 64); ++i) (void)nlohmann::json(a.unicode_value(i)).dump();
}

}  // namespace bvhbench::fuzz
