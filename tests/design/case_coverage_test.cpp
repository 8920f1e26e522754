// Every branch of the case-file schema (src/design/case_file.cpp), table-driven (issue 9:
// >= 95% branch coverage of the parsers, measured by tools/coverage.sh). Each edit of a valid
// case gives the documented code and a message naming the key; a failed parse leaves the
// arena where it was and the CaseFile empty.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "splintcore/design.h"
#include "support/case_refusal.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

// A small valid case; each test case replaces one marked part.
std::string make_case(const std::string& root_extra = "", const std::string& jaws = "",
                      const std::string& base_extra = "", const std::string& picks = "") {
  const std::string default_jaws =
      R"([{"role": "maxilla", "mesh": "u.stl"},
          {"role": "mandible", "mesh": "l.stl",
           "transform": [1,0,0,0, 0,1,0,0, 0,0,1,-2, 0,0,0,1]}])";
  const std::string default_picks =
      R"("upper": [{"position": [0, 0, 1]}, {"position": [10, 0, 1]}],
         "lower": [{"position": [0, 0, -1]}, {"position": [10, 0, -1]}])";
  return std::string("{\"splintcore_case\": 1, \"case_id\": \"c-1\", \"units\": \"mm\",") +
         " \"jaws\": " + (jaws.empty() ? default_jaws : jaws) + "," + root_extra + " \"base\": {" +
         base_extra + (picks.empty() ? default_picks : picks) + "}}";
}

struct Case {
  const char* name;
  std::string text;
  StatusCode code;
  const char* fragment;
};

// Each case is refused with its code and a message holding its fragment and naming the file;
// the arena is as it was and the CaseFile empty.
void expect_refusals(const std::vector<Case>& cases) {
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    test::expect_case_refused(c.text, c.code, c.fragment);
  }
}

TEST(CaseCoverage, EveryErrorIsNamed) {
  auto picks = [](const std::string& upper_pick) {
    return R"("upper": [)" + upper_pick + R"(, {"position": [10, 0, 1]}],
              "lower": [{"position": [0, 0, -1]}, {"position": [10, 0, -1]}])";
  };
  const std::vector<Case> cases = {
      {"not json", "{", StatusCode::kParseError, "expected a string key"},
      {"not an object", "[1]", StatusCode::kInvalidArgument, "\"the case\" must be object"},
      {"no version", "{}", StatusCode::kInvalidArgument, "no \"splintcore_case\""},
      {"version string", R"({"splintcore_case": "1"})", StatusCode::kInvalidArgument,
       "must be number"},
      {"version zero", R"({"splintcore_case": 0})", StatusCode::kInvalidArgument, "outside"},
      {"version fraction", R"({"splintcore_case": 1.5})", StatusCode::kInvalidArgument,
       "must be an integer"},
      {"version newer", R"({"splintcore_case": 2})", StatusCode::kUnsupported, "newer"},
      {"unknown root key", make_case(R"("colour": 1,)"), StatusCode::kInvalidArgument,
       "unknown key \"colour\""},
      {"case id type", make_case(R"("case_id": 5,)"), StatusCode::kParseError, "duplicate key"},
      {"case id number", R"({"splintcore_case": 1, "case_id": 5})", StatusCode::kInvalidArgument,
       "\"case_id\" must be string"},
      {"units", R"({"splintcore_case": 1, "units": "inch"})", StatusCode::kInvalidArgument,
       "\"units\" must be \"mm\""},
      {"units empty", R"({"splintcore_case": 1, "units": ""})", StatusCode::kInvalidArgument,
       "non-empty string"},
      {"case id not plain", R"({"splintcore_case": 1, "case_id": "a/b"})",
       StatusCode::kInvalidArgument, "\"case_id\" must be 1-64"},
      {"case id nul", R"({"splintcore_case": 1, "case_id": "a\u0000"})", StatusCode::kParseError,
       "not allowed"},
      {"jaws not array", make_case("", "{}"), StatusCode::kInvalidArgument,
       "\"jaws\" must be array"},
      {"jaw not object", make_case("", "[1]"), StatusCode::kInvalidArgument,
       "\"jaws\" must be object"},
      {"jaw unknown key", make_case("", R"([{"role": "maxilla", "mesh": "a", "x": 1}])"),
       StatusCode::kInvalidArgument, "unknown key \"x\" in a jaw"},
      {"jaw no role", make_case("", R"([{"mesh": "a"}])"), StatusCode::kInvalidArgument,
       "a jaw needs \"role\""},
      {"jaw no mesh", make_case("", R"([{"role": "maxilla"}])"), StatusCode::kInvalidArgument,
       "a jaw needs \"role\""},
      {"jaw bad role", make_case("", R"([{"role": "upper", "mesh": "a"}])"),
       StatusCode::kInvalidArgument, "\"maxilla\" or \"mandible\""},
      {"jaw role type", make_case("", R"([{"role": 1, "mesh": "a"}])"),
       StatusCode::kInvalidArgument, "\"role\" must be string"},
      {"jaw mesh empty", make_case("", R"([{"role": "maxilla", "mesh": ""}])"),
       StatusCode::kInvalidArgument, "non-empty"},
      {"transform type", make_case("", R"([{"role": "maxilla", "mesh": "a", "transform": 1}])"),
       StatusCode::kInvalidArgument, "\"transform\" must be array"},
      {"transform count",
       make_case("", R"([{"role": "maxilla", "mesh": "a", "transform": [1, 0, 0]}])"),
       StatusCode::kInvalidArgument, "16 numbers"},
      {"transform value", make_case("", R"([{"role": "maxilla", "mesh": "a",
                          "transform": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,"x"]}])"),
       StatusCode::kInvalidArgument, "must be number"},
      {"transform range", make_case("", R"([{"role": "maxilla", "mesh": "a",
                          "transform": [1,0,0,0, 0,1,0,0, 0,0,1,1e7, 0,0,0,1]}])"),
       StatusCode::kInvalidArgument, "outside"},
      {"transform not rigid", make_case("", R"([{"role": "maxilla", "mesh": "a",
                          "transform": [2,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}])"),
       StatusCode::kInvalidArgument, "\"transform\": "},
      {"two maxillae",
       make_case("", R"([{"role": "maxilla", "mesh": "a"}, {"role": "maxilla", "mesh": "b"}])"),
       StatusCode::kInvalidArgument, "two jaws with the role \"maxilla\""},
      {"no base", R"({"splintcore_case": 1})", StatusCode::kInvalidArgument, "no \"base\""},
      {"base type", R"({"splintcore_case": 1, "base": []})", StatusCode::kInvalidArgument,
       "\"base\" must be object"},
      {"base unknown key", make_case("", "", R"("x": 1,)"), StatusCode::kInvalidArgument,
       "unknown key \"x\" in \"base\""},
      {"occlusal zero", make_case("", "", R"("occlusal_normal": [0, 0, 0],)"),
       StatusCode::kInvalidArgument, "must not be the zero vector"},
      {"occlusal count", make_case("", "", R"("occlusal_normal": [0, 1],)"),
       StatusCode::kInvalidArgument, "needs 3 numbers, has 2"},
      {"occlusal type", make_case("", "", R"("occlusal_normal": 1,)"), StatusCode::kInvalidArgument,
       "must be array"},
      {"spacing small", make_case("", "", R"("spacing_mm": 0,)"), StatusCode::kInvalidArgument,
       "\"spacing_mm\" is 0, outside [0.01, 50]"},
      {"spacing nan-ish", make_case("", "", R"("spacing_mm": null,)"), StatusCode::kInvalidArgument,
       "must be number, not null"},
      {"corner radius", make_case("", "", R"("corner_radius_mm": 21,)"),
       StatusCode::kInvalidArgument, "corner_radius_mm"},
      {"corner segments 3", make_case("", "", R"("corner_segments": 3,)"),
       StatusCode::kInvalidArgument, "1, 2, 4, 8 or 16"},
      {"corner segments fraction", make_case("", "", R"("corner_segments": 2.5,)"),
       StatusCode::kInvalidArgument, "1, 2, 4, 8 or 16"},
      {"corner segments 32", make_case("", "", R"("corner_segments": 32,)"),
       StatusCode::kInvalidArgument, "outside"},
      {"inner length", make_case("", "", R"("inner_length_mm": -1,)"), StatusCode::kInvalidArgument,
       "inner_length_mm"},
      {"outside length", make_case("", "", R"("outside_length_mm": 101,)"),
       StatusCode::kInvalidArgument, "outside_length_mm"},
      {"no upper", make_case("", "", "", R"("lower": [])"), StatusCode::kInvalidArgument,
       "needs \"upper\" and \"lower\""},
      {"no lower", make_case("", "", "", R"("upper": [])"), StatusCode::kInvalidArgument,
       "needs \"upper\" and \"lower\""},
      {"upper type", make_case("", "", "", R"("upper": {}, "lower": [])"),
       StatusCode::kInvalidArgument, "\"upper\" must be array"},
      {"pick type", make_case("", "", "", picks("1")), StatusCode::kInvalidArgument,
       "\"upper\" must be object"},
      {"pick unknown key", make_case("", "", "", picks(R"({"position": [0,0,1], "y": 1})")),
       StatusCode::kInvalidArgument, "unknown key \"y\" in a pick"},
      {"pick no position", make_case("", "", "", picks(R"({"normal": [0,0,1]})")),
       StatusCode::kInvalidArgument, "pick without \"position\" in \"upper\""},
      {"pick position range", make_case("", "", "", picks(R"({"position": [0,0,2e6]})")),
       StatusCode::kInvalidArgument, "\"position\" is"},
      {"pick zero normal",
       make_case("", "", "", picks(R"({"position": [0,0,1], "normal": [0,0,0]})")),
       StatusCode::kInvalidArgument, "\"normal\" must not be the zero vector"},
      {"pick zero direction",
       make_case("", "", "", picks(R"({"position": [0,0,1], "direction": [0,0,0]})")),
       StatusCode::kInvalidArgument, "\"direction\" must not be the zero vector"},
      {"pick inner length",
       make_case("", "", "", picks(R"({"position": [0,0,1], "inner_length_mm": 200})")),
       StatusCode::kInvalidArgument, "inner_length_mm"},
      {"pick outside length",
       make_case("", "", "", picks(R"({"position": [0,0,1], "outside_length_mm": -2})")),
       StatusCode::kInvalidArgument, "outside_length_mm"},
      {"lower pick error", make_case("", "", "", R"("upper": [], "lower": [{"position": 1}])"),
       StatusCode::kInvalidArgument, "\"position\" must be array"},
      {"unpaired", make_case("", "", "", R"("upper": [{"position": [0,0,1]}], "lower": [])"),
       StatusCode::kInvalidArgument, "do not pair up: 1 upper, 0 lower"},
      {"insertion zero", make_case(R"("insertion_direction": [0,0,0],)"),
       StatusCode::kInvalidArgument, "\"insertion_direction\" must not be the zero vector"},
      {"blockout type", make_case(R"("insertion_direction": [0,0,1], "blockout": 1,)"),
       StatusCode::kInvalidArgument, "\"blockout\" must be object"},
      {"blockout unknown", make_case(R"("insertion_direction": [0,0,1], "blockout": {"q": 1},)"),
       StatusCode::kInvalidArgument, "unknown key \"q\""},
      {"blockout without direction", make_case(R"("blockout": {},)"), StatusCode::kInvalidArgument,
       "needs \"insertion_direction\""},
      {"blockout voxel", make_case(R"("insertion_direction": [0,0,1], "blockout": {"voxel": 2},)"),
       StatusCode::kInvalidArgument, "\"voxel\""},
      {"blockout inset",
       make_case(R"("insertion_direction": [0,0,1], "blockout": {"voxel": 0.1, "inset": 0.5},)"),
       StatusCode::kInvalidArgument, "\"inset\""},
      {"blockout closing range",
       make_case(
           R"("insertion_direction": [0,0,1], "blockout": {"voxel": 0.1, "closing_radius": 5},)"),
       StatusCode::kInvalidArgument, "\"closing_radius\""},
      {"blockout closing small",
       make_case(
           R"("insertion_direction": [0,0,1], "blockout": {"voxel": 0.1, "closing_radius": 0.1},)"),
       StatusCode::kInvalidArgument, "0 or at least two voxels"},
      {"printer type", make_case(R"("printer": 1,)"), StatusCode::kInvalidArgument,
       "\"printer\" must be string"},
      {"memory cap text", make_case(R"("memory_cap": "lots",)"), StatusCode::kInvalidArgument,
       "\"memory_cap\" must be a size"},
      {"memory cap zero text", make_case(R"("memory_cap": "0",)"), StatusCode::kInvalidArgument,
       "\"memory_cap\" must be a size"},
      {"memory cap type", make_case(R"("memory_cap": true,)"), StatusCode::kInvalidArgument,
       "must be a string such as"},
      {"memory cap range", make_case(R"("memory_cap": 0,)"), StatusCode::kInvalidArgument,
       "outside"},
      {"memory cap fraction", make_case(R"("memory_cap": 1000.5,)"), StatusCode::kInvalidArgument,
       "whole number of bytes"},
      {"output type", make_case(R"("output": [],)"), StatusCode::kInvalidArgument,
       "\"output\" must be object"},
      {"output unknown", make_case(R"("output": {"mesh": "a"},)"), StatusCode::kInvalidArgument,
       "unknown key \"mesh\" in \"output\""},
      {"output splint type", make_case(R"("output": {"splint": 1},)"), StatusCode::kInvalidArgument,
       "\"splint\" must be string"},
      {"output splint path", make_case(R"("output": {"splint": "../../etc/x.stl"},)"),
       StatusCode::kInvalidArgument, "\"splint\" must be a file name in the output folder"},
      {"output splint absolute", make_case(R"("output": {"splint": "/tmp/x.stl"},)"),
       StatusCode::kInvalidArgument, "must be a file name in the output folder"},
      {"output report path", make_case(R"("output": {"report": "a/r.json"},)"),
       StatusCode::kInvalidArgument, "\"report\" must be a file name in the output folder"},
      {"output job type", make_case(R"("output": {"job": 3},)"), StatusCode::kInvalidArgument,
       "\"job\" must be string"},
      {"output job path", make_case(R"("output": {"job": "../job.3mf"},)"),
       StatusCode::kInvalidArgument, "\"job\" must be a file name in the output folder"},
      {"output report type", make_case(R"("output": {"report": []},)"),
       StatusCode::kInvalidArgument, "\"report\" must be string"},
  };
  expect_refusals(cases);
}

TEST(CaseCoverage, EveryOptionalKeyIsRead) {
  const std::string text = make_case(
      R"("insertion_direction": [0, 0, 2], "printer": "eden260", "memory_cap": "64M",
         "blockout": {"voxel": 0.2, "inset": 0.3, "closing_radius": 0.5},
         "output": {"splint": "s.stl", "report": "r.json"},)",
      "",
      R"("occlusal_normal": [0, 0, 1], "spacing_mm": 0.4, "corner_radius_mm": 0.5,
         "corner_segments": 8, "inner_length_mm": 2, "outside_length_mm": 2.5,)",
      R"("upper": [{"position": [0, 0, 1], "normal": [1, 0, 0], "direction": [0, 1, 0],
                    "inner_length_mm": 1, "outside_length_mm": 1.5},
                   {"position": [10, 0, 1]}],
         "lower": [{"position": [0, 0, -1]}, {"position": [10, 0, -1]}])");
  test::TestArena t(size_t{1} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(Context(&t.arena), text.data(), text.size(), "case.json", &c));
  EXPECT_STREQ(c.case_id, "c-1");
  ASSERT_EQ(c.jaws.size(), 2u);
  EXPECT_STREQ(c.jaws[1].role, "mandible");
  EXPECT_TRUE(c.has_insertion_direction);
  EXPECT_TRUE(c.has_blockout);
  EXPECT_EQ(c.memory_cap, uint64_t{64} << 20);
  EXPECT_STREQ(c.output_splint, "s.stl");
  EXPECT_STREQ(c.output_report, "r.json");
  EXPECT_EQ(c.base.corner_segments, 8u);
  EXPECT_EQ(c.upper[0].inner_length, 1.0);
  EXPECT_EQ(c.upper[1].inner_length, 2.0);  // the base's default
  EXPECT_EQ(c.lower[0].outside_length, 2.5);
  // A memory cap as a byte count.
  const std::string bytes = make_case(R"("memory_cap": 1048576,)");
  SPLINTCORE_ASSERT_OK(parse_case(Context(&t.arena), bytes.data(), bytes.size(), "case.json", &c));
  EXPECT_EQ(c.memory_cap, 1048576u);
}

// A jaw's scan, the label, the placement and the spacer's keys: every refusal named (these were
// reached only by the pipeline's tests before, which the coverage job does not run), every key
// read, and the arena bounds the parser states.
TEST(CaseCoverage, ScanLabelPlacementAndClearanceKeys) {
  auto scan_jaws = [](const std::string& scan) {
    return R"([{"role": "maxilla", "mesh": "u.stl", "scan": )" + scan +
           R"(}, {"role": "mandible", "mesh": "l.stl"}])";
  };
  const std::string lm3 = R"([[[0,0,0],[0,0,0]], [[1,0,0],[1,0,0]], [[0,1,0],[0,1,0]]])";
  const std::vector<Case> cases = {
      {"scan without path", make_case("", scan_jaws("{}")), StatusCode::kInvalidArgument,
       "\"scan\" needs \"path\""},
      {"scan landmarks too few",
       make_case("", scan_jaws(R"({"path": "s.stl", "landmarks": [[[0,0,0],[0,0,0]]]})")),
       StatusCode::kInvalidArgument, "\"landmarks\" needs 3 to 64 pairs"},
      {"scan landmark pair",
       make_case(
           "",
           scan_jaws(
               R"({"path": "s.stl", "landmarks": [[[0,0,0]], [[1,0,0],[1,0,0]], [[0,1,0],[0,1,0]]]})")),
       StatusCode::kInvalidArgument, "a landmark pair is"},
      {"scan as a list", make_case("", scan_jaws(R"([{"path": "s.stl"}])")),
       StatusCode::kInvalidArgument, "\"scan\" is a list"},
      {"two scans of one jaw",
       make_case("", R"([{"role": "maxilla", "mesh": "u.stl", "scan": {"path": "a.stl"}},
                         {"role": "maxilla", "mesh": "v.stl", "scan": {"path": "b.stl"}},
                         {"role": "mandible", "mesh": "l.stl"}])"),
       StatusCode::kInvalidArgument, "each with a \"scan\""},
      {"label without text", make_case(R"("label": {"mode": "engrave"},)"),
       StatusCode::kInvalidArgument, "\"label\" needs \"text\""},
      {"label mode", make_case(R"("label": {"text": "A", "mode": "carve"},)"),
       StatusCode::kInvalidArgument, "\"mode\" must be \"engrave\""},
      {"placement", make_case(R"("placement": "floor",)"), StatusCode::kInvalidArgument,
       "\"placement\" must be \"case\""},
      {"inset with clearance", make_case(R"("insertion_direction": [0, 0, 1],
                 "blockout": {"voxel": 0.2, "clearance": 0.1, "inset": 0.1},)"),
       StatusCode::kInvalidArgument, "\"inset\" and \"clearance\" exclude each other"},
  };
  expect_refusals(cases);
  // Every key read, within the parser's own bound.
  const std::string text = make_case(
      R"("label": {"text": "P 7", "mode": "emboss"}, "placement": "tray",
         "insertion_direction": [0, 0, 1],
         "blockout": {"voxel": 0.2, "clearance": 0.1, "inset": 0},)",
      scan_jaws(R"({"path": "s.stl", "landmarks": )" + lm3 +
                R"(, "trim": 0.5, "min_overlap": 0.4, "crowns_within_mm": 1.5})"));
  test::TestArena t(static_cast<size_t>(parse_case_bound(text.size())));
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(Context(&t.arena), text.data(), text.size(), "case.json", &c));
  ASSERT_EQ(c.jaws.size(), 2u);
  ASSERT_TRUE(c.jaws[0].has_scan);
  EXPECT_STREQ(c.jaws[0].scan.path, "s.stl");
  EXPECT_EQ(c.jaws[0].scan.landmarks.size(), 3u);
  EXPECT_EQ(c.jaws[0].scan.trim, 0.5);
  EXPECT_EQ(c.jaws[0].scan.min_overlap, 0.4);
  EXPECT_EQ(c.jaws[0].scan.crowns_within_mm, 1.5);
  EXPECT_TRUE(c.has_label);
  EXPECT_EQ(c.label.mode, LabelMode::kEmboss);
  EXPECT_TRUE(c.place_on_tray);
  EXPECT_EQ(c.blockout.offset, 0.1);
  EXPECT_EQ(c.blockout.inset, 0.0);
  // The base's bound grows with the picks and the sections.
  EXPECT_GT(case_base_bound(c, 100, 8), case_base_bound(c, 10, 8));
}

// The automatic outline's keys ("base": {"auto": {...}}): every error named, every key read.
TEST(CaseCoverage, AutoOutlineKeys) {
  const std::string none = R"("auto": {})";
  auto with_auto = [](const std::string& body, const std::string& root = "") {
    return make_case(root, "", "", std::string(R"("auto": )") + body);
  };
  const std::vector<Case> cases = {
      {"auto not an object", with_auto("[1]"), StatusCode::kInvalidArgument,
       "\"auto\" must be object"},
      {"auto unknown key", with_auto(R"({"depth": 2})"), StatusCode::kInvalidArgument,
       "unknown key \"depth\" in \"auto\""},
      {"auto and picks", make_case("", "", R"("auto": {},)"), StatusCode::kInvalidArgument,
       "give either \"auto\" or"},
      {"auto and normal", make_case("", "", R"("occlusal_normal": [0, 0, 1],)", none),
       StatusCode::kInvalidArgument, "give either \"auto\" or"},
      {"depth zero", with_auto(R"({"indentation_depth_mm": 0})"), StatusCode::kInvalidArgument,
       "\"indentation_depth_mm\" is 0, outside"},
      {"overhang", with_auto(R"({"overhang_mm": 11})"), StatusCode::kInvalidArgument,
       "\"overhang_mm\" is 11, outside"},
      {"spacing", with_auto(R"({"pick_spacing_mm": 1})"), StatusCode::kInvalidArgument,
       "\"pick_spacing_mm\" is 1, outside"},
      {"opening", with_auto(R"({"bite_opening_mm": 0.05})"), StatusCode::kInvalidArgument,
       "\"bite_opening_mm\" is 0.05, outside"},
      {"survey type", with_auto(R"({"survey": 1})"), StatusCode::kInvalidArgument,
       "\"survey\" must be true or false"},
      {"survey and direction",
       with_auto(R"({"survey": true})", R"("insertion_direction": [0, 0, 1],)"),
       StatusCode::kInvalidArgument, "both choose the direction"},
      {"distal ends not an array", with_auto(R"({"distal_ends": {"x": 1}})"),
       StatusCode::kInvalidArgument, "\"distal_ends\" must be array, not object"},
      {"distal ends one point", with_auto(R"({"distal_ends": [[1, 2, 3]]})"),
       StatusCode::kInvalidArgument, "\"distal_ends\" needs 2 points, one a side"},
      {"distal ends three points",
       with_auto(R"({"distal_ends": [[1, 2, 3], [4, 5, 6], [7, 8, 9]]})"),
       StatusCode::kInvalidArgument, "\"distal_ends\" needs 2 points"},
      {"distal end 0 not a point", with_auto(R"({"distal_ends": [1, [4, 5, 6]]})"),
       StatusCode::kInvalidArgument, "\"distal_ends\" must be array, not number"},
      {"distal end 1 short", with_auto(R"({"distal_ends": [[1, 2, 3], [4, 5]]})"),
       StatusCode::kInvalidArgument, "\"distal_ends\" needs 3 numbers, has 2"},
      {"distal end 1 too far", with_auto(R"({"distal_ends": [[1, 2, 3], [4, 5, 2e6]]})"),
       StatusCode::kInvalidArgument, "\"distal_ends\" is 2e+06, outside"},
      {"neither picks nor auto", make_case("", "", "", R"("spacing_mm": 0.5)"),
       StatusCode::kInvalidArgument, "needs \"upper\" and \"lower\" pick lists, or \"auto\""},
  };
  expect_refusals(cases);
  // Every key read; blockout without an insertion direction is fine with auto.
  const std::string text =
      make_case(R"("blockout": {"voxel": 0.2},)", "", "",
                R"("auto": {"indentation_depth_mm": 1.5, "overhang_mm": 1, "pick_spacing_mm": 5,
                  "bite_opening_mm": 2.5, "survey": true,
                  "distal_ends": [[-20.5, -7, 0.25], [21, -6.5, 0]]})");
  test::TestArena t(size_t{1} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(Context(&t.arena), text.data(), text.size(), "case.json", &c));
  EXPECT_TRUE(c.has_auto_outline);
  EXPECT_TRUE(c.has_blockout);
  EXPECT_FALSE(c.has_insertion_direction);
  EXPECT_EQ(c.outline.indentation_depth_mm, 1.5);
  EXPECT_EQ(c.outline.overhang_mm, 1.0);
  EXPECT_EQ(c.outline.pick_spacing_mm, 5.0);
  EXPECT_TRUE(c.outline.has_bite_opening);
  EXPECT_EQ(c.outline.bite_opening_mm, 2.5);
  EXPECT_TRUE(c.outline.survey);
  EXPECT_TRUE(c.outline.has_distal_ends);
  EXPECT_EQ(c.outline.distal_ends[0], (Vec3{-20.5, -7, 0.25}));
  EXPECT_EQ(c.outline.distal_ends[1], (Vec3{21, -6.5, 0}));
  EXPECT_TRUE(c.upper.empty());
  // The defaults.
  const std::string plain = with_auto("{}");
  SPLINTCORE_ASSERT_OK(parse_case(Context(&t.arena), plain.data(), plain.size(), "case.json", &c));
  EXPECT_EQ(c.outline.indentation_depth_mm, 2.0);
  EXPECT_EQ(c.outline.pick_spacing_mm, 3.0);
  EXPECT_FALSE(c.outline.has_bite_opening);
  EXPECT_FALSE(c.outline.survey);
  EXPECT_FALSE(c.outline.has_distal_ends);
}

TEST(CaseCoverage, CtKeys) {
  auto ct = [](const std::string& body) { return make_case("\"ct\": {" + body + "},"); };
  const std::vector<Case> cases = {
      {"hu_max fraction", ct(R"("volume": "v.nrrd", "hu_max": 400.5)"),
       StatusCode::kInvalidArgument, "\"hu_max\" must be an integer"},
      {"smooth fraction", ct(R"("volume": "v.nrrd", "smooth": 2.5)"), StatusCode::kInvalidArgument,
       "\"smooth\" must be an integer"},
      {"decimate fraction", ct(R"("volume": "v.nrrd", "decimate": 1000.5)"),
       StatusCode::kInvalidArgument, "\"decimate\" must be an integer"},
      {"connectivity 18", ct(R"("volume": "v.nrrd", "connectivity": 18)"),
       StatusCode::kInvalidArgument, "\"connectivity\" must be 6 or 26"},
  };
  expect_refusals(cases);
  // Accepted: 26-connectivity, smoothing, no decimation.
  const std::string text = ct(R"("volume": "v.nrrd", "hu_min": -100, "hu_max": 2000,
                                  "connectivity": 26, "smooth": 3)");
  test::TestArena t(size_t{1} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(Context(&t.arena), text.data(), text.size(), "case.json", &c));
  EXPECT_STREQ(c.ct_volume, "v.nrrd");
  EXPECT_EQ(c.ct_window.lo, -100);
  EXPECT_EQ(c.ct_grow.connectivity, Connectivity::k26);
  EXPECT_EQ(c.ct_smooth.iterations, 3u);
  EXPECT_EQ(c.ct_decimate.target_triangles, 0u);
}

TEST(CaseCoverage, OptionalPartsLeftOut) {
  // An output with only the splint's name; a blockout without closing.
  const std::string text = make_case(
      R"("insertion_direction": [0, 0, 1], "blockout": {"voxel": 0.2, "closing_radius": 0},
         "output": {"splint": "s.stl"},)");
  test::TestArena t(size_t{1} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(Context(&t.arena), text.data(), text.size(), "case.json", &c));
  EXPECT_STREQ(c.output_splint, "s.stl");
  EXPECT_EQ(c.output_report, nullptr);
  EXPECT_TRUE(c.has_blockout);
  EXPECT_EQ(c.blockout.closing_radius, 0.0);
}

TEST(CaseCoverage, BaseFailuresLeaveTheArenaAsItWas) {
  // The upper picks, then the lower picks, then the base itself fail: nothing stays.
  const std::string same_place = R"({"position": [0, 0, -1]}, {"position": [0, 0, -1]})";
  const std::vector<std::pair<std::string, const char*>> cases = {
      {make_case("", "", "", R"("upper": [{"position": [0, 0, 1]}, {"position": [0, 0, 1]}],
                               "lower": [{"position": [0, 0, -1]}, {"position": [10, 0, -1]}])"),
       "upper pick 1"},
      {make_case("", "", "",
                 R"("upper": [{"position": [0, 0, 1]}, {"position": [10, 0, 1]}],
                               "lower": [)" +
                     same_place + "]"),
       "lower pick 1"},
      {make_case("", "",
                 R"("spacing_mm": 0.5, "inner_length_mm": 0.01, "outside_length_mm": 0.01,)",
                 R"("upper": [{"position": [0, 0, 1]}, {"position": [10, 0, 1]}],
                    "lower": [{"position": [0, 0, 1]}, {"position": [10, 0, 1]}])"),
       ""},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.first);
    test::TestArena t(size_t{16} << 20);
    CaseFile cf;
    SPLINTCORE_ASSERT_OK(
        parse_case(Context(&t.arena), c.first.data(), c.first.size(), "case.json", &cf));
    const size_t used = t.arena.used();
    Mesh base(&t.arena);
    BaseReport report;
    Status s = build_case_base(Context(&t.arena), cf, &base, &report);
    EXPECT_FALSE(s.is_ok());
    EXPECT_NE(std::string(s.message()).find(c.second), std::string::npos) << s.message();
    EXPECT_EQ(t.arena.used(), used);
    EXPECT_TRUE(base.vertices.empty() && base.triangles.empty());
  }
}

}  // namespace
}  // namespace splintcore
