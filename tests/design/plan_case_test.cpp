// The case file's "plan" (two-jaw surgery, issue 32; src/design/case_file.cpp, parse_plan):
// a good plan is read exactly; every bad key or value is refused with the key named and its
// line and column, the arena as it was.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "splintcore/design.h"
#include "support/case_refusal.h"
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

// Each case refused with kInvalidArgument, its fragment in the message, named where (file,
// line and column of the value); the arena as it was and no plan.
void expect_refused(const std::vector<Bad>& cases) {
  for (const Bad& c : cases) {
    SCOPED_TRACE(c.name);
    test::expect_case_refused(c.text, StatusCode::kInvalidArgument, c.fragment, true);
  }
}

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
  expect_refused(cases);
}

// A plan case whose splints have their own picks: `picks` is the plan's "picks" value, `base`
// the base's inside.
std::string picks_case(const std::string& picks, const std::string& base = R"("spacing_mm": 0.5)") {
  return std::string(R"({"splintcore_case": 1,
 "jaws": [{"role": "maxilla", "mesh": "u.stl"}, {"role": "mandible", "mesh": "l.stl"}],
 "base": {)") +
         base + R"(},
 "plan": {)" +
         kGoodPlan + R"(, "picks": )" + picks + "}}";
}

const char* const kSplintPicks = R"({
  "intermediate": {"upper": [{"position": [1, 2, 3]}, {"position": [4, 5, 6]}],
                   "lower": [{"position": [1, 2, 0]}, {"position": [4, 5, 0]}]},
  "final": {"upper": [{"position": [1, 4, 4], "inner_length_mm": 7}, {"position": [4, 7, 7]},
                      {"position": [8, 9, 7]}],
            "lower": [{"position": [1, 4, 0]}, {"position": [4, 7, 0]}, {"position": [8, 9, 0]}]}
})";

TEST(PlanCase, EachSplintsPicksAreReadWrittenAndGivenToItsSplint) {
  test::TestArena t(size_t{1} << 20);
  Context ctx(&t.arena);
  const std::string text = picks_case(kSplintPicks, R"("spacing_mm": 0.5, "inner_length_mm": 4)");
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, text.data(), text.size(), "case.json", &c));
  ASSERT_TRUE(c.has_plan && c.plan.has_picks);
  EXPECT_FALSE(c.has_auto_outline);
  EXPECT_TRUE(c.upper.empty() && c.lower.empty());  // the base gives none
  ASSERT_EQ(c.plan.upper[0].size(), 2u);
  ASSERT_EQ(c.plan.lower[0].size(), 2u);
  ASSERT_EQ(c.plan.upper[1].size(), 3u);
  ASSERT_EQ(c.plan.lower[1].size(), 3u);
  EXPECT_EQ(c.plan.upper[0][1].position.y, 5.0);
  EXPECT_EQ(c.plan.lower[1][2].position.x, 8.0);
  EXPECT_EQ(c.plan.upper[0][0].inner_length, 4.0);  // the base's default
  EXPECT_EQ(c.plan.upper[1][0].inner_length, 7.0);  // the pick's own

  // Each splint's case takes its own picks.
  for (int k = 0; k < 2; ++k) {
    PlanSplintReport r;
    CaseJaw jaws[2];
    CaseFile derived;
    SPLINTCORE_ASSERT_OK(plan_splint_case(c, r, k == 1, jaws, &derived));
    EXPECT_FALSE(derived.has_plan);
    EXPECT_EQ(derived.upper.data(), c.plan.upper[k].data());
    EXPECT_EQ(derived.lower.data(), c.plan.lower[k].data());
  }

  // Written and read again: the same picks, still the plan's.
  std::string written;
  const ByteSink sink = test::string_sink(&written);
  SPLINTCORE_ASSERT_OK(write_case(c, sink));
  CaseFile again;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, written.data(), written.size(), "written", &again));
  ASSERT_TRUE(again.plan.has_picks);
  EXPECT_TRUE(again.upper.empty());
  for (int k = 0; k < 2; ++k) {
    ASSERT_EQ(again.plan.upper[k].size(), c.plan.upper[k].size());
    ASSERT_EQ(again.plan.lower[k].size(), c.plan.lower[k].size());
    for (size_t i = 0; i < c.plan.upper[k].size(); ++i) {
      EXPECT_TRUE(again.plan.upper[k][i].position == c.plan.upper[k][i].position);
      EXPECT_EQ(again.plan.upper[k][i].inner_length, c.plan.upper[k][i].inner_length);
      EXPECT_TRUE(again.plan.lower[k][i].position == c.plan.lower[k][i].position);
    }
  }
}

TEST(PlanCase, BadSplintPicksAreNamed) {
  const std::string picks = kSplintPicks;
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string p = picks;
    const size_t at = p.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return p.replace(at, from.size(), to);
  };
  const std::vector<Bad> cases = {
      {"picks in the base too",
       picks_case(picks,
                  R"("upper": [{"position": [1, 2, 3]}], "lower": [{"position": [1, 2, 0]}])"),
       "leave \"upper\" out of \"base\""},
      {"auto too", picks_case(picks, R"("auto": {})"), "leave \"auto\" out of \"base\""},
      {"not an object", picks_case("[1]"), "\"picks\" must be object"},
      {"unknown splint", picks_case(replaced("\"final\"", "\"middle\"")),
       "unknown key \"middle\" in \"plan\"'s \"picks\""},
      {"a splint missing", picks_case(R"({"intermediate": {"upper": [], "lower": []}})"),
       "\"plan\"'s \"picks\" needs \"final\""},
      {"a list missing",
       picks_case(replaced("\"lower\": [{\"position\": [1, 4, 0]}, "
                           "{\"position\": [4, 7, 0]}, {\"position\": [8, 9, 0]}]",
                           "\"lowr\": []")),
       "unknown key \"lowr\" in final"},
      {"a list left out",
       picks_case(R"({"intermediate": {"upper": [], "lower": []}, "final": {"upper": []}})"),
       "the final splint's \"picks\" needs \"upper\" and \"lower\" pick lists"},
      {"lists that do not pair", picks_case(replaced(", {\"position\": [8, 9, 0]}", "")),
       "upper and lower pick lists do not pair up: 3 upper, 2 lower"},
      {"a bad pick", picks_case(replaced("[4, 5, 6]", "[4, 5]")), "\"position\" needs 3 numbers"},
  };
  expect_refused(cases);
}

}  // namespace
}  // namespace splintcore
