// The out-of-core ebp_octree method (ooc_method.hpp): the harness adapter over ebp::OutOfCore,
// with the check that the store was built from the mesh the job names.
#include "methods/ebp_octree/ooc_method.hpp"

#include <algorithm>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "harness/core/mesh.hpp"
#include "harness/core/shared_structure_method.hpp"
#include "harness/util/errors.hpp"
#include "methods/ebp_octree/build_option_params.hpp"
#include "methods/ebp_octree/ebp_adapter.hpp"
#include "methods/ebp_octree/store/out_of_core.hpp"
#include "methods/ebp_octree/store/store_file.hpp"

namespace bvhbench {
namespace {

const char* const kStore = "store";

/// One thread's queries: an ebp::OutOfCore with a page cache of its own over the shared store.
///
/// Why a cache per thread and not one shared: a cache entry holds its page's ebp::Query, whose
/// stamps and path state one query writes as it goes, so a shared entry could serve one thread at
/// a time only (a lock per page, held for a whole page search); and a shared cache's hits,
/// misses and evictions would depend on how the threads interleave, so its counters would not be
/// deterministic. Per thread, each cache sees only its own thread's queries: the counters depend
/// on the input and T alone, and no lock is taken on the query path. The cost: a page several
/// threads need is read and decoded once per thread, and the job's cache_mb is split evenly
/// between the T caches, so that the budget still bounds the job's memory.
class EbpOocQueries final : public QueryState {
 public:
  EbpOocQueries(std::shared_ptr<const ebp::StoreReader> store, std::size_t cache_bytes, bool coherent, bool cold,
                bool certificate, bool adaptive, bool chained_sign)
      : ooc_(std::move(store), cache_bytes, coherent, cold) {
    ooc_.set_certificate(certificate);
    ooc_.set_adaptive_certificate(adaptive);
    ooc_.set_chained_sign(chained_sign);
  }
  bool inside(const Vec3d& p) override { return ooc_.inside(p); }
  DistanceResult distance(const Vec3d& p) override { return to_distance_result(ooc_.distance(p)); }
  void reset_path() override { ooc_.reset_path(); }
  std::vector<Counter> counters() const override {
    std::vector<Counter> c = ebp_counters(ooc_.counters());
    const ebp::PageCache& k = ooc_.cache();
    c.insert(c.end(), {{"cache_hits", k.hits}, {"cache_misses", k.misses}, {"bytes_read", k.bytes_read},
                       {"cache_evictions", k.evictions}});
    return c;
  }
  void reset_counters() override { ooc_.reset_counters(); }
  const ebp::OutOfCore& ooc() const { return ooc_; }

 private:
  ebp::OutOfCore ooc_;
};

class EbpOocMethod final : public SharedStructureMethod<EbpOocQueries> {
 public:
  explicit EbpOocMethod(const Params& p)
      : path_(p.get(kStore)),
        cache_bytes_(std::size_t(p.get_int("cache_mb")) << 20),
        cold_(p.get_bool("cold")),
        coherent_(p.get_bool("coherent")),
        certificate_(p.get_bool("certificate")),
        adaptive_(p.get("certificate_policy") == "auto"),
        chained_sign_(p.get_bool("chained_sign")) {}

  void build(const Mesh& mesh, const BuildContext& ctx) override { open(mesh.summary(), ctx); }
  bool reads_structure() const override { return true; }
  void open(const MeshSummary& mesh, const BuildContext& ctx) override {
    thread_cache_bytes_ = cache_bytes_ / std::size_t(std::max(1, ctx.threads));
    store_ = std::make_shared<const ebp::StoreReader>(path_);
    const ebp::FileHeader& h = store_->header();
    if (h.num_triangles != mesh.triangles)
      throw file_error(path_, "built for a mesh of " + std::to_string(h.num_triangles) + " triangles, " + mesh.path +
                                  " has " + std::to_string(mesh.triangles));
    const auto info = nlohmann::json::parse(store_->info_json(), nullptr, false);
    if (info.is_object() && info.contains("mesh_sha256") && info["mesh_sha256"].is_string() && !mesh.sha256.empty() &&
        info["mesh_sha256"].get<std::string>() != mesh.sha256)
      throw file_error(path_, "built from another mesh (sha256 differs from " + mesh.path + ")");
    start_queries();
  }
  /// The options the store was built with, from its header: what a result records as ran.
  /// And face_sign=false: a store's pages do not carry the face sides (face_sides.hpp), so its
  /// signs come from the inside query whatever the option says.
  std::map<std::string, std::string> build_options_read() const override {
    if (!store_) return {};
    std::map<std::string, std::string> read = build_option_texts(ebp::header_build_params(store_->header()));
    read["face_sign"] = "false";
    return read;
  }
  /// The threads `ebp build` ran on, from the store's info section (null in a store that does
  /// not say): a store job did not build on its own threads.
  std::optional<nlohmann::json> build_threads_read() const override {
    if (!store_) return std::nullopt;
    const auto info = nlohmann::json::parse(store_->info_json(), nullptr, false);
    if (info.is_object() && info.contains("threads") && info["threads"].is_number_integer()) return info["threads"];
    return nlohmann::json(nullptr);
  }
  /// The pinned store and the method's own thread's cache (every further thread's cache may hold
  /// as much again, within its share of the budget).
  std::size_t structure_bytes() const override { return own_state() ? own_state()->ooc().bytes() : 0; }
  nlohmann::json info() const override {
    if (!own_state()) return nlohmann::json::object();
    const ebp::OutOfCore& ooc = own_state()->ooc();
    const ebp::FileHeader& h = store_->header();
    nlohmann::json j;
    j["store"] = path_;
    j["store_bytes"] = h.file_size;
    j["pages"] = h.num_pages;
    j["top_nodes"] = h.num_top_nodes;
    j["leaf_level"] = h.leaf_level;
    j["nodes"] = h.nodes;
    j["triangle_refs"] = h.triangle_refs;
    j["cache_budget_bytes"] = cache_bytes_;
    j["cache_budget_bytes_per_thread"] = thread_cache_bytes_;  // one page cache per query thread
    j["pinned_bytes"] = store_->pinned_bytes() + ooc.cache().bookkeeping_bytes();
    j["cache_eviction"] = ebp::PageCache::kEviction;
    j["cold"] = cold_;
    return j;
  }

 private:
  std::unique_ptr<EbpOocQueries> make_state() const override {
    return std::make_unique<EbpOocQueries>(store_, thread_cache_bytes_, coherent_, cold_, certificate_, adaptive_,
                                           chained_sign_);
  }
  std::string path_;
  std::size_t cache_bytes_, thread_cache_bytes_ = 0;
  bool cold_, coherent_, certificate_, adaptive_, chained_sign_;
  std::shared_ptr<const ebp::StoreReader> store_;
};

}  // namespace

std::vector<ParamSpec> ooc_params() {
  return {
      {kStore, ParamType::text, ParamRole::build, "", "out of core: answer from this .ebp store through a page cache", {}},
      {"cache_mb", ParamType::integer, ParamRole::query, "256", "out of core: page cache budget in MiB", {}, 1, 1 << 20},
      {"cold", ParamType::boolean, ParamRole::query, "false",
       "out of core: evict the file from the OS cache and empty the page cache before each pass", {}},
  };
}

bool is_out_of_core(const Params& p) { return !p.get(kStore).empty(); }

void check_ooc_options(const Params& p) {
  // A store carries the build options it was made with (its header; the result records those):
  // one given beside it would be recorded as run but never used, so it is refused. The options
  // of the store's page cache mean nothing without one.
  if (is_out_of_core(p)) {
    for (const ParamSpec& s : build_option_specs())
      if (p.given(s.name))
        throw InputError("method ebp_octree: " + s.name + "=" + p.given().at(s.name) + " given beside store=" + p.get(kStore) +
                         ": a store was built with its own build options (its header; `bvhbench ebp info` shows "
                         "them), and a result records those");
    if (p.given("face_sign") && p.get_bool("face_sign"))
      throw InputError("method ebp_octree: face_sign=" + p.given().at("face_sign") + " given beside store=" + p.get(kStore) +
                       ": a store's pages do not carry the face sides the sign from the closest face needs (an "
                       "in-memory build has them)");
    return;
  }
  for (const ParamSpec& s : ooc_params())
    if (s.name != kStore && p.given(s.name))
      throw InputError("method ebp_octree: " + s.name + "=" + p.given().at(s.name) +
                       " is an option of the out-of-core store: give store=FILE.ebp with it");
}

std::unique_ptr<Method> make_ebp_ooc_method(const Params& p) { return std::make_unique<EbpOocMethod>(p); }

}  // namespace bvhbench
