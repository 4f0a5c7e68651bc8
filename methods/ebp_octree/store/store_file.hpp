#pragma once
/// What the two writers of a `.ebp` store (the in-memory writer, writer.cpp; the external build,
/// build/external_build.cpp) share besides the page codec: the header's fixed fields, a checksummed
/// section, and the header written last. Both write through bvhbench::AtomicOutputFile.
#include <cstddef>
#include <cstdint>

#include "harness/util/atomic_file.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/store/format.hpp"

namespace ebp {

/// A header with magic, version, size, frame (origin, root_lo, root_size, leaf_level), the input's
/// triangle count, the build parameters, the page target (at least 4096) and the closed flag;
/// every count, section and the checksum zero, for the writer to fill.
FileHeader new_file_header(const Vec3d& origin, const Vec3d& root_lo, double root_size, int leaf_level, std::uint32_t num_triangles,
                           const BuildParams& params, std::size_t page_target, bool closed);

/// The build options a header keeps (every other field of BuildParams at its default), each from
/// the slot kBuildOptions names.
BuildParams header_build_params(const FileHeader& h);

/// Writes `n` bytes at `*off` as section `*s` (offset, size, CRC-32C), then moves `*off` to the
/// next 8-byte boundary.
void write_section(bvhbench::AtomicOutputFile& f, std::uint64_t* off, const void* data, std::size_t n, Section* s);

/// Cuts the file to h.file_size, seals the header with its checksum and writes it at offset 0.
void write_header(bvhbench::AtomicOutputFile& f, FileHeader& h);

}  // namespace ebp
