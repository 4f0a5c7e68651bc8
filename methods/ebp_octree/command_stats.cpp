// `bvhbench ebp stats`: builds the EBP-Octree of a mesh in memory and prints its figures.
#include <cstdio>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "harness/core/mesh.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/util/progress.hpp"
#include "methods/ebp_octree/build_option_params.hpp"
#include "methods/ebp_octree/commands.hpp"
#include "methods/ebp_octree/ebp_method.hpp"

namespace bvhbench {

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
  cmd->add_option("--param", o->params, "Build parameter key=value (repeatable): " + build_option_names());
  cmd->add_option("--threads", o->threads, "Build threads")->check(CLI::Range(1, 1024));
  cmd->add_flag("--json", o->json, "Machine-readable output");
  cmd->callback([o] {
    const Params p = resolve_build_args(parse_param_args(o->params));
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
    std::printf("  bytes / triangle ");
    for (auto& [name, part] : j["bytes_breakdown"].items()) std::printf(" %s %.1f", name.c_str(), part["per_triangle"].get<double>());
    std::printf("\n");
    std::printf("  tightness         bounding volume / cell box: %.3f leaves, %.3f inner nodes (exact polytope volumes)\n",
                j["tightness"]["leaves"].get<double>(), j["tightness"]["inner"].get<double>());
    std::printf("  colouring         %zu winding fallbacks, %zu degenerate edges, %zu leaves without reference\n",
                s.colour_fallbacks, s.degenerate_edges, s.invalid_refs);
    std::printf("  face sides        %zu of %zu faces: front outside, back inside (the distance's sign from them)\n",
                s.front_outside_faces, s.triangles);
    std::printf("  build             %.3f s (distribute %.3f, leaves %.3f, inner %.3f, colour %.3f, derived %.3f of "
                "which face sides %.3f), %d thread(s)\n",
                s.build_seconds, s.seconds_distribute, s.seconds_leaves, s.seconds_inner, s.seconds_colour,
                s.seconds_derived, s.seconds_face_sides, o->threads);
  });
}

}  // namespace bvhbench
