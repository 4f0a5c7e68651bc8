// What both store writers share (store_file.hpp).
#include "methods/ebp_octree/store/store_file.hpp"

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <iterator>

#include "methods/ebp_octree/store/crc32c.hpp"

namespace ebp {
namespace {

// Stores written before the table keep reading: the options sit where the three named fields
// (the two reals, then the integer) always sat.
static_assert(offsetof(FileHeader, build_reals) == 56 && offsetof(FileHeader, build_ints) == 72,
              "the build options' place in the header is fixed");

constexpr bool header_slots_fit() {
  constexpr int reals = int(std::size(FileHeader{}.build_reals)), ints = int(std::size(FileHeader{}.build_ints));
  for (const BuildOption& o : kBuildOptions) {
    const int slots = o.type == BuildOption::Type::real ? reals : ints;
    if (o.header_slot < 0 || o.header_slot >= slots) return false;
    for (const BuildOption& other : kBuildOptions)
      if (&other != &o && other.type == o.type && other.header_slot == o.header_slot) return false;
  }
  return true;
}
static_assert(header_slots_fit(), "every build option has a slot of its own in the header");

}  // namespace

FileHeader new_file_header(const Vec3d& origin, const Vec3d& root_lo, double root_size, int leaf_level, std::uint32_t num_triangles,
                           const BuildParams& params, std::size_t page_target, bool closed) {
  FileHeader h{};
  std::memcpy(h.magic, kStoreMagic, 8);
  h.version = kStoreVersion;
  h.header_size = sizeof(FileHeader);
  for (int k = 0; k < 3; ++k) {
    h.origin[k] = origin[k];
    h.root_lo[k] = root_lo[k];
  }
  h.root_size = root_size;
  h.leaf_level = std::uint32_t(leaf_level);
  h.num_triangles = num_triangles;
  for (const BuildOption& o : kBuildOptions) {
    if (o.type == BuildOption::Type::real)
      h.build_reals[o.header_slot] = o.get(params);
    else
      h.build_ints[o.header_slot] = std::int32_t(o.get(params));
  }
  h.page_target = std::uint32_t(std::max<std::size_t>(page_target, 4096));
  h.flags = closed ? kStoreClosed : 0;
  return h;
}

BuildParams header_build_params(const FileHeader& h) {
  BuildParams p;
  for (const BuildOption& o : kBuildOptions)
    o.set(p, o.type == BuildOption::Type::real ? h.build_reals[o.header_slot] : double(h.build_ints[o.header_slot]));
  return p;
}

void write_section(bvhbench::AtomicOutputFile& f, std::uint64_t* off, const void* data, std::size_t n, Section* s) {
  s->offset = *off;
  s->size = n;
  s->crc = crc32c(data, n);
  if (n) f.write_at(*off, data, n);
  *off = (*off + n + 7) / 8 * 8;
}

void write_header(bvhbench::AtomicOutputFile& f, FileHeader& h) {
  f.resize(h.file_size);
  h.header_crc = 0;
  h.header_crc = crc32c(&h, sizeof h);
  f.write_at(0, &h, sizeof h);
}

}  // namespace ebp
