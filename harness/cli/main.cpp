// bvhbench: benchmark spatial query structures (point-in-solid, distance) on triangle meshes.
// Exit codes: 0 success; 1 a job that did not succeed or a regression (compare); 2 bad usage
// or bad input. Messages go to stderr, results to files or stdout.
#include <iostream>
#include <new>

#include <CLI/CLI.hpp>

#include "harness/cli/commands.hpp"
#include "harness/core/registry.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/printable.hpp"
#include "harness/util/progress.hpp"

int main(int argc, char** argv) {
  using namespace bvhbench;
  CLI::App app{"bvhbench: benchmark spatial query structures on very large triangle meshes"};
  app.require_subcommand(1);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "No progress output");
  app.parse_complete_callback([&] { Progress::set_global_enabled(!quiet); });

  try {
    add_methods_command(app);
    add_kinds_command(app);
    add_queries_command(app);
    add_truth_command(app);
    add_run_command(app);
    add_suite_command(app);
    add_run_child_command(app);
    add_run_group_command(app);
    add_compare_command(app);
    add_mesh_info_command(app);
    for (auto& c : Registry::global().commands()) c.setup(app);
  } catch (const std::exception& e) {
    std::cerr << "bvhbench: internal error while setting up commands: " << printable(e.what()) << "\n";
    return 3;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const ExitCode& e) {
    return e.code;
  } catch (const InputError& e) {
    std::cerr << "bvhbench: " << printable(e.what()) << "\n";
    return 2;
  } catch (const UnsupportedError& e) {
    std::cerr << "bvhbench: unsupported: " << printable(e.what()) << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "bvhbench: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "bvhbench: error: " << printable(e.what()) << "\n";
    return 1;
  }
  return 0;
}
