// Method parameters: defaults, validation, the registry's errors (method specs: test_method_spec.cpp).
#include <gtest/gtest.h>

#include "harness/core/params.hpp"
#include "harness/core/registry.hpp"
#include "harness/util/errors.hpp"

using namespace bvhbench;

namespace {
const std::vector<ParamSpec> kSpecs = {
    {"n", ParamType::integer, "5", "count", {}, 1, 10},
    {"x", ParamType::real, "0.5", "fraction", {}, 0.0, 1.0},
    {"on", ParamType::boolean, "false", "flag", {}},
    {"mode", ParamType::choice, "a", "mode", {"a", "b"}},
    {"name", ParamType::text, "", "free text", {}},
};
}

TEST(Params, DefaultsAndOverrides) {
  Params p = Params::resolve("m", kSpecs, {{"n", "7"}, {"on", "yes"}});
  EXPECT_EQ(p.get_int("n"), 7);
  EXPECT_DOUBLE_EQ(p.get_real("x"), 0.5);
  EXPECT_TRUE(p.get_bool("on"));
  EXPECT_EQ(p.get("mode"), "a");
  EXPECT_EQ(p.non_default_string(), "n=7,on=true");
}

TEST(Params, Rejections) {
  auto bad = [](std::map<std::string, std::string> g) {
    try {
      Params::resolve("m", kSpecs, g);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(bad({{"zzz", "1"}}).find("unknown parameter 'zzz'"), std::string::npos);
  EXPECT_NE(bad({{"n", "abc"}}).find("not an integer"), std::string::npos);
  EXPECT_NE(bad({{"n", "11"}}).find("out of range"), std::string::npos);
  EXPECT_NE(bad({{"x", "nan"}}).find("not a finite number"), std::string::npos);
  EXPECT_NE(bad({{"on", "maybe"}}).find("not a boolean"), std::string::npos);
  EXPECT_NE(bad({{"mode", "c"}}).find("not one of"), std::string::npos);
}

TEST(Registry, KnowsBruteForceAndRejectsUnknown) {
  const Registry& r = Registry::global();
  ASSERT_NE(r.find("brute_force"), nullptr);
  EXPECT_THROW(r.create("no_such_method"), InputError);
  EXPECT_THROW(r.create("brute_force:bogus=1"), InputError);
  const MethodSpec spec = r.resolve("brute_force:winding_threshold=0.25");
  auto m = r.create(spec);
  ASSERT_TRUE(m);
  EXPECT_EQ(spec.info->name, "brute_force");
  EXPECT_DOUBLE_EQ(spec.params.get_real("winding_threshold"), 0.25);
}

TEST(Registry, EveryMethodDeclaresSaneParameters) {
  for (const auto& m : Registry::global().methods()) {
    SCOPED_TRACE(m.name);
    EXPECT_FALSE(m.description.empty());
    EXPECT_TRUE(m.create);
    // Defaults must validate against their own specs.
    EXPECT_NO_THROW(Params::resolve(m.name, m.params, {}));
  }
}
