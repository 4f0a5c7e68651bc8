#pragma once
/// The machine fingerprint: what a *machine-dependent* work counter depends on besides the input.
///
/// Most counters depend only on the input (mesh, query set, parameters) and the build (compiler,
/// flags, library versions): they are the same on every machine. A library that picks its
/// kernels and tree layout from the processor at run time (Embree: SSE, AVX, AVX2 or AVX-512
/// kernels, BVH4 or BVH8, the latter also by CPU model on Intel) visits other nodes and
/// triangles on another processor, for the same input. Methods name such counters in
/// MethodInfo::machine_dependent_counters; each result records them with this fingerprint, and
/// `compare` gates them exactly only when both results carry the same one (compare.hpp,
/// fingerprint_differences; docs/compare.md).
#include <nlohmann/json.hpp>

namespace bvhbench {

/// The processor and the libraries, as a JSON object that two machines share exactly when a
/// dispatching library makes the same choices on both:
///   "cpu":       {"vendor": "AuthenticAMD", "family": 25, "model": 1}  CPUID leaf 0 and 1 (display
///                family and model); the brand string (context.cpu_model) is left out: it is a
///                free-form name ("AMD EPYC" on some VMs) that decides nothing;
///   "isa":       {"sse2": true, ..., "avx512vl": false}  the instruction sets that select a
///                library's kernels, as __builtin_cpu_supports reads them from CPUID (which also
///                checks that the OS saves the AVX and AVX-512 registers);
///   "libraries": the versions of the libraries compiled in (context.libraries);
///   "method":    `method_facts`, what the method's library says it chose (Method::machine_facts).
/// On a processor other than x86, "cpu" holds {"arch": NAME} and "isa" is empty.
nlohmann::json machine_fingerprint(const nlohmann::json& method_facts = nlohmann::json::object());

}  // namespace bvhbench
