// MethodSpec (core/method_spec.hpp) and its resolution by the registry: the text kept byte for
// byte, the pairs as typed, the canonical parameter key, and a bad spec refused with the
// messages the harness has always given.
#include <gtest/gtest.h>

#include "harness/core/method_spec.hpp"
#include "harness/core/registry.hpp"
#include "harness/util/errors.hpp"

using namespace bvhbench;

namespace {
std::string parse_error(const std::string& text) {
  try {
    parse_method_spec(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}
}  // namespace

TEST(MethodSpec, NameOnly) {
  const MethodSpec s = parse_method_spec("brute_force");
  EXPECT_EQ(s.text, "brute_force");
  EXPECT_EQ(s.name, "brute_force");
  EXPECT_TRUE(s.given.empty());
  EXPECT_FALSE(s.resolved());
}

TEST(MethodSpec, KeyValues) {
  const MethodSpec s = parse_method_spec("m:a=1,b=x y");
  EXPECT_EQ(s.name, "m");
  ASSERT_EQ(s.given.size(), 2u);
  EXPECT_EQ(s.given.at("a"), "1");
  EXPECT_EQ(s.given.at("b"), "x y");
  // Empty pairs are skipped; a value may hold '=' and ':'.
  const MethodSpec t = parse_method_spec("m:,a=b=c,,p=/x:y,");
  EXPECT_EQ(t.given, (std::map<std::string, std::string>{{"a", "b=c"}, {"p", "/x:y"}}));
  EXPECT_EQ(t.text, "m:,a=b=c,,p=/x:y,");
}

TEST(MethodSpec, Malformed) {
  EXPECT_EQ(parse_error(":a=1"), "method spec ':a=1': empty method name");
  EXPECT_EQ(parse_error(""), "method spec '': empty method name");
  EXPECT_EQ(parse_error("m:a"), "method spec 'm:a': 'a' is not key=value");
  EXPECT_EQ(parse_error("m:=1"), "method spec 'm:=1': '=1' is not key=value");
  EXPECT_EQ(parse_error("m:a=1,a=2"), "method spec 'm:a=1,a=2': 'a' given twice");
}

TEST(MethodSpec, ResolvedAgainstTheRegistry) {
  const Registry& r = Registry::global();
  const MethodSpec s = r.resolve("brute_force:winding_threshold=0.25");
  ASSERT_TRUE(s.resolved());
  EXPECT_EQ(s.info, r.find("brute_force"));
  EXPECT_EQ(s.text, "brute_force:winding_threshold=0.25");
  EXPECT_EQ(s.given.at("winding_threshold"), "0.25");
  EXPECT_DOUBLE_EQ(s.params.get_real("winding_threshold"), 0.25);
  EXPECT_EQ(s.params_key(), "winding_threshold=0.25");
  EXPECT_TRUE(s.problem.empty());
  // A default given explicitly is no part of the key; the text stays as typed.
  const MethodSpec d = r.resolve("brute_force:winding_threshold=" + r.find("brute_force")->params.at(0).default_value);
  EXPECT_EQ(d.params_key(), "");
  EXPECT_NE(d.text, "brute_force");
  EXPECT_TRUE(r.create(s));
}

// describe() never throws: the problem is the message resolve() throws, and what could be read
// is kept (job_block writes it into the rejected_input result).
TEST(MethodSpec, ABadSpecIsRefusedWithItsMessage) {
  const Registry& r = Registry::global();
  struct Case {
    std::string text, name, problem;
    std::size_t given;
  };
  for (const Case& c : {Case{"m:a", "m:a", "method spec 'm:a': 'a' is not key=value", 0},
                        Case{"no_such_method:a=1", "no_such_method", "unknown method 'no_such_method' (known: ", 1},
                        Case{"brute_force:bogus=1", "brute_force", "method brute_force: unknown parameter 'bogus'", 1},
                        Case{"brute_force:winding_threshold=x", "brute_force",
                             "method brute_force: parameter winding_threshold=x: not a finite number", 1}}) {
    SCOPED_TRACE(c.text);
    const MethodSpec s = r.describe(c.text);
    EXPECT_FALSE(s.resolved());
    EXPECT_EQ(s.text, c.text);
    EXPECT_EQ(s.name, c.name);
    EXPECT_EQ(s.given.size(), c.given);
    EXPECT_EQ(s.problem.rfind(c.problem, 0), 0u) << s.problem;
    EXPECT_EQ(s.params_key(), "");
    try {
      r.resolve(c.text);
      ADD_FAILURE() << "resolved";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), s.problem);
    }
    try {
      r.create(s);
      ADD_FAILURE() << "created";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), s.problem);
    }
  }
  // Testing-only methods are not listed among the known ones.
  EXPECT_EQ(r.describe("x").problem.find("fault"), std::string::npos);
}
