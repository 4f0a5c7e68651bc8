// Fuzz target: the .npz reader and the ZIP container under it (harness/io/npz.hpp, harness/io/zip.hpp;
// zlib's inflate): central directory, ZIP64 records, local headers, stored and deflated entries,
// CRC-32, and each entry's .npy.
//
// Each input is read with and without the entries' CRC-32 check. Beyond the contract
// (fuzz_contract.hpp), every accepted array must be what its header says
// (data of product(shape) * itemsize bytes, kept little-endian) and its unicode strings valid
// UTF-8 (the oracle's `definition` and hashes end up in result JSON).
#include <cstddef>
#include <cstdint>

#include <nlohmann/json.hpp>

#include "fuzz_contract.hpp"
#include "harness/io/npz.hpp"

using namespace bvhbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string name = "fuzz.npz";
  // Read twice: as the runner reads, and without the entries' CRC-32 check, so that mutated
  // entries reach the .npy reader instead of dying at a CRC mismatch.
  for (const bool verify_crc : {true, false}) {
    std::map<std::string, NpyArray> arrays;
    if (!fuzz::accepts(name, [&] { arrays = parse_npz(fuzz::as_text(data, size), name, verify_crc); })) continue;
    for (const auto& [key, a] : arrays) {
      fuzz::check(a.data.size() == a.size() * a.itemsize(), "entry '" + key + "': data size is not product(shape) * itemsize");
      fuzz::check(a.dtype[0] == '<' || a.dtype[0] == '|', "entry '" + key + "': dtype " + a.dtype + " is not in our byte order");
      if (a.dtype[1] == 'U')
        for (std::size_t i = 0; i < std::min<std::size_t>(a.size(), 64); ++i) (void)nlohmann::json(a.unicode_value(i)).dump();
    }
  }
  return 0;
}
