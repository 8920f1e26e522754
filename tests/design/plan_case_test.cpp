// The case file's "plan" (two-jaw surgery, issue 32; src/design/case_file.cpp, parse_plan):
// a good plan is read exactly; every bad key or value is refused with the key named and its
// line and column, the arena as it was.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "splintcore/design.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

const char* const kGoodPlan =
    R"("sequence": "maxilla_first",
       "maxilla": [1,0,0,0, 0,1,0,2, 0,0,1,1, 0,0,0,1],
       "mandible": [0,-1,0,0, 1,0,0,3, 0,0,1,0, 0,0,0,1],
       "hinge_axis": [[-50, -55, 25], [50, -55, 25]],
       "intermediate_opening_mm": 2, "final_opening_mm": 1.5)";

// A case with a plan (`plan` is the plan object's inside), the jaws and the base's extra keys
// replaceable.
std::string plan_case(const std::string& plan, const std::string& jaws = "",
                      const std::string& base = "", const std::string& root_extra = "") {
  const std::string default_jaws =
      R"([{"role": "maxilla", "mesh": "u.stl"}, {"role": "mandible", "mesh": "l.stl"}])";
  return std::string("{\"splintcore_case\": 1,\n \"jaws\": ") +
         (jaws.empty() ? default_jaws : jaws) + ",\n" + root_extra + " \"base\": {\"auto\": {" +
         base + "}},\n \"plan\": " + plan + "}";
}

std::string with(const std::string& replace, const std::string& by) {
  std::string p = std::string("{") + kGoodPlan + "}";
  const size_t at = p.find(replace);
  EXPECT_NE(at, std::string::npos) << replace;
  return p.replace(at, replace.size(), by);
}

TEST(PlanCase, AGoodPlanIsReadExactly) {
  test::TestArena t(size_t{1} << 20);
  const std::string text = plan_case(std::string("{") + kGoodPlan + "}");
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(Context(&t.arena), text.data(), text.size(), "case.json", &c));
  ASSERT_TRUE(c.has_plan);
  EXPECT_FALSE(c.plan.mandible_first);
  EXPECT_EQ(c.plan.maxilla.t[1], 2.0);
  EXPECT_EQ(c.plan.maxilla.t[2], 1.0);
  EXPECT_EQ(c.plan.mandible.r[0][1], -1.0);
  EXPECT_EQ(c.plan.mandible.r[1][0], 1.0);
  EXPECT_EQ(c.plan.mandible.t[1], 3.0);
  EXPECT_EQ(c.plan.hinge[0].x, -50.0);
  EXPECT_EQ(c.plan.hinge[1].z, 25.0);
  EXPECT_EQ(c.plan.intermediate_opening_mm, 2.0);
  EXPECT_EQ(c.plan.final_opening_mm, 1.5);

  const std::string mandible_first = plan_case(with("maxilla_first", "mandible_first"));
  SPLINTCORE_ASSERT_OK(
      parse_case(Context(&t.arena), mandible_first.data(), mandible_first.size(), "m", &c));
  EXPECT_TRUE(c.plan.mandible_first);
  // Without a plan: none.
  const std::string none = R"({"splintcore_case": 1, "base": {"auto": {}}})";
  SPLINTCORE_ASSERT_OK(parse_case(Context(&t.arena), none.data(), none.size(), "n", &c));
  EXPECT_FALSE(c.has_plan);
}

struct Bad {
  const char* name;
  std::string text;
  const char* fragment;
};

TEST(PlanCase, EveryBadKeyOrValueIsNamed) {
  const std::string good = std::string("{") + kGoodPlan + "}";
  const std::vector<Bad> cases = {
      {"plan not an object", plan_case("[1]"), "\"plan\" must be object"},
      {"unknown key", plan_case(with("\"sequence\"", "\"order\": 1, \"sequence\"")),
       "unknown key \"order\" in \"plan\""},
      {"missing key", plan_case(with(", \"final_opening_mm\": 1.5", "")),
       "\"plan\" needs \"final_opening_mm\""},
      {"sequence type", plan_case(with("\"maxilla_first\"", "1")), "\"sequence\" must be string"},
      {"sequence value", plan_case(with("maxilla_first", "both")),
       "\"sequence\" must be \"maxilla_first\" or \"mandible_first\""},
      {"maxilla type",
       plan_case(with("\"maxilla\": [1,0,0,0, 0,1,0,2, 0,0,1,1, 0,0,0,1]", "\"maxilla\": 5")),
       "\"maxilla\" must be array"},
      {"maxilla count", plan_case(with("[1,0,0,0, 0,1,0,2,", "[1,0,0,0, 0,1,0,2, 5,")),
       "\"maxilla\" needs 16 numbers"},
      {"maxilla entry", plan_case(with("0,1,0,2,", "0,1,0,2e7,")), "\"maxilla\" is 2e+07"},
      {"mandible not rigid", plan_case(with("[0,-1,0,0,", "[0,-2,0,0,")), "\"mandible\": "},
      {"hinge type", plan_case(with("[[-50, -55, 25], [50, -55, 25]]", "5")),
       "\"hinge_axis\" must be array"},
      {"hinge count", plan_case(with("[[-50, -55, 25], [50, -55, 25]]", "[[0, 0, 0]]")),
       "\"hinge_axis\" needs 2 points"},
      {"hinge first point", plan_case(with("[-50, -55, 25]", "[-50, -55]")),
       "\"hinge_axis\" needs 3 numbers"},
      {"hinge second point", plan_case(with("[50, -55, 25]", "[50, -55, \"z\"]")),
       "\"hinge_axis\" must be number"},
      {"hinge too short", plan_case(with("[50, -55, 25]", "[-49.5, -55, 25]")),
       "the condyles are 0.5 mm apart"},
      {"intermediate opening",
       plan_case(with("\"intermediate_opening_mm\": 2", "\"intermediate_opening_mm\": 11")),
       "\"intermediate_opening_mm\" is 11, outside [0, 10]"},
      {"final opening", plan_case(with("\"final_opening_mm\": 1.5", "\"final_opening_mm\": -1")),
       "\"final_opening_mm\" is -1, outside [0, 10]"},
      {"one jaw", plan_case(good, R"([{"role": "maxilla", "mesh": "u.stl"}])"),
       "\"plan\" needs \"jaws\" with the preoperative maxilla and mandible"},
      {"jaw transform", plan_case(good, R"([{"role": "maxilla", "mesh": "u.stl"},
                           {"role": "mandible", "mesh": "l.stl",
                            "transform": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}])"),
       "a jaw's \"transform\" and \"plan\" both move it"},
      {"bite opening", plan_case(good, "", "\"bite_opening_mm\": 2"),
       "leave \"bite_opening_mm\" out of \"auto\""},
      {"output splint", plan_case(good, "", "", "\"output\": {\"splint\": \"s.stl\"},"),
       "leave \"splint\" out of \"output\""},
  };
  for (const Bad& c : cases) {
    SCOPED_TRACE(c.name);
    test::TestArena t(size_t{1} << 20);
    ASSERT_NE(t.arena.allocate(16), nullptr);
    const size_t used = t.arena.used();
    CaseFile out;
    Status s = parse_case(Context(&t.arena), c.text.data(), c.text.size(), "case.json", &out);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s) << "\n" << c.text;
    EXPECT_NE(std::string(s.message()).find(c.fragment), std::string::npos) << s.message() << "\n"
                                                                            << c.text;
    EXPECT_STREQ(s.file(), "case.json");
    EXPECT_GT(s.line(), 0u);  // where: line and column of the value
    EXPECT_GT(s.column(), 0u);
    EXPECT_EQ(t.arena.used(), used) << "a failed parse left memory in the arena";
    EXPECT_FALSE(out.has_plan);
  }
}

}  // namespace
}  // namespace splintcore
