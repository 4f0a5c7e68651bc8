// The LeafTri face normal's octahedral code (core/face_normal.hpp): every unit normal encodes
// within kFaceNormalError of its direction, including the axes, the octahedron's edges and the
// fold of the lower hemisphere; the codes stay in the range the store accepts; and the face-plane
// value of a real tree has orient3d's sign wherever it exceeds the leaf's eps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "harness/io/mesh_io.hpp"
#include "methods/ebp_octree/core/face_normal.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/leaf_kernels.hpp"
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"

using namespace ebp_test;

namespace {

/// The code's error, checked against the encoder's own account of it and the bound; its halves
/// never -32768 (the store refuses those).
void expect_encodes(const Vec3d& n) {
  double err = -1;
  const std::uint32_t code = ebp::encode_face_normal(n / norm(n), &err);
  float v[3];
  ebp::decode_face_normal(code, v);
  const Vec3d w{double(v[0]), double(v[1]), double(v[2])};
  EXPECT_NEAR(norm(w / norm(w) - n / norm(n)), err, 1e-12) << n.x << " " << n.y << " " << n.z;
  EXPECT_LE(err, ebp::kFaceNormalError) << n.x << " " << n.y << " " << n.z;
  EXPECT_NE(code & 0xFFFFu, 0x8000u);
  EXPECT_NE(code >> 16, 0x8000u);
}

}  // namespace

TEST(EbpFaceNormal, EveryDirectionEncodesWithinTheBound) {
  for (int a = 0; a < 3; ++a)
    for (double s : {1.0, -1.0}) {
      Vec3d n{0, 0, 0};
      n[a] = s;
      expect_encodes(n);
    }
  for (double x : {-1.0, 1.0})
    for (double y : {-1.0, 1.0})
      for (double z : {-1.0, 0.0, 1e-12, -1e-12, 1.0}) expect_encodes({x, y, z});  // corners, edges, the fold
  std::mt19937_64 rng(7);
  std::normal_distribution<double> N(0, 1);
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    const Vec3d n{N(rng), N(rng), N(rng)};
    double err;
    ebp::encode_face_normal(n / norm(n), &err);
    worst = std::max(worst, err);
  }
  EXPECT_LE(worst, ebp::kFaceNormalError);
  EXPECT_GT(worst, 1e-6);  // a 16-bit grid: the bound is not vacuous
  std::printf("worst direction error over 200k random normals: %.3g rad\n", worst);
}

// Where the float face-plane value exceeds the leaf's eps, its sign is orient3d's: the filter's
// promise, on every triangle of the cow's leaves at points spread over each leaf's cell.
TEST(EbpFaceNormal, PlaneValuesOutsideEpsHaveTheExactSign) {
  const Octree t = build(bvhbench::load_mesh(shared_mesh("cow.obj")));
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-1, 1);
  const double half = 0.5 * t.cell_size(t.leaf_level);
  std::size_t decided = 0, undecided = 0;
  for (const Leaf& lf : t.leaves) {
    for (int i = 0; i < 8; ++i) {
      const Vec3d p{lf.centre[0] + U(rng) * half, lf.centre[1] + U(rng) * half, lf.centre[2] + U(rng) * half};
      const float pl[3] = {float(p.x - double(lf.centre[0])), float(p.y - double(lf.centre[1])),
                           float(p.z - double(lf.centre[2]))};
      for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
        const LeafTri& tr = t.tris[lf.tri_begin + k];
        if (tr.flags() & kDegenerate) continue;
        const float s = face_plane_value(tr, pl);
        if (!(std::fabs(s) > lf.eps)) { ++undecided; continue; }
        ++decided;
        ASSERT_EQ(s > 0 ? 1 : -1, orient3d(to_d(tr.a), to_d(tr.b), to_d(tr.c), p)) << "leaf " << (&lf - t.leaves.data());
      }
    }
  }
  EXPECT_GT(decided, 50000u);
  EXPECT_LT(undecided, decided / 100);  // the filter still decides nearly every side
}
