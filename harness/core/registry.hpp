#pragma once
/// The method registry. The runner never names a method: each folder under methods/ provides
/// `void bvhbench_register_<name>(bvhbench::Registry&)`, and methods/CMakeLists.txt has the one
/// registration line that makes the build call it (see methods/README.md).
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "harness/core/inside_definition.hpp"
#include "harness/core/method.hpp"
#include "harness/core/method_spec.hpp"

namespace CLI { class App; }

namespace bvhbench {

/// Which jobs of a suite one built structure of a method configuration may serve. A suite runs
/// the jobs of one structure (mesh, method with its options, threads) in one child process after
/// one build (docs/results.md, "Shared builds"); a method narrows that where its
/// structure is particular to more than its options.
enum class StructureSharing {
  /// Every query type and query set on the mesh: build() reads nothing of the queries to come,
  /// and queries leave nothing in the structure but path state (reset before each pass).
  every_job,
  /// The jobs of one query type: build() reads BuildContext::query_type (it builds only what
  /// that type needs, e.g. an index that only distance queries use).
  same_query_type,
  /// Each job alone: build() reads the query points (BuildContext::query_bounds sizes a band or a
  /// cache), or queries leave state a later job would inherit (an out-of-core page cache).
  job_alone,
};

struct MethodInfo {
  /// A declaration's first line: the method's name and description; the rest is set field by field.
  static MethodInfo named(std::string name, std::string description) {
    MethodInfo m;
    m.name = std::move(name);
    m.description = std::move(description);
    return m;
  }

  std::string name;          ///< [a-z0-9_]+
  std::string description;   ///< one line
  Capabilities caps;
  std::vector<ParamSpec> params;
  std::function<std::unique_ptr<Method>(const Params&)> create;
  bool testing_only = false;  ///< hidden from default listings (fault injection)
  /// The work counters (names as counters() reports them) whose values depend on the machine
  /// as well as on the input: counts made inside a library that picks its kernels or its tree
  /// layout from the processor at run time (Embree). Results record them with the machine
  /// fingerprint (machine_fingerprint.hpp), and `compare` gates them exactly only against a
  /// baseline made under the same fingerprint; elsewhere it reports them without failing.
  /// Every counter not named here depends only on the input (mesh, query set, parameters) and the
  /// build, and gates exactly on every machine. Default: none. That is the safe side for a gate:
  /// a counter wrongly left portable fails the gate on the first other machine, loudly and by
  /// name; one wrongly named here would silently stop gating on every other machine.
  std::vector<std::string> machine_dependent_counters;
  /// The method's default sweep: the variants a suite's `methods: all` runs, each the text after
  /// `NAME:` in a method spec ("k=v,k=v"; "" = every option at its default). Declared beside the
  /// options, as each algorithm's sweep lives beside it in ann-benchmarks; empty: the method
  /// takes no part in `methods: all` (it needs an input a suite cannot supply, such as a store).
  /// Every entry must resolve against `params` (Registry::add checks).
  std::vector<std::string> sweep = {""};
  /// What its inside(p), and the sign of its distance(p), compute, and the input it promises to
  /// handle (inside_definition.hpp): per configuration, the first variant whose options match.
  /// Empty: undeclared, judged against the oracle's default definition as results made before
  /// declarations were. Every `when` key and threshold option must be one of `params`
  /// (Registry::add checks). A result records the resolved definition as job.inside.
  std::vector<InsideVariant> inside;
  /// Checks that the options make sense together, beyond each one alone (e.g. build options
  /// given beside a prebuilt store); throws InputError naming them. Optional.
  std::function<void(const Params&)> check;
  /// Which jobs one structure of a configuration may serve (StructureSharing). Unset: every job
  /// (every_job). Set it when build() reads BuildContext's query fields, or when queries leave
  /// state in the structure beyond path state; a suite reads it to group jobs before running.
  std::function<StructureSharing(const Params&)> sharing;
};

/// The options that shape the structure of `spec`, "k=v,k=v" off their defaults (as
/// MethodSpec::params_key): its build options alone for a method that takes query options after
/// its build (Capabilities::query_options_after_build), else every option. "" when unresolved.
std::string structure_key(const MethodSpec& spec);

/// Whether `method`, an instance of `info`, answers `q`: the registered capability, narrowed by
/// the instance (Method::supports).
bool answers(const MethodInfo& info, const Method& method, QueryType q);

/// Why `m`'s path coherence is declared inconsistently ("" when it is not): a method with the
/// coherence capability declares the boolean query option `coherent` (false by default), one
/// without it declares no such option. Registry::add refuses such a method.
std::string coherence_problem(const MethodInfo& m);

/// Why `m.sweep` does not resolve against `m.params` (the first bad entry and the reason), ""
/// when every entry does.
std::string sweep_problem(const MethodInfo& m);

/// Why `m.inside` does not fit `m.params` (a `when` key or a threshold option that is not a
/// declared option, a threshold option that is not real), "" when it does.
std::string inside_declaration_problem(const MethodInfo& m);

/// Extra `bvhbench` subcommands a method brings (e.g. `bvhbench ebp stats`). `setup` adds the
/// subcommand to the CLI app, with its options and callback.
struct CommandInfo {
  std::string name;
  std::function<void(CLI::App& app)> setup;
};

class Registry {
 public:
  /// Throws std::logic_error on a duplicate name or a sweep entry that does not resolve.
  void add(MethodInfo info);
  void add_command(CommandInfo cmd);
  /// Notes a method this build knows of but cannot offer here (a Python method whose package is
  /// not installed), with why: `bvhbench methods` shows the note, and naming the method gets it
  /// as the problem instead of "unknown method".
  void add_left_out(const std::string& name, const std::string& why);
  /// Notes a fact about how methods were found that a user should see (which Python interpreter
  /// and packages the Python methods use); `bvhbench methods` shows it.
  void add_note(const std::string& note) { notes_.push_back(note); }
  const std::vector<std::string>& notes() const { return notes_; }
  /// Method name -> why it is left out, in the order noted.
  const std::vector<std::pair<std::string, std::string>>& left_out() const { return left_out_; }
  /// Whether `name` is a method this build left out (add_left_out), rather than unknown.
  bool is_left_out(const std::string& name) const;
  const MethodInfo* find(const std::string& name) const;
  const std::vector<MethodInfo>& methods() const { return methods_; }
  const std::vector<CommandInfo>& commands() const { return commands_; }

  /// Parses `text` ("NAME:k=v,...", method_spec.hpp) and resolves it against this registry:
  /// the method and its full, validated parameter set. Never throws for bad text: a spec that
  /// cannot be parsed, names an unknown method or gives a bad parameter comes back unresolved
  /// with its `problem` (the message resolve() throws) and as much of name and given as was read.
  MethodSpec describe(const std::string& text) const;
  /// describe(), but throws InputError(problem) for a spec it cannot resolve: the parser's
  /// message, "unknown method 'X' (known: ...)", or the parameter's "method X: parameter ...".
  MethodSpec resolve(const std::string& text) const;

  /// Creates the method of a spec resolved against this registry. Throws InputError(problem)
  /// for an unresolved one.
  std::unique_ptr<Method> create(const MethodSpec& spec) const;
  /// create(resolve(text)): for tests and tools that name a method in code.
  std::unique_ptr<Method> create(const std::string& text) const;

  /// The method specs of a suite's `methods: all`: every method that is not testing-only, not in
  /// `except`, with each entry of its sweep ("NAME" or "NAME:ENTRY"), in registration order.
  std::vector<std::string> all_method_specs(const std::vector<std::string>& except = {}) const;

  /// The registry with every method compiled into this build.
  static const Registry& global();

 private:
  std::vector<MethodInfo> methods_;
  std::vector<CommandInfo> commands_;
  std::vector<std::pair<std::string, std::string>> left_out_;
  std::vector<std::string> notes_;
};

/// Generated by CMake from methods/CMakeLists.txt: calls each method's registration function.
void register_all_methods(Registry& r);

}  // namespace bvhbench
