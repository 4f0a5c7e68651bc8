// `bvhbench ebp verify`: every section and page of a store checked as a query would load it
// (the check: store/verify.cpp); exit 2 if any is bad.
#include <cstdio>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"
#include "harness/util/progress.hpp"
#include "methods/ebp_octree/commands.hpp"
#include "methods/ebp_octree/store/verify.hpp"

namespace bvhbench {

void add_verify_command(CLI::App& ebp_cmd) {
  struct Opts {
    std::string path;
    bool json = false, all = false;
    int threads = 2;  // as `ebp build`; from the OS cache two threads check 1.5-1.7x faster (OUT_OF_CORE.md)
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = ebp_cmd.add_subcommand(
      "verify", "Check every section and every page of a store (.ebp) as a query would load it; exit 2 if any is bad");
  cmd->add_option("store", o->path, "Store (.ebp)")->required();
  cmd->add_flag("--all", o->all, "List every bad page instead of stopping at the first");
  cmd->add_option("--threads", o->threads, "Pages checked in parallel (at most the cores)")->check(CLI::Range(1, 1024));
  cmd->add_flag("--json", o->json, "Machine-readable report on stdout (exit code as without it)");
  cmd->callback([o] {
    ebp::VerifyOptions vo;
    vo.all = o->all;
    vo.threads = o->threads;
    Progress prog("verifying " + o->path, 1.0, !o->json);
    vo.progress = [&](std::uint64_t done, std::uint64_t total) { prog.update(total ? double(done) / double(total) : 1.0); };
    const ebp::VerifyReport rep = ebp::verify_store(o->path, vo);
    prog.finish();  // the check is done, whatever it found: the line goes before the findings
    const double mib = double(rep.bytes_read) / 1048576.0;
    const double rate = rep.seconds > 0 ? double(rep.bytes_read) / rep.seconds : 0.0;
    if (o->json) {
      nlohmann::json problems = nlohmann::json::array();
      for (const ebp::VerifyProblem& p : rep.problems) {
        nlohmann::json j{{"page", nullptr}, {"problem", p.problem}, {"message", p.message}};
        if (p.page >= 0) j["page"] = p.page, j["offset"] = p.offset, j["size"] = p.size;
        problems.push_back(j);
      }
      const nlohmann::json j{{"path", printable(o->path)},  {"ok", rep.ok()},
                             {"file_bytes", rep.file_bytes}, {"pages", rep.pages},
                             {"pages_checked", rep.pages_checked}, {"bytes_read", rep.bytes_read},
                             {"seconds", rep.seconds},       {"bytes_per_second", rate},
                             {"all", o->all},                {"problems", problems}};
      std::cout << j.dump(2) << "\n";
    } else if (rep.ok()) {
      std::printf("ok %s: %lu pages, %.1f MiB checked in %.2f s (%.0f MiB/s)\n", printable(o->path).c_str(),
                  (unsigned long)rep.pages, mib, rep.seconds, rate / 1048576.0);
    } else {
      for (const ebp::VerifyProblem& p : rep.problems) std::cerr << "bvhbench: " << p.message << "\n";
      const bool page_problem = rep.problems.back().page >= 0;
      if (o->all && page_problem)
        std::cerr << "bvhbench: " << printable(o->path) << ": " << rep.problems.size() << " bad of " << rep.pages
                  << " pages\n";
      else if (page_problem && rep.pages_checked < rep.pages)
        std::cerr << "bvhbench: stopped at the first bad page (" << rep.pages_checked << " of " << rep.pages
                  << " checked); --all lists every bad page\n";
    }
    if (!rep.ok()) throw ExitCode{2};
  });
}

}  // namespace bvhbench
