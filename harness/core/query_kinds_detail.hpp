#pragma once
/// Internals of the query kinds (query_kinds*.cpp), exposed for their tests: the generators,
/// the surface sampler, the triangle grid used for closest points, and the haptic path layout.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "harness/core/geometry.hpp"
#include "harness/core/mesh.hpp"
#include "harness/core/params.hpp"
#include "harness/core/triangle_source.hpp"
#include "harness/util/scratch_array.hpp"

namespace bvhbench {
class Progress;
}

namespace bvhbench::query_kinds_detail {

std::vector<Vec3d> random_points_in_box(const Box3d& box, std::size_t n, std::uint64_t seed, const Params& p);
std::vector<Vec3d> random_points(const TriangleSource& mesh, std::size_t n, std::uint64_t seed, const Params& p);
std::vector<Vec3d> near_points(const TriangleSource& mesh, std::size_t n, std::uint64_t seed, const Params& p);
std::vector<Vec3d> surface_points(const TriangleSource& mesh, std::size_t n, std::uint64_t seed, const Params& p);
std::vector<Vec3d> haptic_path(const TriangleSource& mesh, std::size_t n, std::uint64_t seed, const Params& p);
std::vector<Vec3d> contact_path(const TriangleSource& mesh, std::size_t n, std::uint64_t seed, const Params& p);

/// Area-weighted triangle picking: the first triangle whose running sum of areas (in triangle
/// order) exceeds u times the total. The running sum is kept at the end of every chunk of
/// kChunk triangles only (8 bytes per chunk, not per triangle: 4 MB at 128M triangles); a pick
/// adds up its chunk's areas again, in the same order, so it is the same double sum and the same
/// triangle as over a full prefix-sum array. Zero-area triangles are never picked. The source must
/// outlive the sampler.
class AreaSampler {
 public:
  static constexpr std::size_t kChunk = 256;
  /// Throws InputError if the mesh has no area at all.
  explicit AreaSampler(const TriangleSource& mesh);
  /// A triangle with probability proportional to its area, from u in [0, 1).
  std::uint32_t pick(double u) const;
  double total_area() const { return chunk_end_.empty() ? 0.0 : chunk_end_.back(); }
 private:
  const TriangleSource& mesh_;
  std::vector<double> chunk_end_;  ///< the running sum at the end of each chunk
};

/// A point uniform on triangle (a, b, c) from two uniforms in [0, 1).
Vec3d uniform_in_triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c, double r1, double r2);

/// Exact closest-point queries for points near the surface: a dense uniform grid over the
/// mesh's box, each triangle listed in every cell its box overlaps (CSR: #cells+1 offsets, then
/// triangle ids). A query is given an upper bound r on the distance (in a haptic loop the
/// previous closest point gives it) and tests the triangles of the cells overlapping the box
/// p +- r, so the answer is exact whenever some surface point lies within r; ties go to the
/// lower triangle id, so the answer does not depend on the cells (nor on how the grid is held).
/// The cell size is at least `min_cell` and twice the average edge length, grown until the grid
/// has at most `max_cells` cells. Over a paged source (TriangleSource::scratch) the grid pages
/// too: its ids go to a scratch file, written a slab of cells at a time, and are read back
/// through a cache, all within shares of the source's budget.
class TriangleGrid {
 public:
  /// `progress` (optional) is advanced by 2 units per triangle over the build.
  TriangleGrid(const TriangleSource& source, double min_cell, std::size_t max_cells = std::size_t(1) << 26,
               Progress* progress = nullptr);
  struct Hit {
    Vec3d point;            ///< closest point on the mesh
    std::uint32_t triangle; ///< its triangle
    double distance;        ///< |p - point|
  };
  /// Closest point to p among the triangles within distance r (r must be > 0 and at least the
  /// true distance for an exact answer; a larger r only costs time). found=false if none.
  bool closest(const Vec3d& p, double r, Hit* hit) const;
  double cell_size() const { return h_; }
  std::size_t num_cells() const { return std::size_t(n_[0]) * n_[1] * n_[2]; }
  std::size_t num_refs() const { return offsets_.empty() ? 0 : offsets_.back(); }
  std::uint64_t triangles_tested() const { return tested_; }
  bool paged() const { return paged_ids_ != nullptr; }
  /// Runs of cells whose ids were written in one pass over the triangles (1 in memory).
  std::size_t slabs() const { return slabs_; }

 private:
  const TriangleSource& source_;
  Vec3d lo_;
  double h_ = 1;
  int n_[3] = {1, 1, 1};
  std::vector<std::uint32_t> offsets_;  // #cells + 1
  std::vector<std::uint32_t> ids_;      // in memory
  std::unique_ptr<ScratchArray<std::uint32_t>> paged_ids_;  // or paged
  std::size_t slabs_ = 0;
  mutable std::uint64_t tested_ = 0;
  int cell_coord(double x, int axis) const;
  void cell_range(std::uint32_t t, int lo[3], int hi[3]) const;
  std::size_t linear(int x, int y, int z) const;
  void fill(std::size_t slab_ids, Progress* progress);
  /// A triangle's first and last cell (linear indices: the corners of its range of cells).
  struct CellSpan {
    std::uint32_t first, last;
  };
  void count_cells(ScratchArray<CellSpan>* spans, Progress* progress);
  void write_slab(std::size_t c0, std::size_t c1, const ScratchArray<CellSpan>* spans, std::vector<std::uint32_t>& slab,
                  Progress* progress);
};

/// The fixed layout of a haptic path: every episode has `approach` samples coming in from free
/// space, `contact` samples in the contact band, and `leave` samples going away. Episode e
/// covers samples [e * total(), (e + 1) * total()); the last one may be cut short by n. For the
/// `contact` kind (approach_and_leave false) approach and leave are 0 and approach_distance too.
struct HapticLayout {
  std::size_t approach = 0, contact = 0, leave = 0;
  std::size_t total() const { return approach + contact + leave; }
  double units_per_metre = 1;  ///< mesh units per metre (bbox diagonal / model_size_m)
  double max_step = 0;         ///< largest allowed step between samples, mesh units
  double band = 0;             ///< contact band half-width, mesh units
  double approach_distance = 0;  ///< start distance from the surface, mesh units
};
/// `p`: the kind's resolved parameters (query_kind_params). Throws InputError (naming the kind
/// and the parameters) for speeds that exceed max_speed together.
HapticLayout haptic_layout(const TriangleSource& mesh, const Params& p, bool approach_and_leave = true);

}  // namespace bvhbench::query_kinds_detail
