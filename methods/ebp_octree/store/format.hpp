#pragma once
/// The on-disk EBP-Octree (`.ebp`), its layout: a paged, checksummed file that the out-of-core queries read
/// through a page cache (out_of_core.hpp). See OUT_OF_CORE.md beside this file for the why.
///
/// File layout (little-endian, plain data, every section 8-byte aligned, pages 4 KiB aligned):
///   FileHeader (512 bytes, CRC-32C of itself)
///   top nodes     : the tree above the pages, pre-order; TopNode kind `page` = a page root
///   top children  : 8 u32 per top inner node
///   top planes    : bounding planes of the top nodes (page roots included), root frame
/// Every coordinate (root_lo, planes, vertices) is in the tree's frame: world - FileHeader::origin.
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
///
/// The page codec (page_codec.hpp) encodes and decodes one page; the writer (writer.hpp) and the
/// external build write files, the reader (reader.hpp) and `ebp verify` (verify.hpp) read them.
#include <cstdint>

#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

inline constexpr char kStoreMagic[8] = {'E', 'B', 'P', 'O', 'C', 'T', '\r', '\n'};
/// 3: 48-byte LeafTris (octahedral face normals, flags in the index's top bits).
/// 2 stored 64-byte LeafTris (float face normals); 1 also stored world coordinates, not the tree's
/// frame (FileHeader::origin). Older versions are refused with what changed (reader.cpp).
inline constexpr std::uint32_t kStoreVersion = 3;
inline constexpr std::uint32_t kPageMagic = 0x47504245u;  // "EBPG"
inline constexpr std::uint64_t kPageAlign = 4096;
inline constexpr std::uint64_t kMaxPageBytes = std::uint64_t(1) << 30;  ///< reader's limit per page
/// FileHeader::flags: the tree's Octree::closed (when the in-memory structure has that field):
/// every page tree gets it, so that coherent inside queries may use path independence.
inline constexpr std::uint64_t kStoreClosed = 1;


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
  /// The build options, each in the slot its entry of kBuildOptions names (core/build_params.hpp;
  /// store_file.hpp reads and writes them).
  double build_reals[2];
  std::int32_t build_ints[1];
  std::uint32_t page_target;  ///< bytes: the packing target of the writer
  std::uint64_t nodes, inner, leaves, white, black, triangle_refs, planes;  ///< of the whole tree
  std::uint64_t num_pages, num_top_nodes, num_top_children, num_top_planes;
  std::uint64_t file_size;
  Section top_nodes, top_children, top_planes, info, pages, directory;
  std::uint64_t flags;  ///< kStoreClosed (zero in files written before it existed)
  /// The frame origin (Octree::origin): root_lo, planes and every float coordinate of the pages
  /// are relative to it; a query point is translated by -origin once, in double.
  double origin[3];
  std::uint8_t reserved[512 - 8 - 4 - 4 - 32 - 8 - 16 - 8 - 56 - 32 - 8 - 6 * 24 - 8 - 24 - 8];
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

}  // namespace ebp
