// The out-of-core ebp_octree method (ooc_method.hpp): the harness adapter over ebp::OutOfCore,
// with the check that the store was built from the mesh the job names.
#include "methods/ebp_octree/ooc_method.hpp"

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "harness/core/mesh.hpp"
#include "harness/util/errors.hpp"
#include "methods/ebp_octree/ebp_adapter.hpp"
#include "methods/ebp_octree/store/out_of_core.hpp"

namespace bvhbench {
namespace {

class EbpOocMethod final : public Method {
 public:
  explicit EbpOocMethod(const Params& p)
      : path_(p.get("store")),
        cache_bytes_(std::size_t(p.get_int("cache_mb")) << 20),
        cold_(p.get_bool("cold")),
        coherent_(p.get_bool("coherent")),
        certificate_(p.get_bool("certificate")),
        chained_sign_(p.get_bool("chained_sign")) {}

  void build(const Mesh& mesh, const BuildContext&) override {
    ooc_.emplace(path_, cache_bytes_, coherent_, cold_);
    ooc_->set_certificate(certificate_);
    ooc_->set_chained_sign(chained_sign_);
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
            {"exact_fallbacks", c.exact_fallbacks}, {"certificate_renewals", c.certificate_renewals},
            {"certificate_served", c.certificate_served}, {"signs_chained", c.signs_chained}, {"cache_hits", k.hits},
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
  bool cold_, coherent_, certificate_, chained_sign_;
  std::optional<ebp::OutOfCore> ooc_;
};

}  // namespace

std::unique_ptr<Method> make_ebp_ooc_method(const Params& p) { return std::make_unique<EbpOocMethod>(p); }

}  // namespace bvhbench
