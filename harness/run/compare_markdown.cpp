#include "harness/run/compare_markdown.hpp"

#include <sstream>

#include "harness/run/compare_format.hpp"
#include "harness/util/printable.hpp"

using json = nlohmann::json;

namespace bvhbench {

using namespace compare_format;

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

/// The heading, the two sides and how the verdicts are reached.
void write_preamble(std::ostringstream& o, const json& rep, int gating) {
  const json& opt = rep["options"];
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
}

/// One pair's row of the table: gates, verdict, job, throughput, change, p, why (cut at 300 chars).
void write_pair_row(std::ostringstream& o, const json& p) {
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

/// The counts by verdict, and the machine-dependent counters not gated.
void write_summary(std::ostringstream& o, const json& s, int gating) {
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
}

/// Full lists of what changed, for the rows whose cells were cut short.
void write_changed_lists(std::ostringstream& o, const json& pairs) {
  bool header = false;
  for (auto& p : pairs) {
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
  for (auto& p : pairs) {
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
}

}  // namespace

std::string compare_markdown(const json& rep) {
  std::ostringstream o;
  const json& s = rep["summary"];
  const int gating = s["gating"].get<int>();
  write_preamble(o, rep, gating);
  o << "| | verdict | job | q/s base -> new | change (normalised) | p | why |\n";
  o << "|---|---|---|---:|---:|---:|---|\n";
  for (auto& p : rep["pairs"]) write_pair_row(o, p);
  write_summary(o, s, gating);
  write_changed_lists(o, rep["pairs"]);
  if (gating)
    o << "\nIf these changes are intended, regenerate the baseline (docs/compare.md, `make rebaseline`) "
         "and commit it with the change.\n";
  return o.str();
}

}  // namespace bvhbench
