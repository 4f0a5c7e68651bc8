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
#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/build_option_params.hpp"
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
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
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

/// The options of `ebp build`.
struct BuildOpts {
  std::string mesh, out, tmp;
  std::vector<std::string> params;
  double budget_mb = 0;
  int threads = 2;
  int page_kb = 16;
  bool json = false;
  bool in_memory = false;
  int fail_after_pages = -1;  // test hook
};

/// What both builds start from: the resolved options, the output path, the temporary directory
/// and the memory budget, and the time the command started.
struct BuildJob {
  const BuildOpts& o;
  Params params;
  ebp::BuildParams bp;
  std::filesystem::path out;
  TempDir tmp;
  double budget = 0;
  std::chrono::steady_clock::time_point t0;
  double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); }
  /// The test hook --fail-after-pages, called before each page is written.
  void before_page(std::uint32_t id) const {
    if (o.fail_after_pages >= 0 && id >= std::uint32_t(o.fail_after_pages))
      throw std::runtime_error("simulated failure (--fail-after-pages)");
  }
  /// A failure of the build or the write, said with what was left behind (nothing).
  std::runtime_error nothing_written(const std::exception& e) const {
    return std::runtime_error(std::string(e.what()) + "; nothing written (no " + o.out + ", temporary files removed)");
  }
};

std::filesystem::path checked_out_path(const std::string& out) {
  const std::filesystem::path abs = std::filesystem::absolute(out);
  if (!std::filesystem::is_directory(abs.parent_path())) throw file_error(out, "the output directory does not exist");
  return abs;
}

/// Vertices that would take more than half the budget as float are paged from a temporary file
/// through a cache of an eighth of it (OUT_OF_CORE.md, "Vertices out of core").
ebp::VertexPaging vertex_paging(const BuildJob& job) {
  ebp::VertexPaging paging;
  paging.held_limit = std::size_t(job.budget / 2);
  paging.tmp_dir = job.tmp.path.string();
  paging.cache_bytes = std::size_t(job.budget / 8);
  return paging;
}

/// The external build's options: the store's info section, progress, interruption and the test hook.
ebp::ExtBuildOptions external_options(const BuildJob& job, ebp::TriangleSource& src, Progress& prog) {
  ebp::ExtBuildOptions eo;
  eo.params = job.bp;
  eo.memory_budget = std::size_t(job.budget);
  eo.tmp_dir = job.tmp.path.string();
  eo.page_target = std::size_t(job.o.page_kb) * 1024;
  eo.info_json = [&job, &src](const ebp::ExtBuildReport& r) {
    const ebp::Stats& s = r.stats;
    nlohmann::json info = store_info(job.o.mesh, src.sha256(), s, job.params, job.o.threads);
    info["build"] = {{"kind", "external"}, {"memory_budget_bytes", job.budget}, {"runs", r.runs},
                     {"spill_bytes", r.spill_bytes}, {"records", r.records}, {"streamed_mesh", src.streaming()},
                     {"colour_fallbacks", s.colour_fallbacks}, {"degenerate_edges", s.degenerate_edges},
                     {"vertices_paged", src.vertex_page_reads().first > 0}};
    return info.dump();
  };
  eo.progress = [&prog](const char*, double f) { prog.update(f); };
  eo.check = [] { SignalGuard::check(); };
  eo.before_page = [&job](std::uint32_t id) { job.before_page(id); };
  return eo;
}

/// The external build's summary: JSON (--json) or lines.
void report_external(const BuildJob& job, const ebp::ExtBuildReport& rep, const ebp::TriangleSource& src,
                     const ebp::VertexPaging& paging) {
  const BuildOpts& o = job.o;
  const std::uint64_t peak = peak_rss_bytes();
  const WriteSummary sum{job.out.string(), rep.stats.triangles, rep.pages, rep.file_bytes, peak,
                         rep.seconds_total, job.seconds(), job.budget, o.threads};
  const auto [vertex_reads, vertex_misses] = src.vertex_page_reads();
  if (o.json) {
    nlohmann::json j = sum.json();
    j["runs"] = rep.runs;
    j["spill_bytes"] = rep.spill_bytes;
    j["records"] = rep.records;
    j["skeleton_bytes"] = rep.skeleton_bytes;
    j["min_budget_bytes"] = rep.min_budget_bytes;
    j["streamed_mesh"] = src.streaming();
    if (vertex_reads > 0)
      j["vertex_pages"] = {{"cache_bytes", paging.cache_bytes}, {"reads", vertex_reads}, {"misses", vertex_misses}};
    j["seconds"] = {{"frame", rep.seconds_frame}, {"distribute", rep.seconds_distribute},
                    {"merge_build", rep.seconds_merge_build}, {"colour", rep.seconds_colour}};
    std::cout << j.dump(2) << "\n";
    return;
  }
  sum.print_wrote();
  std::printf("external build: %lu sorted run(s), %.1f MiB spilled; frame %.1f s, distribution %.1f s, "
              "merge+build %.1f s, colouring %.1f s\n",
              (unsigned long)rep.runs, double(rep.spill_bytes) / 1048576.0, rep.seconds_frame,
              rep.seconds_distribute, rep.seconds_merge_build, rep.seconds_colour);
  if (vertex_reads > 0)
    std::printf("vertices paged from a temporary file (%.0f MiB as float) through a %.0f MiB cache: "
                "%.2f%% of %lu vertex reads from the cache\n",
                double(src.num_vertices()) * 12.0 / 1048576.0, double(paging.cache_bytes) / 1048576.0,
                100.0 * double(vertex_reads - vertex_misses) / double(vertex_reads), (unsigned long)vertex_reads);
  std::printf("peak RSS %.0f MiB, memory budget %.0f MiB%s\n", double(peak) / 1048576.0, o.budget_mb,
              double(peak) <= job.budget ? "" : " (EXCEEDED, see OUT_OF_CORE.md: what is bounded)");
  if (double(rep.min_budget_bytes) > job.budget)
    std::printf("note: this model needs a budget of at least %.0f MiB (mesh source %.0f MiB: float vertices or their cache, "
                "read buffers, an STL's weld table; node skeleton and top tree, fixed reserve)\n",
                double(rep.min_budget_bytes) / 1048576.0, double(src.resident_bytes()) / 1048576.0);
}

/// External-memory build (OUT_OF_CORE.md): the mesh is streamed, the (cell, triangle) records
/// are sorted in runs under the temporary directory and merged, pages are written as subtrees
/// complete.
void build_external(const BuildJob& job) {
  const ebp::VertexPaging paging = vertex_paging(job);
  std::unique_ptr<ebp::TriangleSource> src = ebp::open_mesh_source(job.o.mesh, paging);
  SignalGuard::check();
  Progress prog("building " + job.o.out + " (external)", 1.0, !job.o.json);
  const ebp::ExtBuildOptions eo = external_options(job, *src, prog);
  ebp::ExtBuildReport rep;
  try {
    rep = ebp::build_store_external(*src, job.out.string(), eo);
  } catch (const std::invalid_argument& e) {
    throw file_error(job.o.mesh, std::string(e.what()) + "; nothing written (no " + job.o.out + ", temporary files removed)");
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    if (g_signal) throw;
    throw job.nothing_written(e);
  }
  prog.finish();
  report_external(job, rep, *src, paging);
}

/// The mesh loaded and its tree built in memory; the mesh's path and sha256 kept, its arrays freed.
ebp::Octree load_and_build(const BuildJob& job, std::string* mesh_path, std::string* sha256) {
  Progress load("loading " + job.o.mesh, 1.0, !job.o.json);
  Mesh mesh = load_mesh(job.o.mesh);
  load.finish();
  SignalGuard::check();
  ebp::Octree tree;
  Progress prog("building ebp_octree", 1.0, !job.o.json);
  try {
    tree = ebp::build_octree(mesh.vertices, mesh.triangles, job.bp, [&](double f) {
      SignalGuard::check();
      prog.update(f);
    });
  } catch (const std::invalid_argument& e) {
    throw file_error(mesh.path, e.what());
  }
  prog.finish();
  *mesh_path = mesh.path;
  *sha256 = mesh.sha256;
  return tree;  // the store needs the tree only: the mesh goes here
}

/// The tree written as the store, atomically.
void write_tree(const BuildJob& job, const ebp::Octree& tree, const nlohmann::json& info) {
  ebp::StoreWriteOptions wo;
  wo.page_target = std::size_t(job.o.page_kb) * 1024;
  wo.params = job.bp;
  wo.info_json = info.dump();
  Progress wprog("writing " + job.o.out, 1.0, !job.o.json);
  wo.progress = [&](double f) { wprog.update(f); };
  wo.before_page = [&job](std::uint32_t id) {
    SignalGuard::check();
    job.before_page(id);
  };
  try {
    ebp::write_store_atomic(tree, job.out.string(), wo);
  } catch (const std::exception& e) {
    if (g_signal) throw;
    throw job.nothing_written(e);
  }
  wprog.finish();
}

/// The in-memory build (--in-memory): load the mesh, build the tree, write it.
void build_in_memory(const BuildJob& job) {
  std::string mesh_path, sha;
  const ebp::Octree tree = load_and_build(job, &mesh_path, &sha);
  const double build_s = job.seconds();
  SignalGuard::check();
  nlohmann::json info = store_info(mesh_path, sha, tree.stats, job.params, job.o.threads);
  info["tree_bytes"] = tree.bytes();
  write_tree(job, tree, info);
  const double total_s = job.seconds();
  const std::uint64_t peak = peak_rss_bytes();
  const ebp::StoreReader check(job.out.string());
  const ebp::FileHeader& h = check.header();
  const WriteSummary sum{job.out.string(), tree.stats.triangles, h.num_pages, h.file_size, peak, build_s, total_s,
                         job.budget, job.o.threads};
  if (job.o.json) {
    std::cout << sum.json().dump(2) << "\n";
    return;
  }
  sum.print_wrote();
  std::printf("peak RSS %.0f MiB, memory budget %.0f MiB%s\n", double(peak) / 1048576.0, job.o.budget_mb,
              double(peak) <= job.budget ? "" : " (EXCEEDED: the tree is built in memory, see OUT_OF_CORE.md)");
}

void run_build(const BuildOpts& o) {
  const auto t0 = std::chrono::steady_clock::now();
  SignalGuard signals;
  const Params p = resolve_build_args(parse_param_args(o.params));
  const std::filesystem::path out = checked_out_path(o.out);
  const BuildJob job{o, p, build_params(p, o.threads), out, TempDir(o.tmp.empty() ? out.parent_path().string() : o.tmp),
                     o.budget_mb * 1048576.0, t0};
  if (o.in_memory)
    build_in_memory(job);
  else
    build_external(job);
}

}  // namespace

void add_build_command(CLI::App& ebp_cmd) {
  auto o = std::make_shared<BuildOpts>();
  auto* cmd = ebp_cmd.add_subcommand("build", "Build the EBP-Octree of a mesh into an on-disk store (.ebp)");
  cmd->add_option("--mesh", o->mesh, "Mesh (PLY, OBJ, STL or OFF)")->required();
  cmd->add_option("--out", o->out, "Output store (.ebp); appears only when complete")->required();
  cmd->add_option("--memory-budget", o->budget_mb, "Memory budget in MiB (see OUT_OF_CORE.md: what it bounds)")
      ->required()
      ->check(CLI::Range(1.0, 1e9));
  cmd->add_option("--tmp", o->tmp, "Directory for temporary files (default: beside --out)");
  cmd->add_option("--param", o->params, "Build parameter key=value (repeatable): " + build_option_names());
  cmd->add_option("--threads", o->threads, "Build threads")->check(CLI::Range(1, 1024));
  cmd->add_option("--page-kb", o->page_kb, "Target page size in KiB (subtrees packed up to it)")->check(CLI::Range(4, 1 << 20));
  cmd->add_option("--fail-after-pages", o->fail_after_pages, "Testing: fail after writing N pages")->group("");
  cmd->add_flag("--json", o->json, "Machine-readable summary");
  cmd->add_flag("--in-memory", o->in_memory,
                "Load the mesh and build the tree in memory, then write it (the old path: peak RSS follows the model)");
  cmd->callback([o] { run_build(*o); });
}

}  // namespace bvhbench
