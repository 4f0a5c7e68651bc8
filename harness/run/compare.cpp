// `bvhbench compare BASE NEW`: pairs the jobs of two result sets and says, per pair, whether
// anything changed. Design and rationale: docs/compare.md.
#include "harness/run/compare.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "harness/run/compare_format.hpp"
#include "harness/run/mann_whitney.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/json_path.hpp"
#include "harness/util/printable.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

using namespace compare_format;

namespace {



double median_of(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size();
  return m % 2 ? v[m / 2] : 0.5 * (v[m / 2 - 1] + v[m / 2]);
}

/// A human name for a job: the suite's id, else what identifies it.
std::string job_label(const json& r) {
  std::string id = str(json_at(r, {"job", "id"}));
  if (!id.empty()) return id;
  std::string mesh = str(json_at(r, {"job", "mesh", "name"}));
  if (mesh.empty()) mesh = fs::path(str(json_at(r, {"job", "mesh", "path"}), "?")).stem().string();
  std::string q = str(json_at(r, {"job", "queries", "kind"}));
  if (q.empty()) q = fs::path(str(json_at(r, {"job", "queries", "path"}), "?")).stem().string();
  const json& n = json_at(r, {"job", "queries", "n"});
  if (n.is_number()) q += "-n" + show(n);  // not get<long long>(): a float beyond its range is undefined
  std::string spec = str(json_at(r, {"job", "method_spec"}), str(json_at(r, {"job", "method"})));
  return mesh + "__" + q + "__" + str(json_at(r, {"job", "query"}), "?") + "__" + spec;
}

/// The pairing key of the contract: method, resolved parameters, mesh sha256, query-set
/// sha256, query type. Empty when the result does not carry them all (e.g. a status row written
/// for a job whose child crashed before it read its inputs).
std::string primary_key(const json& r) {
  const json& msha = json_at(r, {"job", "mesh", "sha256"});
  const json& qsha = json_at(r, {"job", "queries", "sha256"});
  const json& query = json_at(r, {"job", "query"});
  if (!msha.is_string() || !qsha.is_string() || !query.is_string()) return "";
  const json& params = json_at(r, {"job", "params"});
  return str(json_at(r, {"job", "method"})) + "|" + (params.is_object() ? params.dump() : "{}") + "|" +
         msha.get<std::string>() + "|" + qsha.get<std::string>() + "|" + query.get<std::string>();
}

/// The fallback key for results without hashes: the job's name as the suite wrote it.
std::string secondary_key(const json& r) {
  const json& n = json_at(r, {"job", "queries", "n"});
  const json& seed = json_at(r, {"job", "queries", "seed"});
  return job_label(r) + "|" + (n.is_number() ? n.dump() : "") + "|" + (seed.is_number() ? seed.dump() : "");
}

/// Leaves of a JSON tree as "a.b.c" -> value. File paths are not results: skipped.
void flatten(const json& j, const std::string& prefix, std::map<std::string, json>* out) {
  if (j.is_object()) {
    for (auto& [k, v] : j.items()) {
      if (k == "truth" || k == "path" || (k.size() > 5 && k.compare(k.size() - 5, 5, "_path") == 0)) continue;
      flatten(v, prefix.empty() ? k : prefix + "." + k, out);
    }
  } else {
    (*out)[prefix] = j;
  }
}

/// One leaf path of either of two JSON trees, with its value in each (null where it is absent).
struct PairedLeaf {
  std::string path;
  json base, fresh;
};

/// The union of the leaves (flatten) of two trees, sorted by path.
std::vector<PairedLeaf> paired_leaves(const json& base, const json& fresh) {
  std::map<std::string, json> fb, fn;
  flatten(base, "", &fb);
  flatten(fresh, "", &fn);
  std::vector<PairedLeaf> out;
  for (auto& [k, v] : fb) out.push_back({k, v, fn.count(k) ? fn[k] : json(nullptr)});
  for (auto& [k, v] : fn)
    if (!fb.count(k)) out.push_back({k, json(nullptr), v});
  std::sort(out.begin(), out.end(), [](const PairedLeaf& x, const PairedLeaf& y) { return x.path < y.path; });
  return out;
}

/// Whether leaf `dotted` (a path as flatten writes it) is in `tree`: a leaf only the fresh result
/// has is a field added to its block since the baseline was made (what a method's inside is
/// judged against, say), news rather than a change.
bool has_leaf(const json& tree, const std::string& dotted) {
  std::map<std::string, json> leaves;
  flatten(tree, "", &leaves);
  return leaves.count(dotted) != 0;
}

bool same_value(const json& a, const json& b, double rtol) {
  if (a.is_number() && b.is_number()) {
    const double x = a.get<double>(), y = b.get<double>();
    if (x == y) return true;
    // Integers (counts) are exact; a tolerance only for floating summaries.
    if (!a.is_number_float() && !b.is_number_float()) return false;
    return std::fabs(x - y) <= rtol * std::max(std::fabs(x), std::fabs(y));
  }
  return a == b;
}


/// A short name for a machine fingerprint, for the report's header: CPU and widest vector ISA.
std::string fingerprint_label(const json& fp) {
  if (!fp.is_object()) return "(no fingerprint)";
  const json& cpu = json_at(fp, {"cpu"});
  std::string s = str(json_at(cpu, {"vendor"}), str(json_at(cpu, {"arch"}), "?"));
  if (json_at(cpu, {"family"}).is_number()) s += " family " + json_at(cpu, {"family"}).dump();
  if (json_at(cpu, {"model"}).is_number()) s += " model " + json_at(cpu, {"model"}).dump();
  auto has = [&](const char* f) { return json_at(fp, {"isa", f}) == json(true); };
  const char* widest = has("avx512f") && has("avx512dq") && has("avx512cd") && has("avx512bw") && has("avx512vl")
                           ? "avx512"
                       : has("avx2") && has("fma") ? "avx2"
                       : has("avx")                ? "avx"
                       : has("sse4.2")             ? "sse4.2"
                       : has("sse2")               ? "sse2"
                                                   : "?";
  return s + ", " + widest;
}

/// The reason machine-dependent counters of this pair are not gated, or "" when they are: both
/// results carry a machine fingerprint and the two are equal. `diffs` receives the differences.
std::string machine_not_gated_reason(const json& b, const json& n, std::vector<std::string>* diffs) {
  const json& fb = json_at(b, {"machine_dependent", "fingerprint"});
  const json& fn = json_at(n, {"machine_dependent", "fingerprint"});
  if (!fb.is_object()) return "the baseline has no machine fingerprint (made before results recorded one)";
  if (!fn.is_object()) return "the new result has no machine fingerprint";
  *diffs = fingerprint_differences(fb, fn);
  if (diffs->empty()) return "";
  std::string s = "machine fingerprints differ: ";
  for (std::size_t i = 0; i < diffs->size(); ++i) s += (i ? ", " : "") + (*diffs)[i];
  return s;
}

std::vector<double> qps_samples(const json& r) {
  std::vector<double> v;
  for (auto& s : json_at(r, {"queries", "throughput_qps", "samples"}))
    if (s.is_number()) v.push_back(s.get<double>());
  return v;
}

/// Throughput statistics of one pair, normalised by each side's calibration when both have one.
json timing_block(const json& b, const json& n, const CompareOptions& opt) {
  json t;
  std::vector<double> xb = qps_samples(b), xn = qps_samples(n);
  t["n_base"] = xb.size();
  t["n_new"] = xn.size();
  t["base_qps_median"] = xb.empty() ? json(nullptr) : json(median_of(xb));
  t["new_qps_median"] = xn.empty() ? json(nullptr) : json(median_of(xn));
  const json& cb = json_at(b, {"calibration", "median_seconds"});
  const json& cn = json_at(n, {"calibration", "median_seconds"});
  const std::string kb = str(json_at(b, {"calibration", "kernel"})), kn = str(json_at(n, {"calibration", "kernel"}));
  const bool calibrated = cb.is_number() && cn.is_number() && cb.get<double>() > 0 && cn.get<double>() > 0 && kb == kn;
  t["calibrated"] = calibrated;
  t["base_calibration_s"] = cb;
  t["new_calibration_s"] = cn;
  std::string note;
  if (calibrated) {
    // qps x kernel seconds: the same on a machine k times slower, where both scale by k.
    for (double& v : xb) v *= cb.get<double>();
    for (double& v : xn) v *= cn.get<double>();
  } else if (kb != kn && !kb.empty() && !kn.empty()) {
    note = "calibration kernels differ (" + kb + " vs " + kn + "): raw throughput compared";
  } else {
    note = std::string("no calibration in ") + (cb.is_number() ? "NEW" : cn.is_number() ? "BASE" : "either set") +
           ": raw throughput compared";
  }
  if (xb.empty() || xn.empty()) {
    t["verdict"] = "unchanged";
    t["change"] = nullptr;
    t["p_value"] = nullptr;
    t["note"] = "no per-repetition throughput samples: not compared";
    return t;
  }
  const double mb = median_of(xb), mn = median_of(xn);
  const double change = mb > 0 ? mn / mb - 1 : 0;
  MannWhitney mw = mann_whitney_u(xb, xn);
  t["change"] = change;
  t["p_value"] = mw.p_value;
  t["test"] = mw.exact ? "mann-whitney exact" : "mann-whitney normal";
  // The smallest p-value the test can reach with these sizes (both samples fully separated):
  // below alpha only with enough repetitions (5 per side at alpha 0.01).
  std::string verdict = "unchanged";
  if (std::fabs(change) > opt.threshold && mw.p_value < opt.alpha) verdict = change < 0 ? "regressed" : "improved";
  else if (std::fabs(change) > opt.threshold)
    note += std::string(note.empty() ? "" : "; ") + "beyond threshold but not significant (p=" + fmt(mw.p_value, "%.3g") + ")";
  t["verdict"] = verdict;
  if (!note.empty()) t["note"] = note;
  return t;
}

json side_info(const ResultSet& s) {
  std::set<std::string> hosts, commits, cpus, machines;
  for (auto& r : s.results) {
    if (str(json_at(r, {"status"})) == "ok") machines.insert(fingerprint_label(json_at(r, {"machine_dependent", "fingerprint"})));
    std::string h = str(json_at(r, {"context", "host"}));
    if (!h.empty()) hosts.insert(h);
    std::string c = str(json_at(r, {"context", "git_commit"}));
    // printable(): a cut may split a UTF-8 sequence, and the set goes into the JSON report.
    if (!c.empty()) commits.insert(printable(c.substr(0, 12)) + (json_at(r, {"context", "git_dirty"}) == json(true) ? "+dirty" : ""));
    std::string cpu = str(json_at(r, {"context", "cpu_model"}));
    if (!cpu.empty()) cpus.insert(cpu);
  }
  return {{"path", s.path}, {"results", s.results.size()}, {"hosts", hosts}, {"commits", commits}, {"cpus", cpus},
          {"machines", machines}};
}

/// A row being decided: its JSON, the reasons found so far, its verdict and whether it gates.
struct Row {
  json p;
  json reasons = json::array();
  std::string verdict;
  bool gates = false;
  void reason(const std::string& code, const std::string& detail) {
    reasons.push_back({{"code", code}, {"detail", detail}});
  }
};

/// What names the pair's job in a row.
json row_header(const json& any) {
  json p;
  p["job"] = job_label(any);
  p["method"] = str(json_at(any, {"job", "method"}));
  p["params_key"] = str(json_at(any, {"job", "params_key"}));
  p["mesh"] = str(json_at(any, {"job", "mesh", "name"}));
  p["query_kind"] = str(json_at(any, {"job", "queries", "kind"}));
  p["query"] = str(json_at(any, {"job", "query"}));
  return p;
}

/// The inputs in which a pair paired by job id differs (a query generator, a mesh file or a
/// default parameter changed): then the deterministic figures cannot be compared, the baseline
/// is stale. "" when none. Parameters are compared only when both are ok (status rows carry
/// unresolved ones); of an object, only the keys that differ are named.
std::string changed_inputs(const json& b, const json& n, bool both_ok) {
  std::string inputs;
  auto add = [&](const std::string& item) { inputs += (inputs.empty() ? "" : ", ") + item; };
  auto differs = [&](std::initializer_list<const char*> path, const char* what, bool both_ok_only) {
    const json& x = json_at(b, path);
    const json& y = json_at(n, path);
    if (both_ok_only && !both_ok) return;
    if (x.is_null() || y.is_null() || x == y) return;
    if (x.is_object() && y.is_object()) {
      std::set<std::string> keys;
      for (auto& [k, v] : x.items()) keys.insert(k);
      for (auto& [k, v] : y.items()) keys.insert(k);
      for (auto& k : keys) {
        const json vx = x.contains(k) ? x[k] : json(nullptr), vy = y.contains(k) ? y[k] : json(nullptr);
        if (vx != vy) add(std::string(what) + " " + k + " " + show(vx) + " -> " + show(vy));
      }
      return;
    }
    add(std::string(what) + " " + (x.is_string() ? printable(x.get<std::string>().substr(0, 16)) : x.dump()) + " -> " +
        (y.is_string() ? printable(y.get<std::string>().substr(0, 16)) : y.dump()));
  };
  differs({"job", "mesh", "sha256"}, "mesh sha256", false);
  differs({"job", "queries", "sha256"}, "query-set sha256", false);
  differs({"job", "method"}, "method", true);
  differs({"job", "params"}, "params", true);
  differs({"job", "query"}, "query", false);
  return inputs;
}

std::string changes_text(const json& list, const char* name_key) {
  std::string d;
  for (auto& c : list) d += (d.empty() ? "" : ", ") + c[name_key].get<std::string>() + " " + change_text(c["base"], c["new"]);
  return d;
}

/// The counters of two ok results. Those NEW declares machine-dependent (its code knows best)
/// gate exactly only when both sides carry the same machine fingerprint; otherwise they are
/// reported. Returns whether a gating counter changed.
bool compare_counters(const json& b, const json& n, Row& row) {
  std::set<std::string> machine;
  for (auto& v : json_at(n, {"machine_dependent", "counters"})) machine.insert(v.get<std::string>());
  std::vector<std::string> fp_diffs;
  const std::string not_gated_why = machine.empty() ? "" : machine_not_gated_reason(b, n, &fp_diffs);
  json counters = json::array(), counters_not_gated = json::array();
  std::size_t not_gated_values = 0;
  auto object_at = [](const json& r) { return json_at(r, {"counters"}).is_object() ? json_at(r, {"counters"}) : json::object(); };
  for (auto& [k, vb, vn] : paired_leaves(object_at(b), object_at(n))) {
    const bool changed = !same_value(vb, vn, 0.0);
    // A counter that appears or disappears is a change of the method's code: it gates.
    if (!not_gated_why.empty() && machine.count(k) && !vb.is_null() && !vn.is_null()) {
      ++not_gated_values;
      if (changed) counters_not_gated.push_back({{"name", k}, {"base", vb}, {"new", vn}});
    } else if (changed) {
      counters.push_back({{"name", k}, {"base", vb}, {"new", vn}});
    }
  }
  if (!counters.empty()) {
    row.reason("counters_changed", changes_text(counters, "name"));
    row.p["counters"] = counters;
  }
  if (!machine.empty())
    row.p["machine_dependent"] = {{"counters", machine},
                                  {"gated", not_gated_why.empty()},
                                  {"not_gated_because", not_gated_why.empty() ? json(nullptr) : json(not_gated_why)},
                                  {"fingerprint_differences", fp_diffs},
                                  {"values_not_gated", not_gated_values}};
  if (!counters_not_gated.empty()) {
    row.reason("machine_counters_not_gated", changes_text(counters_not_gated, "name") + "; not gated: " + not_gated_why);
    row.p["counters_not_gated"] = counters_not_gated;
  }
  return !counters.empty();
}

/// The accuracy of two ok results, within opt.rtol. Returns whether it changed.
bool compare_accuracy(const json& b, const json& n, const CompareOptions& opt, Row& row) {
  json accuracy = json::array();
  const json& ab = json_at(b, {"accuracy"});
  const json& an = json_at(n, {"accuracy"});
  if (ab.is_null() != an.is_null()) {
    accuracy.push_back({{"field", "accuracy"}, {"base", ab.is_null() ? "none" : "measured"}, {"new", an.is_null() ? "none" : "measured"}});
  } else if (!ab.is_null()) {
    for (auto& [k, vb, vn] : paired_leaves(ab, an))
      if (!same_value(vb, vn, opt.rtol) && !(vb.is_null() && !has_leaf(ab, k)))
        accuracy.push_back({{"field", k}, {"base", vb}, {"new", vn}});
  }
  if (accuracy.empty()) return false;
  row.reason("accuracy_changed", changes_text(accuracy, "field"));
  row.p["accuracy"] = accuracy;
  return true;
}

/// Both ok: deterministic work first, then accuracy, then timing.
void compare_ok_pair(const json& b, const json& n, const CompareOptions& opt, Row& row) {
  const bool counters_changed = compare_counters(b, n, row);
  const bool accuracy_changed = compare_accuracy(b, n, opt, row);
  const json& bb = json_at(b, {"build", "structure_bytes"});
  const json& bn = json_at(n, {"build", "structure_bytes"});
  if (bb.is_number() && bn.is_number() && bb != bn) row.p["structure_bytes"] = {{"base", bb}, {"new", bn}};

  json t = timing_block(b, n, opt);
  const std::string tv = t["verdict"];
  row.p["timing"] = t;
  if (tv != "unchanged") {
    const bool tg = opt.timing_gates && tv == "regressed";
    row.reason(tv == "regressed" ? "throughput_regressed" : "throughput_improved",
               "normalised throughput " + fmt(100 * t["change"].get<double>(), "%+.1f") + "%, p=" +
                   fmt(t["p_value"].get<double>(), "%.2g") + (tv == "regressed" && !opt.timing_gates ? " (reported, not gating)" : ""));
    row.gates = row.gates || tg;
  }
  if (counters_changed || accuracy_changed) {
    row.verdict = "regressed";  // any change of deterministic work or accuracy: rebaseline or fix
    row.gates = true;
  } else {
    row.verdict = tv;
  }
}

/// A pair present on both sides: inputs, then statuses, then (both ok) the figures.
void compare_both(const json& b, const json& n, const CompareOptions& opt, Row& row) {
  const std::string sb = str(json_at(b, {"status"})), sn = str(json_at(n, {"status"}));
  row.p["status"] = {{"base", sb}, {"new", sn}};
  const std::string inputs = changed_inputs(b, n, sb == "ok" && sn == "ok");
  if (!inputs.empty()) row.reason("inputs_changed", inputs);
  if (sb == "ok" && sn != "ok") {
    row.verdict = "failed";
    row.gates = true;
    row.reason("failed", "status ok -> " + sn + (str(json_at(n, {"message"})).empty() ? "" : ": " + str(json_at(n, {"message"}))));
  } else if (sb != "ok" && sn == "ok") {
    row.verdict = "improved";
    row.reason("fixed", "status " + sb + " -> ok");
  } else if (sb != sn) {
    row.verdict = "regressed";
    row.gates = true;
    row.reason("status_changed", "status " + sb + " -> " + sn);
  } else if (sb != "ok") {
    row.verdict = "unchanged";
  } else {
    compare_ok_pair(b, n, opt, row);
  }
}

/// One row: everything known about a (base, new) pair. Either may be null (missing / new).
json compare_pair(const json* b, const json* n, const CompareOptions& opt) {
  Row row;
  row.p = row_header(b ? *b : *n);
  if (!n) {
    row.verdict = "missing";
    row.gates = !opt.ignore_missing;
    row.reason("missing", "in BASE, not in NEW");
  } else if (!b) {
    row.verdict = "new";
    row.reason("new", "in NEW, not in BASE");
  } else {
    compare_both(*b, *n, opt, row);
  }
  if (!row.reasons.empty() && row.reasons[0]["code"] == "inputs_changed") {
    row.gates = true;
    if (row.verdict == "unchanged" || row.verdict == "improved") row.verdict = "regressed";
  }
  row.p["verdict"] = row.verdict;
  row.p["reasons"] = row.reasons;
  row.p["gates"] = row.gates;
  return row.p;
}

/// Pairs results in stages: same primary key and same job id; same primary key; same
/// secondary key (results without hashes, such as status rows of crashed jobs).
std::vector<std::pair<const json*, const json*>> pair_up(const ResultSet& base, const ResultSet& fresh) {
  std::vector<bool> used_b(base.results.size()), used_n(fresh.results.size());
  std::vector<std::pair<const json*, const json*>> pairs;
  using KeyFn = std::string (*)(const json&);
  const KeyFn stages[] = {
      [](const json& r) { std::string k = primary_key(r); return k.empty() ? k : k + "#" + str(json_at(r, {"job", "id"})); },
      [](const json& r) { return primary_key(r); },
      [](const json& r) { return secondary_key(r); },
  };
  for (KeyFn key : stages) {
    std::multimap<std::string, std::size_t> by_key;
    for (std::size_t i = 0; i < fresh.results.size(); ++i)
      if (!used_n[i]) {
        std::string k = key(fresh.results[i]);
        if (!k.empty()) by_key.emplace(k, i);
      }
    for (std::size_t i = 0; i < base.results.size(); ++i) {
      if (used_b[i]) continue;
      std::string k = key(base.results[i]);
      if (k.empty()) continue;
      auto it = by_key.find(k);
      if (it == by_key.end()) continue;
      pairs.push_back({&base.results[i], &fresh.results[it->second]});
      used_b[i] = used_n[it->second] = true;
      by_key.erase(it);
    }
  }
  for (std::size_t i = 0; i < base.results.size(); ++i)
    if (!used_b[i]) pairs.push_back({&base.results[i], nullptr});
  for (std::size_t i = 0; i < fresh.results.size(); ++i)
    if (!used_n[i]) pairs.push_back({nullptr, &fresh.results[i]});
  return pairs;
}

int severity(const json& p) {
  static const std::map<std::string, int> order = {{"failed", 0}, {"regressed", 1}, {"missing", 2},
                                                   {"improved", 3}, {"new", 4}, {"unchanged", 5}};
  auto it = order.find(p["verdict"].get<std::string>());
  return (p["gates"].get<bool>() ? 0 : 10) + (it == order.end() ? 9 : it->second);
}

}  // namespace

std::vector<std::string> fingerprint_differences(const json& base, const json& fresh) {
  std::vector<std::string> out;
  for (auto& [k, vb, vn] : paired_leaves(base, fresh))
    if (vb != vn) out.push_back(k + " " + show(vb) + " -> " + show(vn));
  return out;
}

json compare_result_sets(const ResultSet& base, const ResultSet& fresh, const CompareOptions& opt) {
  json rows = json::array();
  for (auto& [b, n] : pair_up(base, fresh)) rows.push_back(compare_pair(b, n, opt));
  std::stable_sort(rows.begin(), rows.end(), [](const json& a, const json& b) {
    int sa = severity(a), sb = severity(b);
    return sa != sb ? sa < sb : a["job"].get<std::string>() < b["job"].get<std::string>();
  });
  json summary = {{"failed", 0}, {"regressed", 0}, {"missing", 0}, {"improved", 0}, {"new", 0}, {"unchanged", 0}};
  int gating = 0;
  std::size_t ng_jobs = 0, ng_values = 0, ng_changed = 0;
  std::set<std::string> ng_why;
  for (auto& r : rows) {
    summary[r["verdict"].get<std::string>()] = summary[r["verdict"].get<std::string>()].get<int>() + 1;
    gating += r["gates"].get<bool>() ? 1 : 0;
    if (!r.contains("machine_dependent") || r["machine_dependent"]["gated"].get<bool>()) continue;
    const std::size_t values = r["machine_dependent"]["values_not_gated"].get<std::size_t>();
    if (values == 0) continue;
    ++ng_jobs;
    ng_values += values;
    ng_changed += r.contains("counters_not_gated") ? r["counters_not_gated"].size() : 0;
    ng_why.insert(r["machine_dependent"]["not_gated_because"].get<std::string>());
  }
  summary["gating"] = gating;
  // Machine-dependent counter values compared under differing (or missing) fingerprints.
  summary["not_gated"] = {{"jobs", ng_jobs}, {"counters", ng_values}, {"changed", ng_changed}, {"why", ng_why}};
  return {{"schema", "bvhbench.compare/1"},
          {"base", side_info(base)},
          {"new", side_info(fresh)},
          {"options",
           {{"threshold", opt.threshold},
            {"alpha", opt.alpha},
            {"timing", opt.timing_gates ? "gate" : "report"},
            {"ignore_missing", opt.ignore_missing},
            {"rtol", opt.rtol}}},
          {"summary", summary},
          {"pairs", rows},
          {"exit_code", gating ? 1 : 0}};
}

}  // namespace bvhbench
