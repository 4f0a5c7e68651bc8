#pragma once
/// The on-disk EBP-Octree (`.ebp`): a paged, checksummed file that the out-of-core queries read
/// through a page cache (ebp_ooc.hpp). See OUT_OF_CORE.md beside this file for the why.
///
/// File layout (little-endian, plain data, every section 8-byte aligned, pages 4 KiB aligned):
///   FileHeader (512 bytes, CRC-32C of itself)
///   top nodes     : the tree above the pages, pre-order; TopNode kind `page` = a page root
///   top children  : 8 u32 per top inner node
///   top planes    : bounding planes of the top nodes (page roots included), root frame
///   info          : UTF-8 JSON (build statistics, for `bvhbench ebp info`)
///   pages         : in octcode order, each a self-contained slice (PageHeader + arrays)
///   directory     : one PageEntry per page (offset, size, CRC-32C, parent code)
/// Every section and every page has its CRC-32C; the reader checks magic, version, sizes,
/// offsets (inside the file, non-overlapping), every index of a page before use, and checksums.
///
/// A page holds one or more sibling subtrees (children of the same top node, packed greedily up
/// to a target size) with their nodes, children, planes, leaves, triangle blocks (inline float
/// coordinates) and the table local -> input triangle index. Loaded, it becomes an ordinary
/// ebp::Octree in the *global* frame whose node 0 is the root: the path from the root to the
/// pages' parent is rebuilt as a chain of plane-less inner nodes, every other branch points to
/// one white dummy. The existing ebp::Query then answers inside the page unchanged.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

inline constexpr char kStoreMagic[8] = {'E', 'B', 'P', 'O', 'C', 'T', '\r', '\n'};
inline constexpr std::uint32_t kStoreVersion = 1;
inline constexpr std::uint32_t kPageMagic = 0x47504245u;  // "EBPG"
inline constexpr std::uint64_t kPageAlign = 4096;
inline constexpr std::uint64_t kMaxPageBytes = std::uint64_t(1) << 30;  ///< reader's limit per page
/// FileHeader::flags: the tree's Octree::closed (when the in-memory structure has that field):
/// every page tree gets it, so that coherent inside queries may use path independence.
inline constexpr std::uint64_t kStoreClosed = 1;

/// CRC-32C (Castagnoli), hardware (SSE 4.2) when the CPU has it.
std::uint32_t crc32c(const void* data, std::size_t n, std::uint32_t crc = 0);

struct Section {
  std::uint64_t offset = 0, size = 0;
  std::uint32_t crc = 0, pad = 0;
};
static_assert(sizeof(Section) == 24, "Section is 24 bytes");

struct FileHeader {
  char magic[8];
  std::uint32_t version;
  std::uint32_t header_size;  ///< sizeof(FileHeader)
  double root_lo[3];
  double root_size;
  std::uint32_t leaf_level;
  std::uint32_t num_triangles;  ///< of the input mesh
  double leaf_factor, cluster_angle;
  std::int32_t max_planes;
  std::uint32_t page_target;  ///< bytes: the packing target of the writer
  std::uint64_t nodes, inner, leaves, white, black, triangle_refs, planes;  ///< of the whole tree
  std::uint64_t num_pages, num_top_nodes, num_top_children, num_top_planes;
  std::uint64_t file_size;
  Section top_nodes, top_children, top_planes, info, pages, directory;
  std::uint64_t flags;  ///< kStoreClosed (zero in files written before it existed)
  std::uint8_t reserved[512 - 8 - 4 - 4 - 32 - 8 - 16 - 8 - 56 - 32 - 8 - 6 * 24 - 8 - 8];
  std::uint32_t header_crc;  ///< CRC-32C of the header with this field zero
  std::uint32_t pad;
};
static_assert(sizeof(FileHeader) == 512, "FileHeader is 512 bytes");

enum class TopKind : std::uint8_t { white = 0, black = 1, inner = 2, page = 3 };

struct TopNode {
  Octcode code;
  std::uint32_t plane_begin;
  std::uint16_t plane_count;
  TopKind kind;
  std::uint8_t pad;
  std::uint32_t index;  ///< inner: first of 8 entries in top children; page: page id
  std::uint32_t pad2;
};
static_assert(sizeof(TopNode) == 24, "TopNode is 24 bytes");

struct PageEntry {
  std::uint64_t offset;
  std::uint32_t size;
  std::uint32_t crc;
  Octcode parent;  ///< code of the top node whose children the page holds (root page: ~0)
  std::uint32_t triangles;  ///< LeafTri records
  std::uint32_t nodes;
};
static_assert(sizeof(PageEntry) == 32, "PageEntry is 32 bytes");
inline constexpr Octcode kNoParent = ~Octcode(0);

struct PageHeader {
  std::uint32_t magic;
  std::uint32_t page_id;
  Octcode parent;  ///< kNoParent: the page holds the whole tree (root page)
  std::uint32_t nroots, nnodes, nchildren, nplanes, nleaves, ntris, nlocal, pad;
};
static_assert(sizeof(PageHeader) == 48, "PageHeader is 48 bytes");
struct PageRoot {
  std::uint32_t octant;  ///< in the parent (0 for the root page)
  std::uint32_t node;    ///< page-local node index
};

/// Options of the writer.
struct StoreWriteOptions {
  std::size_t page_target = 64 * 1024;  ///< bytes: subtrees are packed into pages up to this size
  BuildParams params;                   ///< recorded in the header
  std::string info_json = "{}";        ///< build statistics, recorded in the info section
  std::function<void(double)> progress;
  /// Test hook: called before each page is written (throw to simulate a failure midway).
  std::function<void(std::uint32_t page)> before_page;
};

/// Writes `tree` as a `.ebp` at `path` (the file is written in place: callers wanting atomicity
/// write to a temporary name and rename, as `write_store_atomic` does). Throws std::runtime_error
/// on an I/O error (naming the file).
void write_store(const Octree& tree, const std::string& path, const StoreWriteOptions& opt);
/// write_store to `path + ".tmp"`, fsync, rename to `path`; on any failure removes the temporary.
void write_store_atomic(const Octree& tree, const std::string& path, const StoreWriteOptions& opt);

/// A loaded page: an ordinary Octree (global frame, chain from the root, see above) and the map
/// from its local triangle indices to the input mesh's.
struct Page {
  std::uint32_t id = 0;
  std::uint32_t chain = 0;  ///< nodes[0, chain - 1) are the root-to-parent chain, nodes[chain - 1] the dummy (0: root page)
  Octree tree;
  std::vector<std::uint32_t> global_tri;
  std::size_t bytes() const {
    return tree.bytes() + tree.derived_bytes() + global_tri.capacity() * sizeof(std::uint32_t);
  }
};

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

  /// Reassembles the whole in-memory tree (for tests: round trip). Node order may differ from
  /// the original's only where the original was not pre-order; answers are the same.
  Octree load_all() const;

 private:
  void open_and_check();
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
