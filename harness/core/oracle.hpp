#pragma once
/// The exact oracle behind `bvhbench truth`: reference answers every method is checked against.
///
/// Independent of the methods under test: its own BVH (double-precision queries over boxes
/// rounded outward to float), its own point-triangle distance, and exact orientation predicates
/// (CGAL's filtered exact predicates, used in oracle.cpp only).
///
/// Inside. The winding number w(p) is evaluated as
///     w(p) = (signed crossings of the ray p + t*(+x), t > 0, with the mesh)
///          + sum over the boundary edges u->v of the solid angle / 4 pi of the half-infinite
///            strip swept from the edge along -x,
/// which is an identity for any triangle mesh (the mesh plus the strips is a closed cycle, whose
/// winding number is the ray's crossing count). Crossings are decided with exact predicates and a
/// symbolic perturbation of p by (eps^3, eps, eps^2) (simulation of simplicity), so a ray through
/// an edge or a vertex, or a point on a face, is classified consistently. On a closed mesh (no
/// boundary edge) w(p) is thus the exact integer winding number; on an open mesh it is the
/// generalized winding number (Jacobson et al. 2013) with an exact integer part and a floating
/// point sum over the boundary edges only.
///   - `exact` definition (no boundary edge): inside iff w != 0;
///   - `winding_number` definition (open mesh): inside iff |w| > 1/2.
/// Both ignore the orientation of the surface: an inside-out closed mesh bounds the same solid.
/// That default `inside` is what a method that declares no definition is judged against.
///
/// Beside it, per point, what each definition of inside says (core/inside_definition.hpp): the
/// winding number w (judging winding_number, nonzero_winding and generalized_winding_number),
/// and the parity of the same perturbed ray's crossings, unsigned (judging ray_parity). Which of
/// them are defined depends on the mesh (`definitions()`): parity where every edge is used an even
/// number of times (then every ray has that parity), the integer winding number where the mesh is
/// closed and consistently oriented, the generalized winding number always.
///
/// Distance. The unsigned distance to the closest triangle, in double, with every triangle
/// within `tie_tolerance` of the minimum recorded as a tie (a shared edge or vertex, or a
/// symmetric configuration): the closest triangle is the lowest-indexed of them.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "harness/core/geometry.hpp"

namespace bvhbench {

struct Mesh;

/// Up to this many tied triangle indices are stored per query (`tied_triangles`, N x kMaxTied).
constexpr int kMaxTied = 8;

struct OracleNearest {
  double distance = 0;           ///< unsigned, to the closest triangle
  Vec3d closest;                 ///< closest point on it
  Vec3d normal;                  ///< its unit face normal (right-hand rule); 0 if degenerate
  std::int64_t triangle = -1;    ///< lowest index among the tied triangles
  std::int64_t tie_count = 0;    ///< triangles within the tie tolerance of the minimum (>= 1)
  std::array<std::int64_t, kMaxTied> tied;  ///< the first kMaxTied of them by index, -1 padded
};

/// The oracle's answers for a query set, query by query (shapes: N, or N x 3, N x kMaxTied).
struct OracleAnswers {
  std::string definition;                 ///< "exact" | "winding_number": the default `inside`'s
  std::vector<std::string> definitions;   ///< the definitions defined on this mesh (Oracle::definitions)
  std::vector<std::uint8_t> inside;
  std::vector<std::uint8_t> parity;       ///< odd count of the perturbed ray's crossings
  std::vector<double> winding, distance;
  std::vector<Vec3d> closest, normal;
  std::vector<std::int64_t> triangle, tie_count, tied;  ///< tied: N * kMaxTied, row-major
  double tie_tolerance = 0;
  std::size_t boundary_edges = 0;
  std::size_t odd_edges = 0, nonmanifold_edges = 0, solid_boundary_edges = 0;  ///< Oracle's edge counts
};

class Oracle {
 public:
  /// Builds the acceleration structure over `mesh` (which must outlive the oracle), in parallel
  /// with the current TBB thread budget. `tie_tolerance_rel` is relative to the bounding-box
  /// diagonal. `verbose` prints stage timings on stderr.
  explicit Oracle(const Mesh& mesh, double tie_tolerance_rel = 1e-12, bool verbose = false);
  Oracle(Mesh&&, double = 0, bool = false) = delete;  ///< the mesh must outlive the oracle
  ~Oracle();
  Oracle(const Oracle&) = delete;
  Oracle& operator=(const Oracle&) = delete;

  /// True when every undirected edge is used as often in each direction (a closed, consistently
  /// oriented surface, non-manifold allowed): the `exact` definition applies.
  bool closed() const { return boundary_.empty(); }
  std::size_t boundary_edge_count() const { return boundary_.size(); }
  /// The edge counts below leave zero-area triangles out (never crossed, no solid angle).
  /// Undirected edges used by an odd number of triangles: 0 when the mesh is closed (mod 2), so
  /// that every ray's crossing count has the same parity.
  std::size_t odd_edge_count() const { return odd_edges_; }
  /// Undirected edges used by more than two triangles.
  std::size_t nonmanifold_edge_count() const { return nonmanifold_edges_; }
  /// Boundary edges counted with their orientation (as boundary_edge_count()): 0 when the mesh
  /// is closed and consistently oriented, so that w is an integer wherever it is defined.
  std::size_t solid_boundary_edge_count() const { return solid_boundary_edges_; }
  /// The definitions of inside defined on this mesh (inside_definition.hpp's names): ray_parity
  /// when odd_edge_count() is 0, winding_number and nonzero_winding when
  /// solid_boundary_edge_count() is 0, and generalized_winding_number always.
  std::vector<std::string> definitions() const;
  double diagonal() const { return diagonal_; }
  double tie_tolerance() const { return tie_tol_; }

  /// Winding number at p (exact integer when closed()).
  double winding(const Vec3d& p) const;
  /// Inside by the definition in force (see the file comment).
  bool inside_from_winding(double w) const;
  /// Signed crossing count of the ray p + t*(+x), t > 0 (exact, symbolically perturbed).
  long crossings(const Vec3d& p) const { return ray_crossings(p).net; }
  struct RayCrossings {
    long net = 0;      ///< signed: +1 leaving through a front face, -1 through a back face
    bool odd = false;  ///< the parity of the crossings, whatever their sign
  };
  /// The crossings of that ray, signed and counted mod 2, in one traversal.
  RayCrossings ray_crossings(const Vec3d& p) const;
  OracleNearest nearest(const Vec3d& p) const;

  /// All answers for these points, in parallel over the current TBB thread budget.
  OracleAnswers answer(const std::vector<Vec3d>& points) const;

  /// BVH node: bounds rounded outward to float; a leaf when count > 0 (triangles
  /// prims_[index .. index+count)), else children at this+1 and nodes_[index].
  struct Node {
    float lo[3];
    std::uint32_t index;
    float hi[3];
    std::uint32_t count;
  };
  static_assert(sizeof(Node) == 32, "two nodes per cache line");

 private:
  void build_bvh(bool verbose);
  void find_boundary();
  /// w(p) from the ray's net crossing count: that count plus the boundary edges' strips.
  double winding_from(const Vec3d& p, long net_crossings) const;

  const Mesh& mesh_;
  double diagonal_ = 0, tie_tol_ = 0;
  std::size_t odd_edges_ = 0, nonmanifold_edges_ = 0, solid_boundary_edges_ = 0;
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> prims_;
  std::vector<std::array<Vec3d, 2>> boundary_;  ///< boundary edges u->v, with multiplicity
};

/// True if a, b and c lie on one line (two or three of them coinciding included), decided
/// exactly with the oracle's predicates: a triangle of zero area.
bool collinear_exact(const Vec3d& a, const Vec3d& b, const Vec3d& c);

}  // namespace bvhbench
