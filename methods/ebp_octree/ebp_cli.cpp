// The harness side of the out-of-core EBP-Octree: the method variant `ebp_octree:store=M.ebp`
// (the adapter in ebp_method.cpp delegates here when `store` is given) and the commands
// `bvhbench ebp build`, `bvhbench ebp info` and `bvhbench ebp verify` (the check itself is
// ebp_verify.cpp; all attached to the `ebp` group by one hook line in ebp_method.cpp). See
// OUT_OF_CORE.md.
#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "methods/ebp_octree/ebp_adapter.hpp"
#include "methods/ebp_octree/build/external_build.hpp"
#include "methods/ebp_octree/store/out_of_core.hpp"
#include "methods/ebp_octree/store/store.hpp"
#include "methods/ebp_octree/store/verify.hpp"
#include "harness/cli/commands.hpp"
#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/process_memory.hpp"
#include "harness/util/progress.hpp"

namespace bvhbench {

std::unique_ptr<Method> make_ebp_ooc_method(const Params& p);
void add_ebp_store_commands(CLI::App& ebp_cmd);

namespace {

// ---------------------------------------------------------------------------------------------
// The method variant
class EbpOocMethod final : public Method {
 public:
  explicit EbpOocMethod(const Params& p)
      : path_(p.get("store")),
        cache_bytes_(std::size_t(p.get_int("cache_mb")) << 20),
        cold_(p.get_bool("cold")),
        coherent_(p.get_bool("coherent")) {}

  void build(const Mesh& mesh, const BuildContext&) override {
    ooc_.emplace(path_, cache_bytes_, coherent_, cold_);
    const ebp::FileHeader& h = ooc_->store().header();
    if (!mesh.triangles.empty() && h.num_triangles != mesh.num_triangles())
      throw file_error(path_, "built for a mesh of " + std::to_string(h.num_triangles) + " triangles, " + mesh.path +
                                  " has " + std::to_string(mesh.num_triangles()));
    const auto info = nlohmann::json::parse(ooc_->store().info_json(), nullptr, false);
    if (info.is_object() && info.contains("mesh_sha256") && info["mesh_sha256"].is_string() && !mesh.sha256.empty() &&
        info["mesh_sha256"].get<std::string>() != mesh.sha256)
      throw file_error(path_, "built from another mesh (sha256 differs from " + mesh.path + ")");
  }
  bool supports(QueryType) const override { return true; }
  bool inside(const Vec3d& p) override { return ooc_->inside(p); }
  DistanceResult distance(const Vec3d& p) override { return to_distance_result(ooc_->distance(p)); }
  void reset_path() override {
    if (ooc_) ooc_->reset_path();
  }
  std::size_t structure_bytes() const override { return ooc_ ? ooc_->bytes() : 0; }
  std::vector<Counter> counters() const override {
    if (!ooc_) return {};
    const ebp::QueryCounters c = ooc_->counters();
    const ebp::PageCache& k = ooc_->cache();
    return {{"nodes_visited", c.nodes_visited}, {"planes_tested", c.planes_tested},
            {"triangles_tested", c.triangles_tested}, {"hit_white", c.hit_white},
            {"hit_black", c.hit_black}, {"hit_convex", c.hit_convex},
            {"hit_concave", c.hit_concave}, {"hit_special", c.hit_special},
            {"exact_fallbacks", c.exact_fallbacks}, {"cache_hits", k.hits},
            {"cache_misses", k.misses}, {"bytes_read", k.bytes_read},
            {"cache_evictions", k.evictions}};
  }
  void reset_counters() override {
    if (ooc_) ooc_->reset_counters();
  }
  nlohmann::json info() const override {
    if (!ooc_) return nlohmann::json::object();
    const ebp::FileHeader& h = ooc_->store().header();
    nlohmann::json j;
    j["store"] = path_;
    j["store_bytes"] = h.file_size;
    j["pages"] = h.num_pages;
    j["top_nodes"] = h.num_top_nodes;
    j["leaf_level"] = h.leaf_level;
    j["nodes"] = h.nodes;
    j["triangle_refs"] = h.triangle_refs;
    j["cache_budget_bytes"] = cache_bytes_;
    j["pinned_bytes"] = ooc_->store().pinned_bytes() + ooc_->cache().bookkeeping_bytes();
    j["cold"] = cold_;
    return j;
  }

 private:
  std::string path_;
  std::size_t cache_bytes_;
  bool cold_, coherent_;
  std::optional<ebp::OutOfCore> ooc_;
};

// ---------------------------------------------------------------------------------------------
// `ebp build`: interrupt handling and temporary files
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

std::map<std::string, std::string> parse_kv(const std::vector<std::string>& kvs) {
  std::map<std::string, std::string> given;
  for (const std::string& kv : kvs) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError("--param " + kv + ": expected key=value");
    if (given.count(kv.substr(0, eq))) throw InputError("--param " + kv.substr(0, eq) + " given twice");
    given[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  return given;
}

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
    const MethodInfo* mi = Registry::global().find("ebp_octree");
    if (!mi) throw std::logic_error("ebp_octree is not registered");
    std::map<std::string, std::string> given = parse_kv(o->params);
    for (const char* k : {"store", "cache_mb", "cold", "coherent"})
      if (given.count(k)) throw InputError(std::string("--param ") + k + ": not a build parameter");
    const Params p = Params::resolve("ebp_octree", mi->params, given);
    ebp::BuildParams bp;
    bp.leaf_factor = p.get_real("leaf_factor");
    bp.max_planes = int(p.get_int("max_planes"));
    bp.cluster_angle = p.get_real("cluster_angle");
    bp.threads = o->threads;

    const std::filesystem::path out = std::filesystem::absolute(o->out);
    if (!std::filesystem::is_directory(out.parent_path()))
      throw file_error(o->out, "the output directory does not exist");
    TempDir tmp(o->tmp.empty() ? out.parent_path().string() : o->tmp);
    const double budget = o->budget_mb * 1048576.0;
    if (!o->in_memory) {
      // External-memory build (OUT_OF_CORE.md): the mesh is streamed, the (cell, triangle)
      // records are sorted in runs under tmp and merged, pages are written as subtrees complete.
      std::unique_ptr<ebp::TriangleSource> src = ebp::open_mesh_source(o->mesh);
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
                         {"colour_fallbacks", s.colour_fallbacks}, {"degenerate_edges", s.degenerate_edges}};
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
        std::printf("peak RSS %.0f MiB, memory budget %.0f MiB%s\n", double(peak) / 1048576.0, o->budget_mb,
                    double(peak) <= budget ? "" : " (EXCEEDED, see OUT_OF_CORE.md: what is bounded)");
        if (double(rep.min_budget_bytes) > budget)
          std::printf("note: this model needs a budget of at least %.0f MiB (mesh source %.0f MiB: float vertices, "
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
    j["root"] = {{"lo", {h.root_lo[0], h.root_lo[1], h.root_lo[2]}}, {"size", h.root_size}};
    j["leaf_level"] = h.leaf_level;
    j["levels"] = h.leaf_level + 1;
    j["triangles"] = h.num_triangles;
    j["closed"] = (h.flags & ebp::kStoreClosed) != 0;
    j["params"] = {{"leaf_factor", h.leaf_factor}, {"max_planes", h.max_planes}, {"cluster_angle", h.cluster_angle}};
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
    std::printf("  root cube         lo (%.9g, %.9g, %.9g), size %.9g\n", h.root_lo[0], h.root_lo[1], h.root_lo[2], h.root_size);
    std::printf("  levels            %u (leaf level %u)\n", h.leaf_level + 1, h.leaf_level);
    std::printf("  parameters        leaf_factor=%g max_planes=%d cluster_angle=%g\n", h.leaf_factor, h.max_planes, h.cluster_angle);
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

void add_verify_command(CLI::App& ebp_cmd) {
  struct Opts {
    std::string path;
    bool json = false, all = false;
    int threads = 2;  // as `ebp build`; from the OS cache two threads check 1.5-1.7x faster (OUT_OF_CORE.md)
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = ebp_cmd.add_subcommand(
      "verify", "Check every section and every page of a store (.ebp) as a query would load it; exit 2 if any is bad");
  cmd->add_option("store", o->path, "Store (.ebp)")->required();
  cmd->add_flag("--all", o->all, "List every bad page instead of stopping at the first");
  cmd->add_option("--threads", o->threads, "Pages checked in parallel (at most the cores)")->check(CLI::Range(1, 1024));
  cmd->add_flag("--json", o->json, "Machine-readable report on stdout (exit code as without it)");
  cmd->callback([o] {
    ebp::VerifyOptions vo;
    vo.all = o->all;
    vo.threads = o->threads;
    Progress prog("verifying " + o->path, 1.0, !o->json);
    vo.progress = [&](std::uint64_t done, std::uint64_t total) { prog.update(total ? double(done) / double(total) : 1.0); };
    const ebp::VerifyReport rep = ebp::verify_store(o->path, vo);
    prog.finish();  // the check is done, whatever it found: the line goes before the findings
    const double mib = double(rep.bytes_read) / 1048576.0;
    const double rate = rep.seconds > 0 ? double(rep.bytes_read) / rep.seconds : 0.0;
    if (o->json) {
      nlohmann::json problems = nlohmann::json::array();
      for (const ebp::VerifyProblem& p : rep.problems) {
        nlohmann::json j{{"page", nullptr}, {"problem", p.problem}, {"message", p.message}};
        if (p.page >= 0) j["page"] = p.page, j["offset"] = p.offset, j["size"] = p.size;
        problems.push_back(j);
      }
      const nlohmann::json j{{"path", printable(o->path)},  {"ok", rep.ok()},
                             {"file_bytes", rep.file_bytes}, {"pages", rep.pages},
                             {"pages_checked", rep.pages_checked}, {"bytes_read", rep.bytes_read},
                             {"seconds", rep.seconds},       {"bytes_per_second", rate},
                             {"all", o->all},                {"problems", problems}};
      std::cout << j.dump(2) << "\n";
    } else if (rep.ok()) {
      std::printf("ok %s: %lu pages, %.1f MiB checked in %.2f s (%.0f MiB/s)\n", printable(o->path).c_str(),
                  (unsigned long)rep.pages, mib, rep.seconds, rate / 1048576.0);
    } else {
      for (const ebp::VerifyProblem& p : rep.problems) std::cerr << "bvhbench: " << p.message << "\n";
      const bool page_problem = rep.problems.back().page >= 0;
      if (o->all && page_problem)
        std::cerr << "bvhbench: " << printable(o->path) << ": " << rep.problems.size() << " bad of " << rep.pages
                  << " pages\n";
      else if (page_problem && rep.pages_checked < rep.pages)
        std::cerr << "bvhbench: stopped at the first bad page (" << rep.pages_checked << " of " << rep.pages
                  << " checked); --all lists every bad page\n";
    }
    if (!rep.ok()) throw ExitCode{2};
  });
}

}  // namespace

std::unique_ptr<Method> make_ebp_ooc_method(const Params& p) { return std::make_unique<EbpOocMethod>(p); }

void add_ebp_store_commands(CLI::App& ebp_cmd) {
  add_build_command(ebp_cmd);
  add_info_command(ebp_cmd);
  add_verify_command(ebp_cmd);
}

}  // namespace bvhbench
