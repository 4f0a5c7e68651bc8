// embree: Embree 3 (Debian's 3.13) over one triangle geometry, used the way an expert would.
//
//  - Geometry: float32 vertices and uint32 index triples, owned by the method and *shared* with
//    Embree (rtcSetSharedGeometryBuffer, no copy inside Embree). The vertex buffer has one spare
//    element because Embree reads the last vertex with a 16-byte load.
//  - distance(p): rtcPointQuery with our own callback. Embree hands us candidate triangle ids in
//    traversal order; the callback computes the exact point-triangle distance in *double* on our
//    own arrays (Ericson's closest point, the same routine as brute_force, on the float32
//    vertices promoted to double), keeps the best (ties to the lowest index, as brute_force) and
//    shrinks the query radius to it. Double, not float: the answer is then exact for the float32
//    mesh the method holds, and the closest triangle agrees with the reference except for true
//    ties. The radius Embree culls with is a float around a float copy of p: we round it up by
//    the float error of both, so no closer triangle can be culled.
//    coherent=true seeds the radius with |p - previous closest point| (plus the same margin): the
//    previous closest point lies on the surface, so that is a valid upper bound, and answers are
//    identical; if nothing lies within it (it cannot, except by rounding) we query again unbounded.
//    The sign comes from the inside test below.
//  - inside(p): ray parity. An intersect filter records every hit along the ray and rejects it,
//    so one rtcIntersect1 traverses the whole ray and reports all crossings. The same triangle
//    may be reported more than once (spatial splits at quality=high put it in several leaves):
//    hits are deduplicated by triangle id. A hit within kEdgeEps (barycentric) of an edge or a
//    vertex may be counted by both neighbours (or, without robust mode, by neither): such a ray
//    is discarded and shot again in the next of a fixed table of random directions (at most
//    kMaxAttempts per vote). rays=3|5 shoots that many independent rays and takes the majority.
//    Points outside the mesh's box are outside without a ray.
//  - Memory: Embree has no API for its BVH's size. structure_bytes() is our two buffers plus the
//    RSS growth across rtcCommitScene (Embree allocates its BVH there, with its own allocator);
//    info() gives the parts.
//  - Errors: a device error callback records Embree's message; build() checks rtcGetDeviceError
//    after commit and queries check the recorded flag, throwing std::runtime_error with the
//    message (the harness turns it into status `error`). Nothing is thrown through Embree.
#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "harness/core/library_versions.hpp"
#include "harness/core/mesh.hpp"
#include "harness/core/method_support.hpp"
#include "harness/core/registry.hpp"
#include "harness/core/shared_structure_method.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/process_memory.hpp"

namespace bvhbench {
namespace {

static_assert(sizeof(Vec3f) == 12, "Embree's RTC_FORMAT_FLOAT3 buffer is tightly packed floats");
static_assert(sizeof(std::array<std::uint32_t, 3>) == 12, "RTC_FORMAT_UINT3 index buffer");

constexpr float kEdgeEps = 1e-5f;  ///< barycentric distance to an edge that makes a hit ambiguous
constexpr int kDirections = 64;    ///< fixed table of ray directions (deterministic counters)
constexpr int kMaxAttempts = 8;    ///< rays per vote before giving up on a degenerate-free one

struct Options {
  std::string quality = "medium";  // build
  bool robust = true;              // build
  int rays = 1;                    // query
  bool coherent = false;           // query
};

/// The options of ParamRole::query: what set_query_options changes on a built scene.
void read_query_options(const Params& p, Options& o) {
  o.rays = int(p.get_int("rays"));
  o.coherent = p.get_bool("coherent");
}

/// State of one point query, handed to the callback through userPtr.
struct PointQueryState {
  const Vec3f* vertices = nullptr;
  const std::array<std::uint32_t, 3>* triangles = nullptr;
  Vec3d p;             ///< the query point, in double (Embree only sees a float copy)
  double margin = 0;     ///< added to a distance before it becomes Embree's float radius
  double best_d2 = std::numeric_limits<double>::infinity();
  std::int64_t best = -1;
  Vec3d best_q;
  std::uint64_t tested = 0;
};

/// A float radius that is >= d plus the float rounding of the query point and of Embree's
/// box-distance arithmetic.
inline float search_radius(double d, double margin) {
  const float r = float((d + margin) * (1.0 + 1e-6));
  return std::nextafter(r, std::numeric_limits<float>::infinity());
}

bool point_query_callback(RTCPointQueryFunctionArguments* args) {
  auto& s = *static_cast<PointQueryState*>(args->userPtr);
  ++s.tested;
  const std::uint32_t id = args->primID;
  const auto& t = s.triangles[id];
  const Vec3d q = closest_point_on_triangle(s.p, Vec3d(s.vertices[t[0]]), Vec3d(s.vertices[t[1]]),
                                            Vec3d(s.vertices[t[2]]));
  const double d2 = squared_norm(q - s.p);
  if (d2 < s.best_d2 || (d2 == s.best_d2 && std::int64_t(id) < s.best)) {
    s.best_d2 = d2;
    s.best = id;
    s.best_q = q;
    const float r = search_radius(std::sqrt(d2), s.margin);
    if (r < args->query->radius) {
      args->query->radius = r;
      return true;  // the radius shrank: Embree re-culls with it
    }
  }
  return false;
}

/// Per-ray state: the intersect context comes first so the filter can get back to the rest.
struct RayState {
  RTCIntersectContext context;
  std::vector<std::uint32_t>* hits;
  bool near_edge;
};

void all_hits_filter(const RTCFilterFunctionNArguments* args) {
  auto* s = reinterpret_cast<RayState*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    const float u = RTCHitN_u(args->hit, args->N, i), v = RTCHitN_v(args->hit, args->N, i);
    if (std::min({u, v, 1.0f - u - v}) < kEdgeEps) s->near_edge = true;
    s->hits->push_back(RTCHitN_primID(args->hit, args->N, i));
    args->valid[i] = 0;  // reject: traversal goes on to the next crossing
  }
}

const char* error_name(RTCError e) {
  switch (e) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "error";
}

/// The built scene and what queries read, shared read-only by every thread's queries (Embree's
/// rtcIntersect1 and rtcPointQuery on a committed scene may be called from any thread at once).
struct EmbreeStructure {
  Options opt;
  std::vector<Vec3f> vertices;                         // #V + 1 (padding), float32
  std::vector<std::array<std::uint32_t, 3>> triangles;  // #F
  Box3d bounds;
  double magnitude = 0;  // largest |coordinate| of the mesh
  std::size_t degenerate_count = 0;
  std::array<Vec3f, kDirections> directions;

  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::size_t bvh_bytes = 0;
  // What the device error callback recorded, from whichever thread Embree called it on.
  std::atomic<bool> failed{false};
  std::mutex error_mutex;
  std::string error;  // guarded by error_mutex

  static void on_error(void* self, RTCError code, const char* str) {
    auto* s = static_cast<EmbreeStructure*>(self);
    std::lock_guard<std::mutex> lock(s->error_mutex);
    s->failed = true;
    if (s->error.empty()) s->error = std::string(error_name(code)) + (str ? std::string(": ") + str : "");
  }

  /// Turns a recorded device error into an exception at the method boundary.
  void check(const char* where) {
    const RTCError e = rtcGetDeviceError(device);
    if (e == RTC_ERROR_NONE && !failed) return;
    std::string msg;
    {
      std::lock_guard<std::mutex> lock(error_mutex);
      msg = error.empty() ? error_name(e) : error;
    }
    throw std::runtime_error(std::string("embree: ") + where + ": " + msg);
  }
};

/// One thread's queries: its hit list, the coherent seed and its counters.
class EmbreeQueries final : public QueryState {
 public:
  explicit EmbreeQueries(EmbreeStructure& s) : s_(s) {}

  void reset_path() override { has_prev_ = false; }

  bool inside(const Vec3d& p) override {
    const bool r = inside_impl(p);
    if (s_.failed) s_.check("a ray query");
    return r;
  }

  DistanceResult distance(const Vec3d& p) override {
    PointQueryState s;
    s.vertices = s_.vertices.data();
    s.triangles = s_.triangles.data();
    s.p = p;
    const Vec3f pf(p);
    // Float rounding of the query point (|pf - p| <= sqrt(3) 2^-24 max|p_i|) plus Embree's float
    // box arithmetic at the scene's magnitude: a few float epsilons of the largest coordinate.
    s.margin = 4.0 * std::numeric_limits<float>::epsilon() *
               (s_.magnitude + std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}));
    const float seeded = (s_.opt.coherent && has_prev_) ? search_radius(norm(p - prev_closest_), s.margin)
                                                         : std::numeric_limits<float>::infinity();
    point_query(s, pf, seeded);
    if (s.best < 0 && seeded != std::numeric_limits<float>::infinity()) {
      ++fallbacks_;
      point_query(s, pf, std::numeric_limits<float>::infinity());
    }
    if (s_.failed) s_.check("rtcPointQuery");
    if (s.best < 0) throw std::runtime_error("embree: rtcPointQuery found no triangle");
    triangles_tested_ += s.tested;

    DistanceResult r;
    r.closest = s.best_q;
    r.triangle = s.best;
    r.normal = face_normal(s_.vertices, s_.triangles[std::size_t(s.best)]);
    const double d = std::sqrt(s.best_d2);
    r.distance = (d > 0 && inside_impl(p)) ? -d : d;
    if (s_.opt.coherent) {
      prev_closest_ = s.best_q;
      has_prev_ = true;
    }
    return r;
  }

  std::vector<Counter> counters() const override {
    return {{"triangles_tested", triangles_tested_},
            {"point_queries", point_queries_},
            {"rays_shot", rays_shot_},
            {"ray_hits_reported", hits_reported_},
            {"undecided", undecided_}};
  }
  void reset_counters() override {
    triangles_tested_ = point_queries_ = rays_shot_ = hits_reported_ = undecided_ = 0;
  }
  std::uint64_t fallbacks() const { return fallbacks_; }

 private:
  void point_query(PointQueryState& s, const Vec3f& pf, float radius) {
    ++point_queries_;
    RTCPointQuery q;
    q.x = pf.x, q.y = pf.y, q.z = pf.z;
    q.time = 0.f;
    q.radius = radius;
    RTCPointQueryContext ctx;  // per query, on this thread's stack
    rtcInitPointQueryContext(&ctx);
    rtcPointQuery(s_.scene, &q, &ctx, &point_query_callback, &s);
  }

  /// Parity of the crossings along the ray from o in direction d; false in *degenerate* when a
  /// hit was too close to an edge to be counted reliably.
  bool parity(const Vec3f& o, const Vec3f& d, bool* degenerate) {
    hits_.clear();
    RayState s;
    rtcInitIntersectContext(&s.context);
    s.hits = &hits_;
    s.near_edge = false;
    RTCRayHit rh;
    rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
    rh.ray.tnear = 0.f;
    rh.ray.tfar = std::numeric_limits<float>::infinity();
    rh.ray.time = 0.f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(s_.scene, &s.context, &rh);
    ++rays_shot_;
    hits_reported_ += hits_.size();
    std::sort(hits_.begin(), hits_.end());
    const std::size_t crossings = std::size_t(std::unique(hits_.begin(), hits_.end()) - hits_.begin());
    *degenerate = s.near_edge;
    return (crossings & 1) == 1;
  }

  bool inside_impl(const Vec3d& p) {
    if (!s_.bounds.contains(p)) return false;
    const Vec3f o(p);
    int next = 0, votes_in = 0;
    for (int v = 0; v < s_.opt.rays; ++v) {
      bool odd = false, degenerate = true;
      for (int a = 0; a < kMaxAttempts && degenerate; ++a)
        odd = parity(o, s_.directions[std::size_t(next++ % kDirections)], &degenerate);
      if (degenerate) ++undecided_;
      votes_in += odd ? 1 : 0;
    }
    return 2 * votes_in > s_.opt.rays;
  }

  EmbreeStructure& s_;  // read-only but for check(), which reads the recorded error
  std::vector<std::uint32_t> hits_;
  bool has_prev_ = false;
  Vec3d prev_closest_;
  std::uint64_t triangles_tested_ = 0, point_queries_ = 0, rays_shot_ = 0, hits_reported_ = 0,
                undecided_ = 0, fallbacks_ = 0;
};

class Embree final : public SharedStructureMethod<EmbreeQueries> {
 public:
  explicit Embree(const Options& o) : s_(std::make_unique<EmbreeStructure>()) {
    s_->opt = o;
    std::mt19937_64 rng(0x5eedbeefULL);
    std::normal_distribution<double> n01;
    for (auto& d : s_->directions) {
      Vec3d v;
      do v = Vec3d(n01(rng), n01(rng), n01(rng));
      while (norm(v) < 1e-3);
      d = Vec3f(normalized(v));
    }
  }

  /// The scene stays; the next queries vote and hint as `params` say, from a fresh state.
  void set_query_options(const Params& params) override {
    read_query_options(params, s_->opt);
    start_queries();
  }

  ~Embree() override {
    if (s_->scene) rtcReleaseScene(s_->scene);
    if (s_->device) rtcReleaseDevice(s_->device);
  }

  void build(const Mesh& mesh, const BuildContext& ctx) override {
    if (mesh.triangles.empty()) throw InputError("embree: the mesh has no triangle");
    if (mesh.triangles.size() >= std::numeric_limits<std::uint32_t>::max())
      throw InputError("embree: more triangles than 32-bit primitive ids can address");

    EmbreeStructure& s = *s_;
    const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
    s.vertices = float32_vertices(mesh.vertices, 1);  // + 1: Embree reads the last vertex with a 16-byte load
    for (std::size_t i = 0; i < nv; ++i) s.bounds.add(Vec3d(s.vertices[i]));
    s.triangles.assign(mesh.triangles.begin(), mesh.triangles.end());
    for (const auto& t : s.triangles)
      if (squared_norm(cross(Vec3d(s.vertices[t[1]]) - Vec3d(s.vertices[t[0]]),
                             Vec3d(s.vertices[t[2]]) - Vec3d(s.vertices[t[0]]))) == 0)
        ++s.degenerate_count;
    const Vec3d far = vmax(vmax(s.bounds.lo, -s.bounds.lo), vmax(s.bounds.hi, -s.bounds.hi));
    s.magnitude = std::max({far.x, far.y, far.z});

    // The device's threads build the BVH: the job's build threads, as every method's build.
    const std::string config = "threads=" + std::to_string(std::max(1, ctx.threads)) + ",verbose=0";
    s.device = rtcNewDevice(config.c_str());
    if (!s.device)
      throw std::runtime_error(std::string("embree: rtcNewDevice(\"") + config +
                               "\") failed: " + error_name(rtcGetDeviceError(nullptr)));
    rtcSetDeviceErrorFunction(s.device, &EmbreeStructure::on_error, &s);

    const RTCBuildQuality quality = s.opt.quality == "low"    ? RTC_BUILD_QUALITY_LOW
                                    : s.opt.quality == "high" ? RTC_BUILD_QUALITY_HIGH
                                                              : RTC_BUILD_QUALITY_MEDIUM;
    s.scene = rtcNewScene(s.device);
    rtcSetSceneFlags(s.scene, s.opt.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(s.scene, quality);
    RTCGeometry geom = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, quality);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s.vertices.data(),
                               0, sizeof(Vec3f), nv);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, s.triangles.data(),
                               0, sizeof(s.triangles[0]), nt);
    rtcSetGeometryIntersectFilterFunction(geom, &all_hits_filter);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(s.scene, geom);
    rtcReleaseGeometry(geom);
    s.check("building the scene");

    const std::size_t rss0 = current_rss_bytes();
    rtcCommitScene(s.scene);
    const std::size_t rss1 = current_rss_bytes();
    s.check("rtcCommitScene");
    s.bvh_bytes = rss1 > rss0 ? rss1 - rss0 : 0;
    start_queries();
  }


  std::size_t structure_bytes() const override { return buffer_bytes() + s_->bvh_bytes; }

  /// Embree 3 does not say which ISA it dispatched to (AVX or AVX2), but its native ray packet
  /// widths say the vector width of the kernels it enabled: 4 (SSE), 8 (AVX, AVX2), 16
  /// (AVX-512), after the CPU, the ISAs compiled into the library and any `isa=` configuration.
  nlohmann::json machine_facts() const override {
    if (!s_->device) return nlohmann::json::object();
    std::vector<int> widths;
    if (rtcGetDeviceProperty(s_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED)) widths.push_back(4);
    if (rtcGetDeviceProperty(s_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED)) widths.push_back(8);
    if (rtcGetDeviceProperty(s_->device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)) widths.push_back(16);
    return {{"embree_native_ray_widths", widths}};
  }

  nlohmann::json info() const override {
    return {{"triangles", s_->triangles.size()},
            {"degenerate_triangles", s_->degenerate_count},
            {"quality", s_->opt.quality},
            {"robust", s_->opt.robust},
            {"embree_version", RTC_VERSION_STRING},
            {"bytes",
             {{"buffers", buffer_bytes()},
              {"bvh_rss_delta", s_->bvh_bytes},
              {"note", "Embree has no size API: its BVH is the RSS growth across rtcCommitScene"}}},
            {"coherent_fallbacks", own_state() ? own_state()->fallbacks() : 0}};
  }

 private:
  std::unique_ptr<EmbreeQueries> make_state() const override { return std::make_unique<EmbreeQueries>(*s_); }

  std::size_t buffer_bytes() const {
    return s_->vertices.capacity() * sizeof(Vec3f) + s_->triangles.capacity() * sizeof(s_->triangles[0]);
  }

  // On the heap: the device's error callback holds its address, and its mutex does not move.
  std::unique_ptr<EmbreeStructure> s_;
};

}  // namespace
}  // namespace bvhbench

void bvhbench_register_embree(bvhbench::Registry& r) {
  using namespace bvhbench;
  note_library_version("embree", RTC_VERSION_STRING);
  MethodInfo m = MethodInfo::named("embree",
                                   "Embree 3 triangle scene: rtcPointQuery with an exact double closest-point callback; inside "
                                   "by all-hits ray parity with jittered re-shots and majority vote");
  // Capabilities, said once here (false unless set).
  m.caps.inside = true; m.caps.distance = true; m.caps.closest_triangle = true; m.caps.coherence = true;
  m.caps.query_options_after_build = true;  // rays and coherent are read by the queries alone
  m.caps.concurrent_queries = true;  // per-thread query contexts, hit lists and counters over the committed scene
  m.caps.build_threads = BuildThreads::job;  // builds on the job's threads (TBB or the device's)
  // Embree picks its kernels (SSE2, SSE4.2, AVX, AVX2, AVX-512) from the processor when the
  // device is made, and with them the BVH it builds (BVH8 where it may use AVX, else BVH4; on
  // Intel also by CPU model) and the float arithmetic of its tests (AVX2 and AVX-512 kernels
  // fuse multiply-adds, SSE and AVX ones do not). Forcing each ISA on one AVX-512 machine
  // (device config isa=avx512|avx2|avx|sse4.2|sse2) over the CI meshes, query sets and the
  // parameters quality, robust, rays and coherent moved triangles_tested in every distance job
  // and nothing else. Counter by counter:
  m.machine_dependent_counters = {
      // The candidates Embree's traversal hands to our callback: which leaves it opens, in which
      // order, and so how soon the radius shrinks, follow the BVH's layout and width.
      "triangles_tested",
      // Every crossing the filter sees, once per leaf reference of the triangle: spatial splits
      // (quality=high) duplicate references by the builder's layout, and with robust=false an
      // edge crossing is reported by both neighbours or neither by the kernel's rounding.
      "ray_hits_reported",
      // A vote is re-shot when a hit's barycentrics, computed by Embree's kernel, lie within
      // kEdgeEps of an edge: a fused or unfused multiply-add moves a hit across that line. Rare
      // (unchanged across the five ISAs above), but decided by the machine, not by the input.
      "rays_shot",
      "undecided",  // the votes whose every re-shot was near an edge: the same decision
  };
  // point_queries is ours alone: one rtcPointQuery per distance query, plus one only when a
  // coherent seed radius found nothing, which the margin in search_radius() rules out whatever
  // the rounding of Embree's box tests (a change is a broken margin, worth failing the gate).
  m.params = {
      {"quality", ParamType::choice, ParamRole::build, "medium", "BVH build quality (high = spatial splits)",
       {"low", "medium", "high"}},
      {"robust", ParamType::boolean, ParamRole::build, "true",
       "RTC_SCENE_FLAG_ROBUST: watertight ray-triangle tests (no ray slips between neighbours)", {}},
      {"rays", ParamType::integer, ParamRole::query, "1", "rays per inside test, majority vote", {"1", "3", "5"}},
      {"coherent", ParamType::boolean, ParamRole::query, "false",
       "seed the point-query radius with the distance to the previous closest point", {}},
  };
  // Every hit along a ray, mod 2 (a vote of `rays` of them): parity, defined on closed input.
  m.inside = {{{}, {InsideRule::ray_parity, false, 0.5, InputContract::closed}, ""}};
  // Swept by `methods: all`: the defaults and the coherent variant (which only a path tells apart).
  m.sweep = {"", "coherent=true"};
  m.create = [](const Params& p) -> std::unique_ptr<Method> {
    Options o;
    o.quality = p.get("quality");
    o.robust = p.get_bool("robust");
    read_query_options(p, o);
    return std::make_unique<Embree>(o);
  };
  r.add(std::move(m));
}
