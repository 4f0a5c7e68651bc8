// The EBP-Octree's build options, declared once (kBuildOptions): the method's typed options, the
// store's header written and read, and what a job on a store records of the store's own build.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/util/errors.hpp"
#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/build_option_params.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/ebp_method.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/store_file.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "support/test_support.hpp"

namespace {

using bvhbench::ParamSpec;

TEST(EbpBuildOptions, TheMethodDeclaresEachOptionOfTheTableWithItsDefault) {
  const std::map<std::string, std::string> defaults = {{"leaf_factor", "5"}, {"max_planes", "8"}, {"cluster_angle", "30"}};
  std::map<std::string, std::string> declared;
  for (const ParamSpec& s : bvhbench::ebp_params())
    if (bvhbench::is_build_option(s.name)) {
      EXPECT_EQ(s.role, bvhbench::ParamRole::build) << s.name;
      declared[s.name] = s.default_value;
    }
  EXPECT_EQ(declared, defaults);
  EXPECT_EQ(bvhbench::build_option_names(), "leaf_factor, max_planes, cluster_angle");
  EXPECT_FALSE(bvhbench::is_build_option("store"));
  EXPECT_FALSE(bvhbench::is_build_option("threads"));
}

TEST(EbpBuildOptions, ResolvedOptionsBecomeTheBuildParams) {
  const bvhbench::Params p = bvhbench::resolve_build_args({{"leaf_factor", "2.5"}, {"max_planes", "3"}});
  const ebp::BuildParams bp = bvhbench::build_params(p, 4);
  EXPECT_EQ(bp.leaf_factor, 2.5);
  EXPECT_EQ(bp.max_planes, 3);
  EXPECT_EQ(bp.cluster_angle, 30.0);
  EXPECT_EQ(bp.threads, 4);
  EXPECT_THROW(bvhbench::resolve_build_args({{"store", "x.ebp"}}), bvhbench::InputError);
  EXPECT_THROW(bvhbench::resolve_build_args({{"coherent", "true"}}), bvhbench::InputError);
}

TEST(EbpBuildOptions, TheHeaderKeepsEachOptionInItsSlot) {
  ebp::BuildParams bp;
  bp.leaf_factor = 3.25;
  bp.max_planes = 6;
  bp.cluster_angle = 12.5;
  const ebp::FileHeader h = ebp::new_file_header({}, {}, 1.0, 3, 10, bp, 4096, false);
  // Where stores written before the table keep them: leaf_factor, cluster_angle, max_planes.
  EXPECT_EQ(h.build_reals[0], 3.25);
  EXPECT_EQ(h.build_reals[1], 12.5);
  EXPECT_EQ(h.build_ints[0], 6);
  const ebp::BuildParams back = ebp::header_build_params(h);
  EXPECT_EQ(back.leaf_factor, 3.25);
  EXPECT_EQ(back.max_planes, 6);
  EXPECT_EQ(back.cluster_angle, 12.5);
  const std::map<std::string, std::string> texts = {{"cluster_angle", "12.5"}, {"leaf_factor", "3.25"}, {"max_planes", "6"}};
  EXPECT_EQ(bvhbench::build_option_texts(back), texts);
  EXPECT_EQ(bvhbench::build_option_json(back).dump(), R"({"cluster_angle":12.5,"leaf_factor":3.25,"max_planes":6})");
}

/// A store of `m` built with leaf_factor 3 and max_planes 6, its info section `info`.
std::string write_store(const bvhbench::Mesh& m, const std::string& path, const std::string& info) {
  ebp::BuildParams bp;
  bp.leaf_factor = 3;
  bp.max_planes = 6;
  const ebp::Octree t = ebp::build_octree(m.vertices, m.triangles, bp);
  ebp::StoreWriteOptions o;
  o.params = bp;
  o.info_json = info;
  ebp::write_store_atomic(t, path, o);
  return path;
}

// A store job records what the store says of its build: its options, and the threads it was
// built on (null where an older store does not say), never the job's; and face_sign=false (its
// pages do not carry the face sides, so its signs come from the inside query).
TEST(EbpBuildOptions, AStoreJobRecordsTheStoresOwnBuild) {
  const bvhbench::test::TmpDir dir("ebp_build_options_test");
  const bvhbench::Mesh m = bvhbench::test::torus(40, 20);
  const bvhbench::Registry& reg = bvhbench::Registry::global();
  bvhbench::BuildContext ctx;
  ctx.threads = 2;
  const std::map<std::string, std::string> options = {
      {"cluster_angle", "30"}, {"leaf_factor", "3"}, {"max_planes", "6"}, {"face_sign", "false"}};

  auto with_threads = reg.create("ebp_octree:store=" + write_store(m, dir.file("new.ebp"), R"({"threads":3})"));
  with_threads->build(m, ctx);
  EXPECT_EQ(with_threads->build_options_read(), options);
  ASSERT_TRUE(with_threads->build_threads_read().has_value());
  EXPECT_EQ(*with_threads->build_threads_read(), nlohmann::json(3));

  auto old = reg.create("ebp_octree:store=" + write_store(m, dir.file("old.ebp"), R"({"mesh":"torus"})"));
  old->build(m, ctx);
  ASSERT_TRUE(old->build_threads_read().has_value());
  EXPECT_TRUE(old->build_threads_read()->is_null());

  auto in_memory = reg.create("ebp_octree:leaf_factor=3");
  in_memory->build(m, ctx);
  EXPECT_FALSE(in_memory->build_threads_read().has_value());
  EXPECT_TRUE(in_memory->build_options_read().empty());
}

}  // namespace
