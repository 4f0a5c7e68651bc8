// Method parameters: defaults, validation, the registry's errors (method specs: test_method_spec.cpp).
#include <gtest/gtest.h>

#include "harness/core/params.hpp"
#include "harness/core/registry.hpp"
#include "harness/util/errors.hpp"

using namespace bvhbench;

namespace {
const std::vector<ParamSpec> kSpecs = {
    {"n", ParamType::integer, ParamRole::build, "5", "count", {}, 1, 10},
    {"x", ParamType::real, ParamRole::query, "0.5", "fraction", {}, 0.0, 1.0},
    {"on", ParamType::boolean, ParamRole::query, "false", "flag", {}},
    {"mode", ParamType::choice, ParamRole::build, "a", "mode", {"a", "b"}},
    {"name", ParamType::text, ParamRole::build, "", "free text", {}},
    {"odd", ParamType::integer, ParamRole::query, "1", "one of a few numbers", {"1", "3", "5"}},
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

// An unknown key names the declared one it probably was; a range may exclude its minimum (a
// length, a speed: > 0), and the message says which bound was crossed. Query kinds declare their
// parameters the same way (query_set.hpp), and resolve_for names them as their owner.
TEST(Params, SuggestionsAndExcludedMinimum) {
  auto message = [](const std::string& owner, const std::vector<ParamSpec>& specs,
                    std::map<std::string, std::string> g) {
    try {
      Params::resolve_for(owner, specs, g);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message("method m", kSpecs, {{"mdoe", "a"}}),
            "method m: unknown parameter 'mdoe' (did you mean 'mode'? known: n, x, on, mode, name, odd)");
  EXPECT_EQ(message("method m", kSpecs, {{"zzzzzz", "1"}}).find("did you mean"), std::string::npos);
  ParamSpec speed{"speed", ParamType::real, ParamRole::query, "0.1", "m/s", {}};
  speed.min = 0;
  speed.min_excluded = true;
  EXPECT_EQ(message("query kind 'k'", {speed}, {{"speed", "0"}}), "query kind 'k': parameter speed=0: must be > 0");
  EXPECT_EQ(message("query kind 'k'", {speed}, {{"speed", "-1"}}), "query kind 'k': parameter speed=-1: must be > 0");
  EXPECT_DOUBLE_EQ(Params::resolve_for("query kind 'k'", {speed}, {{"speed", "1e-9"}}).get_real("speed"), 1e-9);
  EXPECT_EQ(message("method m", kSpecs, {{"x", "2"}}), "method m: parameter x=2: out of range [0, 1]");
}

// One configuration, one key: the key is printed from the typed value, not the text given.
TEST(Params, CanonicalKeyFromTypedValues) {
  EXPECT_EQ(Params::resolve("m", kSpecs, {{"x", "0.25"}}).non_default_string(), "x=0.25");
  EXPECT_EQ(Params::resolve("m", kSpecs, {{"x", "0.250"}}).non_default_string(), "x=0.25");
  EXPECT_EQ(Params::resolve("m", kSpecs, {{"x", "2.5e-1"}}).non_default_string(), "x=0.25");
  EXPECT_EQ(Params::resolve("m", kSpecs, {{"x", "1.0"}}).non_default_string(), "x=1");
  EXPECT_EQ(Params::resolve("m", kSpecs, {{"x", ".5"}}).non_default_string(), "");  // the default
  EXPECT_EQ(Params::resolve("m", kSpecs, {{"n", "+07"}}).non_default_string(), "n=7");
  EXPECT_EQ(Params::resolve("m", kSpecs, {{"on", "0"}}).values().at("on"), "false");
  // A number with choices: checked by value, so "3.0" is not an integer but "03" is 3.
  EXPECT_EQ(Params::resolve("m", kSpecs, {{"odd", "03"}}).get_int("odd"), 3);
  EXPECT_THROW(Params::resolve("m", kSpecs, {{"odd", "2"}}), InputError);
  // Reading an option as another type than declared is the program's mistake, not the user's.
  EXPECT_THROW(Params::resolve("m", kSpecs, {}).get_real("n"), std::logic_error);
}

TEST(Params, ValuesReadFromAStructureReplaceTheSpecsButNotTheDefaults) {
  const Params p = Params::resolve("m", kSpecs, {{"mode", "b"}});
  const Params ran = p.with_values("m", kSpecs, {{"n", "3"}});
  EXPECT_EQ(ran.get_int("n"), 3);
  EXPECT_EQ(ran.get("mode"), "b");
  EXPECT_EQ(ran.non_default_string(), "mode=b,n=3");
  EXPECT_THROW(p.with_values("m", kSpecs, {{"n", "99"}}), InputError);
}

// The EBP-Octree's leaf_factor, the case that showed the problem: 5.0 and 5 are one key.
TEST(Registry, RealOptionsShareOneKey) {
  const Registry& r = Registry::global();
  if (!r.find("ebp_octree")) GTEST_SKIP() << "ebp_octree not in this build";
  EXPECT_EQ(r.resolve("ebp_octree:leaf_factor=8.0").params_key(), r.resolve("ebp_octree:leaf_factor=8").params_key());
  EXPECT_EQ(r.resolve("ebp_octree:leaf_factor=5.0").params_key(), "");
  EXPECT_EQ(r.resolve("ebp_octree:leaf_factor=5").params_key(), "");
}

// A store carries its build options: one given beside it is refused, naming both; and so is
// the sign from the closest face, which needs the face sides a store's pages do not carry.
TEST(Registry, EbpBuildOptionBesideAStoreIsRefused) {
  const Registry& r = Registry::global();
  if (!r.find("ebp_octree")) GTEST_SKIP() << "ebp_octree not in this build";
  auto expect_refused_naming = [&](const std::string& spec, const std::string& option) {
    try {
      r.resolve(spec);
      ADD_FAILURE() << spec << ": accepted";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(option), std::string::npos) << msg;
      EXPECT_NE(msg.find("store=m.ebp"), std::string::npos) << msg;
    }
  };
  expect_refused_naming("ebp_octree:store=m.ebp,leaf_factor=8", "leaf_factor=8");
  EXPECT_THROW(r.resolve("ebp_octree:cache_mb=64"), InputError);  // a store's option without a store
  EXPECT_NO_THROW(r.resolve("ebp_octree:store=m.ebp,coherent=true,cache_mb=64"));
  expect_refused_naming("ebp_octree:store=m.ebp,face_sign=true", "face_sign=true");
  EXPECT_NO_THROW(r.resolve("ebp_octree:store=m.ebp,face_sign=false"));
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
    // Defaults must validate against their own specs, and the sweep against the options.
    EXPECT_NO_THROW(Params::resolve(m.name, m.params, {}));
    EXPECT_EQ(sweep_problem(m), "");
  }
}

// Path coherence has one spelling: the capability and a boolean query option `coherent`, false by
// default, together or not at all (docs/architecture.md, "Path coherence").
TEST(Params, CoherenceIsDeclaredOneWay) {
  MethodInfo m;
  m.name = "m";
  EXPECT_EQ(coherence_problem(m), "");
  m.caps.coherence = true;
  EXPECT_NE(coherence_problem(m), "");  // the capability without the option
  m.params = {{"coherent", ParamType::boolean, ParamRole::query, "false", "keep state along a path", {}}};
  EXPECT_EQ(coherence_problem(m), "");
  m.params[0].default_value = "true";
  EXPECT_NE(coherence_problem(m), "");  // on by default: its row would not be the method's own
  m.params[0].default_value = "false";
  m.params[0].role = ParamRole::build;
  EXPECT_NE(coherence_problem(m), "");
  m.params[0].role = ParamRole::query;
  m.caps.coherence = false;
  EXPECT_NE(coherence_problem(m), "");  // the option without the capability
  for (const MethodInfo& r : Registry::global().methods()) EXPECT_EQ(coherence_problem(r), "") << r.name;
}
