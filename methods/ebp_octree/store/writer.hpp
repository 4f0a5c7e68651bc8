#pragma once
/// Writes an in-memory Octree as a `.ebp` store (format.hpp): the tree cut into a pinned top and
/// pages of sibling subtrees packed up to a target size, each page encoded by page_codec.hpp.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

/// Options of the writer.
struct StoreWriteOptions {
  std::size_t page_target = 64 * 1024;  ///< bytes: subtrees are packed into pages up to this size
  BuildParams params;                   ///< recorded in the header
  std::string info_json = "{}";        ///< build statistics, recorded in the info section
  std::function<void(double)> progress;
  /// Test hook: called before each page is written (throw to simulate a failure midway).
  std::function<void(std::uint32_t page)> before_page;
};

/// Writes `tree` as a `.ebp` at `path`, atomically: to a temporary beside it (bvhbench::AtomicOutputFile),
/// fsync'ed, then renamed; on any failure the temporary is removed and `path` is left as it was.
/// Throws std::runtime_error on an I/O error (naming the file), std::invalid_argument on an empty
/// tree.
void write_store_atomic(const Octree& tree, const std::string& path, const StoreWriteOptions& opt);

}  // namespace ebp
