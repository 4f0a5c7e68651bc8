// What both store writers share (store_file.hpp).
#include "methods/ebp_octree/store/store_file.hpp"

#include <algorithm>
#include <cstring>

#include "methods/ebp_octree/store/crc32c.hpp"

namespace ebp {

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
  h.leaf_factor = params.leaf_factor;
  h.cluster_angle = params.cluster_angle;
  h.max_planes = params.max_planes;
  h.page_target = std::uint32_t(std::max<std::size_t>(page_target, 4096));
  h.flags = closed ? kStoreClosed : 0;
  return h;
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
