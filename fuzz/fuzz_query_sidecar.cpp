// Fuzz target: the check of a query set's sidecar JSON (harness/query_set.hpp: parse_sidecar),
// for a query set of 3 points.
//
// Beyond the contract (fuzz_contract.hpp), an accepted sidecar must give what the runner reads
// from it without a JSON type error: the kind (a string), the seed and the mesh hash as values
// of the result JSON, which must print.
#include <cstddef>
#include <cstdint>

#include "fuzz_contract.hpp"
#include "query_set.hpp"

using namespace bvhbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string name = "fuzz.json";
  QuerySet q;
  if (!fuzz::accepts(name, [&] { q.meta = parse_sidecar(fuzz::as_text(data, size), name, "fuzz.npy", 3); })) return 0;
  // As run_job does.
  const nlohmann::json job = {{"kind", q.kind()},
                              {"n", 3},
                              {"seed", q.meta.value("seed", nlohmann::json(nullptr))},
                              {"mesh_sha256", q.meta.value("mesh_sha256", nlohmann::json(nullptr))},
                              {"mesh_mismatch", q.meta.contains("mesh_sha256") && q.meta["mesh_sha256"] != "0123"}};
  (void)job.dump();
  return 0;
}
