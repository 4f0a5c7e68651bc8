#pragma once
/// The method interface: the one seam between the harness and a spatial query structure.
///
/// Lifecycle (driven by run_job.cpp):
///   1. the registry creates the method from validated Params;
///   2. build(mesh, ctx) once; the harness times it and then *releases the mesh*, so a method
///      keeps its own copy of what queries need (and its structure_bytes() says how much);
///   3. for each replay pass: reset_path(), then inside(p) or distance(p) for every query,
///      in the query set's order (haptic paths are sequences; coherent methods may carry state
///      from one query to the next, declared as a parameter);
///   4. counters() are read after the counted pass, structure_bytes() after build.
/// Virtual calls happen here, once per query, never per primitive.
///
/// Threads (a job's `threads` T > 1): a method whose queries may run concurrently hands out one
/// QueryState per thread over its shared, built structure (new_query_state()); each thread replays
/// its own part of the queries through its own state, with its own path state and counters. A
/// method that hands out none is `unsupported` for T > 1: never run from two threads at once.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/geometry.hpp"
#include "harness/core/params.hpp"

namespace bvhbench {

struct Mesh;
struct MeshSummary;
class Progress;

enum class QueryType { inside, distance };
const char* to_string(QueryType q);
QueryType parse_query_type(const std::string& s);  ///< "inside" | "distance"; InputError otherwise

/// Answer to a distance query at p.
struct DistanceResult {
  double distance = 0;   ///< signed: negative inside the solid
  Vec3d closest;         ///< closest point on the surface
  Vec3d normal;          ///< unit outward normal of the closest triangle (the contact normal)
  std::int64_t triangle = -1;  ///< index of the closest triangle in the input mesh, -1 if unknown
};

/// Whose threads build the structure: the job's build threads (a job's T, the same for every
/// method that can use them), one thread, or threads a library picks by itself (unknown here).
enum class BuildThreads { job, one, library };

struct Capabilities {
  bool inside = false;
  bool distance = false;
  bool closest_triangle = false;  ///< distance() fills `triangle`
  bool coherence = false;         ///< has a coherent (path-state) variant as a parameter
  bool out_of_core = false;
  /// Hands out per-thread query states (Method::new_query_state): runs at threads > 1. Declared
  /// here so that `bvhbench methods` and a suite can tell before building; false by default.
  bool concurrent_queries = false;
  /// Takes another configuration's query options over its built structure
  /// (Method::set_query_options): a suite builds once for configurations that differ only in
  /// options of ParamRole::query (coherent, a vote, a cache budget) and runs them one after another.
  bool query_options_after_build = false;
  /// What a result records as build.threads: T, 1, or null (the library's own choice).
  BuildThreads build_threads = BuildThreads::one;
};

/// A named work counter, summed over the queries since reset_counters().
struct Counter {
  std::string name;   ///< snake_case, e.g. "nodes_visited", "triangles_tested"
  std::uint64_t value = 0;
};

/// What build() may use besides the mesh.
struct BuildContext {
  int threads = 1;                       ///< job's thread budget (1 = single thread)
  QueryType query_type = QueryType::inside;  ///< what will be asked: build only what it needs
  Box3d query_bounds;                    ///< box of the query points (to size bands, caches)
  std::string query_kind;                ///< "random", "haptic", ... (informative)
  // No temporary folder or memory budget: no method builds out of core inside a job. The
  // EBP-Octree's out-of-core build is `bvhbench ebp build --memory-budget --tmp`, whose store a
  // job then reads (ebp_octree:store=FILE).
  Progress* progress = nullptr;          ///< optional; methods may create their own
};

/// What one thread asks with: the queries, the state carried from one query to the next along a
/// path, and the work counters. A Method is one (its own, for a single thread); a method that
/// declares concurrent queries makes more (Method::new_query_state), one per thread.
///
/// Cache-line aligned, so that the states of two threads never share a line: each writes its
/// counters and path state in the hot loop (false sharing would serialise them at many threads).
class alignas(64) QueryState {
 public:
  virtual ~QueryState() = default;

  /// Point-in-solid. Default: unsupported.
  virtual bool inside(const Vec3d& p);
  /// Signed distance, closest point, contact normal, closest triangle. Default: unsupported.
  virtual DistanceResult distance(const Vec3d& p);

  /// Forgets state carried between consecutive queries (called before each replay pass).
  virtual void reset_path() {}

  /// Work counters since the last reset_counters() (totals, not means).
  virtual std::vector<Counter> counters() const { return {}; }
  virtual void reset_counters() {}
};

class Method : public QueryState {
 public:
  /// Builds the structure. May throw InputError (input it refuses), UnsupportedError, or
  /// anything else (becomes status `error`).
  virtual void build(const Mesh& mesh, const BuildContext& ctx) = 0;

  /// Whether the structure is read from a file (a prebuilt store) and needs the mesh's summary
  /// alone: a job then calls open() with a summary made by a streamed pass over the mesh file,
  /// never loading the mesh (a 128M-triangle model is 3 GB in memory), in place of build().
  /// Default: false.
  virtual bool reads_structure() const { return false; }
  /// For a method that reads_structure(): opens the structure, checking that it was made from
  /// `mesh` (its triangle count, its file's sha256). The default throws std::logic_error.
  virtual void open(const MeshSummary& mesh, const BuildContext& ctx);

  /// Whether this instance, with its options, answers q, where that is narrower than what the
  /// method registered (MethodInfo::caps, where capabilities are said): a Python method asks its
  /// module. Default: as registered. Read through answers() (registry.hpp).
  virtual bool supports(QueryType) const { return true; }

  /// A new query state over this method's built structure, for one more thread. Called after
  /// build(), never concurrently with itself; the state may then run on any one thread at the
  /// same time as this method's own queries and every other state's, and answers exactly as this
  /// method would on the same sequence of queries (the same answers, path state and counters).
  /// It must not outlive the method. nullptr (the default): this method's queries must never run
  /// concurrently, and a job with threads > 1 is `unsupported`. A method that returns states
  /// declares Capabilities::concurrent_queries.
  virtual std::unique_ptr<QueryState> new_query_state() const { return nullptr; }

  /// The query options (ParamRole::query) of another configuration of this method, whose build
  /// options are this one's: the queries and query states that follow ask as it would, over the
  /// structure already built, with fresh path state and counters. Called after build(), between
  /// jobs, never during queries. A method that overrides it declares
  /// Capabilities::query_options_after_build; the default throws std::logic_error.
  virtual void set_query_options(const Params& params);

  /// Bytes of the method's own structure, including its copy of the geometry.
  virtual std::size_t structure_bytes() const = 0;

  /// The options the structure itself decides, by option name, as text its declaration reads:
  /// for a structure read from a file (a prebuilt store), the options it was built with, and any
  /// query option it cannot honour, as it runs. A result records these in place of the spec's,
  /// so that it states what ran. Read after build(). Default: none (the structure was built
  /// from the spec's options).
  virtual std::map<std::string, std::string> build_options_read() const { return {}; }

  /// For a structure read from a file: the threads it was built with, as the file records them
  /// (JSON null where the file does not say). A result records this as build.threads, not the
  /// job's T. Read after build(). Default: nullopt, the job built the structure itself.
  virtual std::optional<nlohmann::json> build_threads_read() const { return std::nullopt; }

  /// Facts about the built structure worth recording (levels, node counts, ...).
  virtual nlohmann::json info() const { return nlohmann::json::object(); }

  /// What a library this method calls chose on this machine that its machine-dependent counters
  /// (MethodInfo::machine_dependent_counters) depend on, as far as the library tells (e.g.
  /// Embree's native SIMD widths). Read after the counted pass; it becomes part of the result's
  /// machine fingerprint. Default: nothing to add.
  virtual nlohmann::json machine_facts() const { return nlohmann::json::object(); }
};

}  // namespace bvhbench
