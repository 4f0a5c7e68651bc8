// `bvhbench queries`: make a query set (points + sidecar) on a mesh.
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <unistd.h>

#include "harness/cli/commands.hpp"
#include "harness/core/query_set.hpp"
#include "harness/io/mesh_io.hpp"
#include "harness/io/paged_triangles.hpp"
#include "harness/io/query_set_io.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/key_value.hpp"
#include "harness/util/progress.hpp"

namespace bvhbench {

namespace {

/// The points, from the mesh held the cheapest way that gives the same bytes: a kind that needs
/// only the box from a streamed pass over the file; another from the loaded mesh when it fits
/// the memory budget, or else paged from temporary files in `scratch_dir`.
template <class Opts>
std::vector<Vec3d> generate(const QueryKind& kind, const Opts& o, const std::string& scratch_dir,
                            const std::map<std::string, double>& given, nlohmann::json* meta) {
  if (kind.generate_in_box) return generate_queries(summarize_mesh(o.mesh), o.kind, o.n, o.seed, given, meta);
  const std::uint64_t budget = std::uint64_t(o.memory_budget_mb) << 20;
  std::uint64_t need = 0;
  {
    // The header's counts (bounded by the file's size); a format without them (OBJ, STL) by
    // its size, which is more than its mesh holds in memory.
    auto reader = MeshReader::open(o.mesh);
    need = reader->num_triangles() > 0 ? in_memory_generation_bytes(reader->num_vertices(), reader->num_triangles())
                                       : std::filesystem::file_size(o.mesh);
  }
  if (need <= budget) return generate_queries(load_mesh(o.mesh), o.kind, o.n, o.seed, given, meta);
  std::cerr << "queries: " << o.mesh << " needs about " << (need >> 20) << " MiB in memory, over --memory-budget "
            << o.memory_budget_mb << ": paged from temporary files in " << scratch_dir << "\n";
  Progress progress("queries: paging " + o.mesh, double(std::filesystem::file_size(o.mesh)));
  const PagedTriangles paged(o.mesh, ScratchSpace{scratch_dir, std::size_t(budget)}, &progress);
  progress.finish();
  return generate_queries(paged, o.kind, o.n, o.seed, given, meta);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// `bvhbench queries --mesh M --kind K --n N --seed S --out Q.npy [--param k=v ...] [--memory-budget MB]`
// ---------------------------------------------------------------------------------------------
void add_queries_command(CLI::App& app) {
  struct Opts {
    std::string mesh, kind = "random", out;
    std::size_t n = 100000;
    std::uint64_t seed = 1;
    std::vector<std::string> params;
    std::size_t memory_budget_mb = 1024;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = app.add_subcommand("queries", "Generate a query set (NAME.npy + NAME.json)");
  cmd->add_option("--mesh", o->mesh, "Mesh (PLY, OBJ, STL or OFF)")->required();
  cmd->add_option("--kind", o->kind, "Query kind: random, near, haptic, contact, surface ...");
  cmd->add_option("--n", o->n, "Number of points")->check(CLI::PositiveNumber);
  cmd->add_option("--seed", o->seed, "Random seed");
  cmd->add_option("--param", o->params, "Generator parameter key=value (repeatable)");
  cmd->add_option("--out", o->out, "Output .npy (its .json sidecar is written beside it)")->required();
  cmd->add_option("--memory-budget", o->memory_budget_mb,
                  "MiB the generation may hold; a mesh that needs more is paged from temporary files "
                  "beside --out (the same points)")
      ->default_val(1024)
      ->check(CLI::Range(std::size_t(1), std::size_t(1) << 40));
  cmd->callback([o] {
    // Checked against the kind's declaration before the mesh is read (query_set.hpp).
    std::map<std::string, std::string> text;
    for (auto& kv : o->params) add_key_value(kv, "--param", text);
    const QueryKind& kind = query_kind(o->kind);
    const std::map<std::string, double> given = query_param_values(kind, query_kind_params(kind, text));
    if (o->out.size() < 4 || o->out.compare(o->out.size() - 4, 4, ".npy") != 0)
      throw InputError("--out " + o->out + ": must end in .npy");
    // The output folder is checked before the (possibly long) generation: a missing or
    // unwritable folder is bad usage (exit 2), not a failure found minutes later.
    const std::filesystem::path dir = std::filesystem::path(o->out).parent_path().empty()
                                          ? std::filesystem::path(".")
                                          : std::filesystem::path(o->out).parent_path();
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec))
      throw InputError("--out " + o->out + ": folder " + dir.string() + " does not exist");
    if (::access(dir.c_str(), W_OK) != 0)
      throw InputError("--out " + o->out + ": folder " + dir.string() + " is not writable");
    nlohmann::json meta;
    const std::vector<Vec3d> pts = generate(kind, *o, dir.string(), given, &meta);
    try {
      write_query_set(o->out, pts, meta);
    } catch (const std::runtime_error& e) {
      throw InputError(e.what());  // names the file and the reason (e.g. no space left)
    }
  });
}

}  // namespace bvhbench
