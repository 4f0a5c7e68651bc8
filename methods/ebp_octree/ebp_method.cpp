// The ebp_octree method: the in-memory harness adapter over the EBP-Octree core (core/query.hpp),
// its parameters, and its registration, which attaches the out-of-core variant (ooc_method.hpp)
// and the `bvhbench ebp` commands (commands.hpp).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "methods/ebp_octree/ebp_method.hpp"

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/core/shared_structure_method.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/progress.hpp"
#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/build_option_params.hpp"
#include "methods/ebp_octree/commands.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/ebp_adapter.hpp"
#include "methods/ebp_octree/ooc_method.hpp"

namespace bvhbench {

std::vector<ParamSpec> ebp_params() {
  std::vector<ParamSpec> specs = build_option_specs();
  const std::vector<ParamSpec> query = {
      {"coherent", ParamType::boolean, ParamRole::query, "false",
       "path coherence: seed distance with the previous closest triangle, reuse the previous leaf", {}},
      {"certificate", ParamType::boolean, ParamRole::query, "true",
       "coherent distance: answer from a certificate (the triangles near the last renewal) while the probe "
       "stays in its ball; same answers", {}},
      {"certificate_policy", ParamType::choice, ParamRole::query, "auto",
       "coherent distance with certificate: auto = certificates where their work per query (from the counters) "
       "is below a plain search's, plain streaks elsewhere; always = a certificate at every renewal; same answers",
       {"auto", "always"}},
      {"chained_sign", ParamType::boolean, ParamRole::query, "true",
       "coherent distance on closed meshes: the previous query's sign when the step is shorter than the "
       "two queries' distances together (no inside test); same answers", {}},
      {"face_sign", ParamType::boolean, ParamRole::query, "true",
       "distance on closed meshes, in memory: the sign from the closest face where it decides it exactly (the "
       "one nearest triangle, clean, front outside; no inside test); same answers. A store's pages do not carry "
       "the face sides: a store job records false", {}},
  };
  specs.insert(specs.end(), query.begin(), query.end());
  const std::vector<ParamSpec> ooc = ooc_params();
  specs.insert(specs.end(), ooc.begin(), ooc.end());
  return specs;
}

Params resolve_build_args(const std::map<std::string, std::string>& given) {
  const std::vector<ParamSpec> specs = ebp_params();
  for (const ParamSpec& s : specs)
    if (!is_build_option(s.name) && given.count(s.name))
      throw InputError("--param " + s.name + ": not a build option (build options: " + build_option_names() + ")");
  return Params::resolve("ebp_octree", specs, given);
}

ebp::Octree build_tree(const Mesh& mesh, const ebp::BuildParams& bp, Progress* external) {
  std::unique_ptr<Progress> own;
  Progress* prog = external;
  if (!prog) {
    own = std::make_unique<Progress>("building ebp_octree", 1.0, mesh.num_triangles() > 200000);
    prog = own.get();
  }
  try {
    ebp::Octree t = ebp::build_octree(mesh.vertices, mesh.triangles, bp, [&](double f) { prog->update(f); });
    if (own) own->finish();
    return t;
  } catch (const std::invalid_argument& e) {
    // A mesh made in memory has no path: then the message is the method's alone.
    throw InputError(mesh.path.empty() ? std::string(e.what()) : mesh.path + ": " + e.what());
  }
}

nlohmann::json stats_json(const ebp::Octree& t) {
  const ebp::Stats& s = t.stats;
  const std::size_t grey = s.inner + s.leaves;
  nlohmann::json j;
  j["frame_origin"] = {t.origin.x, t.origin.y, t.origin.z};
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
  // Where the bytes go, part by part (DESIGN.md, "Bytes per triangle"): capacities, as bytes() counts.
  {
    const double nt = s.triangles ? double(s.triangles) : 1.0;
    nlohmann::json parts = nlohmann::json::object();
    auto part = [&](const char* name, std::size_t bytes, std::size_t count) {
      parts[name] = {{"bytes", bytes}, {"count", count}, {"per_triangle", double(bytes) / nt}};
    };
    part("leaf_triangles", t.tris.capacity() * sizeof(ebp::LeafTri), t.tris.size());
    part("nodes", t.nodes.capacity() * sizeof(ebp::Node), t.nodes.size());
    part("children", t.children.capacity() * sizeof(std::uint32_t), t.children.size());
    part("planes", t.planes.capacity() * sizeof(ebp::Plane), t.planes.size());
    part("leaves", t.leaves.capacity() * sizeof(ebp::Leaf), t.leaves.size());
    part("block_boxes", t.blocks.capacity() * sizeof(ebp::BlockBox), t.blocks.size());
    part("leaf_block_index", t.leaf_block.capacity() * sizeof(std::uint32_t), t.leaf_block.size());
    part("group_boxes", t.groups.capacity() * sizeof(ebp::BlockBox) + t.leaf_group.capacity() * sizeof(std::uint32_t),
         t.groups.size());
    part("node_boxes", t.node_box.capacity() * sizeof(ebp::BlockBox), t.node_box.size());
    part("sub_references", t.sub_refs.capacity() * sizeof(ebp::SubRef), t.sub_refs.size());
    part("sub_reference_sides", t.sub_sides.capacity(), t.sub_sides.size());
    part("face_sides", t.front_outside.capacity() * sizeof(std::uint64_t), t.front_outside.size());
    j["bytes_breakdown"] = parts;
  }
  j["bytes"] = t.bytes() + t.derived_bytes();
  j["derived_bytes"] = t.derived_bytes();  // boxes and sub-references, computed at build/load
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
                                  {"colour", s.seconds_colour},
                                  {"derived", s.seconds_derived},
                                  {"face_sides", s.seconds_face_sides}};
  j["front_outside_faces"] = s.front_outside_faces;
  return j;
}

namespace {

/// One thread's queries: an ebp::Query (its stamps, path state and counters) over the shared tree.
class EbpQueries final : public QueryState {
 public:
  EbpQueries(const ebp::Octree& tree, bool coherent, bool certificate, bool adaptive, bool chained_sign, bool face_sign)
      : tree_(tree), query_(tree, coherent) {
    query_.set_certificate(certificate);
    query_.set_adaptive_certificate(adaptive);
    query_.set_chained_sign(chained_sign);
    query_.set_face_sign(face_sign);
  }
  // The query point into the tree's frame once, in double; the closest point back (octree.hpp).
  bool inside(const Vec3d& p) override { return query_.inside(tree_.to_frame(p)); }
  DistanceResult distance(const Vec3d& p) override {
    DistanceResult r = to_distance_result(query_.distance(tree_.to_frame(p)));
    r.closest = tree_.to_world(r.closest);
    return r;
  }
  void reset_path() override { query_.reset_path(); }
  std::vector<Counter> counters() const override { return ebp_counters(query_.counters); }
  void reset_counters() override { query_.counters = {}; }

 private:
  const ebp::Octree& tree_;
  ebp::Query query_;
};

class EbpOctreeMethod final : public SharedStructureMethod<EbpQueries> {
 public:
  explicit EbpOctreeMethod(const Params& p) : params_(p), coherent_(p.get_bool("coherent")) {}

  void build(const Mesh& mesh, const BuildContext& ctx) override {
    tree_ = build_tree(mesh, build_params(params_, ctx.threads), ctx.progress);
    start_queries();
  }
  /// The tree stays; the next queries ask as `params` say (coherent, certificates, chained
  /// sign), from a fresh state. Its build options are the tree's own (build_groups.hpp).
  void set_query_options(const Params& params) override {
    params_ = params;
    coherent_ = params.get_bool("coherent");
    start_queries();
  }
  /// The tree and one query's stamps (every further thread's query state holds as many again).
  std::size_t structure_bytes() const override {
    return tree_.bytes() + tree_.derived_bytes() +
           (own_state() ? (std::size_t(tree_.num_triangles) + tree_.leaves.size()) * sizeof(std::uint32_t) : 0);
  }
  nlohmann::json info() const override { return stats_json(tree_); }

 private:
  std::unique_ptr<EbpQueries> make_state() const override {
    return std::make_unique<EbpQueries>(tree_, coherent_, params_.get_bool("certificate"),
                                        params_.get("certificate_policy") == "auto",
                                        params_.get_bool("chained_sign"), params_.get_bool("face_sign"));
  }
  Params params_;
  bool coherent_;
  ebp::Octree tree_;
};

}  // namespace
}  // namespace bvhbench

void bvhbench_register_ebp_octree(bvhbench::Registry& r) {
  using namespace bvhbench;
  MethodInfo m = MethodInfo::named("ebp_octree",
                                   "EBP-Octree (Aguilera, Melero, Feito 2016): octree with face-parallel bounding planes; exact inside by "
                                   "winding-number crossings, branch-and-bound distance");
  // Capabilities, said once here (false unless set).
  m.caps.inside = true;
  m.caps.distance = true;
  m.caps.closest_triangle = true;
  m.caps.coherence = true;
  m.caps.out_of_core = true;
  // In memory one ebp::Query per thread over the const tree; out of core one page cache per thread
  // over the shared store reader (ooc_method.cpp says why).
  m.caps.concurrent_queries = true;
  // In memory the query options (coherent, certificates, chained sign) are read by the queries
  // alone; a store's jobs run each alone (sharing, below), so they are never asked to.
  m.caps.query_options_after_build = true;
  m.caps.build_threads = BuildThreads::job;  // builds on the job's threads (TBB or the device's)
  m.machine_dependent_counters = {};  // none: our own traversal, compiled with the build's flags
  m.params = ebp_params();
  // The integer winding number by signed crossings from a reference point, inside iff w >= 1
  // (DESIGN.md, "Inside"): built for closed, consistently oriented meshes.
  m.inside = {{{}, {InsideRule::winding_number, false, 0.5, InputContract::closed_oriented}, ""}};
  m.check = check_ooc_options;
  // Swept by `methods: all`: the defaults and the coherent variant (which only a path tells
  // apart). No store: a suite has none to give.
  m.sweep = {"", "coherent=true"};
  // Out of core, the page cache a job's passes fill would be the next job's warm start: a store
  // is opened for each job (cheap). In memory the tree serves every job.
  m.sharing = [](const Params& p) {
    return p.get("store").empty() ? StructureSharing::every_job : StructureSharing::job_alone;
  };
  m.create = [](const Params& p) -> std::unique_ptr<Method> {
    if (is_out_of_core(p)) return make_ebp_ooc_method(p);
    return std::make_unique<EbpOctreeMethod>(p);
  };
  r.add(std::move(m));
  r.add_command({"ebp", add_ebp_commands});
}
