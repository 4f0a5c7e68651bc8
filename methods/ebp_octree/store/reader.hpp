#pragma once
/// Reads a `.ebp` store (format.hpp): header, top tree and directory checked and pinned at open,
/// pages read, checked and decoded (page_codec.hpp) on demand.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/page_codec.hpp"

namespace ebp {

/// The read side: header, top tree and directory in memory (pinned), pages on demand.
class StoreReader {
 public:
  struct Options {
    bool verify_checksums = true;  ///< off only in the fuzzer (to reach the structural checks)
  };
  /// Opens and validates the file. Throws bvhbench::InputError naming the file and the problem.
  explicit StoreReader(const std::string& path, Options opt);
  explicit StoreReader(const std::string& path) : StoreReader(path, Options{}) {}
  /// From bytes in memory (fuzzing, tests): `name` is used in messages.
  StoreReader(std::vector<std::uint8_t> bytes, const std::string& name, Options opt);
  ~StoreReader();
  StoreReader(const StoreReader&) = delete;
  StoreReader& operator=(const StoreReader&) = delete;

  const std::string& path() const { return path_; }
  const FileHeader& header() const { return h_; }
  const std::vector<TopNode>& top_nodes() const { return top_nodes_; }
  const std::vector<std::uint32_t>& top_children() const { return top_children_; }
  const std::vector<Plane>& top_planes() const { return top_planes_; }
  const std::vector<PageEntry>& directory() const { return dir_; }
  const std::string& info_json() const { return info_; }
  std::size_t pinned_bytes() const;

  /// Reads, checks and decodes page `id`. Throws InputError on a bad page. `bytes_read` += size.
  std::unique_ptr<Page> load_page(std::uint32_t id, std::uint64_t* bytes_read = nullptr) const;
  /// Evicts the file from the OS page cache (posix_fadvise DONTNEED); no-op for in-memory bytes.
  void drop_os_cache() const;
  /// Asks the OS to read page `id` into its page cache in the background (posix_fadvise
  /// WILLNEED), so that a load_page() soon after finds it there; no-op for in-memory bytes.
  void will_need(std::uint32_t id) const;

  /// Reassembles the whole in-memory tree (for tests: round trip). Node order may differ from
  /// the original's only where the original was not pre-order; answers are the same.
  Octree load_all() const;

 private:
  /// At open, in this order: the header (magic, version, checksum, sizes, frame), the sections'
  /// sizes and places, the pinned sections read (checksums), the top tree from its root (returns,
  /// per page, whether the top tree names it), the directory's pages.
  void open_and_check();
  void check_header();
  void check_sections() const;
  void load_sections();
  std::vector<std::uint8_t> check_top_tree();
  void check_directory(const std::vector<std::uint8_t>& page_seen) const;
  PageContext page_context(std::uint32_t id) const;
  void read_at(std::uint64_t off, void* dst, std::size_t n) const;
  [[noreturn]] void fail(const std::string& what) const;
  std::string path_;
  int fd_ = -1;
  std::vector<std::uint8_t> mem_;  // in-memory bytes (fuzzing)
  bool in_memory_ = false;
  Options opt_;
  std::uint64_t file_size_ = 0;
  FileHeader h_{};
  std::vector<TopNode> top_nodes_;
  std::vector<std::uint32_t> top_children_;
  std::vector<Plane> top_planes_;
  std::vector<PageEntry> dir_;
  std::string info_;
  std::vector<Octcode> page_parent_;        // per page: the code of the top node holding it
  std::vector<std::uint8_t> page_octants_;  // per page: octants of its roots in that parent
};

}  // namespace ebp
