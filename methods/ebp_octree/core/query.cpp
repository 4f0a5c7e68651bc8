// The query state over a built Octree (query.hpp): its construction and the path reset. The
// queries: query_inside.cpp (point location and exact point-in-solid), query_distance.cpp
// (branch and bound).
#include <algorithm>
#include <cstddef>
#include <stdexcept>

#include "methods/ebp_octree/core/certificate.hpp"
#include "methods/ebp_octree/core/leaf_blocks.hpp"
#include "methods/ebp_octree/core/query.hpp"

namespace ebp {

Query::Query(const Octree& tree, bool coherent)
    : t_(tree),
      coherent_(coherent),
      stamp_(tree.num_triangles, 0),
      leaf_stamp_(tree.leaves.size(), 0),
      path_(std::make_unique<CertifiedPath>()) {
  if (!has_leaf_blocks(t_)) throw std::logic_error("ebp::Query: the Octree lacks its leaf blocks (compute_leaf_blocks)");
  std::uint32_t mb = 0;
  for (const Leaf& lf : t_.leaves) mb = std::max(mb, block_count(lf.tri_count));
  order_.resize(mb);
  block_d2_.resize(mb);
}

Query::~Query() = default;

std::size_t Query::state_bytes() const {
  return stamp_.capacity() * sizeof(std::uint32_t) + leaf_stamp_.capacity() * sizeof(std::uint32_t) +
         order_.capacity() * sizeof(order_[0]) + block_d2_.capacity() * sizeof(double) + sizeof(CertifiedPath) +
         (coherent_ ? 2 * sizeof(NearSet) : 0);
}
Query::Query(Query&&) noexcept = default;

void Query::set_scan_kernel(ScanKernel k) { path_->cert.set_kernel(k); }

void Query::set_adaptive_certificate(bool on) { path_->set_adaptive(on); }

void Query::reset_path() {
  path_->reset();
  last_node_ = UINT32_MAX;
  last_tri_ = UINT32_MAX;
  last_leaf_ = UINT32_MAX;
  last_leaf_node_ = UINT32_MAX;
  prev_ok_ = false;
  if (near_) near_->valid = false;
  if (dnear_) dnear_->valid = false;
  dprev_ok_ = false;
  dnear_backoff_ = 0;
  dnear_scale_ = 1.0;
  dnear_served_ = dnear_losses_ = 0;
  dnear_tried_ = dnear_first_ = false;
  walk_.root = UINT32_MAX;  // a new path walks from the root again: each pass counts the same work
}

}  // namespace ebp
