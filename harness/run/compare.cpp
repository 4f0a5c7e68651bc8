// `bvhbench compare BASE NEW`: pairs the jobs of two result sets and says, per pair, whether
// anything changed. Design and rationale: docs/compare.md.
#include "harness/run/compare.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include <CLI/CLI.hpp>

#include "harness/run/result_schema.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/json_input.hpp"
#include "harness/util/json_path.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

// ---------------------------------------------------------------------------------------------
// Mann-Whitney U
// ---------------------------------------------------------------------------------------------
namespace {

/// Mid-ranks (1-based) of the pooled sample, and the tie groups' sizes.
std::vector<double> midranks(const std::vector<double>& pooled, std::vector<std::size_t>* ties) {
  const std::size_t n = pooled.size();
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return pooled[a] < pooled[b]; });
  std::vector<double> rank(n);
  for (std::size_t i = 0; i < n;) {
    std::size_t j = i;
    while (j + 1 < n && pooled[order[j + 1]] == pooled[order[i]]) ++j;
    const double r = 0.5 * double(i + 1 + j + 1);
    for (std::size_t k = i; k <= j; ++k) rank[order[k]] = r;
    if (ties) ties->push_back(j - i + 1);
    i = j + 1;
  }
  return rank;
}

}  // namespace

MannWhitney mann_whitney_u(const std::vector<double>& x, const std::vector<double>& y, bool force_exact,
                           bool force_asymptotic) {
  MannWhitney r;
  const std::size_t n1 = x.size(), n2 = y.size(), n = n1 + n2;
  if (n1 == 0 || n2 == 0) return r;
  std::vector<double> pooled(x);
  pooled.insert(pooled.end(), y.begin(), y.end());
  std::vector<std::size_t> ties;
  const std::vector<double> rank = midranks(pooled, &ties);
  double r1 = 0;
  for (std::size_t i = 0; i < n1; ++i) r1 += rank[i];
  r.u1 = r1 - double(n1) * double(n1 + 1) / 2;
  const double u2 = double(n1) * double(n2) - r.u1;
  r.u = std::max(r.u1, u2);

  const bool exact = force_exact || (!force_asymptotic && n1 <= kMannWhitneyExactMax && n2 <= kMannWhitneyExactMax);
  if (exact) {
    // Permutation distribution of the first sample's rank sum: count the n1-subsets of the
    // pooled ranks by their sum. Ranks are doubled so that mid-ranks (k + 1/2) are integers.
    std::vector<long> r2(n);
    long total2 = 0;
    for (std::size_t i = 0; i < n; ++i) total2 += (r2[i] = std::lround(2 * rank[i]));
    const long obs2 = std::lround(2 * r1);
    // ways[k][s]: number of k-subsets of the ranks seen so far with doubled sum s.
    std::vector<std::vector<long double>> ways(n1 + 1, std::vector<long double>(std::size_t(total2) + 1, 0.0L));
    ways[0][0] = 1;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = std::min(i + 1, n1); k >= 1; --k)
        for (long s = total2; s >= r2[i]; --s) ways[k][std::size_t(s)] += ways[k - 1][std::size_t(s - r2[i])];
    long double all = 0, le = 0, ge = 0;
    for (long s = 0; s <= total2; ++s) {
      const long double w = ways[n1][std::size_t(s)];
      all += w;
      if (s <= obs2) le += w;
      if (s >= obs2) ge += w;
    }
    r.p_value = double(std::min<long double>(1.0L, 2.0L * std::min(le, ge) / all));
    r.exact = true;
  } else {
    double tie_term = 0;
    for (std::size_t t : ties) tie_term += double(t) * double(t) * double(t) - double(t);
    const double nn = double(n);
    const double var = double(n1) * double(n2) / 12.0 * ((nn + 1) - tie_term / (nn * (nn - 1)));
    if (var <= 0) {
      r.p_value = 1;  // every value equal: nothing to tell apart
    } else {
      const double z = (r.u - double(n1) * double(n2) / 2 - 0.5) / std::sqrt(var);
      r.p_value = std::min(1.0, std::max(0.0, std::erfc(z / std::sqrt(2.0))));
    }
    r.exact = false;
  }
  return r;
}

// ---------------------------------------------------------------------------------------------
// Reading result sets
// ---------------------------------------------------------------------------------------------
namespace {


std::string str(const json& j, const std::string& fallback = "") {
  return j.is_string() ? j.get<std::string>() : fallback;
}

json read_result_file(const std::string& file) {
  std::ifstream f(file, std::ios::binary);
  if (!f) throw file_error(file, "cannot read");
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw file_error(file, "read failed");
  return parse_result(text, file);
}

}  // namespace

json parse_result(const std::string& text, const std::string& file) {
  json r = parse_json_input(text, file);
  ResultSchema::get().validate(r, file);
  return r;
}

ResultSet load_result_set(const std::string& path) {
  ResultSet set;
  set.path = path;
  std::error_code ec;
  const fs::path p(path);
  if (!fs::exists(p, ec)) throw file_error(path, "no such file or folder");
  if (fs::is_directory(p, ec)) {
    const fs::path dir = fs::is_directory(p / "runs", ec) ? p / "runs" : p;
    fs::directory_iterator it(dir, ec), end;
    if (ec) throw file_error(dir.string(), "cannot list folder: " + ec.message());
    for (; it != end; it.increment(ec)) {
      if (ec) throw file_error(dir.string(), "cannot list folder: " + ec.message());
      if (it->path().extension() == ".json" && !fs::is_directory(it->path(), ec)) set.files.push_back(it->path().string());
    }
    if (set.files.empty()) throw file_error(dir.string(), "no result files (*.json): not a result folder?");
    std::sort(set.files.begin(), set.files.end());
  } else {
    set.files.push_back(path);
  }
  for (auto& f : set.files) set.results.push_back(read_result_file(f));
  return set;
}

// ---------------------------------------------------------------------------------------------
// The comparison
// ---------------------------------------------------------------------------------------------
namespace {

std::string fmt(double v, const char* f = "%.6g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

/// The shortest decimal that reads back as the same double: exact, and readable.
std::string shortest(double v) {
  for (int prec = 6; prec < 17; ++prec) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (std::strtod(buf, nullptr) == v) return buf;
  }
  return fmt(v, "%.17g");
}

std::string show(const json& v) {
  if (v.is_null()) return "(none)";
  if (v.is_number_float()) return shortest(v.get<double>());
  return v.dump();
}

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

std::string change_text(const json& a, const json& b) {
  std::string s = show(a) + " -> " + show(b);
  if (a.is_number() && b.is_number() && a.get<double>() != 0)
    s += " (" + fmt(100.0 * (b.get<double>() / a.get<double>() - 1), "%+.3g") + "%)";
  return s;
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

/// One row: everything known about a (base, new) pair. Either may be null (missing / new).
json compare_pair(const json* b, const json* n, const CompareOptions& opt) {
  const json& any = b ? *b : *n;
  json p;
  p["job"] = job_label(any);
  p["method"] = str(json_at(any, {"job", "method"}));
  p["params_key"] = str(json_at(any, {"job", "params_key"}));
  p["mesh"] = str(json_at(any, {"job", "mesh", "name"}));
  p["query_kind"] = str(json_at(any, {"job", "queries", "kind"}));
  p["query"] = str(json_at(any, {"job", "query"}));
  json reasons = json::array();
  bool gates = false;
  std::string verdict;
  auto reason = [&](const std::string& code, const std::string& detail) {
    reasons.push_back({{"code", code}, {"detail", detail}});
  };
  if (!n) {
    verdict = "missing";
    gates = !opt.ignore_missing;
    reason("missing", "in BASE, not in NEW");
  } else if (!b) {
    verdict = "new";
    reason("new", "in NEW, not in BASE");
  } else {
    const std::string sb = str(json_at(*b, {"status"})), sn = str(json_at(*n, {"status"}));
    p["status"] = {{"base", sb}, {"new", sn}};
    // Paired by job id although the inputs differ (a query generator, a mesh file or a default
    // parameter changed): the deterministic figures cannot be compared, the baseline is stale.
    std::string inputs;
    auto differs = [&](std::initializer_list<const char*> path, const char* what, bool both_ok_only) {
      const json& x = json_at(*b, path);
      const json& y = json_at(*n, path);
      if (both_ok_only && (sb != "ok" || sn != "ok")) return;  // status rows carry unresolved params
      if (x.is_null() || y.is_null() || x == y) return;
      if (x.is_object() && y.is_object()) {  // name the parameters that differ, not all of them
        std::set<std::string> keys;
        for (auto& [k, v] : x.items()) keys.insert(k);
        for (auto& [k, v] : y.items()) keys.insert(k);
        for (auto& k : keys) {
          const json vx = x.contains(k) ? x[k] : json(nullptr), vy = y.contains(k) ? y[k] : json(nullptr);
          if (vx != vy) inputs += (inputs.empty() ? "" : ", ") + std::string(what) + " " + k + " " + show(vx) + " -> " + show(vy);
        }
        return;
      }
      inputs += (inputs.empty() ? "" : ", ") + std::string(what) + " " +
                (x.is_string() ? printable(x.get<std::string>().substr(0, 16)) : x.dump()) + " -> " +
                (y.is_string() ? printable(y.get<std::string>().substr(0, 16)) : y.dump());
    };
    differs({"job", "mesh", "sha256"}, "mesh sha256", false);
    differs({"job", "queries", "sha256"}, "query-set sha256", false);
    differs({"job", "method"}, "method", true);
    differs({"job", "params"}, "params", true);
    differs({"job", "query"}, "query", false);
    if (!inputs.empty()) reason("inputs_changed", inputs);
    if (sb == "ok" && sn != "ok") {
      verdict = "failed";
      gates = true;
      reason("failed", "status ok -> " + sn + (str(json_at(*n, {"message"})).empty() ? "" : ": " + str(json_at(*n, {"message"}))));
    } else if (sb != "ok" && sn == "ok") {
      verdict = "improved";
      reason("fixed", "status " + sb + " -> ok");
    } else if (sb != sn) {
      verdict = "regressed";
      gates = true;
      reason("status_changed", "status " + sb + " -> " + sn);
    } else if (sb != "ok") {
      verdict = "unchanged";
    } else {
      // Both ok: deterministic work first, then accuracy, then timing.
      // The counters NEW declares machine-dependent (its code knows best) gate exactly only
      // when both sides carry the same machine fingerprint; otherwise they are reported.
      std::set<std::string> machine;
      for (auto& v : json_at(*n, {"machine_dependent", "counters"})) machine.insert(v.get<std::string>());
      std::vector<std::string> fp_diffs;
      const std::string not_gated_why = machine.empty() ? "" : machine_not_gated_reason(*b, *n, &fp_diffs);
      json counters = json::array(), counters_not_gated = json::array();
      std::size_t not_gated_values = 0;
      for (auto& [k, vb, vn] : paired_leaves(json_at(*b, {"counters"}).is_object() ? json_at(*b, {"counters"}) : json::object(),
                                             json_at(*n, {"counters"}).is_object() ? json_at(*n, {"counters"}) : json::object())) {
        const bool changed = !same_value(vb, vn, 0.0);
        // A counter that appears or disappears is a change of the method's code: it gates.
        if (!not_gated_why.empty() && machine.count(k) && !vb.is_null() && !vn.is_null()) {
          ++not_gated_values;
          if (changed) counters_not_gated.push_back({{"name", k}, {"base", vb}, {"new", vn}});
        } else if (changed) {
          counters.push_back({{"name", k}, {"base", vb}, {"new", vn}});
        }
      }
      auto changes_text = [](const json& list) {
        std::string d;
        for (auto& c : list) d += (d.empty() ? "" : ", ") + c["name"].get<std::string>() + " " + change_text(c["base"], c["new"]);
        return d;
      };
      if (!counters.empty()) {
        reason("counters_changed", changes_text(counters));
        p["counters"] = counters;
      }
      if (!machine.empty())
        p["machine_dependent"] = {{"counters", machine},
                                  {"gated", not_gated_why.empty()},
                                  {"not_gated_because", not_gated_why.empty() ? json(nullptr) : json(not_gated_why)},
                                  {"fingerprint_differences", fp_diffs},
                                  {"values_not_gated", not_gated_values}};
      if (!counters_not_gated.empty()) {
        reason("machine_counters_not_gated", changes_text(counters_not_gated) + "; not gated: " + not_gated_why);
        p["counters_not_gated"] = counters_not_gated;
      }
      json accuracy = json::array();
      const json& ab = json_at(*b, {"accuracy"});
      const json& an = json_at(*n, {"accuracy"});
      if (ab.is_null() != an.is_null()) {
        accuracy.push_back({{"field", "accuracy"}, {"base", ab.is_null() ? "none" : "measured"}, {"new", an.is_null() ? "none" : "measured"}});
      } else if (!ab.is_null()) {
        for (auto& [k, vb, vn] : paired_leaves(ab, an))
          if (!same_value(vb, vn, opt.rtol)) accuracy.push_back({{"field", k}, {"base", vb}, {"new", vn}});
      }
      if (!accuracy.empty()) {
        std::string d;
        for (auto& a : accuracy) d += (d.empty() ? "" : ", ") + a["field"].get<std::string>() + " " + change_text(a["base"], a["new"]);
        reason("accuracy_changed", d);
        p["accuracy"] = accuracy;
      }
      const json& bb = json_at(*b, {"build", "structure_bytes"});
      const json& bn = json_at(*n, {"build", "structure_bytes"});
      if (bb.is_number() && bn.is_number() && bb != bn) p["structure_bytes"] = {{"base", bb}, {"new", bn}};

      json t = timing_block(*b, *n, opt);
      const std::string tv = t["verdict"];
      p["timing"] = t;
      const bool deterministic_change = !counters.empty() || !accuracy.empty();
      if (tv != "unchanged") {
        const bool tg = opt.timing_gates && tv == "regressed";
        reason(tv == "regressed" ? "throughput_regressed" : "throughput_improved",
               "normalised throughput " + fmt(100 * t["change"].get<double>(), "%+.1f") + "%, p=" +
                   fmt(t["p_value"].get<double>(), "%.2g") + (tv == "regressed" && !opt.timing_gates ? " (reported, not gating)" : ""));
        gates = gates || tg;
      }
      if (deterministic_change) {
        verdict = "regressed";  // any change of deterministic work or accuracy: rebaseline or fix
        gates = true;
      } else {
        verdict = tv;
      }
    }
  }
  if (!reasons.empty() && reasons[0]["code"] == "inputs_changed") {
    gates = true;
    if (verdict == "unchanged" || verdict == "improved") verdict = "regressed";
  }
  p["verdict"] = verdict;
  p["reasons"] = reasons;
  p["gates"] = gates;
  return p;
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

// ---------------------------------------------------------------------------------------------
// Markdown
// ---------------------------------------------------------------------------------------------
namespace {

std::string join(const json& arr) {
  std::string s;
  for (auto& v : arr) s += (s.empty() ? "" : ", ") + v.get<std::string>();
  return s.empty() ? "?" : s;
}

std::string md_cell(std::string s) {
  std::string o;
  for (char c : s) o += c == '|' ? std::string("\\|") : c == '\n' ? std::string(" ") : std::string(1, c);
  return o;
}

std::string qps_text(const json& v) {
  return v.is_number() ? fmt(v.get<double>(), "%.4g") : std::string("-");
}

}  // namespace

std::string compare_markdown(const json& rep) {
  std::ostringstream o;
  const json& s = rep["summary"];
  const json& opt = rep["options"];
  const int gating = s["gating"].get<int>();
  o << "## bvhbench compare: " << (gating ? "REGRESSION (" + std::to_string(gating) + " gating)" : std::string("OK"))
    << "\n\n";
  for (const char* side : {"base", "new"}) {
    const json& b = rep[side];
    o << "- " << (std::string(side) == "base" ? "BASE" : "NEW") << ": `" << b["path"].get<std::string>() << "`, "
      << b["results"].get<std::size_t>() << " results; host " << join(b["hosts"]) << "; commit " << join(b["commits"])
      << "; machine " << join(b["machines"]) << "\n";
  }
  o << "- Counters, accuracy and statuses: exact (any change gates), except the counters a method declares "
       "machine-dependent, which gate only when both results carry the same machine fingerprint and are "
       "otherwise reported, not gated. Throughput: normalised by the "
       "calibration kernel; a change counts when it exceeds "
    << fmt(100 * opt["threshold"].get<double>(), "%g") << "% and a two-sided Mann-Whitney U test gives p < "
    << fmt(opt["alpha"].get<double>(), "%g") << "; timing verdicts "
    << (opt["timing"] == "gate" ? "gate" : "are reported only (--timing report)") << ".\n\n";
  o << "| | verdict | job | q/s base -> new | change (normalised) | p | why |\n";
  o << "|---|---|---|---:|---:|---:|---|\n";
  for (auto& p : rep["pairs"]) {
    const json& t = p.contains("timing") ? p["timing"] : json(nullptr);
    std::string why;
    for (auto& r : p["reasons"]) {
      if (r["code"] == "missing" || r["code"] == "new") why += r["detail"].get<std::string>();
      else why += (why.empty() ? "" : "; ") + r["code"].get<std::string>() + ": " + r["detail"].get<std::string>();
    }
    if (why.empty() && p.contains("status") && p["status"]["new"] != "ok")
      why = "status " + p["status"]["new"].get<std::string>() + " (as in BASE)";
    if (t.is_object() && t.contains("note")) why += (why.empty() ? "" : "; ") + t["note"].get<std::string>();
    if (why.size() > 300) why = printable(why.substr(0, 297)) + "...";
    std::string qps = "-", change = "-", pv = "-";
    if (t.is_object()) {
      qps = qps_text(t["base_qps_median"]) + " -> " + qps_text(t["new_qps_median"]);
      if (t["change"].is_number()) change = fmt(100 * t["change"].get<double>(), "%+.1f") + "%";
      if (t["p_value"].is_number()) pv = fmt(t["p_value"].get<double>(), "%.2g");
    }
    o << "| " << (p["gates"].get<bool>() ? "**x**" : "") << " | " << p["verdict"].get<std::string>() << " | "
      << md_cell(p["job"].get<std::string>()) << " | " << qps << " | " << change << " | " << pv << " | " << md_cell(why)
      << " |\n";
  }
  o << "\n" << s["failed"].get<int>() << " failed, " << s["regressed"].get<int>() << " regressed, "
    << s["missing"].get<int>() << " missing, " << s["improved"].get<int>() << " improved, " << s["new"].get<int>()
    << " new, " << s["unchanged"].get<int>() << " unchanged; " << gating << " gating.\n";
  const json& ng = s["not_gated"];
  if (ng["counters"].get<std::size_t>() > 0) {
    std::string why;
    for (auto& w : ng["why"]) why += (why.empty() ? "" : "; ") + w.get<std::string>();
    o << "\nNot gated: " << ng["counters"].get<std::size_t>() << " machine-dependent counter values in "
      << ng["jobs"].get<std::size_t>() << " jobs, " << ng["changed"].get<std::size_t>() << " of them changed, because "
      << why << ".\n";
  }

  // Full lists of what changed, for the rows above whose cells were cut short.
  bool header = false;
  for (auto& p : rep["pairs"]) {
    if (!p.contains("counters") && !p.contains("accuracy")) continue;
    if (!header) o << "\n### Changed counters and accuracy\n";
    header = true;
    o << "\n`" << p["job"].get<std::string>() << "`\n";
    if (p.contains("counters"))
      for (auto& c : p["counters"]) o << "- counter `" << c["name"].get<std::string>() << "`: " << change_text(c["base"], c["new"]) << "\n";
    if (p.contains("accuracy"))
      for (auto& a : p["accuracy"]) o << "- accuracy `" << a["field"].get<std::string>() << "`: " << change_text(a["base"], a["new"]) << "\n";
  }
  header = false;
  for (auto& p : rep["pairs"]) {
    if (!p.contains("counters_not_gated")) continue;
    if (!header)
      o << "\n### Machine-dependent counters, reported and not gated\n\n"
           "They depend on the processor as well as on the input; a baseline made on a machine with the same "
           "fingerprint gates them exactly (docs/compare.md, \"The CI gate\").\n";
    header = true;
    o << "\n`" << p["job"].get<std::string>() << "`: not gated because " << p["machine_dependent"]["not_gated_because"].get<std::string>() << "\n";
    for (auto& c : p["counters_not_gated"])
      o << "- counter `" << c["name"].get<std::string>() << "`: " << change_text(c["base"], c["new"]) << "\n";
  }
  if (gating)
    o << "\nIf these changes are intended, regenerate the baseline (docs/compare.md, `make rebaseline`) "
         "and commit it with the change.\n";
  return o.str();
}

}  // namespace bvhbench
