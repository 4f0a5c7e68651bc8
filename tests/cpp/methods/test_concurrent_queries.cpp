// Queries on several threads (harness/run/thread_replay.hpp), for every registered method that
// declares concurrent queries, its coherent variant, and the out-of-core EBP-Octree: with T = 2
// and 4 threads every answer is the one a single thread gives on the same queries, bit for bit:
//  - random points split between the threads: each thread's part against a single-thread replay
//    of that part (from a reset path; for a method without path state, the whole set's replay);
//  - a haptic path as T probes: each probe's path against a single-thread replay of that path;
// the work counters of a T-thread pass are the same from one fresh instance to another; and a
// method that does not declare concurrent queries is refused for T > 1 (unsupported), never run.
#include <gtest/gtest.h>

#include <cctype>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/mesh.hpp"
#include "harness/core/query_set.hpp"
#include "harness/core/registry.hpp"
#include "harness/io/query_set_io.hpp"
#include "harness/run/run_job.hpp"
#include "harness/run/thread_replay.hpp"
#include "harness/util/errors.hpp"
#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

constexpr std::size_t kRandom = 400;  ///< random points
constexpr std::size_t kPath = 300;    ///< haptic path length

const Mesh& cow() {
  static const Mesh m = load_shared_mesh("cow.obj");
  return m;
}

/// An out-of-core store of the cow with small pages (so that a query visits several), once.
const std::string& cow_store() {
  static const std::string path = [] {
    static TmpDir dir("concurrent_queries_test");
    ebp::BuildParams bp;
    bp.threads = 1;
    const ebp::Octree t = ebp::build_octree(cow().vertices, cow().triangles, bp);
    ebp::StoreWriteOptions o;
    o.page_target = 4096;
    o.info_json = "{}";
    const std::string p = dir.file("cow.ebp");
    ebp::write_store_atomic(t, p, o);
    return p;
  }();
  return path;
}

/// Every method that declares concurrent queries (and its coherent variant), and the EBP-Octree
/// out of core with a 1 MiB cache (split between the threads' caches: evictions happen).
std::vector<std::string> concurrent_specs() {
  std::vector<std::string> out;
  for (const MethodInfo& m : Registry::global().methods()) {
    if (m.testing_only || !m.caps.concurrent_queries) continue;
    out.push_back(m.name);
    if (m.caps.coherence) out.push_back(m.name + ":coherent=true");
  }
  out.push_back("ebp_octree:store=@cow_store,cache_mb=1");
  out.push_back("ebp_octree:store=@cow_store,cache_mb=1,coherent=true");
  return out;
}

std::string resolve(std::string spec) {
  const std::string at = "@cow_store";
  const auto i = spec.find(at);
  if (i != std::string::npos) spec.replace(i, at.size(), cow_store());
  return spec;
}

struct Case {
  std::string spec;
  QueryType query;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.spec << " " << to_string(c.query); }

std::vector<Case> cases() {
  std::vector<Case> out;
  for (const auto& s : concurrent_specs())
    for (QueryType q : {QueryType::inside, QueryType::distance}) out.push_back({s, q});
  return out;
}

std::string case_name(const testing::TestParamInfo<Case>& info) {
  std::string s = info.param.spec + "_" + to_string(info.param.query);
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

QuerySet make_set(const std::string& kind, std::size_t n) {
  QuerySet qs;
  qs.path = kind;
  qs.points = generate_queries(cow(), kind, n, 1, {}, &qs.meta);
  return qs;
}

std::unique_ptr<Method> build(const std::string& spec, QueryType q, const std::vector<std::vector<Vec3d>>& sets) {
  auto m = Registry::global().create(resolve(spec));
  BuildContext ctx;
  ctx.query_type = q;
  ctx.threads = 4;  // the most threads a replay below uses (sizes the out-of-core caches' share)
  for (const auto& s : sets)
    for (const Vec3d& p : s) ctx.query_bounds.add(p);
  m->build(cow(), ctx);
  return m;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same_bits(const Vec3d& a, const Vec3d& b) { return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z); }

/// Answer i of `a` and answer j of `b` are the same, bit for bit.
bool same_answer(const Answers& a, std::size_t i, const Answers& b, std::size_t j) {
  if (a.type == QueryType::inside) return a.inside[i] == b.inside[j];
  return same_bits(a.distance[i], b.distance[j]) && same_bits(a.closest[i], b.closest[j]) &&
         same_bits(a.normal[i], b.normal[j]) && a.triangle[i] == b.triangle[j];
}

/// One thread's answers to `s` through `m` itself, from a reset path.
Answers single_thread(Method& m, QueryType q, const ThreadStream& s) {
  ThreadedReplay one(m, q, {{s.points, s.n, 0}});
  Answers a;
  one.counted_pass(&a);
  return a;
}

class ConcurrentQueries : public testing::TestWithParam<Case> {};

TEST_P(ConcurrentQueries, SplitPointsAnswerAsOneThread) {
  const Case& c = GetParam();
  const QuerySet rnd = make_set("random", kRandom);
  auto m = build(c.spec, c.query, {rnd.points});
  Answers whole;
  ThreadedReplay(*m, c.query, split_streams(rnd.points, 1)).counted_pass(&whole);
  const bool coherent = c.spec.find("coherent=true") != std::string::npos;
  for (int threads : {2, 4}) {
    const std::vector<ThreadStream> parts = split_streams(rnd.points, threads);
    ThreadedReplay replay(*m, c.query, parts);
    ASSERT_EQ(replay.total(), kRandom);
    Answers got;
    replay.counted_pass(&got);
    for (const ThreadStream& part : parts) {
      const Answers ref = single_thread(*m, c.query, part);
      for (std::size_t i = 0; i < part.n; ++i) {
        ASSERT_TRUE(same_answer(got, part.offset + i, ref, i))
            << threads << " threads: query " << part.offset + i << " differs from a single thread's replay of its part";
        if (!coherent) {
          ASSERT_TRUE(same_answer(got, part.offset + i, whole, part.offset + i))
              << threads << " threads: query " << part.offset + i << " differs from the whole set's replay";
        }
      }
    }
  }
}

TEST_P(ConcurrentQueries, HapticProbesAnswerAsOneThreadOnTheirPath) {
  const Case& c = GetParam();
  const QuerySet path = make_set("haptic", kPath);
  ASSERT_TRUE(replays_as_probes(path));
  const auto paths = probe_paths(cow(), path, 4);
  ASSERT_EQ(paths.size(), 4u);
  for (std::size_t k = 1; k < paths.size(); ++k) {
    ASSERT_EQ(paths[k].size(), kPath);
    EXPECT_FALSE(same_bits(paths[k][kPath / 2], paths[0][kPath / 2])) << "probe " << k << " replays probe 0's path";
  }
  EXPECT_EQ(paths[0], path.points);
  auto m = build(c.spec, c.query, paths);
  for (int threads : {2, 4}) {
    const std::vector<std::vector<Vec3d>> mine(paths.begin(), paths.begin() + threads);
    const std::vector<ThreadStream> probes = probe_streams(mine);
    ThreadedReplay replay(*m, c.query, probes);
    ASSERT_EQ(replay.total(), kPath * std::size_t(threads));
    Answers got;
    replay.counted_pass(&got);
    for (const ThreadStream& probe : probes) {
      const Answers ref = single_thread(*m, c.query, probe);
      for (std::size_t i = 0; i < probe.n; ++i)
        ASSERT_TRUE(same_answer(got, probe.offset + i, ref, i))
            << threads << " probes: probe " << probe.offset / kPath << " query " << i
            << " differs from a single thread's replay of its path";
    }
  }
}

TEST_P(ConcurrentQueries, CountersOfAThreadedPassAreDeterministic) {
  const Case& c = GetParam();
  const QuerySet rnd = make_set("random", kRandom);
  const QuerySet path = make_set("haptic", kPath);
  const auto paths = probe_paths(cow(), path, 3);
  auto counted = [&](const std::vector<ThreadStream>& streams) {
    auto m = build(c.spec, c.query, {rnd.points, paths[0], paths[1], paths[2]});  // a fresh instance
    ThreadedReplay replay(*m, c.query, streams);
    Answers a;
    replay.counted_pass(&a);
    return counter_values(replay.counters());
  };
  for (const auto& streams : {split_streams(rnd.points, 4), probe_streams(paths)}) {
    const auto first = counted(streams), second = counted(streams);
    EXPECT_EQ(first, second);
    std::uint64_t work = 0;
    for (const auto& [name, v] : first) work += v;
    EXPECT_GT(work, 0u) << "no work counted";
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, ConcurrentQueries, testing::ValuesIn(cases()), case_name);

/// A method that answers but declares nothing about threads: the default of the interface.
class SingleThreadOnly final : public Method {
 public:
  void build(const Mesh&, const BuildContext&) override {}
  bool inside(const Vec3d& p) override { return p.x < 0; }
  std::size_t structure_bytes() const override { return 1; }
};

TEST(ConcurrentQueriesRefused, WithoutPerThreadStateMoreThanOneThreadIsUnsupported) {
  SingleThreadOnly m;
  m.build(cow(), BuildContext{});
  EXPECT_EQ(m.new_query_state(), nullptr);
  const std::vector<Vec3d> pts = {Vec3d(-1, 0, 0), Vec3d(1, 0, 0), Vec3d(-2, 0, 0)};
  EXPECT_THROW(ThreadedReplay(m, QueryType::inside, split_streams(pts, 2)), UnsupportedError);
  Answers a;
  ThreadedReplay(m, QueryType::inside, split_streams(pts, 1)).counted_pass(&a);  // one thread: fine
  EXPECT_EQ(a.inside, (std::vector<std::uint8_t>{1, 0, 1}));
}

TEST(ConcurrentQueriesRefused, AJobOnMoreThreadsOfAMethodWithoutConcurrencyIsUnsupported) {
  const MethodInfo* fault = Registry::global().find("fault");
  ASSERT_NE(fault, nullptr);
  ASSERT_FALSE(fault->caps.concurrent_queries);
  TmpDir dir("concurrent_queries_job");
  JobSpec spec;
  spec.mesh_path = shared_mesh_path("cow.obj");
  spec.method = Registry::global().describe("fault");
  spec.queries_path = dir.file("q.npy");
  spec.query_type = QueryType::inside;
  spec.threads = 2;
  spec.progress = false;
  // A real query set: the refusal must come from the method's declaration, not from bad input.
  {
    nlohmann::json meta;
    const auto pts = generate_queries(cow(), "random", 10, 1, {}, &meta);
    write_query_set(spec.queries_path, pts, meta);
  }
  const nlohmann::json r = run_job(spec);
  EXPECT_EQ(r["status"], "unsupported") << r.dump(2);
  EXPECT_NE(r["message"].get<std::string>().find("threads"), std::string::npos) << r["message"];
  spec.threads = 1;
  EXPECT_EQ(run_job(spec)["status"], "ok");
}

}  // namespace
