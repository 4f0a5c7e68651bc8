// libFuzzer target for the .ebp reader (ebp_store.cpp): any bytes must be either rejected with
// bvhbench::InputError or accepted and answer queries without crashing, hanging or reading out
// of bounds. Checksums are verified on half of the inputs and skipped on the other half (chosen
// by the first byte), so that the structural checks behind them are reached too.
//
// Build: cmake -DBVHBENCH_FUZZ=ON -DCMAKE_CXX_COMPILER=clang++ ... && ninja fuzz_ebp_reader
// Run:   ./fuzz_ebp_reader -max_total_time=600 corpus/   (seed corpus: small stores, see
//        OUT_OF_CORE.md)
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ebp_cache.hpp"
#include "ebp_ooc.hpp"
#include "ebp_store.hpp"
#include "errors.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  ebp::StoreReader::Options opt;
  opt.verify_checksums = (data[0] & 1) == 0;
  try {
    ebp::StoreReader r(std::vector<std::uint8_t>(data + 1, data + size), "fuzz.ebp", opt);
    ebp::PageCache cache(r, 1 << 16, (data[0] & 2) != 0);
    const std::size_t n = std::min<std::size_t>(r.directory().size(), 16);
    const ebp::FileHeader& h = r.header();
    const ebp::Vec3d lo(h.root_lo[0], h.root_lo[1], h.root_lo[2]);
    for (std::uint32_t id = 0; id < n; ++id) {
      ebp::PageCache::Entry& e = cache.get(id);
      // A few queries through the page's own structure.
      for (int k = 0; k < 4; ++k) {
        const double f = 0.13 + 0.23 * k;
        const ebp::Vec3d p = lo + ebp::Vec3d(f, 1 - f, 0.5 * f) * h.root_size;
        (void)e.query->inside(p);
        (void)e.query->distance(p);
      }
    }
  } catch (const bvhbench::InputError&) {
  }
  return 0;
}
