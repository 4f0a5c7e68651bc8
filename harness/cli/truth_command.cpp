// `bvhbench truth --mesh M --queries Q --out T.npz [--threads N]`: the exact oracle's answers for
// a query set (Q.npy, Q.xyz or Q.csv; definitions in oracle.hpp, file layout in
// docs/results.md). Not benchmarked, so it uses every core unless told otherwise.
#include <chrono>
#include <iostream>
#include <memory>
#include <thread>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include "harness/cli/commands.hpp"
#include "harness/core/mesh.hpp"
#include "harness/core/oracle.hpp"
#include "harness/core/query_set.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/io/oracle_file.hpp"
#include "harness/io/query_set_io.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/progress.hpp"

namespace bvhbench {

void add_truth_command(CLI::App& app) {
  struct Opts {
    std::string mesh, queries, out;
    int threads = 0;
    double tie_tolerance = 1e-12;
    bool quiet = false;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = app.add_subcommand("truth", "Compute exact oracle answers (inside, winding, distance, closest "
                                          "triangle with ties) for a query set");
  cmd->add_option("--mesh", o->mesh, "Mesh (PLY, OBJ, STL or OFF)")->required();
  cmd->add_option("--queries", o->queries,
                  "Query set: .npy (float64/float32, N x 3) or .xyz/.csv text, one point a line; a "
                  ".json sidecar beside it is optional")
      ->required();
  cmd->add_option("--out", o->out, "Oracle file .npz")->required();
  cmd->add_option("--threads", o->threads, "Threads (default: all cores)")->check(CLI::Range(0, 1024));
  cmd->add_option("--tie-tolerance", o->tie_tolerance,
                  "Triangles within this fraction of the diagonal of the minimum distance are ties")
      ->check(CLI::Range(0.0, 1e-3));
  cmd->add_flag("--quiet", o->quiet, "No timings on stderr");
  cmd->callback([o] {
    using Clock = std::chrono::steady_clock;
    const int threads = o->threads > 0 ? o->threads : int(std::max(1u, std::thread::hardware_concurrency()));
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    const bool verbose = !o->quiet;
    auto t0 = Clock::now();
    const QuerySet queries = load_query_set(o->queries);
    const std::vector<Vec3d>& pts = queries.points;
    const std::string& qsha = queries.sha256;
    Mesh mesh = load_mesh(o->mesh);
    auto t1 = Clock::now();
    Oracle oracle(mesh, o->tie_tolerance, verbose);
    auto t2 = Clock::now();
    OracleAnswers a = oracle.answer(pts);
    auto t3 = Clock::now();
    write_oracle_npz(o->out, a, mesh.sha256, qsha);
    auto sec = [](auto d) { return std::chrono::duration<double>(d).count(); };
    std::string defined;
    for (const std::string& d : a.definitions) defined += (defined.empty() ? "" : ", ") + d;
    if (verbose) std::cerr << "truth: definitions of inside defined on this mesh: " << defined << "\n";
    if (verbose)
      std::cerr << "truth: " << pts.size() << " queries on " << mesh.num_triangles() << " triangles ("
                << a.definition << "), " << threads << " thread(s): load " << sec(t1 - t0) << " s, build "
                << sec(t2 - t1) << " s, queries " << sec(t3 - t2) << " s ("
                << (sec(t3 - t2) > 0 ? double(pts.size()) / sec(t3 - t2) : 0.0) << " q/s)\n";
  });
}

}  // namespace bvhbench
