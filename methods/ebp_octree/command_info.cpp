// `bvhbench ebp info`: the header, levels, counts and sizes of a store.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>

#include <nlohmann/json.hpp>

#include "methods/ebp_octree/build_option_params.hpp"
#include "methods/ebp_octree/commands.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/store_file.hpp"

namespace bvhbench {

void add_info_command(CLI::App& ebp_cmd) {
  struct Opts {
    std::string path;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = ebp_cmd.add_subcommand("info", "Print the header, levels, counts and sizes of a store (.ebp)");
  cmd->add_option("store", o->path, "Store (.ebp)")->required();
  cmd->add_flag("--json", o->json, "Machine-readable output");
  cmd->callback([o] {
    const ebp::StoreReader r(o->path);
    const ebp::FileHeader& h = r.header();
    std::uint64_t page_min = UINT64_MAX, page_max = 0, page_sum = 0;
    for (const ebp::PageEntry& e : r.directory()) {
      page_min = std::min<std::uint64_t>(page_min, e.size);
      page_max = std::max<std::uint64_t>(page_max, e.size);
      page_sum += e.size;
    }
    std::map<int, std::uint64_t> top_levels;
    for (const ebp::TopNode& t : r.top_nodes()) top_levels[ebp::octcode_level(t.code)]++;
    nlohmann::json info = nlohmann::json::parse(r.info_json(), nullptr, false);
    if (info.is_discarded()) info = nlohmann::json::object();
    nlohmann::json j;
    j["path"] = o->path;
    j["version"] = h.version;
    j["file_bytes"] = h.file_size;
    j["frame_origin"] = {h.origin[0], h.origin[1], h.origin[2]};
    j["root"] = {{"lo", {h.root_lo[0], h.root_lo[1], h.root_lo[2]}}, {"size", h.root_size}};
    j["leaf_level"] = h.leaf_level;
    j["levels"] = h.leaf_level + 1;
    j["triangles"] = h.num_triangles;
    j["closed"] = (h.flags & ebp::kStoreClosed) != 0;
    const ebp::BuildParams built = ebp::header_build_params(h);
    j["params"] = build_option_json(built);
    j["nodes"] = {{"total", h.nodes}, {"grey_inner", h.inner}, {"grey_leaves", h.leaves},
                  {"white", h.white}, {"black", h.black}};
    j["triangle_refs"] = h.triangle_refs;
    j["planes"] = h.planes;
    j["top"] = {{"nodes", h.num_top_nodes}, {"children", h.num_top_children}, {"planes", h.num_top_planes},
                {"pinned_bytes", r.pinned_bytes()}};
    nlohmann::json per_level = nlohmann::json::object();
    for (auto& [l, n] : top_levels) per_level[std::to_string(l)] = n;
    j["top"]["nodes_per_level"] = per_level;
    j["pages"] = {{"count", h.num_pages}, {"target_bytes", h.page_target}, {"min_bytes", page_min},
                  {"max_bytes", page_max}, {"mean_bytes", double(page_sum) / double(h.num_pages)},
                  {"total_bytes", page_sum}};
    auto sec = [](const ebp::Section& s) { return nlohmann::json{{"offset", s.offset}, {"size", s.size}}; };
    j["sections"] = {{"top_nodes", sec(h.top_nodes)}, {"top_children", sec(h.top_children)},
                     {"top_planes", sec(h.top_planes)}, {"info", sec(h.info)},
                     {"pages", sec(h.pages)}, {"directory", sec(h.directory)}};
    j["build"] = info;
    if (o->json) {
      std::cout << j.dump(2) << "\n";
      return;
    }
    std::printf("EBP-Octree store %s (version %u, %.1f MiB)\n", o->path.c_str(), h.version, double(h.file_size) / 1048576.0);
    std::printf("  mesh              %s (%u triangles, %s)\n", info.value("mesh", std::string("?")).c_str(), h.num_triangles,
                (h.flags & ebp::kStoreClosed) ? "closed" : "not known to be closed");
    std::printf("  frame origin      (%.17g, %.17g, %.17g)\n", h.origin[0], h.origin[1], h.origin[2]);
    std::printf("  root cube         lo (%.9g, %.9g, %.9g) in the frame, size %.9g\n", h.root_lo[0], h.root_lo[1], h.root_lo[2], h.root_size);
    std::printf("  levels            %u (leaf level %u)\n", h.leaf_level + 1, h.leaf_level);
    std::printf("  parameters       ");
    for (const ebp::BuildOption& opt : ebp::kBuildOptions) std::printf(" %s=%g", opt.name, opt.get(built));
    std::printf("\n");
    std::printf("  nodes             %lu: %lu grey inner, %lu grey leaves, %lu white, %lu black\n",
                (unsigned long)h.nodes, (unsigned long)h.inner, (unsigned long)h.leaves, (unsigned long)h.white,
                (unsigned long)h.black);
    if (info.contains("nodes_per_level")) std::printf("  nodes per level   %s\n", info["nodes_per_level"].dump().c_str());
    std::printf("  triangle refs     %lu; planes %lu\n", (unsigned long)h.triangle_refs, (unsigned long)h.planes);
    std::printf("  top (pinned)      %lu nodes, levels %s, %.1f KiB in memory\n", (unsigned long)h.num_top_nodes,
                per_level.dump().c_str(), double(r.pinned_bytes()) / 1024.0);
    std::printf("  pages             %lu (target %u B): min %lu, mean %.0f, max %lu bytes; %.1f MiB in all\n",
                (unsigned long)h.num_pages, h.page_target, (unsigned long)page_min, double(page_sum) / double(h.num_pages),
                (unsigned long)page_max, double(page_sum) / 1048576.0);
  });
}

}  // namespace bvhbench
