// `bvhbench ebp build`: the `.ebp` store of a mesh, by the external-memory build (the default)
// or in memory (--in-memory), written atomically; SIGINT/SIGTERM leave nothing behind.
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/process_memory.hpp"
#include "harness/util/progress.hpp"
#include "methods/ebp_octree/build/external_build.hpp"
#include "methods/ebp_octree/commands.hpp"
#include "methods/ebp_octree/ebp_method.hpp"
#include "methods/ebp_octree/store/format.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/writer.hpp"

namespace bvhbench {
namespace {

// Interrupt handling and temporary files
volatile std::sig_atomic_t g_signal = 0;
extern "C" void on_signal(int s) { g_signal = s; }

struct SignalGuard {
  struct sigaction old_int {}, old_term {};
  SignalGuard() {
    g_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);
  }
  ~SignalGuard() {
    sigaction(SIGINT, &old_int, nullptr);
    sigaction(SIGTERM, &old_term, nullptr);
  }
  static void check() {
    if (g_signal)
      throw std::runtime_error(std::string("interrupted by ") + (g_signal == SIGINT ? "SIGINT" : "SIGTERM") +
                               "; nothing written, temporary files removed");
  }
};

/// A private temporary directory, removed with everything in it on scope exit.
struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& parent) {
    std::string tmpl = (std::filesystem::path(parent) / "ebp-build-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) throw file_error(parent, "cannot create a temporary directory there");
    path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

/// The store's info section (`ebp info`, the method's mesh check), the same for both builds;
/// each adds what only it knows.
nlohmann::json store_info(const std::string& mesh_path, const std::string& sha256, const ebp::Stats& s,
                          const Params& p, int threads) {
  nlohmann::json info;
  info["mesh"] = mesh_path;
  info["mesh_sha256"] = sha256;
  info["triangles"] = s.triangles;
  info["params"] = p.values();
  info["threads"] = threads;
  info["leaf_level"] = s.leaf_level;
  info["leaf_size"] = s.leaf_size;
  info["average_edge"] = s.average_edge;
  info["nodes_per_level"] = s.nodes_per_level;
  info["leaf_configurations"] = {{"convex", s.convex}, {"concave", s.concave}, {"special", s.special}};
  info["max_refs_per_leaf"] = s.max_refs_per_leaf;
  info["build_seconds"] = s.build_seconds;
  return info;
}

/// What both builds report when the store is written: the JSON summary (--json) or its first line.
struct WriteSummary {
  std::string out;
  std::uint64_t triangles = 0, pages = 0, bytes = 0, peak_rss = 0;
  double build_s = 0, total_s = 0, budget = 0;
  int threads = 1;
  nlohmann::json json() const {
    return {{"out", out},
            {"triangles", triangles},
            {"pages", pages},
            {"bytes", bytes},
            {"build_seconds", build_s},
            {"total_seconds", total_s},
            {"triangles_per_second", double(triangles) / total_s},
            {"peak_rss_bytes", peak_rss},
            {"memory_budget_bytes", budget},
            {"within_budget", double(peak_rss) <= budget}};
  }
  void print_wrote() const {
    std::printf("wrote %s: %lu triangles, %lu pages, %.1f MiB in %.1f s (%.0f triangles/s, %d threads)\n",
                out.c_str(), (unsigned long)triangles, (unsigned long)pages, double(bytes) / 1048576.0, total_s,
                double(triangles) / total_s, threads);
  }
};

}  // namespace

void add_build_command(CLI::App& ebp_cmd) {
  struct Opts {
    std::string mesh, out, tmp;
    std::vector<std::string> params;
    double budget_mb = 0;
    int threads = 2;
    int page_kb = 16;
    bool json = false;
    bool in_memory = false;
    int fail_after_pages = -1;  // test hook
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = ebp_cmd.add_subcommand("build", "Build the EBP-Octree of a mesh into an on-disk store (.ebp)");
  cmd->add_option("--mesh", o->mesh, "Mesh (PLY, OBJ, STL or OFF)")->required();
  cmd->add_option("--out", o->out, "Output store (.ebp); appears only when complete")->required();
  cmd->add_option("--memory-budget", o->budget_mb, "Memory budget in MiB (see OUT_OF_CORE.md: what it bounds)")
      ->required()
      ->check(CLI::Range(1.0, 1e9));
  cmd->add_option("--tmp", o->tmp, "Directory for temporary files (default: beside --out)");
  cmd->add_option("--param", o->params, "Build parameter key=value (repeatable): leaf_factor, max_planes, cluster_angle");
  cmd->add_option("--threads", o->threads, "Build threads")->check(CLI::Range(1, 1024));
  cmd->add_option("--page-kb", o->page_kb, "Target page size in KiB (subtrees packed up to it)")->check(CLI::Range(4, 1 << 20));
  cmd->add_option("--fail-after-pages", o->fail_after_pages, "Testing: fail after writing N pages")->group("");
  cmd->add_flag("--json", o->json, "Machine-readable summary");
  cmd->add_flag("--in-memory", o->in_memory,
                "Load the mesh and build the tree in memory, then write it (the old path: peak RSS follows the model)");
  cmd->callback([o] {
    const auto t0 = std::chrono::steady_clock::now();
    SignalGuard signals;
    const Params p = resolve_build_args(parse_param_args(o->params));
    const ebp::BuildParams bp = build_params(p, o->threads);

    const std::filesystem::path out = std::filesystem::absolute(o->out);
    if (!std::filesystem::is_directory(out.parent_path()))
      throw file_error(o->out, "the output directory does not exist");
    TempDir tmp(o->tmp.empty() ? out.parent_path().string() : o->tmp);
    const double budget = o->budget_mb * 1048576.0;
    if (!o->in_memory) {
      // External-memory build (OUT_OF_CORE.md): the mesh is streamed, the (cell, triangle)
      // records are sorted in runs under tmp and merged, pages are written as subtrees complete.
      // Vertices that would take more than half the budget as float are paged from a temporary
      // file through a cache of an eighth of it (OUT_OF_CORE.md, "Vertices out of core").
      ebp::VertexPaging paging;
      paging.held_limit = std::size_t(budget / 2);
      paging.tmp_dir = tmp.path.string();
      paging.cache_bytes = std::size_t(budget / 8);
      std::unique_ptr<ebp::TriangleSource> src = ebp::open_mesh_source(o->mesh, paging);
      SignalGuard::check();
      ebp::ExtBuildOptions eo;
      eo.params = bp;
      eo.memory_budget = std::size_t(budget);
      eo.tmp_dir = tmp.path.string();
      eo.page_target = std::size_t(o->page_kb) * 1024;
      const std::string mesh_path = o->mesh;
      const bool streaming = src->streaming();
      eo.info_json = [&](const ebp::ExtBuildReport& r) {
        const ebp::Stats& s = r.stats;
        nlohmann::json info = store_info(mesh_path, src->sha256(), s, p, o->threads);
        info["build"] = {{"kind", "external"}, {"memory_budget_bytes", budget}, {"runs", r.runs},
                         {"spill_bytes", r.spill_bytes}, {"records", r.records}, {"streamed_mesh", streaming},
                         {"colour_fallbacks", s.colour_fallbacks}, {"degenerate_edges", s.degenerate_edges},
                         {"vertices_paged", src->vertex_page_reads().first > 0}};
        return info.dump();
      };
      Progress prog("building " + o->out + " (external)", 1.0, !o->json);
      eo.progress = [&](const char*, double f) { prog.update(f); };
      eo.check = [] { SignalGuard::check(); };
      const int fail_after = o->fail_after_pages;
      eo.before_page = [fail_after](std::uint32_t id) {
        if (fail_after >= 0 && id >= std::uint32_t(fail_after)) throw std::runtime_error("simulated failure (--fail-after-pages)");
      };
      ebp::ExtBuildReport rep;
      try {
        rep = ebp::build_store_external(*src, out.string(), eo);
      } catch (const std::invalid_argument& e) {
        throw file_error(o->mesh, std::string(e.what()) + "; nothing written (no " + o->out + ", temporary files removed)");
      } catch (const InputError&) {
        throw;
      } catch (const std::exception& e) {
        if (g_signal) throw;
        throw std::runtime_error(std::string(e.what()) + "; nothing written (no " + o->out + ", temporary files removed)");
      }
      prog.finish();
      const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const std::uint64_t peak = peak_rss_bytes();
      const WriteSummary sum{out.string(), rep.stats.triangles, rep.pages, rep.file_bytes, peak,
                             rep.seconds_total, total_s, budget, o->threads};
      nlohmann::json j = sum.json();
      j["runs"] = rep.runs;
      j["spill_bytes"] = rep.spill_bytes;
      j["records"] = rep.records;
      j["skeleton_bytes"] = rep.skeleton_bytes;
      j["min_budget_bytes"] = rep.min_budget_bytes;
      j["streamed_mesh"] = streaming;
      const auto [vertex_reads, vertex_misses] = src->vertex_page_reads();
      if (vertex_reads > 0)
        j["vertex_pages"] = {{"cache_bytes", paging.cache_bytes}, {"reads", vertex_reads}, {"misses", vertex_misses}};
      j["seconds"] = {{"frame", rep.seconds_frame}, {"distribute", rep.seconds_distribute},
                      {"merge_build", rep.seconds_merge_build}, {"colour", rep.seconds_colour}};
      if (o->json) {
        std::cout << j.dump(2) << "\n";
      } else {
        sum.print_wrote();
        std::printf("external build: %lu sorted run(s), %.1f MiB spilled; frame %.1f s, distribution %.1f s, "
                    "merge+build %.1f s, colouring %.1f s\n",
                    (unsigned long)rep.runs, double(rep.spill_bytes) / 1048576.0, rep.seconds_frame,
                    rep.seconds_distribute, rep.seconds_merge_build, rep.seconds_colour);
        if (vertex_reads > 0)
          std::printf("vertices paged from a temporary file (%.0f MiB as float) through a %.0f MiB cache: "
                      "%.2f%% of %lu vertex reads from the cache\n",
                      double(src->num_vertices()) * 12.0 / 1048576.0, double(paging.cache_bytes) / 1048576.0,
                      100.0 * double(vertex_reads - vertex_misses) / double(vertex_reads), (unsigned long)vertex_reads);
        std::printf("peak RSS %.0f MiB, memory budget %.0f MiB%s\n", double(peak) / 1048576.0, o->budget_mb,
                    double(peak) <= budget ? "" : " (EXCEEDED, see OUT_OF_CORE.md: what is bounded)");
        if (double(rep.min_budget_bytes) > budget)
          std::printf("note: this model needs a budget of at least %.0f MiB (mesh source %.0f MiB: float vertices or their cache, "
                      "read buffers, an STL's weld table; node skeleton and top tree, fixed reserve)\n",
                      double(rep.min_budget_bytes) / 1048576.0, double(src->resident_bytes()) / 1048576.0);
      }
      return;
    }

    Progress load("loading " + o->mesh, 1.0, !o->json);
    Mesh mesh = load_mesh(o->mesh);
    load.finish();
    SignalGuard::check();
    const std::size_t ntri = mesh.num_triangles();
    ebp::Octree tree;
    {
      Progress prog("building ebp_octree", 1.0, !o->json);
      try {
        tree = ebp::Octree::build(mesh.vertices, mesh.triangles, bp, [&](double f) {
          SignalGuard::check();
          prog.update(f);
        });
      } catch (const std::invalid_argument& e) {
        throw file_error(mesh.path, e.what());
      }
      prog.finish();
    }
    const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string sha = mesh.sha256, mesh_path = mesh.path;
    Mesh().vertices.swap(mesh.vertices);  // the store needs the tree only
    std::vector<std::array<std::uint32_t, 3>>().swap(mesh.triangles);
    SignalGuard::check();

    nlohmann::json info = store_info(mesh_path, sha, tree.stats, p, o->threads);
    info["tree_bytes"] = tree.bytes();

    ebp::StoreWriteOptions wo;
    wo.page_target = std::size_t(o->page_kb) * 1024;
    wo.params = bp;
    wo.info_json = info.dump();
    Progress wprog("writing " + o->out, 1.0, !o->json);
    wo.progress = [&](double f) { wprog.update(f); };
    const int fail_after = o->fail_after_pages;
    wo.before_page = [fail_after](std::uint32_t id) {
      SignalGuard::check();
      if (fail_after >= 0 && id >= std::uint32_t(fail_after)) throw std::runtime_error("simulated failure (--fail-after-pages)");
    };
    try {
      ebp::write_store_atomic(tree, out.string(), wo);
    } catch (const std::exception& e) {
      if (g_signal) throw;
      throw std::runtime_error(std::string(e.what()) + "; nothing written (no " + o->out + ", temporary files removed)");
    }
    wprog.finish();
    const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::uint64_t peak = peak_rss_bytes();
    const ebp::StoreReader check(out.string());
    const ebp::FileHeader& h = check.header();
    const WriteSummary sum{out.string(), ntri, h.num_pages, h.file_size, peak, build_s, total_s, budget, o->threads};
    if (o->json) {
      std::cout << sum.json().dump(2) << "\n";
    } else {
      sum.print_wrote();
      std::printf("peak RSS %.0f MiB, memory budget %.0f MiB%s\n", double(peak) / 1048576.0, o->budget_mb,
                  double(peak) <= budget ? "" : " (EXCEEDED: the tree is built in memory, see OUT_OF_CORE.md)");
    }
  });
}

}  // namespace bvhbench
