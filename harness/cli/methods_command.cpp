// `bvhbench methods`: what is registered, what it answers, which of its counters depend on the
// machine, its options (type, role, default) and the default sweep a `methods: all` suite runs.
#include <map>
#include <iostream>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "harness/cli/commands.hpp"
#include "harness/cli/param_listing.hpp"
#include "harness/core/registry.hpp"

namespace bvhbench {

namespace {

nlohmann::json method_json(const MethodInfo& m) {
  nlohmann::json j;
  j["name"] = m.name;
  j["description"] = m.description;
  j["capabilities"] = {{"inside", m.caps.inside},
                       {"distance", m.caps.distance},
                       {"closest_triangle", m.caps.closest_triangle},
                       {"coherence", m.caps.coherence},
                       {"out_of_core", m.caps.out_of_core},
                       {"concurrent_queries", m.caps.concurrent_queries},
                       {"query_options_after_build", m.caps.query_options_after_build}};
  j["build_threads"] = m.caps.build_threads == BuildThreads::job   ? "job"
                       : m.caps.build_threads == BuildThreads::one ? "one"
                                                                   : "library";
  j["testing_only"] = m.testing_only;
  // What its inside means, per configuration (inside_definition.hpp); [] when undeclared.
  j["inside"] = declaration_json(m.inside);
  j["params"] = params_json("method " + m.name, m.params);
  j["sweep"] = m.sweep;  // what a suite's `methods: all` runs of it
  // Counters compare gates exactly only against a baseline of the same machine fingerprint.
  j["machine_dependent_counters"] = m.machine_dependent_counters;
  return j;
}

/// "  inside: ray parity; input: closed\n", one line per configuration that differs.
std::string inside_lines(const MethodInfo& m) {
  if (m.inside.empty()) return "  inside: not declared (judged against the oracle's default definition)\n";
  std::string out;
  for (const InsideVariant& v : m.inside) {
    std::string when;
    for (const auto& [k, value] : v.when) when += (when.empty() ? "" : ",") + k + "=" + value;
    std::string text = v.definition.text();
    if (!v.threshold_option.empty()) {
      const std::size_t at = text.find(" > ");
      const std::size_t end = text.find_first_of(" ;", at + 3);
      if (at != std::string::npos) text.replace(at + 3, end - at - 3, v.threshold_option);
    }
    out += "  inside" + (when.empty() ? std::string() : " (" + when + ")") + ": " + text + "\n";
  }
  return out;
}

}  // namespace

void add_methods_command(CLI::App& app) {
  auto as_json = std::make_shared<bool>(false);
  auto all = std::make_shared<bool>(false);
  auto* cmd = app.add_subcommand("methods", "List the registered methods, capabilities and parameters");
  cmd->add_flag("--json", *as_json, "Machine-readable output");
  cmd->add_flag("--all", *all, "Include testing-only methods (fault injection)");
  cmd->callback([=] {
    const Registry& reg = Registry::global();
    if (*as_json) {
      nlohmann::json out = nlohmann::json::array();
      for (auto& m : reg.methods())
        if (*all || !m.testing_only) out.push_back(method_json(m));
      std::cout << out.dump(2) << "\n";
      // The array stays the listing scripts read; what is left out is said on stderr.
      for (const auto& note : reg.notes()) std::cerr << "note: " << note << "\n";
      for (const auto& [name, why] : reg.left_out())
        std::cerr << "note: method " << name << " left out: " << why << "\n";
      return;
    }
    for (auto& m : reg.methods()) {
      if (m.testing_only && !*all) continue;
      std::string caps;
      auto add = [&](bool on, const char* s) { if (on) caps += (caps.empty() ? "" : ", ") + std::string(s); };
      add(m.caps.inside, "inside");
      add(m.caps.distance, "distance");
      add(m.caps.closest_triangle, "closest-triangle");
      add(m.caps.coherence, "coherence");
      add(m.caps.out_of_core, "out-of-core");
      add(m.caps.concurrent_queries, "concurrent-queries");
      add(m.caps.query_options_after_build, "query-options-after-build");
      std::cout << m.name << (m.testing_only ? " [testing only]" : "") << "\n"
                << "  " << m.description << "\n"
                << "  answers: " << (caps.empty() ? "nothing" : caps) << "\n"
                << "  build threads: "
                << (m.caps.build_threads == BuildThreads::job   ? "the job's (--threads)"
                    : m.caps.build_threads == BuildThreads::one ? "one"
                                                                : "the library's own choice")
                << "\n";
      std::cout << inside_lines(m);
      std::string machine;
      for (auto& c : m.machine_dependent_counters) machine += (machine.empty() ? "" : ", ") + c;
      std::cout << "  machine-dependent counters: "
                << (machine.empty() ? "none (every counter depends on the input alone)"
                                    : machine + " (gated only against a baseline of the same machine fingerprint)")
                << "\n";
      print_params(std::cout, "method " + m.name, m.params);
      std::string sweep;
      for (const auto& e : m.sweep) sweep += (sweep.empty() ? "" : "; ") + (e.empty() ? std::string("defaults") : e);
      std::cout << "  methods: all runs: " << (m.sweep.empty() ? "none (not in methods: all)" : sweep) << "\n";
      std::cout << "\n";
    }
    for (const auto& note : reg.notes()) std::cout << "note: " << note << "\n";
    for (const auto& [name, why] : reg.left_out())
      std::cout << "note: method " << name << " left out: " << why << "\n";
  });
}

}  // namespace bvhbench
