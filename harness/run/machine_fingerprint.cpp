#include "harness/run/machine_fingerprint.hpp"

#include <string>

#if defined(__x86_64__) || defined(__i386__)
#include <cpuid.h>
#else
#include <sys/utsname.h>
#endif

#include "harness/run/system_info.hpp"

namespace bvhbench {

namespace {

#if defined(__x86_64__) || defined(__i386__)

/// Vendor, display family and display model, as CPUID leaves 0 and 1 give them (the formulas of
/// the Intel and AMD manuals; Embree's CPU-model table reads the same two numbers).
nlohmann::json cpu_identity() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (!__get_cpuid(0, &a, &b, &c, &d)) return {{"vendor", "unknown"}};
  char vendor[13] = {0};
  for (int i = 0; i < 4; ++i) {
    vendor[i] = char((b >> (8 * i)) & 0xff);
    vendor[4 + i] = char((d >> (8 * i)) & 0xff);
    vendor[8 + i] = char((c >> (8 * i)) & 0xff);
  }
  nlohmann::json j = {{"vendor", std::string(vendor)}};
  if (a < 1 || !__get_cpuid(1, &a, &b, &c, &d)) return j;
  const unsigned base_family = (a >> 8) & 0xf, base_model = (a >> 4) & 0xf;
  const unsigned family = base_family == 0xf ? base_family + ((a >> 20) & 0xff) : base_family;
  const unsigned model =
      (base_family == 0x6 || base_family == 0xf) ? base_model + (((a >> 16) & 0xf) << 4) : base_model;
  j["family"] = family;
  j["model"] = model;
  return j;
}

/// The instruction sets that decide which kernels a dispatching library runs: Embree's SSE2,
/// SSE4.2 (+ POPCNT), AVX, AVX2 (+ FMA, BMI1/2) and AVX-512 SKX (F, DQ, CD, BW, VL) targets.
/// __builtin_cpu_supports needs literal names, hence the macro. (F16C and LZCNT, which Embree's
/// AVX2 target also wants, come with every AVX2 processor and are not names clang 14 knows.)
nlohmann::json isa_features() {
  __builtin_cpu_init();
  nlohmann::json j = nlohmann::json::object();
#define BVHBENCH_ISA(name) j[name] = __builtin_cpu_supports(name) != 0
  BVHBENCH_ISA("sse2");
  BVHBENCH_ISA("sse4.1");
  BVHBENCH_ISA("sse4.2");
  BVHBENCH_ISA("popcnt");
  BVHBENCH_ISA("avx");
  BVHBENCH_ISA("fma");
  BVHBENCH_ISA("bmi");
  BVHBENCH_ISA("bmi2");
  BVHBENCH_ISA("avx2");
  BVHBENCH_ISA("avx512f");
  BVHBENCH_ISA("avx512dq");
  BVHBENCH_ISA("avx512cd");
  BVHBENCH_ISA("avx512bw");
  BVHBENCH_ISA("avx512vl");
#undef BVHBENCH_ISA
  return j;
}

#else

nlohmann::json cpu_identity() {
  utsname u{};
  return {{"arch", uname(&u) == 0 ? std::string(u.machine) : std::string("unknown")}};
}

nlohmann::json isa_features() { return nlohmann::json::object(); }

#endif

}  // namespace

nlohmann::json machine_fingerprint(const nlohmann::json& method_facts) {
  static const nlohmann::json cpu = cpu_identity();
  static const nlohmann::json isa = isa_features();
  return {{"cpu", cpu},
          {"isa", isa},
          {"libraries", run_context()["libraries"]},
          {"method", method_facts.is_object() ? method_facts : nlohmann::json::object()}};
}

}  // namespace bvhbench
