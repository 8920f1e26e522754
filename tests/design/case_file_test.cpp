// The case file: the three committed cases parse to what their files say; every schema error
// names the key or value at fault with its line and column; the arena exhaustion loop and the
// truncation loop; and each case builds a closed, valid base solid, the same bytes every run.

#include <gtest/gtest.h>

#include <charconv>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "splintcore/design.h"
#include "splintcore/json.h"
#include "splintcore/mesh.h"
#include "splintcore/platform.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::format;

std::string fixture(const char* name) {
  std::vector<uint8_t> bytes =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/" + name);
  return std::string(bytes.begin(), bytes.end());
}

// Parses `text` from a heap copy of exactly its length (no NUL after it).
Status parse(Arena& arena, const std::string& text, CaseFile* out, const char* name = "case.json") {
  std::unique_ptr<char[]> copy(new char[text.size() > 0 ? text.size() : 1]);
  if (!text.empty()) std::memcpy(copy.get(), text.data(), text.size());
  Context ctx(&arena);
  return parse_case(ctx, copy.get(), text.size(), name, out);
}

void expect_vec(const Vec3& v, double x, double y, double z) {
  EXPECT_EQ(v.x, x);
  EXPECT_EQ(v.y, y);
  EXPECT_EQ(v.z, z);
}

// A number of the "base" object as the raw JSON has it (the section spacing is a tuning knob
// that the fixture generator changes; the test follows the file).
double base_number(const std::string& text, const char* key) {
  test::TestArena a(size_t{1} << 20);
  Context ctx(&a.arena);
  JsonDocument doc;
  Status s = parse_json(ctx, text.data(), text.size(), JsonLimits{}, nullptr, &doc);
  EXPECT_TRUE(s.is_ok()) << format(s);
  if (!s.is_ok()) return -1;
  const JsonValue* base = doc.member(doc.root(), "base");
  const JsonValue* v = base != nullptr ? doc.member(*base, key) : nullptr;
  EXPECT_NE(v, nullptr) << key;
  return v != nullptr ? v->number : -1;
}

bool is_identity(const RigidTransform& t) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (t.r[i][j] != (i == j ? 1.0 : 0.0)) return false;
    }
  }
  return t.t == Vec3{};
}

// ---------------------------------------------------------------------------------------------
// The committed cases.

const char* const kFixtures[] = {"paper_scale.json", "rounded.json", "uneven.json"};

TEST(CaseFile, PaperScaleFields) {
  test::TestArena a(size_t{4} << 20);
  CaseFile c;
  const std::string text = fixture("paper_scale.json");
  SPLINTCORE_ASSERT_OK(parse(a.arena, text, &c));
  EXPECT_EQ(c.version, 1u);
  EXPECT_STREQ(c.case_id, "phantom-paper-scale");
  ASSERT_EQ(c.jaws.size(), 2u);
  EXPECT_STREQ(c.jaws[0].role, "maxilla");
  EXPECT_STREQ(c.jaws[0].mesh, "maxilla.stl");
  EXPECT_TRUE(is_identity(c.jaws[0].transform));
  EXPECT_STREQ(c.jaws[1].role, "mandible");
  EXPECT_STREQ(c.jaws[1].mesh, "mandible.stl");
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_EQ(c.jaws[1].transform.r[i][j], i == j ? 1.0 : 0.0);
  }
  expect_vec(c.jaws[1].transform.t, 0, 0, -2.0);

  expect_vec(c.occlusal_normal, 0, 0, 1);
  EXPECT_EQ(c.base.spacing_mm, base_number(text, "spacing_mm"));
  EXPECT_GE(c.base.spacing_mm, 0.01);
  EXPECT_EQ(c.base.corner_radius_mm, 0.0);  // not given: sharp corners
  EXPECT_EQ(c.base.corner_segments, 4u);
  ASSERT_EQ(c.upper.size(), 14u);
  ASSERT_EQ(c.lower.size(), 14u);
  // Lengths come from the base's defaults (4.0 and 3.5) since no pick overrides them.
  for (size_t i = 0; i < 14; ++i) {
    for (const Pick* p : {&c.upper[i], &c.lower[i]}) {
      EXPECT_EQ(p->inner_length, 4.0) << i;
      EXPECT_EQ(p->outside_length, 3.5) << i;
      EXPECT_NE(p->normal, Vec3{}) << i;
      EXPECT_EQ(p->direction, Vec3{}) << i;  // not given
    }
  }
  expect_vec(c.upper[0].position, 24.5961, -7.5192, 1.6);
  expect_vec(c.upper[0].normal, 0.9445, -0.1023, -0.31);
  expect_vec(c.upper[13].position, -24.5961, -7.5192, 1.6);
  expect_vec(c.lower[0].position, 23.6122, -7.2507, -1.6);
  expect_vec(c.lower[13].position, -23.6122, -7.2507, -1.6);
  expect_vec(c.lower[13].normal, -0.9445, -0.1019, 0.31);

  EXPECT_TRUE(c.has_insertion_direction);
  expect_vec(c.insertion_direction, 0, 0, 1);
  EXPECT_STREQ(c.printer, "eden260");
  EXPECT_EQ(c.memory_cap, uint64_t{67108864});  // "64M"
  ASSERT_NE(c.output_splint, nullptr);
  ASSERT_NE(c.output_report, nullptr);
  EXPECT_STREQ(c.output_splint, "splint.stl");
  EXPECT_STREQ(c.output_report, "report.json");
}

TEST(CaseFile, RoundedFields) {
  test::TestArena a(size_t{4} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse(a.arena, fixture("rounded.json"), &c));
  EXPECT_EQ(c.version, 1u);
  EXPECT_STREQ(c.case_id, "phantom-rounded");
  EXPECT_EQ(c.jaws.size(), 0u);
  expect_vec(c.occlusal_normal, 0, 0, 1);  // the default
  EXPECT_EQ(c.base.spacing_mm, 1.0);
  EXPECT_EQ(c.base.corner_radius_mm, 0.8);
  EXPECT_EQ(c.base.corner_segments, 4u);
  ASSERT_EQ(c.upper.size(), 12u);
  ASSERT_EQ(c.lower.size(), 12u);
  for (size_t i = 0; i < 12; ++i) {
    for (const Pick* p : {&c.upper[i], &c.lower[i]}) {
      EXPECT_EQ(p->inner_length, 4.5) << i;
      EXPECT_EQ(p->outside_length, 3.0) << i;
      EXPECT_NE(p->normal, Vec3{}) << i;
      EXPECT_EQ(p->direction, Vec3{}) << i;
    }
  }
  expect_vec(c.upper[5].position, 3.934, 43.4934, 1.8);
  expect_vec(c.lower[11].normal, -0.9483, -0.0566, 0.31);
  // Everything after the base takes its default.
  EXPECT_FALSE(c.has_insertion_direction);
  expect_vec(c.insertion_direction, 0, 0, 1);
  EXPECT_STREQ(c.printer, "eden260");
  EXPECT_EQ(c.memory_cap, 0u);
  EXPECT_EQ(c.output_splint, nullptr);
  EXPECT_EQ(c.output_report, nullptr);
}

TEST(CaseFile, UnevenFields) {
  test::TestArena a(size_t{4} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse(a.arena, fixture("uneven.json"), &c));
  EXPECT_STREQ(c.case_id, "phantom-uneven");
  expect_vec(c.occlusal_normal, 0, 0.05, 1);  // kept as written (make_lines normalises)
  EXPECT_EQ(c.base.spacing_mm, 0.5);
  EXPECT_EQ(c.base.corner_radius_mm, 0.0);
  ASSERT_EQ(c.upper.size(), 16u);
  ASSERT_EQ(c.lower.size(), 16u);
  // Per-pick lengths (the generator: 3.5 + 0.1 (i % 4) and 3.0 + 0.15 ((i + 1) % 3)), and an
  // explicit direction on every third pick, a surface normal on the others.
  const double inner[] = {3.5, 3.6, 3.7, 3.8};
  const double outside[] = {3.15, 3.3, 3.0};
  for (size_t i = 0; i < 16; ++i) {
    for (const Pick* p : {&c.upper[i], &c.lower[i]}) {
      EXPECT_EQ(p->inner_length, inner[i % 4]) << i;
      EXPECT_EQ(p->outside_length, outside[i % 3]) << i;
      if (i % 3 == 0) {
        EXPECT_NE(p->direction, Vec3{}) << i;
        EXPECT_EQ(p->normal, Vec3{}) << i;
        EXPECT_EQ(p->direction.z, 0.0) << i;
      } else {
        EXPECT_EQ(p->direction, Vec3{}) << i;
        EXPECT_NE(p->normal, Vec3{}) << i;
        EXPECT_EQ(p->normal.z, 0.2) << i;
      }
    }
  }
  expect_vec(c.upper[0].position, 26.4618, -9.1388, 1.5);
  expect_vec(c.upper[0].direction, 0.993, -0.1181, 0.0);
  expect_vec(c.lower[7].normal, 0.0802, 0.9968, 0.2);
  EXPECT_FALSE(c.has_insertion_direction);
  EXPECT_EQ(c.memory_cap, 0u);
}

// Every pick of every fixture against the raw JSON (an independent walk of the same file).
TEST(CaseFile, EveryPickMatchesTheJson) {
  for (const char* name : kFixtures) {
    SCOPED_TRACE(name);
    const std::string text = fixture(name);
    test::TestArena a(size_t{4} << 20);
    CaseFile c;
    SPLINTCORE_ASSERT_OK(parse(a.arena, text, &c, name));
    Context ctx(&a.arena);
    JsonDocument doc;
    SPLINTCORE_ASSERT_OK(parse_json(ctx, text.data(), text.size(), JsonLimits{}, name, &doc));
    const JsonValue* base = doc.member(doc.root(), "base");
    ASSERT_NE(base, nullptr);
    auto number_or = [&](const JsonValue& object, const char* key, double fallback) {
      const JsonValue* v = doc.member(object, key);
      return v != nullptr ? v->number : fallback;
    };
    auto vec_or_zero = [&](const JsonValue& object, const char* key) {
      const JsonValue* v = doc.member(object, key);
      if (v == nullptr) return Vec3{};
      const JsonValue& x = doc.at(v->first_child);
      const JsonValue& y = doc.at(x.next_sibling);
      const JsonValue& z = doc.at(y.next_sibling);
      return Vec3{x.number, y.number, z.number};
    };
    const double inner_default = number_or(*base, "inner_length_mm", 3.0);
    const double outside_default = number_or(*base, "outside_length_mm", 3.0);
    for (const char* list : {"upper", "lower"}) {
      const JsonValue* picks = doc.member(*base, list);
      const Span<const Pick> parsed = std::strcmp(list, "upper") == 0 ? c.upper : c.lower;
      ASSERT_EQ(parsed.size(), picks->child_count);
      size_t i = 0;
      for (uint32_t k = picks->first_child; k != kJsonNone; k = doc.at(k).next_sibling, ++i) {
        const JsonValue& p = doc.at(k);
        EXPECT_EQ(parsed[i].position, vec_or_zero(p, "position")) << list << i;
        EXPECT_EQ(parsed[i].normal, vec_or_zero(p, "normal")) << list << i;
        EXPECT_EQ(parsed[i].direction, vec_or_zero(p, "direction")) << list << i;
        EXPECT_EQ(parsed[i].inner_length, number_or(p, "inner_length_mm", inner_default));
        EXPECT_EQ(parsed[i].outside_length, number_or(p, "outside_length_mm", outside_default));
      }
    }
  }
}

// A small valid case whose parts a test replaces. '@' marks where an error must point; it is
// removed before parsing.
struct CaseParts {
  std::string head = "\"splintcore_case\": 1,\n";
  std::string root;  // root members, each ending in ",\n"
  std::string base;  // base members, each ending in ",\n"
  std::string pick;  // more members of the first upper pick, each starting with ", "
  std::string upper = "[{\"position\": [0, 0, 1]%PICK%}, {\"position\": [10, 0, 1]}]";
  std::string lower = "[{\"position\": [0, 0, -1]}, {\"position\": [10, 0, -1]}]";

  std::string text() const {
    std::string u = upper;
    const size_t at = u.find("%PICK%");
    if (at != std::string::npos) u.replace(at, 6, pick);
    return "{\n  " + head + root + "  \"base\": {\n" + base + "    \"upper\": " + u +
           ",\n    \"lower\": " + lower + "\n  }\n}\n";
  }
};

CaseParts with_root(const std::string& s) {
  CaseParts p;
  p.root = s;
  return p;
}
CaseParts with_base(const std::string& s) {
  CaseParts p;
  p.base = s;
  return p;
}
CaseParts with_pick(const std::string& s) {
  CaseParts p;
  p.pick = s;
  return p;
}

void expect_case_error(std::string text, StatusCode code,
                       std::initializer_list<const char*> fragments) {
  SCOPED_TRACE(::testing::Message() << "case:\n" << text);
  const size_t at = text.find('@');
  ASSERT_NE(at, std::string::npos) << "no '@' marker";
  text.erase(at, 1);
  ASSERT_EQ(text.find('@'), std::string::npos) << "two '@' markers";
  uint64_t line = 1, column = 1;
  for (size_t i = 0; i < at; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  test::TestArena a(size_t{1} << 20);
  CaseFile c;
  Status s = parse(a.arena, text, &c);
  ASSERT_FALSE(s.is_ok());
  EXPECT_EQ(s.code(), code) << format(s);
  EXPECT_EQ(s.line(), line) << format(s);
  EXPECT_EQ(s.column(), column) << format(s);
  EXPECT_STREQ(s.file(), "case.json");
  const std::string where =
      "case.json:" + std::to_string(line) + ":" + std::to_string(column) + ": ";
  EXPECT_EQ(format(s).rfind(where, 0), 0u) << format(s);
  for (const char* f : fragments) {
    EXPECT_NE(std::strstr(s.message(), f), nullptr)
        << "message \"" << s.message() << "\" lacks \"" << f << "\"";
  }
}

void expect_invalid(const CaseParts& parts, std::initializer_list<const char*> fragments) {
  expect_case_error(parts.text(), StatusCode::kInvalidArgument, fragments);
}

TEST(CaseFile, TheSmallTemplateIsValidAndTakesTheDefaults) {
  test::TestArena a(size_t{1} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse(a.arena, CaseParts{}.text(), &c));
  EXPECT_EQ(c.version, 1u);
  EXPECT_STREQ(c.case_id, "");
  EXPECT_EQ(c.jaws.size(), 0u);
  expect_vec(c.occlusal_normal, 0, 0, 1);
  const BaseParams defaults;
  EXPECT_EQ(c.base.spacing_mm, defaults.spacing_mm);
  EXPECT_EQ(c.base.corner_radius_mm, defaults.corner_radius_mm);
  EXPECT_EQ(c.base.corner_segments, defaults.corner_segments);
  ASSERT_EQ(c.upper.size(), 2u);
  ASSERT_EQ(c.lower.size(), 2u);
  EXPECT_EQ(c.upper[0].inner_length, 3.0);
  EXPECT_EQ(c.upper[0].outside_length, 3.0);
  expect_vec(c.lower[1].position, 10, 0, -1);
  EXPECT_FALSE(c.has_insertion_direction);
  EXPECT_STREQ(c.printer, "eden260");
  EXPECT_EQ(c.memory_cap, 0u);
  EXPECT_EQ(c.output_splint, nullptr);
}

TEST(CaseFile, PickLengthsDefaultAndOverride) {
  test::TestArena a(size_t{1} << 20);
  CaseFile c;
  CaseParts p;
  p.base = "    \"inner_length_mm\": 4,\n";  // outside_length_mm not given: 3
  p.pick = ", \"outside_length_mm\": 2.5, \"inner_length_mm\": 0";
  SPLINTCORE_ASSERT_OK(parse(a.arena, p.text(), &c));
  EXPECT_EQ(c.upper[0].inner_length, 0.0);
  EXPECT_EQ(c.upper[0].outside_length, 2.5);
  EXPECT_EQ(c.upper[1].inner_length, 4.0);
  EXPECT_EQ(c.upper[1].outside_length, 3.0);
  EXPECT_EQ(c.lower[0].inner_length, 4.0);
  EXPECT_EQ(c.lower[0].outside_length, 3.0);
  // Boundaries are inclusive.
  p.base =
      "    \"inner_length_mm\": 100, \"outside_length_mm\": 0, \"spacing_mm\": 0.01,\n"
      "    \"corner_radius_mm\": 20, \"corner_segments\": 16,\n";
  p.pick = ", \"normal\": [0, 1, 0], \"direction\": [1e-6, -1e6, 1e6]";
  a.arena.reset();
  SPLINTCORE_ASSERT_OK(parse(a.arena, p.text(), &c));
  EXPECT_EQ(c.upper[1].inner_length, 100.0);
  EXPECT_EQ(c.upper[1].outside_length, 0.0);
  EXPECT_EQ(c.base.spacing_mm, 0.01);
  EXPECT_EQ(c.base.corner_radius_mm, 20.0);
  EXPECT_EQ(c.base.corner_segments, 16u);
  expect_vec(c.upper[0].normal, 0, 1, 0);
  expect_vec(c.upper[0].direction, 1e-6, -1e6, 1e6);
  for (const char* segments : {"1", "2", "4", "8", "16.0"}) {
    p = CaseParts{};
    p.base = std::string("    \"corner_segments\": ") + segments + ",\n";
    a.arena.reset();
    SPLINTCORE_EXPECT_OK(parse(a.arena, p.text(), &c));
  }
}

TEST(CaseFile, JawTransformsAndOtherRootValues) {
  test::TestArena a(size_t{1} << 20);
  CaseFile c;
  // A quarter turn about z with a translation, a byte count as the memory cap.
  CaseParts parts;
  parts.head = "\"splintcore_case\": 1.0,\n";
  parts.root =
      "  \"case_id\": \"A-z_0.9\",\n  \"units\": \"mm\",\n"
      "  \"jaws\": [{\"mesh\": \"lower jaw.stl\", \"role\": \"mandible\",\n"
      "            \"transform\": [0, -1, 0, 1,  1, 0, 0, 2,  0, 0, 1, 3,  0, 0, 0, 1]}],\n"
      "  \"insertion_direction\": [0.1, 0, 1],\n"
      "  \"printer\": \"other\",\n"
      "  \"memory_cap\": 1048576,\n"
      "  \"output\": {\"report\": \"r.json\"},\n";
  const std::string text = parts.text();
  SPLINTCORE_ASSERT_OK(parse(a.arena, text, &c));
  EXPECT_EQ(c.version, 1u);
  EXPECT_STREQ(c.case_id, "A-z_0.9");
  ASSERT_EQ(c.jaws.size(), 1u);
  EXPECT_STREQ(c.jaws[0].role, "mandible");
  EXPECT_STREQ(c.jaws[0].mesh, "lower jaw.stl");
  const double r[3][3] = {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_EQ(c.jaws[0].transform.r[i][j], r[i][j]) << i << j;
  }
  expect_vec(c.jaws[0].transform.t, 1, 2, 3);
  EXPECT_TRUE(c.has_insertion_direction);
  expect_vec(c.insertion_direction, 0.1, 0, 1);
  EXPECT_STREQ(c.printer, "other");
  EXPECT_EQ(c.memory_cap, uint64_t{1048576});
  EXPECT_EQ(c.output_splint, nullptr);
  EXPECT_STREQ(c.output_report, "r.json");
  // Byte sizes with each suffix, in either case.
  const struct {
    const char* text;
    uint64_t bytes;
  } sizes[] = {{"\"512K\"", 512ull << 10},
               {"\"2g\"", 2ull << 30},
               {"\"64m\"", 64ull << 20},
               {"\"4096\"", 4096},
               {"1099511627776", 1ull << 40}};
  for (const auto& size : sizes) {
    a.arena.reset();
    SPLINTCORE_ASSERT_OK(parse(
        a.arena, with_root(std::string("  \"memory_cap\": ") + size.text + ",\n").text(), &c));
    EXPECT_EQ(c.memory_cap, size.bytes) << size.text;
  }
  // A 64-character id is the longest allowed.
  a.arena.reset();
  SPLINTCORE_EXPECT_OK(
      parse(a.arena, with_root("  \"case_id\": \"" + std::string(64, 'x') + "\",\n").text(), &c));
}

// ---------------------------------------------------------------------------------------------
// Schema errors.

TEST(CaseFileErrors, UnknownKeysAtEveryLevel) {
  expect_invalid(with_root("  \"colour\": @\"red\",\n"),
                 {"unknown key \"colour\" in the case",
                  "(allowed: splintcore_case case_id units jaws base insertion_direction "
                  "blockout ct printer memory_cap min_thickness max_wall_crossing "
                  "max_sideways_crossing placement label output plan)"});
  expect_invalid(with_base("    \"spacing\": @1,\n"),
                 {"unknown key \"spacing\" in \"base\"",
                  "(allowed: occlusal_normal spacing_mm corner_radius_mm corner_segments "
                  "inner_length_mm outside_length_mm upper lower auto)"});
  expect_invalid(with_pick(", \"colour\": @[1]"),
                 {"unknown key \"colour\" in a pick",
                  "(allowed: position normal direction inner_length_mm outside_length_mm)"});
  expect_invalid(
      with_root("  \"jaws\": [{\"role\": \"maxilla\", \"mesh\": \"m.stl\", \"scale\": @2}],\n"),
      {"unknown key \"scale\" in a jaw", "(allowed: role mesh seed transform scan)"});
  expect_invalid(with_root("  \"output\": {\"splint\": \"s.stl\", \"stl\": @\"x\"},\n"),
                 {"unknown key \"stl\" in \"output\"", "(allowed: splint report job)"});
  // Keys are case-sensitive.
  expect_invalid(with_root("  \"Case_ID\": @\"x\",\n"), {"unknown key \"Case_ID\""});
}

TEST(CaseFileErrors, WrongTypes) {
  expect_case_error("@[1, 2]", StatusCode::kInvalidArgument, {"must be object, not array"});
  CaseParts p;
  p.head = "\"splintcore_case\": @\"1\",\n";
  expect_invalid(p, {"\"splintcore_case\" must be number, not string"});
  expect_invalid(with_root("  \"case_id\": @7,\n"), {"\"case_id\" must be string, not number"});
  expect_invalid(with_root("  \"units\": @true,\n"), {"\"units\" must be string, not boolean"});
  expect_invalid(with_root("  \"jaws\": @{},\n"), {"\"jaws\" must be array, not object"});
  expect_invalid(with_root("  \"jaws\": [@\"maxilla.stl\"],\n"),
                 {"\"jaws\" must be object, not string"});
  expect_invalid(with_root("  \"jaws\": [{\"role\": @1, \"mesh\": \"m.stl\"}],\n"),
                 {"\"role\" must be string, not number"});
  expect_invalid(with_root("  \"jaws\": [{\"role\": \"maxilla\", \"mesh\": @null}],\n"),
                 {"\"mesh\" must be string, not null"});
  expect_invalid(with_root("  \"jaws\": [{\"role\": \"maxilla\", \"mesh\": \"m\", \"transform\": "
                           "@\"identity\"}],\n"),
                 {"\"transform\" must be array, not string"});
  expect_invalid(with_root("  \"jaws\": [{\"role\": \"maxilla\", \"mesh\": \"m\", \"transform\": "
                           "[1, 0, 0, 0, 0, @\"1\", 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}],\n"),
                 {"\"transform\" must be number, not string"});
  expect_case_error("{\"splintcore_case\": 1, \"base\": @[]}", StatusCode::kInvalidArgument,
                    {"\"base\" must be object, not array"});
  expect_invalid(with_base("    \"occlusal_normal\": @\"z\",\n"),
                 {"\"occlusal_normal\" must be array, not string"});
  expect_invalid(with_base("    \"spacing_mm\": @\"0.5\",\n"),
                 {"\"spacing_mm\" must be number, not string"});
  expect_invalid(with_base("    \"corner_segments\": @true,\n"),
                 {"\"corner_segments\" must be number, not boolean"});
  CaseParts upper;
  upper.upper = "@{}";
  expect_invalid(upper, {"\"upper\" must be array, not object"});
  CaseParts lower;
  lower.lower = "[{\"position\": [0, 0, -1]}, @5]";
  expect_invalid(lower, {"\"lower\" must be object, not number"});
  upper.upper = "[{\"position\": [0, @\"0\", 1]}, {\"position\": [10, 0, 1]}]";
  expect_invalid(upper, {"\"position\" must be number, not string"});
  expect_invalid(with_pick(", \"normal\": @null"), {"\"normal\" must be array, not null"});
  expect_invalid(with_pick(", \"inner_length_mm\": @[3]"),
                 {"\"inner_length_mm\" must be number, not array"});
  expect_invalid(with_root("  \"insertion_direction\": @{},\n"),
                 {"\"insertion_direction\" must be array, not object"});
  expect_invalid(with_root("  \"printer\": @5,\n"), {"\"printer\" must be string, not number"});
  expect_invalid(with_root("  \"memory_cap\": @true,\n"),
                 {"\"memory_cap\" must be a string such as \"256M\" or a number of bytes"});
  expect_invalid(with_root("  \"output\": @[],\n"), {"\"output\" must be object, not array"});
  expect_invalid(with_root("  \"output\": {\"splint\": @1},\n"),
                 {"\"splint\" must be string, not number"});
  expect_invalid(with_root("  \"output\": {\"report\": @\"\"},\n"),
                 {"\"report\" must be a non-empty string"});
}

TEST(CaseFileErrors, MissingRequiredKeys) {
  CaseParts p;
  p.head = "";
  expect_case_error("@" + p.text(), StatusCode::kInvalidArgument,
                    {"not a splintcore case file", "\"splintcore_case\""});
  expect_case_error("@{\"splintcore_case\": 1, \"case_id\": \"x\"}", StatusCode::kInvalidArgument,
                    {"no \"base\" object"});
  expect_case_error("{\"splintcore_case\": 1, \"base\": @{\"lower\": []}}",
                    StatusCode::kInvalidArgument,
                    {"\"base\" needs \"upper\" and \"lower\" pick lists"});
  expect_case_error("{\"splintcore_case\": 1, \"base\": @{\"upper\": []}}",
                    StatusCode::kInvalidArgument,
                    {"\"base\" needs \"upper\" and \"lower\" pick lists"});
  CaseParts no_position;
  no_position.upper = "[{\"position\": [0, 0, 1]}, @{\"normal\": [0, 1, 0]}]";
  expect_invalid(no_position, {"pick without \"position\" in \"upper\""});
  CaseParts no_position_lower;
  no_position_lower.lower = "[@{}, {\"position\": [10, 0, -1]}]";
  expect_invalid(no_position_lower, {"pick without \"position\" in \"lower\""});
  expect_invalid(
      with_root(
          "  \"jaws\": [{\"role\": \"maxilla\", \"mesh\": \"m\"}, @{\"role\": \"mandible\"}],\n"),
      {"a jaw needs \"role\" and either \"mesh\""});
  expect_invalid(with_root("  \"jaws\": [@{\"mesh\": \"m.stl\"}],\n"),
                 {"a jaw needs \"role\" and either \"mesh\""});
}

TEST(CaseFileErrors, VersionAndUnits) {
  CaseParts p;
  p.head = "\"splintcore_case\": @2,\n";
  expect_case_error(p.text(), StatusCode::kUnsupported,
                    {"case format version 2 is newer than this splintcore reads (1)"});
  p.head = "\"splintcore_case\": @17,\n";
  expect_case_error(p.text(), StatusCode::kUnsupported, {"version 17 is newer"});
  p.head = "\"splintcore_case\": @0,\n";
  expect_invalid(p, {"\"splintcore_case\" is 0, outside [1, "});
  p.head = "\"splintcore_case\": @1.5,\n";
  expect_invalid(p, {"\"splintcore_case\" must be an integer"});
  p.head = "\"splintcore_case\": @-1,\n";
  expect_invalid(p, {"\"splintcore_case\" is -1"});

  expect_invalid(with_root("  \"units\": @\"inch\",\n"),
                 {"\"units\" must be \"mm\" (got \"inch\")", "millimetres"});
  expect_invalid(with_root("  \"units\": @\"MM\",\n"), {"\"units\" must be \"mm\""});
  expect_invalid(with_root("  \"units\": @\"\",\n"), {"\"units\" must be a non-empty string"});
}

TEST(CaseFileErrors, CaseIdCharacters) {
  for (const char* bad : {"a/b", "a b", "../etc", "caf\\u00e9", "x\\ty", "a:b", "a\\\\b"}) {
    SCOPED_TRACE(bad);
    expect_invalid(with_root(std::string("  \"case_id\": @\"") + bad + "\",\n"),
                   {"\"case_id\" must be 1-64 letters, digits, '_', '-' or '.'"});
  }
  expect_invalid(with_root("  \"case_id\": @\"" + std::string(65, 'x') + "\",\n"),
                 {"\"case_id\" must be 1-64"});
  expect_invalid(with_root("  \"case_id\": @\"\",\n"), {"\"case_id\" must be a non-empty string"});
}

TEST(CaseFileErrors, VectorsNeedThreeNumbers) {
  CaseParts p;
  p.upper = "[{\"position\": @[0, 0]}, {\"position\": [10, 0, 1]}]";
  expect_invalid(p, {"\"position\" needs 3 numbers, has 2"});
  p.upper = "[{\"position\": [0, 0, 1]}, {\"position\": @[10, 0, 1, 1]}]";
  expect_invalid(p, {"\"position\" needs 3 numbers, has 4"});
  p.upper = "[{\"position\": @[]}, {\"position\": [10, 0, 1]}]";
  expect_invalid(p, {"\"position\" needs 3 numbers, has 0"});
  expect_invalid(with_pick(", \"normal\": @[1, 0]"), {"\"normal\" needs 3 numbers, has 2"});
  expect_invalid(with_pick(", \"direction\": @[1, 0, 0, 0]"),
                 {"\"direction\" needs 3 numbers, has 4"});
  expect_invalid(with_base("    \"occlusal_normal\": @[0, 1],\n"),
                 {"\"occlusal_normal\" needs 3 numbers, has 2"});
  expect_invalid(with_root("  \"insertion_direction\": @[0, 0, 1, 0],\n"),
                 {"\"insertion_direction\" needs 3 numbers, has 4"});
}

TEST(CaseFileErrors, ZeroVectors) {
  expect_invalid(with_pick(", \"normal\": @[0, 0, 0]"), {"\"normal\" must not be the zero vector"});
  expect_invalid(with_pick(", \"direction\": @[0, -0, 0.0]"),
                 {"\"direction\" must not be the zero vector"});
  expect_invalid(with_pick(", \"direction\": @[1e-13, 0, 0]"),
                 {"\"direction\" must not be the zero vector"});
  expect_invalid(with_base("    \"occlusal_normal\": @[0, 0, 0],\n"),
                 {"\"occlusal_normal\" must not be the zero vector"});
  expect_invalid(with_root("  \"insertion_direction\": @[0, 0, 0],\n"),
                 {"\"insertion_direction\" must not be the zero vector"});
  // A position may be the origin.
  test::TestArena a(size_t{1} << 20);
  CaseFile c;
  CaseParts p;
  p.upper = "[{\"position\": [0, 0, 0]}, {\"position\": [10, 0, 1]}]";
  SPLINTCORE_EXPECT_OK(parse(a.arena, p.text(), &c));
}

TEST(CaseFileErrors, NumbersOutOfRange) {
  CaseParts p;
  p.upper = "[{\"position\": [0, @2e6, 1]}, {\"position\": [10, 0, 1]}]";
  expect_invalid(p, {"\"position\" is 2", "outside [-1", "1"});
  p.upper = "[{\"position\": [0, 0, @-1000000.5]}, {\"position\": [10, 0, 1]}]";
  expect_invalid(p, {"\"position\" is -1000000.5, outside ["});
  expect_invalid(with_pick(", \"normal\": [0, 1, @1e7]"), {"\"normal\" is "});
  expect_invalid(with_base("    \"spacing_mm\": @0,\n"),
                 {"\"spacing_mm\" is 0, outside [0.01, 50]"});
  expect_invalid(with_base("    \"spacing_mm\": @50.5,\n"),
                 {"\"spacing_mm\" is 50.5, outside [0.01, 50]"});
  expect_invalid(with_base("    \"spacing_mm\": @-1,\n"), {"\"spacing_mm\" is -1"});
  expect_invalid(with_base("    \"corner_radius_mm\": @-0.1,\n"),
                 {"\"corner_radius_mm\" is -0.1, outside [0, 20]"});
  expect_invalid(with_base("    \"corner_radius_mm\": @20.5,\n"), {"\"corner_radius_mm\" is 20.5"});
  expect_invalid(with_base("    \"corner_segments\": @0,\n"),
                 {"\"corner_segments\" is 0, outside [1, 16]"});
  expect_invalid(with_base("    \"corner_segments\": @17,\n"), {"\"corner_segments\" is 17"});
  for (const char* segments : {"3", "5", "6", "12", "2.5", "15"}) {
    SCOPED_TRACE(segments);
    expect_invalid(with_base(std::string("    \"corner_segments\": @") + segments + ",\n"),
                   {"\"corner_segments\" must be 1, 2, 4, 8 or 16"});
  }
  expect_invalid(with_base("    \"inner_length_mm\": @-1,\n"),
                 {"\"inner_length_mm\" is -1, outside [0, 100]"});
  expect_invalid(with_base("    \"outside_length_mm\": @100.5,\n"),
                 {"\"outside_length_mm\" is 100.5"});
  expect_invalid(with_pick(", \"inner_length_mm\": @101"), {"\"inner_length_mm\" is 101"});
  expect_invalid(with_pick(", \"outside_length_mm\": @-0.5"), {"\"outside_length_mm\" is -0.5"});
  // Memory caps.
  expect_invalid(with_root("  \"memory_cap\": @0,\n"), {"\"memory_cap\" is 0, outside [1, "});
  expect_invalid(with_root("  \"memory_cap\": @-5,\n"), {"\"memory_cap\" is -5"});
  expect_invalid(with_root("  \"memory_cap\": @2e12,\n"), {"\"memory_cap\" is "});
  expect_invalid(with_root("  \"memory_cap\": @1000.5,\n"),
                 {"\"memory_cap\" must be a whole number of bytes"});
  for (const char* bad :
       {"12Q", "0", "", "64MB", "1.5G", "-1M", " 64M", "M", "99999999999999999999"}) {
    SCOPED_TRACE(bad);
    expect_invalid(with_root(std::string("  \"memory_cap\": @\"") + bad + "\",\n"),
                   {"\"memory_cap\" must be a size such as \"256M\", \"2G\" or a byte count"});
  }
}

TEST(CaseFileErrors, Transforms) {
  auto jaw = [](const std::string& transform) {
    return with_root(
        "  \"jaws\": [{\"role\": \"mandible\", \"mesh\": \"m.stl\",\n"
        "    \"transform\": " +
        transform + "}],\n");
  };
  expect_invalid(jaw("@[1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0]"),
                 {"\"transform\" needs 16 numbers (a row-major 4x4 matrix)"});
  expect_invalid(jaw("@[]"), {"\"transform\" needs 16 numbers"});
  // Not rigid: a scale, a shear.
  expect_invalid(jaw("@[2, 0, 0, 0,  0, 2, 0, 0,  0, 0, 2, 0,  0, 0, 0, 1]"),
                 {"\"transform\": ", "transform is not rigid", "scale or shear"});
  expect_invalid(jaw("@[1, 0.5, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]"),
                 {"\"transform\": ", "transform is not rigid"});
  expect_invalid(jaw("@[1.00001, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]"),
                 {"transform is not rigid"});
  // A reflection would turn the mesh inside out.
  expect_invalid(jaw("@[-1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]"),
                 {"\"transform\": ", "transform is a reflection", "inside out"});
  expect_invalid(jaw("@[0, 1, 0, 5,  1, 0, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]"),
                 {"transform is a reflection"});
  // The last row must be 0 0 0 1.
  expect_invalid(jaw("@[1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 2]"),
                 {"\"transform\": ", "last row must be 0 0 0 1"});
  expect_invalid(jaw("@[1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0.1, 0, 0, 1]"),
                 {"last row must be 0 0 0 1"});
  // Entries beyond 1e6 mm are refused before any arithmetic (so nothing can overflow).
  expect_invalid(jaw("[1, 0, 0, @1e300,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]"),
                 {"\"transform\" is 1e+300, outside ["});
  // Non-finite entries cannot reach the schema: JSON has no NaN or infinity, and a number
  // beyond the double range is a parse error, located at the entry.
  expect_case_error(jaw("[1, 0, 0, 0,  0, 1, 0, @1e400,  0, 0, 1, 0,  0, 0, 0, 1]").text(),
                    StatusCode::kParseError, {"number out of double range"});
  expect_case_error(jaw("[1, 0, 0, 0,  0, @NaN, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]").text(),
                    StatusCode::kParseError, {"expected a value, found 'N'"});
  expect_case_error(jaw("[1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, -@Infinity]").text(),
                    StatusCode::kParseError, {"expected a digit, found 'I'"});
  // The check the schema relies on names the transform for non-finite entries too.
  double m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  m[6] = std::numeric_limits<double>::quiet_NaN();
  RigidTransform t;
  Status s = rigid_from_matrix(m, 1e-6, &t);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_NE(std::strstr(s.message(), "transform entry (1,2) is not finite"), nullptr) << format(s);
  // Rigid up to the tolerance is accepted: a rotation written to 4 decimals.
  test::TestArena a(size_t{1} << 20);
  CaseFile c;
  SPLINTCORE_EXPECT_OK(parse(
      a.arena,
      jaw("[0.8660254, -0.5, 0, 0,  0.5, 0.8660254, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]").text(), &c));
}

TEST(CaseFileErrors, ListsThatDoNotPairUp) {
  CaseParts p;
  p.lower =
      "@[{\"position\": [0, 0, -1]}, {\"position\": [5, 0, -1]}, {\"position\": [10, 0, -1]}]";
  expect_invalid(p, {"upper and lower pick lists do not pair up: 2 upper, 3 lower"});
  p.lower = "@[]";
  expect_invalid(p, {"do not pair up: 2 upper, 0 lower"});
}

TEST(CaseFileErrors, JsonErrorsComeThroughLocated) {
  // Syntax errors, duplicate keys and limits from the JSON layer keep their positions.
  expect_case_error(with_base("    \"spacing_mm\": 1,@,\n").text(), StatusCode::kParseError,
                    {"expected a string key, found ','"});
  expect_case_error(with_base("    \"spacing_mm\": 1,\n    \"spacing_mm\": @2,\n").text(),
                    StatusCode::kParseError, {"duplicate key \"spacing_mm\""});
  expect_case_error(with_pick(", \"normal\": [0, 1, 0,@]").text(), StatusCode::kParseError,
                    {"trailing comma"});
  // Nesting beyond the JSON limit is refused without recursing through it.
  std::string deep = "{\"splintcore_case\": 1, \"base\": " + std::string(31, '[') + "@[";
  deep += std::string(100000, '[');
  expect_case_error(deep, StatusCode::kLimitExceeded, {"nesting deeper than 32"});
  // A larger document than the case limit (16 MiB).
  test::TestArena a(size_t{1} << 20);
  CaseFile c;
  std::string huge = CaseParts{}.text();
  huge.append((size_t{16} << 20) - huge.size() + 1, ' ');
  Status s = parse(a.arena, huge, &c);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
}

// ---------------------------------------------------------------------------------------------
// Truncation and arena exhaustion.

TEST(CaseFileRobustness, EveryPrefixIsACleanError) {
  const std::string text = fixture("rounded.json");
  const size_t complete = text.find_last_of('}') + 1;
  test::TestArena a(size_t{1} << 20);
  for (size_t n = 0; n <= text.size(); ++n) {
    a.arena.reset();
    CaseFile c;
    Status s = parse(a.arena, text.substr(0, n), &c, "rounded.json");
    if (n >= complete) {
      ASSERT_TRUE(s.is_ok()) << n << ": " << format(s);
    } else {
      ASSERT_EQ(s.code(), StatusCode::kParseError) << n << ": " << format(s);
      ASSERT_GE(s.line(), 1u);
      ASSERT_NE(s.line(), kNoPosition);
    }
  }
}

bool same_case(const CaseFile& x, const CaseFile& y) {
  auto same_picks = [](Span<const Pick> a, Span<const Pick> b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i) {
      if (a[i].position != b[i].position || a[i].normal != b[i].normal ||
          a[i].direction != b[i].direction || a[i].inner_length != b[i].inner_length ||
          a[i].outside_length != b[i].outside_length) {
        return false;
      }
    }
    return true;
  };
  if (x.jaws.size() != y.jaws.size()) return false;
  for (size_t i = 0; i < x.jaws.size(); ++i) {
    if (std::strcmp(x.jaws[i].role, y.jaws[i].role) != 0 ||
        std::strcmp(x.jaws[i].mesh, y.jaws[i].mesh) != 0 ||
        std::memcmp(&x.jaws[i].transform, &y.jaws[i].transform, sizeof(RigidTransform)) != 0) {
      return false;
    }
  }
  auto same_string = [](const char* a, const char* b) {
    return (a == nullptr) == (b == nullptr) && (a == nullptr || std::strcmp(a, b) == 0);
  };
  return x.version == y.version && std::strcmp(x.case_id, y.case_id) == 0 &&
         x.occlusal_normal == y.occlusal_normal && x.base.spacing_mm == y.base.spacing_mm &&
         x.base.corner_radius_mm == y.base.corner_radius_mm &&
         x.base.corner_segments == y.base.corner_segments && same_picks(x.upper, y.upper) &&
         same_picks(x.lower, y.lower) && x.insertion_direction == y.insertion_direction &&
         x.has_insertion_direction == y.has_insertion_direction &&
         std::strcmp(x.printer, y.printer) == 0 && x.memory_cap == y.memory_cap &&
         same_string(x.output_splint, y.output_splint) &&
         same_string(x.output_report, y.output_report);
}

TEST(CaseFileRobustness, ArenaExhaustionLoop) {
  // Every cap from 0 fails with kArenaExhausted until the first that works; every cap at or
  // above an unlimited run's high-water mark works; whatever works gives the same case.
  struct Free {
    void operator()(unsigned char* p) const { ::operator delete[](p, std::align_val_t{16}); }
  };
  const std::string text = fixture("paper_scale.json");
  test::TestArena big(size_t{4} << 20);
  CaseFile reference;
  SPLINTCORE_ASSERT_OK(parse(big.arena, text, &reference));
  const size_t high_water = big.arena.high_water();
  size_t first_success = 0;
  const size_t step = 5;
  for (size_t cap = 0; cap <= high_water + 64; cap += step) {
    std::unique_ptr<unsigned char[], Free> buffer(
        static_cast<unsigned char*>(::operator new[](cap + 1, std::align_val_t{16})));
    Arena arena(buffer.get(), cap);
    CaseFile c;
    Status s = parse(arena, text, &c);
    if (s.is_ok()) {
      if (first_success == 0) first_success = cap;
      ASSERT_TRUE(same_case(reference, c)) << "cap " << cap;
    } else {
      ASSERT_EQ(s.code(), StatusCode::kArenaExhausted) << "cap " << cap << ": " << format(s);
      ASSERT_EQ(first_success == 0 || cap < high_water, true)
          << "cap " << cap << " failed above the high-water mark " << high_water;
      ASSERT_NE(std::strstr(s.message(), "increase the memory cap"), nullptr) << format(s);
      ASSERT_GT(arena.last_need(), cap);
    }
  }
  EXPECT_GT(first_success, text.size());
  EXPECT_LE(first_success, high_water);
}

// ---------------------------------------------------------------------------------------------
// The base of each case.

struct Built {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  BaseReport report;
};

void build(const char* name, const Executor* executor, Built* out) {
  test::TestArena a(size_t{256} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse(a.arena, fixture(name), &c, name));
  Context ctx(&a.arena, executor, nullptr);
  Mesh mesh(&a.arena);
  SPLINTCORE_ASSERT_OK(build_case_base(ctx, c, &mesh, &out->report));
  ASSERT_GT(mesh.triangles.size(), 0u);
  MeshReport check;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, mesh, &check));
  EXPECT_TRUE(check.is_valid_solid());
  SPLINTCORE_EXPECT_OK(require_valid_solid(check));
  EXPECT_TRUE(check.closed());
  EXPECT_EQ(check.boundary_edges, 0u);
  EXPECT_EQ(check.nonmanifold_edges, 0u);
  EXPECT_EQ(check.shells, 1u);
  EXPECT_EQ(check.genus, 0);
  EXPECT_GT(check.volume, 0.0);
  // Sections of P points joined by ruled quads, and two fanned end caps.
  const uint64_t s = out->report.sections, p = out->report.points_per_section;
  EXPECT_EQ(mesh.vertices.size(), s * p);
  EXPECT_EQ(mesh.triangles.size(), 2 * (s - 1) * p + 2 * (p - 2));
  EXPECT_EQ(out->report.volume, check.volume);  // the same sum over the same mesh
  for (const Vec3& v : mesh.vertices) ASSERT_TRUE(is_finite(v));
  out->vertices.assign(mesh.vertices.begin(), mesh.vertices.end());
  out->triangles.assign(mesh.triangles.begin(), mesh.triangles.end());
}

bool same_bytes(const Built& a, const Built& b) {
  return a.vertices.size() == b.vertices.size() && a.triangles.size() == b.triangles.size() &&
         std::memcmp(a.vertices.data(), b.vertices.data(), a.vertices.size() * sizeof(Vec3)) == 0 &&
         std::memcmp(a.triangles.data(), b.triangles.data(),
                     a.triangles.size() * sizeof(Triangle)) == 0 &&
         a.report.sections == b.report.sections &&
         a.report.points_per_section == b.report.points_per_section &&
         std::memcmp(&a.report.volume, &b.report.volume, sizeof(double)) == 0;
}

TEST(CaseBase, EachFixtureBuildsAValidSolidDeterministically) {
  ThreadExecutor pool(3);
  for (const char* name : kFixtures) {
    SCOPED_TRACE(name);
    Built first, second, threaded;
    build(name, nullptr, &first);
    if (::testing::Test::HasFatalFailure()) return;
    build(name, nullptr, &second);
    build(name, &pool.executor(), &threaded);
    if (::testing::Test::HasFatalFailure()) return;
    EXPECT_TRUE(same_bytes(first, second)) << "two runs differ";
    EXPECT_TRUE(same_bytes(first, threaded)) << "serial and threaded runs differ";
    EXPECT_GT(first.report.sections, 2u);
  }
}

TEST(CaseBase, RoundedCornersAddPointsPerSection) {
  Built sharp, rounded;
  build("paper_scale.json", nullptr, &sharp);
  build("rounded.json", nullptr, &rounded);
  // Four sharp corners against four corners of corner_segments + 1 points each.
  EXPECT_EQ(sharp.report.points_per_section, 4u);
  EXPECT_EQ(rounded.report.points_per_section, 4u * (4u + 1u));
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

// A control character in a file's path (escaped in the JSON, so the document is valid) is
// refused where it stands, named by its byte and place; the message holds none itself. (Names
// have their own rules: a tab in "case_id" breaks the plain-name rule, CaseIdCharacters.)
TEST(CaseFileErrors, ControlCharactersInPaths) {
  expect_invalid(
      with_root("  \"jaws\": [{\"role\": \"maxilla\", \"mesh\": @\"\\u001b[31mred.stl\"}],\n"),
      {"\"mesh\" holds a control character (byte 27 at character 0): a file's path has none"});
  expect_invalid(with_root("  \"jaws\": [{\"role\": \"maxilla\", \"mesh\": \"a.stl\",\n"
                           "    \"scan\": {\"path\": @\"scan\\n.stl\"}}],\n"),
                 {"\"path\" holds a control character (byte 10 at character 4)"});
  expect_invalid(with_root("  \"ct\": {\"volume\": @\"ct\\u007f.nrrd\"},\n"),
                 {"\"volume\" holds a control character (byte 127 at character 2)"});
}

TEST(CaseFileErrors, TwoJawsWithTheSameRole) {
  expect_invalid(with_root("  \"jaws\": [{\"role\": \"maxilla\", \"mesh\": \"a.stl\"},\n"
                           "           {\"role\": @\"maxilla\", \"mesh\": \"b.stl\"}],\n"),
                 {"two jaws with the role \"maxilla\""});
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

TEST(CaseFile, BlockoutTakesItsDefaultsAndChecksItsRanges) {
  test::TestArena a(size_t{1} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse(a.arena, CaseParts{}.text(), &c));
  EXPECT_FALSE(c.has_blockout);
  const std::string dir = "\"insertion_direction\": [0, 0, 1],\n";
  SPLINTCORE_ASSERT_OK(parse(a.arena, with_root(dir + "\"blockout\": {},\n").text(), &c));
  EXPECT_TRUE(c.has_blockout);
  EXPECT_EQ(c.blockout.voxel, 0.1);
  EXPECT_EQ(c.blockout.inset, 0.0);  // "auto": its fallback, the height field, has none
  EXPECT_EQ(c.blockout.closing_radius, 0.0);
  SPLINTCORE_ASSERT_OK(parse(
      a.arena, with_root(dir + "\"blockout\": {\"voxel\": 0.2, \"closing_radius\": 0.5},\n").text(),
      &c));
  EXPECT_EQ(c.blockout.voxel, 0.2);
  EXPECT_EQ(c.blockout.inset, 0.1);  // half the voxel
  EXPECT_EQ(c.blockout.closing_radius, 0.5);
  // Errors name the key.
  const char* bad[] = {
      "\"blockout\": {},\n",  // no insertion direction
      "\"insertion_direction\": [0, 0, 1], \"blockout\": {\"voxel\": 0},\n",
      "\"insertion_direction\": [0, 0, 1], \"blockout\": {\"inset\": 0.2},\n",
      "\"insertion_direction\": [0, 0, 1], \"blockout\": {\"closing_radius\": 0.1},\n",
      "\"insertion_direction\": [0, 0, 1], \"blockout\": {\"radius\": 0.1},\n",
      "\"insertion_direction\": [0, 0, 1], \"blockout\": [0.1],\n",
  };
  const char* names[] = {"insertion_direction", "voxel",  "inset",
                         "closing_radius",      "radius", "blockout"};
  for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); ++i) {
    SCOPED_TRACE(bad[i]);
    const Status s = parse(a.arena, with_root(bad[i]).text(), &c);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
    EXPECT_NE(std::string(s.message()).find(names[i]), std::string::npos) << s.message();
    EXPECT_NE(s.line(), kNoPosition);
  }
}

// The side-wall check's bounds, "max_wall_crossing" (1 by default) and "max_sideways_crossing"
// (0.05): read, written back by write_case (the resolved case) when not the default, and
// absent when it is (so a resolved case reads as before); out of [0, 1] refused naming it.
TEST(CaseFile, SideWallBoundsAreReadAndWrittenBack) {
  test::TestArena a(size_t{1} << 20);
  struct Key {
    const char* name;
    double fallback;
    double CaseFile::*field;
  };
  for (const Key& k : {Key{"max_wall_crossing", 1.0, &CaseFile::max_wall_crossing},
                       Key{"max_sideways_crossing", 0.05, &CaseFile::max_sideways_crossing}}) {
    for (const double given : {-1.0, 0.2, 0.0}) {  // -1: not given
      const std::string text =
          given < 0 ? "" : "\"" + std::string(k.name) + "\": " + std::to_string(given) + ",\n";
      const double value = given < 0 ? k.fallback : given;
      SCOPED_TRACE(text.empty() ? std::string(k.name) + " absent" : text);
      CaseFile c;
      SPLINTCORE_ASSERT_OK(parse(a.arena, with_root(text).text(), &c));
      EXPECT_EQ(c.*k.field, value);
      std::string written;
      SPLINTCORE_ASSERT_OK(write_case(c, test::string_sink(&written)));
      EXPECT_EQ(written.find(k.name) != std::string::npos, given >= 0) << written;
      CaseFile again;
      SPLINTCORE_ASSERT_OK(parse(a.arena, written, &again));
      EXPECT_EQ(again.*k.field, value);
    }
    CaseFile c;
    const std::string bad = "\"" + std::string(k.name) + "\": 1.5,\n";
    const Status s = parse(a.arena, with_root(bad).text(), &c);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(
        std::string(s.message()).find("\"" + std::string(k.name) + "\" is 1.5, outside [0, 1]"),
        std::string::npos)
        << s.message();
  }
}

TEST(CaseFile, BlockoutMethodIsAutoExactVoxelOrHeightfieldAndExactTakesNoVoxelKeys) {
  test::TestArena a(size_t{1} << 20);
  CaseFile c;
  const std::string dir = "\"insertion_direction\": [0, 0, 1],\n";
  // Without "method": voxel when inset or closing_radius is named, else heightfield with a
  // clearance, else auto (the voxel is auto's fallback's grid).
  const char* blockouts[] = {"{}",
                             "{\"voxel\": 0.2}",
                             "{\"inset\": 0.05}",
                             "{\"closing_radius\": 0.5}",
                             "{\"clearance\": 0.2}",
                             "{\"method\": \"auto\", \"voxel\": 0.2}",
                             "{\"method\": \"heightfield\"}",
                             "{\"method\": \"heightfield\", \"clearance\": 0.15}",
                             "{\"method\": \"heightfield\", \"voxel\": 0.2}"};
  const BlockoutMethod methods[] = {
      BlockoutMethod::kAuto,        BlockoutMethod::kAuto,        BlockoutMethod::kVoxel,
      BlockoutMethod::kVoxel,       BlockoutMethod::kHeightfield, BlockoutMethod::kAuto,
      BlockoutMethod::kHeightfield, BlockoutMethod::kHeightfield, BlockoutMethod::kHeightfield};
  for (size_t i = 0; i < sizeof(blockouts) / sizeof(blockouts[0]); ++i) {
    SCOPED_TRACE(blockouts[i]);
    c = CaseFile{};
    SPLINTCORE_ASSERT_OK(
        parse(a.arena, with_root(dir + "\"blockout\": " + blockouts[i] + ",\n").text(), &c));
    EXPECT_TRUE(c.has_blockout);
    EXPECT_EQ(c.blockout_method, methods[i]);
    // write_case gives the same method back.
    std::string written;
    SPLINTCORE_ASSERT_OK(write_case(c, test::string_sink(&written)));
    CaseFile again;
    SPLINTCORE_ASSERT_OK(parse(a.arena, written, &again));
    EXPECT_EQ(again.blockout_method, methods[i]) << written;
    EXPECT_EQ(again.blockout.voxel, c.blockout.voxel);
    EXPECT_EQ(again.blockout.offset, c.blockout.offset);  // the clearance
    // The height field (auto's fallback too) has no inset (nor does anything it writes back).
    if (methods[i] != BlockoutMethod::kVoxel) {
      EXPECT_EQ(c.blockout.inset, 0.0);
      EXPECT_EQ(written.find("inset"), std::string::npos) << written;
    }
  }
  EXPECT_EQ(c.blockout.voxel, 0.2);  // auto's voxel keys are its fallback's
  SPLINTCORE_ASSERT_OK(
      parse(a.arena, with_root(dir + "\"blockout\": {\"method\": \"exact\"},\n").text(), &c));
  EXPECT_EQ(c.blockout_method, BlockoutMethod::kExact);
  // write_case gives it back, and nothing of the voxel method.
  std::string written;
  SPLINTCORE_ASSERT_OK(write_case(c, test::string_sink(&written)));
  EXPECT_NE(written.find("\"blockout\":{\"method\":\"exact\"}"), std::string::npos) << written;
  EXPECT_EQ(written.find("inset"), std::string::npos) << written;
  SPLINTCORE_ASSERT_OK(parse(
      a.arena, with_root(dir + "\"blockout\": {\"method\": \"voxel\", \"voxel\": 0.2},\n").text(),
      &c));
  EXPECT_EQ(c.blockout_method, BlockoutMethod::kVoxel);
  EXPECT_EQ(c.blockout.voxel, 0.2);
  const char* bad[] = {
      "\"blockout\": {\"method\": \"sampled\"},\n",
      "\"blockout\": {\"method\": 1},\n",
      "\"blockout\": {\"method\": \"exact\", \"voxel\": 0.1},\n",
      "\"blockout\": {\"method\": \"exact\", \"inset\": 0.05},\n",
      "\"blockout\": {\"clearance\": 0.2, \"method\": \"exact\"},\n",
      "\"blockout\": {\"method\": \"exact\", \"closing_radius\": 0.5},\n",
      "\"blockout\": {\"method\": \"auto\", \"clearance\": 0.2},\n",
      "\"blockout\": {\"method\": \"heightfield\", \"inset\": 0.05},\n",
      "\"blockout\": {\"method\": \"heightfield\", \"closing_radius\": 0.5},\n",
      "\"blockout\": {\"method\": \"auto\", \"inset\": 0.05},\n",
      "\"blockout\": {\"closing_radius\": 0.5, \"method\": \"auto\"},\n",
  };
  const char* names[] = {"\"auto\", \"exact\", \"voxel\" or \"heightfield\"",
                         "blockout.method",
                         "blockout.voxel",
                         "blockout.inset",
                         "blockout.clearance",
                         "blockout.closing_radius",
                         "say \"method\": \"voxel\"",
                         "blockout.inset",
                         "blockout.closing_radius",
                         "\"auto\" falls back to the height field",
                         "blockout.closing_radius"};
  for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); ++i) {
    SCOPED_TRACE(bad[i]);
    const Status s = parse(a.arena, with_root(dir + bad[i]).text(), &c);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
    EXPECT_NE(std::string(s.message()).find(names[i]), std::string::npos) << s.message();
    EXPECT_NE(s.line(), kNoPosition);
  }
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

TEST(CaseFile, JawsFromCtTakeSeedsAndTheCtObject) {
  test::TestArena a(size_t{1} << 20);
  CaseFile c;
  const std::string ct =
      "\"ct\": {\"volume\": \"ct.nrrd\", \"hu_min\": 250, \"connectivity\": 26, "
      "\"smooth\": 5, \"decimate\": 40000},\n";
  const std::string jaws =
      "\"jaws\": [{\"role\": \"maxilla\", \"seed\": [0, 18, 13]}, "
      "{\"role\": \"mandible\", \"mesh\": \"lower.stl\"}],\n";
  SPLINTCORE_ASSERT_OK(parse(a.arena, with_root(jaws + ct).text(), &c));
  ASSERT_EQ(c.jaws.size(), 2u);
  EXPECT_TRUE(c.jaws[0].has_seed);
  expect_vec(c.jaws[0].seed, 0, 18, 13);
  EXPECT_FALSE(c.jaws[1].has_seed);
  EXPECT_STREQ(c.jaws[1].mesh, "lower.stl");
  EXPECT_STREQ(c.ct_volume, "ct.nrrd");
  EXPECT_EQ(c.ct_window.lo, 250);
  EXPECT_EQ(c.ct_window.hi, 4000);
  EXPECT_EQ(c.ct_grow.connectivity, Connectivity::k26);
  EXPECT_EQ(c.ct_smooth.iterations, 5u);
  EXPECT_EQ(c.ct_decimate.target_triangles, 40000u);
  // Errors name what is wrong, with a line.
  const std::string seed_only = "\"jaws\": [{\"role\": \"maxilla\", \"seed\": [0, 18, 13]}],\n";
  struct Bad {
    std::string root;
    const char* says;
  } bad[] = {
      {seed_only, "no \"ct\""},
      {"\"jaws\": [{\"role\": \"maxilla\"}],\n", "either \"mesh\""},
      {"\"jaws\": [{\"role\": \"maxilla\", \"mesh\": \"a.stl\", \"seed\": [0, 0, 0]}],\n",
       "either \"mesh\""},
      {seed_only + "\"ct\": {},\n", "needs \"volume\""},
      {seed_only + "\"ct\": {\"volume\": \"v\", \"hu_min\": 5000, \"hu_max\": 400},\n",
       "above \"hu_max\""},
      {seed_only + "\"ct\": {\"volume\": \"v\", \"hu_min\": 2.5},\n", "integer"},
      {seed_only + "\"ct\": {\"volume\": \"v\", \"connectivity\": 18},\n", "6 or 26"},
      {seed_only + "\"ct\": {\"volume\": \"v\", \"decimate\": 2},\n", "decimate"},
      {seed_only + "\"ct\": {\"volume\": \"v\", \"spacing\": 1},\n", "unknown key"},
  };
  for (const Bad& b : bad) {
    SCOPED_TRACE(b.root);
    const Status s = parse(a.arena, with_root(b.root).text(), &c);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
    EXPECT_NE(std::string(s.message()).find(b.says), std::string::npos) << s.message();
    EXPECT_NE(s.line(), kNoPosition);
  }
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

// docs/case-format.md's "Numbers" table is this table (design.h, case_numbers()), written as
// below: the doc, the parser and the C API cannot disagree on a range.
std::string case_numbers_markdown() {
  auto num = [](double v) {
    char text[32];
    const auto r = std::to_chars(text, text + sizeof(text), v);
    return std::string(text, r.ptr);
  };
  std::string out = "| key | unit | range | default | also |\n|---|---|---|---|---|\n";
  for (const CaseNumber& n : case_numbers()) {
    std::string range = num(n.lo) + " to " + num(n.hi) + (n.per_voxel ? " voxels" : "");
    if (n.max_mm > 0) range += ", at most " + num(n.max_mm) + " mm";
    if (n.integer) range += ", whole";
    out += "| `" + std::string(n.key) + "` | " + n.unit + " | " + range + " | " + n.default_text +
           " | " + n.rule + " |\n";
  }
  return out;
}

TEST(CaseNumbers, DocumentedTableIsTheLibrarys) {
  const std::vector<uint8_t> bytes =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/../docs/case-format.md");
  const std::string doc(bytes.begin(), bytes.end());
  const std::string begin = "<!-- case numbers: begin (tests/design/case_file_test.cpp) -->\n";
  const std::string end = "<!-- case numbers: end -->";
  const size_t b = doc.find(begin), e = doc.find(end);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(e, std::string::npos);
  const std::string expected = case_numbers_markdown();
  EXPECT_EQ(doc.substr(b + begin.size(), e - b - begin.size()), expected)
      << "docs/case-format.md's table should read:\n"
      << expected;
}

TEST(CaseNumbers, EveryNumberIsFoundAndItsRangeHolds) {
  for (const CaseNumber& n : case_numbers()) {
    EXPECT_EQ(find_case_number(n.key), &n);
    double lo = 0, hi = 0;
    case_number_range(n, 0.1, &lo, &hi);
    EXPECT_LE(lo, hi) << n.key;
  }
  EXPECT_EQ(find_case_number("base.no_such_number"), nullptr);
  // A per-voxel range with a cap in mm: the clearance, 20 voxels but at most 2 mm.
  double lo = 0, hi = 0;
  case_number_range(*find_case_number("blockout.clearance"), 0.05, &lo, &hi);
  EXPECT_EQ(hi, 1.0);
  case_number_range(*find_case_number("blockout.clearance"), 0.5, &lo, &hi);
  EXPECT_EQ(hi, 2.0);
}

}  // namespace
}  // namespace splintcore
