// Fuzz target: `bvhbench compare`'s reading of result files (harness/run/compare.hpp: parse_result,
// the validation that compare relies on), and the comparison itself on what it accepted.
//
// Beyond the contract (fuzz_contract.hpp), an accepted result must go through the whole
// comparison (pairing, counters, accuracy, machine fingerprints, timing statistics, the JSON and
// Markdown reports) without an exception: the input against itself, against a twin whose every
// number differs (so that every counter, accuracy figure, sample and fingerprint field
// changes), and against a twin with other input hashes (paired by job name, so that the inputs
// are reported as changed).
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "fuzz_contract.hpp"
#include "harness/run/compare.hpp"
#include "harness/run/compare_markdown.hpp"

using namespace bvhbench;
using json = nlohmann::json;

namespace {

/// `j` with every number changed, staying of its kind so that the twin still follows the result
/// schema: an integer x to 2 x + 1 (where that fits), any other x to 1.5 x + 1 (where that is
/// finite); booleans and strings as they are.
json numbers_changed(const json& j) {
  if (j.is_object() || j.is_array()) {
    json out = j;
    for (auto it = out.begin(); it != out.end(); ++it) *it = numbers_changed(*it);
    return out;
  }
  if (j.is_number_integer()) {
    const std::int64_t x = j.get<std::int64_t>();
    return (x > -(std::int64_t(1) << 61) && x < (std::int64_t(1) << 61)) ? json(2 * x + 1) : j;
  }
  if (j.is_number()) {
    const double x = 1.5 * j.get<double>() + 1;
    return std::isfinite(x) ? json(x) : j;  // JSON has no infinity: it would print as null
  }
  return j;
}

/// `r` with other mesh and query-set hashes, where it has them.
json hashes_changed(json r) {
  for (const char* part : {"mesh", "queries"})
    if (r.contains("job") && r["job"].is_object() && r["job"].contains(part) && r["job"][part].is_object() &&
        r["job"][part].contains("sha256"))
      r["job"][part]["sha256"] = std::string(64, '0');
  return r;
}

ResultSet set_of(const std::vector<json>& results) {
  ResultSet s;
  s.path = "fuzz";
  for (std::size_t i = 0; i < results.size(); ++i) {
    s.files.push_back("fuzz" + std::to_string(i) + ".json");
    s.results.push_back(results[i]);
  }
  return s;
}

void compare(const ResultSet& base, const ResultSet& fresh, bool timing_gates) {
  CompareOptions opt;
  opt.timing_gates = timing_gates;
  const json report = compare_result_sets(base, fresh, opt);
  (void)report.dump(2);
  (void)compare_markdown(report);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string name = "fuzz.json";
  json r;
  if (!fuzz::accepts(name, [&] { r = parse_result(std::string(fuzz::as_text(data, size)), name); })) return 0;
  const json numbers = numbers_changed(r), hashes = hashes_changed(r);
  // The twins are results as much as the input is: validation must still accept them.
  (void)parse_result(numbers.dump(), "numbers.json");
  (void)parse_result(hashes.dump(), "hashes.json");
  compare(set_of({r}), set_of({r}), true);
  compare(set_of({r}), set_of({numbers}), true);
  compare(set_of({numbers}), set_of({r}), false);
  compare(set_of({r}), set_of({hashes}), true);
  compare(set_of({r, numbers}), set_of({hashes}), true);
  return 0;
}
