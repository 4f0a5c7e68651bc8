#include "harness/run/summary_csv.hpp"

#include <filesystem>
#include <sstream>

#include "harness/run/result_schema.hpp"
#include "harness/util/atomic_file.hpp"
#include "harness/util/json_path.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

namespace {

std::string csv_escape(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) {
    if (c == '"') o += '"';
    o += c == '\n' ? ' ' : c;
  }
  return o + "\"";
}

std::string num(const json& j) {
  if (j.is_null()) return "";
  if (j.is_number_integer() || j.is_number_unsigned()) return std::to_string(j.get<long long>());
  if (j.is_number()) {
    std::ostringstream os;
    os.precision(9);
    os << j.get<double>();
    return os.str();
  }
  if (j.is_boolean()) return j.get<bool>() ? "true" : "false";
  if (j.is_string()) return j.get<std::string>();
  return "";
}

const json& field(const json& r, const std::string& path) { return json_at(r, split_field_path(path)); }

/// One cell, as the schema's summary_csv entry for its column says.
std::string cell(const json& r, const SummaryColumn& c) {
  if (!c.field.empty()) {
    const json& v = field(r, c.field);
    if (v.is_null() && !c.or_stem_of.empty()) {
      const json& p = field(r, c.or_stem_of);
      return p.is_string() ? fs::path(p.get<std::string>()).stem().string() : "";
    }
    return num(v);
  }
  if (!c.ratio_of[0].empty()) {
    const json& a = field(r, c.ratio_of[0]);
    const json& b = field(r, c.ratio_of[1]);
    if (a.is_number() && b.is_number() && b.get<double>() > 0) return num(json(a.get<double>() / b.get<double>()));
    return "";
  }
  if (!c.share_of[0].empty()) {
    const json& a = field(r, c.share_of[0]);
    const json& b = field(r, c.share_of[1]);
    if (!a.is_number() || !b.is_number()) return "";
    const double total = a.get<double>() + b.get<double>();
    return total > 0 ? num(json(a.get<double>() / total)) : "";
  }
  return "";
}

}  // namespace

std::vector<std::string> summary_header() {
  std::vector<std::string> h;
  for (const SummaryColumn& c : ResultSchema::get().summary_columns()) h.push_back(c.column);
  return h;
}

std::vector<std::string> summary_row(const json& r) {
  std::vector<std::string> row;
  for (const SummaryColumn& c : ResultSchema::get().summary_columns()) row.push_back(csv_escape(cell(r, c)));
  return row;
}

void write_summary_csv(const std::string& path, const std::vector<json>& results) {
  std::string text;
  auto line = [&](const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) text += (i ? "," : "") + cells[i];
    text += "\n";
  };
  line(summary_header());
  for (auto& r : results) line(summary_row(r));
  AtomicOutputFile f(path);
  f.write(text);
  f.commit();
}

}  // namespace bvhbench
