#include "harness/run/system_info.hpp"

#include <unistd.h>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include <tbb/version.h>

#include "build_info.hpp"
#include "harness/core/library_versions.hpp"

namespace bvhbench {

namespace {

std::string run_capture(const std::string& cmd) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  pclose(p);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

}  // namespace

std::string iso8601_now() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

nlohmann::json run_context() {
  static const nlohmann::json cached = [] {
    nlohmann::json c;
    c["date"] = iso8601_now();
    char host[256] = {0};
    gethostname(host, sizeof host - 1);
    c["host"] = host;
    std::string cpu = "unknown";
    std::ifstream f("/proc/cpuinfo");
    for (std::string line; std::getline(f, line);) {
      if (line.rfind("model name", 0) == 0) {
        cpu = line.substr(line.find(':') + 2);
        break;
      }
    }
    c["cpu_model"] = cpu;
    c["cores"] = std::thread::hardware_concurrency();
    c["compiler"] = BVHBENCH_COMPILER;
    c["cxx_flags"] = BVHBENCH_CXX_FLAGS;
    c["build_type"] = BVHBENCH_BUILD_TYPE;
    c["bvhbench_version"] = BVHBENCH_VERSION;
    nlohmann::json libs = nlohmann::json::object();
    libs["tbb"] = TBB_VERSION_STRING;
    for (auto& [k, v] : library_versions()) libs[k] = v;
    c["libraries"] = libs;
    std::string src = BVHBENCH_SOURCE_DIR;
    std::string commit = run_capture("git -C '" + src + "' rev-parse HEAD 2>/dev/null");
    c["git_commit"] = commit.empty() ? nlohmann::json(nullptr) : nlohmann::json(commit);
    if (!commit.empty()) {
      // Changes to the sources, not to the result sets kept in the tree: a rebaseline rewrites
      // results/baseline while it runs, and must still record the clean commit it was made from.
      std::string dirty = run_capture("git -C '" + src +
                                      "' status --porcelain --untracked-files=no -- . ':(exclude)results'"
                                      " ':(exclude)tests/fixtures/results_small' 2>/dev/null | head -1");
      c["git_dirty"] = !dirty.empty();
    } else {
      c["git_dirty"] = nullptr;
    }
    return c;
  }();
  nlohmann::json c = cached;
  c["date"] = iso8601_now();
  // Versions may be noted after the first call (registration is lazy).
  for (auto& [k, v] : library_versions()) c["libraries"][k] = v;
  return c;
}

}  // namespace bvhbench
