// The ebp_octree method: the harness adapter over the EBP-Octree core (ebp_octree.hpp), its
// registration, and the `bvhbench ebp ...` command group (`stats` now; the out-of-core store
// adds `build`, `info` and `verify` under the same group).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "methods/ebp_octree/ebp_adapter.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/progress.hpp"

namespace bvhbench {
std::unique_ptr<Method> make_ebp_ooc_method(const Params& p);  // ebp_cli.cpp
void add_ebp_store_commands(CLI::App& ebp_cmd);             // ebp_cli.cpp
namespace {

std::vector<ParamSpec> ebp_params() {
  return {
      {"leaf_factor", ParamType::real, "5",
       "leaf cell size >= leaf_factor x average edge length (the paper: 5)", {}, 0.05, 1e6},
      {"max_planes", ParamType::integer, "8", "bounding planes per node, at most", {}, 0, 64},
      {"cluster_angle", ParamType::real, "30",
       "degrees: face normals closer than this share one bounding plane", {}, 0.5, 90},
      {"coherent", ParamType::boolean, "false",
       "path coherence: seed distance with the previous closest triangle, reuse the previous leaf", {}},
      // out of core (ebp_cli.cpp, OUT_OF_CORE.md): answer from a store built by `bvhbench ebp build`
      {"store", ParamType::text, "", "out of core: answer from this .ebp store through a page cache", {}},
      {"cache_mb", ParamType::integer, "256", "out of core: page cache budget in MiB", {}, 1, 1 << 20},
      {"cold", ParamType::boolean, "false", "out of core: evict the file from the OS cache and empty the page cache before each pass", {}},
  };
}

ebp::BuildParams build_params(const Params& p, int threads) {
  ebp::BuildParams bp;
  bp.leaf_factor = p.get_real("leaf_factor");
  bp.max_planes = int(p.get_int("max_planes"));
  bp.cluster_angle = p.get_real("cluster_angle");
  bp.threads = threads;
  return bp;
}

ebp::Octree build_tree(const Mesh& mesh, const ebp::BuildParams& bp, Progress* external) {
  std::unique_ptr<Progress> own;
  Progress* prog = external;
  if (!prog) {
    own = std::make_unique<Progress>("building ebp_octree", 1.0, mesh.num_triangles() > 200000);
    prog = own.get();
  }
  try {
    ebp::Octree t = ebp::Octree::build(mesh.vertices, mesh.triangles, bp, [&](double f) { prog->update(f); });
    if (own) own->finish();
    return t;
  } catch (const std::invalid_argument& e) {
    throw InputError(mesh.path + ": " + e.what());
  }
}

nlohmann::json stats_json(const ebp::Octree& t) {
  const ebp::Stats& s = t.stats;
  const std::size_t grey = s.inner + s.leaves;
  nlohmann::json j;
  j["leaf_level"] = s.leaf_level;
  j["levels"] = s.leaf_level + 1;
  j["root_size"] = s.root_size;
  j["leaf_size"] = s.leaf_size;
  j["average_edge"] = s.average_edge;
  j["triangles"] = s.triangles;
  j["nodes"] = {{"total", s.nodes},   {"grey_inner", s.inner}, {"grey_leaves", s.leaves},
                {"white", s.white},   {"black", s.black},      {"per_level", s.nodes_per_level}};
  j["leaf_configurations"] = {{"convex", s.convex}, {"concave", s.concave}, {"special", s.special}};
  j["planes"] = {{"total", s.planes},
                 {"per_grey_node_mean", grey ? double(s.planes) / double(grey) : 0.0},
                 {"per_leaf_mean", s.leaves ? double(s.leaf_planes) / double(s.leaves) : 0.0},
                 {"per_inner_mean", s.inner ? double(s.inner_planes) / double(s.inner) : 0.0},
                 {"max_per_node", s.max_planes_per_node}};
  j["triangle_refs"] = {{"total", s.triangle_refs},
                        {"per_triangle", s.triangles ? double(s.triangle_refs) / double(s.triangles) : 0.0},
                        {"per_leaf_mean", s.leaves ? double(s.triangle_refs) / double(s.leaves) : 0.0},
                        {"per_leaf_max", s.max_refs_per_leaf}};
  j["bytes"] = t.bytes() + t.derived_bytes();
  j["derived_bytes"] = t.derived_bytes();  // leaf-block and node boxes, computed at build/load
  j["bytes_per_triangle"] = s.triangles ? double(t.bytes() + t.derived_bytes()) / double(s.triangles) : 0.0;
  j["tightness"] = {
      {"method", "exact: volume of the convex polytope cell box ∩ bounding planes, over the box volume"},
      {"leaves", s.leaf_box_volume > 0 ? s.leaf_volume / s.leaf_box_volume : 0.0},
      {"inner", s.inner_box_volume > 0 ? s.inner_volume / s.inner_box_volume : 0.0}};
  j["colouring"] = {{"winding_fallbacks", s.colour_fallbacks},
                    {"degenerate_edges", s.degenerate_edges},
                    {"leaves_without_reference", s.invalid_refs}};
  j["build_seconds"] = s.build_seconds;
  j["build_breakdown_seconds"] = {{"distribute", s.seconds_distribute},
                                  {"leaves", s.seconds_leaves},
                                  {"inner", s.seconds_inner},
                                  {"colour", s.seconds_colour}};
  return j;
}

class EbpOctreeMethod final : public Method {
 public:
  explicit EbpOctreeMethod(const Params& p) : params_(p), coherent_(p.get_bool("coherent")) {}

  void build(const Mesh& mesh, const BuildContext& ctx) override {
    tree_ = build_tree(mesh, build_params(params_, ctx.threads), ctx.progress);
    query_.emplace(tree_, coherent_);
  }
  bool supports(QueryType) const override { return true; }
  bool inside(const Vec3d& p) override { return query_->inside(p); }
  DistanceResult distance(const Vec3d& p) override { return to_distance_result(query_->distance(p)); }
  void reset_path() override {
    if (query_) query_->reset_path();
  }
  std::size_t structure_bytes() const override {
    return tree_.bytes() + tree_.derived_bytes() +
           (query_ ? (std::size_t(tree_.num_triangles) + tree_.leaves.size()) * sizeof(std::uint32_t) : 0);
  }
  std::vector<Counter> counters() const override {
    if (!query_) return {};
    const ebp::QueryCounters& c = query_->counters;
    return {{"nodes_visited", c.nodes_visited}, {"planes_tested", c.planes_tested},
            {"triangles_tested", c.triangles_tested}, {"hit_white", c.hit_white},
            {"hit_black", c.hit_black}, {"hit_convex", c.hit_convex},
            {"hit_concave", c.hit_concave}, {"hit_special", c.hit_special},
            {"exact_fallbacks", c.exact_fallbacks}};
  }
  void reset_counters() override {
    if (query_) query_->counters = {};
  }
  nlohmann::json info() const override { return stats_json(tree_); }

 private:
  Params params_;
  bool coherent_;
  ebp::Octree tree_;
  std::optional<ebp::Query> query_;
};

void add_stats_command(CLI::App& ebp_cmd) {
  struct Opts {
    std::string mesh;
    std::vector<std::string> params;
    bool json = false;
    int threads = 1;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = ebp_cmd.add_subcommand("stats", "Build the EBP-Octree on a mesh and print its figures");
  cmd->add_option("--mesh", o->mesh, "Mesh (PLY, OBJ, STL or OFF)")->required();
  cmd->add_option("--param", o->params, "Build parameter key=value (repeatable): leaf_factor, max_planes, cluster_angle");
  cmd->add_option("--threads", o->threads, "Build threads")->check(CLI::Range(1, 1024));
  cmd->add_flag("--json", o->json, "Machine-readable output");
  cmd->callback([o] {
    std::map<std::string, std::string> given;
    for (const std::string& kv : o->params) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos || eq == 0) throw InputError("--param " + kv + ": expected key=value");
      if (given.count(kv.substr(0, eq))) throw InputError("--param " + kv.substr(0, eq) + " given twice");
      given[kv.substr(0, eq)] = kv.substr(eq + 1);
    }
    const Params p = Params::resolve("ebp_octree", ebp_params(), given);
    Progress load("loading " + o->mesh, 1.0, !o->json);
    const Mesh mesh = load_mesh(o->mesh);
    load.finish();
    const ebp::Octree t = build_tree(mesh, build_params(p, o->threads), nullptr);
    nlohmann::json j = stats_json(t);
    j["mesh"] = {{"path", mesh.path}, {"sha256", mesh.sha256}, {"triangles", mesh.num_triangles()}};
    j["params"] = p.values();
    j["threads"] = o->threads;
    if (o->json) {
      std::cout << j.dump(2) << "\n";
      return;
    }
    const ebp::Stats& s = t.stats;
    std::printf("EBP-Octree of %s (%zu triangles)\n", mesh.path.c_str(), mesh.num_triangles());
    std::printf("  parameters        %s\n", p.non_default_string().empty() ? "defaults" : p.non_default_string().c_str());
    std::printf("  levels            %d (leaf level %d; leaf cell %.6g = %.2f x average edge %.6g)\n", s.leaf_level + 1,
                s.leaf_level, s.leaf_size, s.leaf_size / s.average_edge, s.average_edge);
    std::printf("  nodes             %zu: %zu grey inner, %zu grey leaves, %zu white, %zu black\n", s.nodes, s.inner,
                s.leaves, s.white, s.black);
    std::printf("  nodes per level  ");
    for (std::size_t n : s.nodes_per_level) std::printf(" %zu", n);
    std::printf("\n  leaf configs      %zu convex, %zu concave, %zu special\n", s.convex, s.concave, s.special);
    std::printf("  planes            %zu; mean %.2f per grey node (%.2f leaf, %.2f inner), max %zu\n", s.planes,
                j["planes"]["per_grey_node_mean"].get<double>(), j["planes"]["per_leaf_mean"].get<double>(),
                j["planes"]["per_inner_mean"].get<double>(), s.max_planes_per_node);
    std::printf("  triangle refs     %zu (%.2f per triangle; %.1f per leaf, max %zu)\n", s.triangle_refs,
                j["triangle_refs"]["per_triangle"].get<double>(), j["triangle_refs"]["per_leaf_mean"].get<double>(),
                s.max_refs_per_leaf);
    std::printf("  memory            %zu bytes, %.1f bytes per triangle (%zu of derived boxes)\n", t.bytes() + t.derived_bytes(),
                j["bytes_per_triangle"].get<double>(), t.derived_bytes());
    std::printf("  tightness         bounding volume / cell box: %.3f leaves, %.3f inner nodes (exact polytope volumes)\n",
                j["tightness"]["leaves"].get<double>(), j["tightness"]["inner"].get<double>());
    std::printf("  colouring         %zu winding fallbacks, %zu degenerate edges, %zu leaves without reference\n",
                s.colour_fallbacks, s.degenerate_edges, s.invalid_refs);
    std::printf("  build             %.3f s (distribute %.3f, leaves %.3f, inner %.3f, colour %.3f), %d thread(s)\n",
                s.build_seconds, s.seconds_distribute, s.seconds_leaves, s.seconds_inner, s.seconds_colour, o->threads);
  });
}

}  // namespace
}  // namespace bvhbench

void bvhbench_register_ebp_octree(bvhbench::Registry& r) {
  using namespace bvhbench;
  MethodInfo m;
  m.name = "ebp_octree";
  m.description =
      "EBP-Octree (Aguilera, Melero, Feito 2016): octree with face-parallel bounding planes; exact inside by "
      "winding-number crossings, branch-and-bound distance";
  m.caps = {/*inside*/ true, /*distance*/ true, /*closest_triangle*/ true, /*coherence*/ true, /*out_of_core*/ true};
  m.machine_dependent_counters = {};  // none: our own traversal, compiled with the build's flags
  m.params = ebp_params();
  m.create = [](const Params& p) -> std::unique_ptr<Method> {
    if (!p.get("store").empty()) return make_ebp_ooc_method(p);  // out of core: ebp_cli.cpp
    return std::make_unique<EbpOctreeMethod>(p);
  };
  r.add(std::move(m));
  // `bvhbench ebp <sub>`: one command group; later issues add subcommands in add_*_command.
  r.add_command({"ebp", [](CLI::App& app) {
                   auto* ebp_cmd = app.add_subcommand("ebp", "EBP-Octree tools (stats; build/info/verify for the on-disk store)");
                   ebp_cmd->require_subcommand(1);
                   add_stats_command(*ebp_cmd);
                   add_ebp_store_commands(*ebp_cmd);  // build, info, verify: ebp_cli.cpp
                 }});
}
