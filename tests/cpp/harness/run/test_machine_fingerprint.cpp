// The machine fingerprint (machine_fingerprint.hpp) and how compare tells two apart
// (fingerprint_differences in compare.hpp). compare's verdicts on real results are tested end to
// end in tests/python/harness/test_compare_machine.py.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "harness/run/compare.hpp"
#include "harness/run/machine_fingerprint.hpp"
#include "harness/run/system_info.hpp"

using namespace bvhbench;
using json = nlohmann::json;

TEST(MachineFingerprint, NamesTheProcessorItsInstructionSetsAndTheLibraries) {
  const json fp = machine_fingerprint({{"embree_native_ray_widths", {4, 8}}});
  ASSERT_TRUE(fp.is_object());
  EXPECT_EQ(fp["libraries"], run_context()["libraries"]);
  EXPECT_EQ(fp["method"], json({{"embree_native_ray_widths", {4, 8}}}));
#if defined(__x86_64__)
  ASSERT_TRUE(fp["cpu"]["vendor"].is_string());
  EXPECT_FALSE(fp["cpu"]["vendor"].get<std::string>().empty());
  EXPECT_TRUE(fp["cpu"]["family"].is_number_unsigned());
  EXPECT_TRUE(fp["cpu"]["model"].is_number_unsigned());
  for (const char* f : {"sse2", "sse4.1", "sse4.2", "popcnt", "avx", "fma", "bmi", "bmi2", "avx2", "avx512f",
                        "avx512dq", "avx512cd", "avx512bw", "avx512vl"}) {
    ASSERT_TRUE(fp["isa"].contains(f)) << f;
    EXPECT_TRUE(fp["isa"][f].is_boolean()) << f;
  }
  EXPECT_EQ(fp["isa"].size(), 14u);
  EXPECT_TRUE(fp["isa"]["sse2"].get<bool>());  // part of x86-64
#else
  EXPECT_TRUE(fp["cpu"]["arch"].is_string());
  EXPECT_TRUE(fp["isa"].empty());
#endif
}

TEST(MachineFingerprint, TheSameOnEveryCallAndWithoutMethodFacts) {
  EXPECT_EQ(machine_fingerprint(), machine_fingerprint());
  EXPECT_EQ(machine_fingerprint()["method"], json::object());
  EXPECT_EQ(machine_fingerprint(json("not an object"))["method"], json::object());
}

TEST(FingerprintDifferences, EqualFingerprintsHaveNone) {
  const json fp = machine_fingerprint({{"embree_native_ray_widths", {4, 8, 16}}});
  EXPECT_TRUE(fingerprint_differences(fp, fp).empty());
  EXPECT_TRUE(fingerprint_differences(json::object(), json::object()).empty());
}

TEST(FingerprintDifferences, NamesEachDifferingLeafSortedByPath) {
  const json base = {{"cpu", {{"vendor", "GenuineIntel"}, {"family", 6}, {"model", 85}}},
                     {"isa", {{"avx2", true}, {"avx512f", true}}},
                     {"libraries", {{"embree", "3.13.5"}}},
                     {"method", {{"embree_native_ray_widths", {4, 8, 16}}}}};
  json fresh = base;
  fresh["cpu"]["model"] = 106;
  fresh["isa"]["avx512f"] = false;
  fresh["method"]["embree_native_ray_widths"] = {4, 8};
  fresh["libraries"].erase("embree");
  fresh["libraries"]["openvdb"] = "10.0.1";
  const std::vector<std::string> want = {
      "cpu.model 85 -> 106",
      "isa.avx512f true -> false",
      "libraries.embree \"3.13.5\" -> (none)",
      "libraries.openvdb (none) -> \"10.0.1\"",
      "method.embree_native_ray_widths [4,8,16] -> [4,8]",
  };
  EXPECT_EQ(fingerprint_differences(base, fresh), want);
  // Symmetric up to the direction of each change.
  EXPECT_EQ(fingerprint_differences(fresh, base).size(), want.size());
}
