// A mesh paged from a scratch copy reads as the loaded mesh does (summary, corners, mean edge
// length: the same doubles), and every query kind makes the same bytes from it, through caches
// and grid slabs small enough that pages come and go.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "harness/core/query_kinds_detail.hpp"
#include "harness/core/query_set.hpp"
#include "harness/core/rng.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/io/paged_triangles.hpp"
#include "harness/util/errors.hpp"
#include "support/test_support.hpp"

namespace bvhbench {
namespace {

namespace qd = query_kinds_detail;

/// A budget small enough that the vertex cache holds a few pages of the bunny's and the grid is
/// written in several slabs.
ScratchSpace tiny_scratch() { return {testing::TempDir(), 1 << 20}; }

bool same_bytes(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3d)) == 0;
}

// Every fixture, in every format: read as the loaded mesh (the same summary, corners and mean
// edge length, to the bit); a file load_mesh refuses is refused with the same message.
TEST(PagedTriangles, ReadsEveryFixtureAsTheLoadedMesh) {
  const auto [good, bad] = test::expect_reads_every_fixture_as_load_mesh(
      [](const std::string& path) { PagedTriangles paged(path, tiny_scratch()); },
      [](const std::string& path, const Mesh& m) {
        const PagedTriangles paged(path, tiny_scratch());
        const MeshSummary s = m.summary();
        EXPECT_EQ(paged.summary().path, s.path);
        EXPECT_EQ(paged.summary().sha256, s.sha256);
        EXPECT_EQ(paged.summary().triangles, s.triangles);
        EXPECT_EQ(paged.summary().vertices, s.vertices);
        EXPECT_EQ(paged.summary().bounds.lo, s.bounds.lo);
        EXPECT_EQ(paged.summary().bounds.hi, s.bounds.hi);
        EXPECT_EQ(paged.average_edge_length(), m.average_edge_length());
        const MeshTriangles loaded(m);
        for (std::uint32_t t = 0; t < m.num_triangles(); ++t) ASSERT_EQ(paged.corners(t), loaded.corners(t)) << t;
      });
  EXPECT_GT(good, 10);
  EXPECT_GT(bad, 30);
}

/// The bunny when the shared meshes are there (a real scan's order), else an octasphere written
/// as PLY.
std::string test_mesh_path() {
  const std::string bunny = std::string(BVHBENCH_SHARED_DIR) + "/meshes/stanford-bunny.obj";
  if (std::filesystem::exists(bunny)) return bunny;
  const std::string ply = testing::TempDir() + "/paged_octasphere.ply";
  write_ply(ply, test::octasphere(5));
  return ply;
}

TEST(PagedTriangles, TheGridPagesAndFindsWhatTheGridInMemoryFinds) {
  const std::string path = test_mesh_path();
  const Mesh m = load_mesh(path);
  const MeshTriangles loaded(m);
  const PagedTriangles paged(path, tiny_scratch());
  const double cell = m.average_edge_length();
  const qd::TriangleGrid in_memory(loaded, cell), on_disk(paged, cell);
  EXPECT_FALSE(in_memory.paged());
  ASSERT_TRUE(on_disk.paged());
  EXPECT_LT(on_disk.num_cells(), in_memory.num_cells());  // the budget caps the offsets
  EXPECT_EQ(in_memory.slabs(), 1u);
  EXPECT_GT(on_disk.slabs(), 1u);  // and the ids written at once
  Rng rng(4);
  const Box3d box = m.bounds();
  for (int i = 0; i < 300; ++i) {
    const Vec3d p(rng.uniform(box.lo.x, box.hi.x), rng.uniform(box.lo.y, box.hi.y), rng.uniform(box.lo.z, box.hi.z));
    qd::TriangleGrid::Hit a{}, b{};
    a.triangle = b.triangle = ~0u;
    const double r = box.diagonal();
    ASSERT_TRUE(in_memory.closest(p, r, &a));
    ASSERT_TRUE(on_disk.closest(p, r, &b));
    ASSERT_EQ(a.triangle, b.triangle) << i;
    ASSERT_EQ(a.point, b.point) << i;
  }
}

// Every kind, from the loaded mesh and from the paged copy: the same points and sidecar, bit for
// bit (the haptic kinds through the paged grid).
TEST(PagedTriangles, EveryKindMakesTheSameBytes) {
  const std::string path = test_mesh_path();
  const Mesh m = load_mesh(path);
  const PagedTriangles paged(path, tiny_scratch());
  for (const QueryKind& kind : query_kinds()) {
    SCOPED_TRACE(kind.name);
    const std::map<std::string, double> given =
        kind.ordered ? std::map<std::string, double>{{"contact_ms", 400}} : std::map<std::string, double>{};
    nlohmann::json meta_loaded, meta_paged;
    const auto a = generate_queries(m, kind.name, 1500, 7, given, &meta_loaded);
    const auto b = generate_queries(paged, kind.name, 1500, 7, given, &meta_paged);
    EXPECT_TRUE(same_bytes(a, b));
    EXPECT_EQ(meta_loaded, meta_paged);
  }
}

TEST(PagedTriangles, AnUnwritableScratchFolderIsNamed) {
  const std::string dir = testing::TempDir() + "/no/such/scratch";
  try {
    PagedTriangles paged(test_mesh_path(), ScratchSpace{dir, 1 << 20});
    ADD_FAILURE() << "paged into a folder that does not exist";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(dir), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace bvhbench
