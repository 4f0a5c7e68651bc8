// Fuzz target: the .ebp store reader (methods/ebp_octree/ebp_store.cpp, from bytes in memory) and
// the queries behind it: any bytes must be either refused with an InputError (the contract,
// fuzz_contract.hpp) or accepted and answer queries without crashing, hanging or reading out of
// bounds. The first input byte chooses: bit 0 clear, checksums are verified; set, they are
// skipped, so that mutations reach the structural checks behind them; bit 1, the page cache is
// coherent. Up to 16 pages are decoded through a 64 KiB page cache, with inside and distance
// queries in each. Build, run, seeds: fuzz/README.md.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "methods/ebp_octree/store/page_cache.hpp"
#include "methods/ebp_octree/store/out_of_core.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "fuzz_contract.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  ebp::StoreReader::Options opt;
  opt.verify_checksums = (data[0] & 1) == 0;
  const std::string name = "fuzz.ebp";
  (void)bvhbench::fuzz::accepts(name, [&] {
    ebp::StoreReader r(std::vector<std::uint8_t>(data + 1, data + size), name, opt);
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
  });
  return 0;
}
