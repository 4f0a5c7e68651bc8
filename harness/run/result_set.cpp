#include "harness/run/result_set.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "harness/run/result_schema.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/json_input.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace bvhbench {

namespace {

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

}  // namespace bvhbench
