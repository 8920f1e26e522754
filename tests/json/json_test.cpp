// The strict JSON parser: every JSON type, escapes and UTF-8, numbers bit-exact against
// strtod, each strictness rule with the exact line and column of its error, the size, depth
// and value limits, truncation of a real case file at every byte offset, and the arena
// exhaustion loop (every cap from 0 until the parse succeeds).
//
// Inputs are copied into heap buffers of exactly their length (never NUL-terminated), so a read
// past the end is caught by AddressSanitizer.

#include "splintcore/json.h"

#include <gtest/gtest.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "support/test_util.h"

namespace splintcore {
namespace {

using test::format;

// The text in a heap buffer of exactly its size: no terminating NUL to lean on.
struct ExactText {
  std::unique_ptr<char[]> bytes;
  size_t size = 0;
  explicit ExactText(const std::string& s)
      : bytes(new char[s.size() > 0 ? s.size() : 1]), size(s.size()) {
    if (size > 0) std::memcpy(bytes.get(), s.data(), size);
  }
  ExactText(const char* data, size_t n) : bytes(new char[n > 0 ? n : 1]), size(n) {
    if (n > 0) std::memcpy(bytes.get(), data, n);
  }
};

// An arena over a 16-byte aligned buffer of exactly `cap` bytes (so needs are reproducible and
// an arena overrun is a heap overflow under ASan).
struct ExactArena {
  struct Free {
    void operator()(unsigned char* p) const { ::operator delete[](p, std::align_val_t{16}); }
  };
  std::unique_ptr<unsigned char[], Free> buffer;
  Arena arena;
  explicit ExactArena(size_t cap)
      : buffer(
            static_cast<unsigned char*>(::operator new[](cap > 0 ? cap : 1, std::align_val_t{16}))),
        arena(buffer.get(), cap) {}
};

Status parse(Arena& arena, const std::string& text, JsonDocument* doc,
             const JsonLimits& limits = JsonLimits{}, const char* name = "t.json") {
  ExactText t(text);
  Context ctx(&arena);
  return parse_json(ctx, t.bytes.get(), t.size, limits, name, doc);
}

std::string str(const JsonValue& v) { return std::string(v.string, v.length); }

// Parses `text` and expects it to be a single string value with these decoded bytes.
void expect_string(const std::string& text, const std::string& expected) {
  SCOPED_TRACE(text);
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  Status s = parse(a.arena, text, &doc);
  ASSERT_TRUE(s.is_ok()) << format(s);
  ASSERT_EQ(doc.root().type, JsonType::kString);
  EXPECT_EQ(str(doc.root()), expected);
  EXPECT_EQ(doc.root().string[doc.root().length], '\0');
}

uint64_t bits(double d) {
  uint64_t b;
  std::memcpy(&b, &d, sizeof(b));
  return b;
}

// Parses `text` as a lone number and expects exactly `expected` (bit for bit).
void expect_number(const std::string& text, double expected) {
  SCOPED_TRACE(text);
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  Status s = parse(a.arena, text, &doc);
  ASSERT_TRUE(s.is_ok()) << format(s);
  ASSERT_EQ(doc.root().type, JsonType::kNumber);
  EXPECT_EQ(bits(doc.root().number), bits(expected)) << doc.root().number << " vs " << expected;
}

struct Bad {
  std::string text;
  uint64_t line;
  uint64_t column;
  const char* message;  // a fragment of the message
};

void expect_bad(const Bad& b, StatusCode code = StatusCode::kParseError,
                const JsonLimits& limits = JsonLimits{}) {
  SCOPED_TRACE(::testing::Message() << "input: \"" << b.text << "\"");
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  Status s = parse(a.arena, b.text, &doc, limits);
  ASSERT_FALSE(s.is_ok());
  EXPECT_EQ(s.code(), code) << format(s);
  EXPECT_EQ(s.line(), b.line) << format(s);
  EXPECT_EQ(s.column(), b.column) << format(s);
  EXPECT_NE(std::strstr(s.message(), b.message), nullptr)
      << "message \"" << s.message() << "\" lacks \"" << b.message << "\"";
  EXPECT_STREQ(s.file(), "t.json");
  // The formatted text leads with NAME:LINE:COL.
  const std::string where =
      "t.json:" + std::to_string(b.line) + ":" + std::to_string(b.column) + ":";
  EXPECT_EQ(format(s).rfind(where, 0), 0u) << format(s);
}

void expect_all_bad(const std::vector<Bad>& list) {
  for (const Bad& b : list) expect_bad(b);
}

std::string fixture(const char* name) {
  std::vector<uint8_t> bytes =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/" + name);
  return std::string(bytes.begin(), bytes.end());
}

// Structural equality of two parsed documents (values, strings, keys, links, positions).
void expect_same_document(const JsonDocument& a, const JsonDocument& b) {
  ASSERT_EQ(a.values.size(), b.values.size());
  for (size_t i = 0; i < a.values.size(); ++i) {
    const JsonValue& x = a.values[i];
    const JsonValue& y = b.values[i];
    ASSERT_EQ(x.type, y.type) << i;
    EXPECT_EQ(x.boolean, y.boolean) << i;
    EXPECT_EQ(bits(x.number), bits(y.number)) << i;
    EXPECT_EQ(x.length, y.length) << i;
    if (x.type == JsonType::kString) {
      EXPECT_EQ(str(x), str(y)) << i;
    }
    EXPECT_EQ(x.key_length, y.key_length) << i;
    if (x.key != nullptr || y.key != nullptr) {
      ASSERT_TRUE(x.key != nullptr && y.key != nullptr) << i;
      EXPECT_STREQ(x.key, y.key) << i;
    }
    EXPECT_EQ(x.first_child, y.first_child) << i;
    EXPECT_EQ(x.next_sibling, y.next_sibling) << i;
    EXPECT_EQ(x.child_count, y.child_count) << i;
    EXPECT_EQ(x.line, y.line) << i;
    EXPECT_EQ(x.column, y.column) << i;
  }
}

// ---------------------------------------------------------------------------------------------
// Valid documents.

TEST(JsonValid, EveryTypeAndTheChildWalk) {
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  const std::string text =
      R"({"n": null, "t": true, "f": false, "i": -12, "d": 0.5, "s": "x", "e": "",)"
      R"( "a": [1, [2, []], {}], "o": {"k": {"deep": [true]}}})";
  Status s = parse(a.arena, text, &doc, JsonLimits{}, "doc.json");
  ASSERT_TRUE(s.is_ok()) << format(s);
  EXPECT_STREQ(doc.name, "doc.json");
  const JsonValue& root = doc.root();
  ASSERT_EQ(root.type, JsonType::kObject);
  EXPECT_EQ(root.child_count, 9u);
  EXPECT_EQ(root.key, nullptr);
  EXPECT_EQ(root.next_sibling, kJsonNone);
  EXPECT_EQ(doc.index_of(root), 0u);

  // The walk visits the members in document order, with their keys.
  const char* keys[] = {"n", "t", "f", "i", "d", "s", "e", "a", "o"};
  const JsonType types[] = {JsonType::kNull,   JsonType::kBool,   JsonType::kBool,
                            JsonType::kNumber, JsonType::kNumber, JsonType::kString,
                            JsonType::kString, JsonType::kArray,  JsonType::kObject};
  uint32_t i = 0;
  for (uint32_t k = root.first_child; k != kJsonNone; k = doc.at(k).next_sibling, ++i) {
    ASSERT_LT(i, 9u);
    const JsonValue& m = doc.at(k);
    EXPECT_STREQ(m.key, keys[i]);
    EXPECT_EQ(m.key_length, 1u);
    EXPECT_EQ(m.type, types[i]) << keys[i];
    EXPECT_EQ(doc.index_of(m), k);
    EXPECT_EQ(doc.member(root, keys[i]), &m);
  }
  EXPECT_EQ(i, 9u);

  EXPECT_TRUE(doc.member(root, "t")->boolean);
  EXPECT_FALSE(doc.member(root, "f")->boolean);
  EXPECT_EQ(doc.member(root, "i")->number, -12.0);
  EXPECT_EQ(doc.member(root, "d")->number, 0.5);
  EXPECT_EQ(str(*doc.member(root, "s")), "x");
  const JsonValue* e = doc.member(root, "e");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->length, 0u);
  ASSERT_NE(e->string, nullptr);
  EXPECT_EQ(e->string[0], '\0');

  // Arrays: [1, [2, []], {}]
  const JsonValue& arr = *doc.member(root, "a");
  ASSERT_EQ(arr.child_count, 3u);
  const JsonValue& a0 = doc.at(arr.first_child);
  EXPECT_EQ(a0.type, JsonType::kNumber);
  EXPECT_EQ(a0.number, 1.0);
  EXPECT_EQ(a0.key, nullptr);  // array elements have no key
  const JsonValue& a1 = doc.at(a0.next_sibling);
  ASSERT_EQ(a1.type, JsonType::kArray);
  EXPECT_EQ(a1.child_count, 2u);
  EXPECT_EQ(doc.at(a1.first_child).number, 2.0);
  const JsonValue& empty_array = doc.at(doc.at(a1.first_child).next_sibling);
  EXPECT_EQ(empty_array.type, JsonType::kArray);
  EXPECT_EQ(empty_array.child_count, 0u);
  EXPECT_EQ(empty_array.first_child, kJsonNone);
  EXPECT_EQ(empty_array.next_sibling, kJsonNone);
  const JsonValue& a2 = doc.at(a1.next_sibling);
  EXPECT_EQ(a2.type, JsonType::kObject);
  EXPECT_EQ(a2.child_count, 0u);
  EXPECT_EQ(a2.first_child, kJsonNone);
  EXPECT_EQ(a2.next_sibling, kJsonNone);

  // Nested objects and member() at each level.
  const JsonValue* o = doc.member(root, "o");
  const JsonValue* k = doc.member(*o, "k");
  ASSERT_NE(k, nullptr);
  const JsonValue* deep = doc.member(*k, "deep");
  ASSERT_NE(deep, nullptr);
  ASSERT_EQ(deep->child_count, 1u);
  EXPECT_TRUE(doc.at(deep->first_child).boolean);

  // member(): absent keys, prefixes of keys, non-objects.
  EXPECT_EQ(doc.member(root, "x"), nullptr);
  EXPECT_EQ(doc.member(root, ""), nullptr);
  EXPECT_EQ(doc.member(*o, "kk"), nullptr);
  EXPECT_EQ(doc.member(*o, "deep"), nullptr);  // not a member of o itself
  EXPECT_EQ(doc.member(arr, "a"), nullptr);
  EXPECT_EQ(doc.member(*doc.member(root, "s"), "x"), nullptr);

  // Values are stored in document order (pre-order).
  EXPECT_EQ(doc.values.size(), 18u);
}

TEST(JsonValid, ScalarRootsAndLiterals) {
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  SPLINTCORE_ASSERT_OK(parse(a.arena, "null", &doc));
  EXPECT_EQ(doc.root().type, JsonType::kNull);
  EXPECT_EQ(doc.values.size(), 1u);
  SPLINTCORE_ASSERT_OK(parse(a.arena, "true", &doc));
  EXPECT_EQ(doc.root().type, JsonType::kBool);
  EXPECT_TRUE(doc.root().boolean);
  SPLINTCORE_ASSERT_OK(parse(a.arena, "false", &doc));
  EXPECT_FALSE(doc.root().boolean);
  SPLINTCORE_ASSERT_OK(parse(a.arena, "\"s\"", &doc));
  EXPECT_EQ(str(doc.root()), "s");
  SPLINTCORE_ASSERT_OK(parse(a.arena, "[true,false,null]", &doc));
  EXPECT_EQ(doc.root().child_count, 3u);
  // The parser never reads beyond `length`: a longer buffer cut short parses the prefix.
  Context ctx(&a.arena);
  const char buffer[] = "12345";
  SPLINTCORE_ASSERT_OK(parse_json(ctx, buffer, 3, JsonLimits{}, nullptr, &doc));
  EXPECT_EQ(doc.root().number, 123.0);
  EXPECT_EQ(doc.name, nullptr);
  SPLINTCORE_ASSERT_OK(parse_json(ctx, "truex", 4, JsonLimits{}, nullptr, &doc));
  EXPECT_TRUE(doc.root().boolean);
}

TEST(JsonValid, TypeNames) {
  EXPECT_STREQ(json_type_name(JsonType::kNull), "null");
  EXPECT_STREQ(json_type_name(JsonType::kBool), "boolean");
  EXPECT_STREQ(json_type_name(JsonType::kNumber), "number");
  EXPECT_STREQ(json_type_name(JsonType::kString), "string");
  EXPECT_STREQ(json_type_name(JsonType::kArray), "array");
  EXPECT_STREQ(json_type_name(JsonType::kObject), "object");
}

TEST(JsonValid, Escapes) {
  expect_string(R"("\"\\\/\b\f\n\r\t")", "\"\\/\b\f\n\r\t");
  expect_string(R"("a\nb")", "a\nb");
  expect_string(R"("\u0041\u0062")", "Ab");
  expect_string(R"("\u007f\u0080")", "\x7f\xc2\x80");      // 1 and 2 byte boundaries
  expect_string(R"("\u00e9\u00E9")", "\xc3\xa9\xc3\xa9");  // lower and upper case hex
  expect_string(R"("\u07FF\u0800")", "\xdf\xbf\xe0\xa0\x80");
  expect_string(R"("\u20AC")", "\xe2\x82\xac");
  expect_string(R"("\uD7FF\uE000\uFFFF")", "\xed\x9f\xbf\xee\x80\x80\xef\xbf\xbf");
  expect_string(R"("\uFEFF")", "\xef\xbb\xbf");  // a BOM inside a string is a character
  // Surrogate pairs decode to one 4-byte sequence.
  expect_string(R"("\uD83D\uDE00")", "\xf0\x9f\x98\x80");      // U+1F600
  expect_string(R"("\ud800\udc00")", "\xf0\x90\x80\x80");      // U+10000
  expect_string(R"("\uDBFF\uDFFF")", "\xf4\x8f\xbf\xbf");      // U+10FFFF
  expect_string(R"("x\uD834\uDD1Ey")", "x\xf0\x9d\x84\x9ey");  // U+1D11E
  expect_string(R"("\\u0041")", "\\u0041");                    // an escaped backslash
  // Escapes in keys are decoded too, and member() finds the decoded key.
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  SPLINTCORE_ASSERT_OK(parse(a.arena, R"({"caf\u00e9": 1, "t\tb": 2})", &doc));
  ASSERT_NE(doc.member(doc.root(), "caf\xc3\xa9"), nullptr);
  EXPECT_EQ(doc.member(doc.root(), "caf\xc3\xa9")->number, 1.0);
  EXPECT_EQ(doc.member(doc.root(), "caf\xc3\xa9")->key_length, 5u);
  ASSERT_NE(doc.member(doc.root(), "t\tb"), nullptr);
  EXPECT_EQ(doc.member(doc.root(), "t\tb")->number, 2.0);
}

TEST(JsonValid, RawUtf8) {
  expect_string("\"caf\xc3\xa9\"", "caf\xc3\xa9");
  expect_string("\"\xe2\x82\xac \xf0\x9f\x98\x80\"", "\xe2\x82\xac \xf0\x9f\x98\x80");
  // The edges of every sequence length and around the surrogate gap.
  expect_string("\"\xc2\x80\xdf\xbf\"", "\xc2\x80\xdf\xbf");
  expect_string("\"\xe0\xa0\x80\xed\x9f\xbf\xee\x80\x80\xef\xbf\xbf\"",
                "\xe0\xa0\x80\xed\x9f\xbf\xee\x80\x80\xef\xbf\xbf");
  expect_string("\"\xf0\x90\x80\x80\xf4\x8f\xbf\xbf\"", "\xf0\x90\x80\x80\xf4\x8f\xbf\xbf");
  expect_string("\"\x7f\"", "\x7f");  // DEL is not a control character in JSON
}

TEST(JsonValid, ByteOrderMarkAndWhitespace) {
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  SPLINTCORE_ASSERT_OK(parse(a.arena, "\xef\xbb\xbf{\"a\": 1}", &doc));
  EXPECT_EQ(doc.root().line, 1u);
  EXPECT_EQ(doc.root().column, 1u);  // the BOM takes no column
  EXPECT_EQ(doc.member(doc.root(), "a")->column, 7u);
  SPLINTCORE_ASSERT_OK(parse(a.arena, "\xef\xbb\xbf 7", &doc));
  EXPECT_EQ(doc.root().number, 7.0);
  EXPECT_EQ(doc.root().column, 2u);

  SPLINTCORE_ASSERT_OK(parse(a.arena, " \t\r\n[ 1 ,\n\t2\r\n, \"x\" ] \r\n\t ", &doc));
  ASSERT_EQ(doc.root().child_count, 3u);
  EXPECT_EQ(doc.root().line, 2u);
  EXPECT_EQ(doc.root().column, 1u);
  const JsonValue& one = doc.at(doc.root().first_child);
  const JsonValue& two = doc.at(one.next_sibling);
  const JsonValue& x = doc.at(two.next_sibling);
  EXPECT_EQ(one.line, 2u);
  EXPECT_EQ(one.column, 3u);
  EXPECT_EQ(two.line, 3u);
  EXPECT_EQ(two.column, 2u);  // a tab is one column
  EXPECT_EQ(x.line, 4u);      // "\r\n" is one line break
  EXPECT_EQ(x.column, 3u);
}

TEST(JsonValid, LineAndColumnOfValues) {
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  const std::string text =
      "{\n"
      "  \"a\": [10, 20],\n"
      "  \"\xc3\xa9\": \"\xe2\x82\xac\", \"b\": true,\n"  // columns count bytes
      "\n"
      "    \"c\": {\"d\": null}\n"
      "}";
  SPLINTCORE_ASSERT_OK(parse(a.arena, text, &doc));
  const JsonValue& root = doc.root();
  EXPECT_EQ(root.line, 1u);
  EXPECT_EQ(root.column, 1u);
  const JsonValue* arr = doc.member(root, "a");
  EXPECT_EQ(arr->line, 2u);
  EXPECT_EQ(arr->column, 8u);
  EXPECT_EQ(doc.at(arr->first_child).column, 9u);
  EXPECT_EQ(doc.at(doc.at(arr->first_child).next_sibling).column, 13u);
  const JsonValue* accent = doc.member(root, "\xc3\xa9");
  EXPECT_EQ(accent->line, 3u);
  EXPECT_EQ(accent->column, 9u);
  const JsonValue* b = doc.member(root, "b");
  EXPECT_EQ(b->line, 3u);
  EXPECT_EQ(b->column, 21u);
  const JsonValue* c = doc.member(root, "c");
  EXPECT_EQ(c->line, 5u);
  EXPECT_EQ(c->column, 10u);
  const JsonValue* d = doc.member(*c, "d");
  EXPECT_EQ(d->line, 5u);
  EXPECT_EQ(d->column, 16u);

  // json_error() places a message at a value.
  Status s = json_error(doc, *d, StatusCode::kInvalidArgument, "d is wrong");
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(s.line(), 5u);
  EXPECT_EQ(s.column(), 16u);
  EXPECT_EQ(format(s), "t.json:5:16: d is wrong");
}

TEST(JsonValid, NumbersExactCases) {
  expect_number("0", 0.0);
  expect_number("-0", -0.0);
  expect_number("-0.0", -0.0);
  expect_number("-0e5", -0.0);
  expect_number("0e500", 0.0);
  expect_number("0.000e-999", 0.0);
  expect_number("1", 1.0);
  expect_number("-12", -12.0);
  expect_number("0.1", 0.1);
  expect_number("1E2", 100.0);
  expect_number("1e+2", 100.0);
  expect_number("1e-2", 0.01);
  expect_number("-1.5e-3", -0.0015);
  expect_number("1e308", 1e308);
  expect_number("1.7976931348623157e308", std::numeric_limits<double>::max());
  expect_number("-1.7976931348623157e308", -std::numeric_limits<double>::max());
  expect_number("2.2250738585072014e-308", std::numeric_limits<double>::min());
  expect_number("5e-324", std::numeric_limits<double>::denorm_min());
  expect_number("4.9406564584124654e-324", std::numeric_limits<double>::denorm_min());
  expect_number("3e-324", std::numeric_limits<double>::denorm_min());  // rounds up to it
  expect_number("9007199254740993", 9007199254740992.0);               // a tie: to even
  expect_number("9007199254740995", 9007199254740996.0);
  // Halfway and just-above-halfway cases that a naive parser rounds wrongly.
  expect_number("2.2250738585072011e-308", 2.2250738585072011e-308);
  expect_number("0.1000000000000000055511151231257827021181583404541015625", 0.1);
  expect_number("123456789012345678901234567890", 123456789012345678901234567890.0);
  // Sign and bit pattern of -0 survive.
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  SPLINTCORE_ASSERT_OK(parse(a.arena, "-0", &doc));
  EXPECT_TRUE(std::signbit(doc.root().number));
}

// A random JSON number: optional '-', an integer part without leading zeros, an optional
// fraction and an optional exponent; mantissas up to 40 digits (sometimes several hundred).
std::string random_number(std::mt19937_64& rng) {
  auto pick = [&](uint64_t n) { return static_cast<int>(rng() % n); };
  std::string s;
  if (pick(2) == 0) s += '-';
  const int int_digits = pick(8) == 0 ? 1 : 1 + pick(pick(5) == 0 ? 40 : 20);
  if (pick(6) == 0) {
    s += '0';
  } else {
    s += static_cast<char>('1' + pick(9));
    for (int i = 1; i < int_digits; ++i) s += static_cast<char>('0' + pick(10));
  }
  if (pick(3) != 0) {
    s += '.';
    const int frac = pick(50) == 0 ? 200 + pick(600) : 1 + pick(30);
    for (int i = 0; i < frac; ++i) s += static_cast<char>('0' + pick(10));
  }
  if (pick(3) != 0) {
    s += pick(2) == 0 ? 'e' : 'E';
    const int sign = pick(3);
    if (sign == 1) s += '+';
    if (sign == 2) s += '-';
    // Exponents near both ends of the double range, and small ones.
    const int e = pick(3) == 0 ? 280 + pick(60) : pick(40);
    if (pick(4) == 0) s += '0';  // leading zeros are allowed in exponents
    s += std::to_string(e);
  }
  return s;
}

bool mantissa_is_zero(const std::string& s) {
  for (char c : s) {
    if (c == 'e' || c == 'E') break;
    if (c >= '1' && c <= '9') return false;
  }
  return true;
}

TEST(JsonValid, NumbersMatchStrtodBitForBit) {
  // strtod (C locale: this program never calls setlocale) rounds correctly in glibc, as does the
  // parser's from_chars: the same text must give the same bits. Where strtod overflows to
  // infinity or underflows a non-zero number to zero, the parser must refuse the number.
  std::mt19937_64 rng(20240611);
  test::TestArena a(size_t{1} << 20);
  int checked = 0, refused = 0, subnormal = 0;
  for (int i = 0; i < 20000; ++i) {
    const std::string s = random_number(rng);
    errno = 0;
    const double expected = std::strtod(s.c_str(), nullptr);
    const bool overflow = std::isinf(expected);
    const bool underflow = expected == 0.0 && !mantissa_is_zero(s);
    a.arena.reset();
    JsonDocument doc;
    Status st = parse(a.arena, s, &doc);
    if (overflow || underflow) {
      EXPECT_EQ(st.code(), StatusCode::kParseError) << s;
      EXPECT_EQ(st.column(), 1u) << s;
      EXPECT_NE(std::strstr(st.message(), "out of double range"), nullptr) << format(st);
      ++refused;
      continue;
    }
    ASSERT_TRUE(st.is_ok()) << s << ": " << format(st);
    ASSERT_EQ(doc.root().type, JsonType::kNumber);
    ASSERT_EQ(bits(doc.root().number), bits(expected)) << s;
    if (expected != 0.0 && std::fabs(expected) < std::numeric_limits<double>::min()) ++subnormal;
    ++checked;
  }
  // The generator reaches every region it is meant to.
  EXPECT_GT(checked, 15000);
  EXPECT_GT(refused, 100);
  EXPECT_GT(subnormal, 5);
}

TEST(JsonValid, NumbersInsideContainersEndAtTheirDelimiters) {
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  SPLINTCORE_ASSERT_OK(parse(a.arena, "[1,-2.5e3,0,-0,7E-1]", &doc));
  const double expected[] = {1, -2500, 0, -0.0, 0.7};
  uint32_t i = 0;
  for (uint32_t k = doc.root().first_child; k != kJsonNone; k = doc.at(k).next_sibling, ++i) {
    EXPECT_EQ(bits(doc.at(k).number), bits(expected[i])) << i;
  }
  EXPECT_EQ(i, 5u);
  SPLINTCORE_ASSERT_OK(parse(a.arena, "{\"a\":1e2}", &doc));
  EXPECT_EQ(doc.member(doc.root(), "a")->number, 100.0);
}

// ---------------------------------------------------------------------------------------------
// Strictness: each rule, with the line and column of the error.

TEST(JsonStrict, TrailingCommas) {
  expect_all_bad({
      {"[1,]", 1, 4, "trailing comma"},
      {"{\"a\":1,}", 1, 8, "trailing comma"},
      {"[1,\n  ]", 2, 3, "trailing comma"},
      {"[,]", 1, 2, "expected a value, found ','"},
      {"[1,,2]", 1, 4, "expected a value, found ','"},
      {"{,}", 1, 2, "expected a string key, found ','"},
  });
}

TEST(JsonStrict, Comments) {
  expect_all_bad({
      {"// note\n1", 1, 1, "expected a value, found '/'"},
      {"[1, /* note */ 2]", 1, 5, "expected a value, found '/'"},
      {"[1 // note\n]", 1, 4, "expected ',' or ']', found '/'"},
      {"{\"a\": 1 # note\n}", 1, 9, "expected ',' or '}', found '#'"},
      {"1 // note", 1, 3, "unexpected data after the JSON value"},
  });
}

TEST(JsonStrict, SingleQuotesAndBareWords) {
  expect_all_bad({
      {"{'a': 1}", 1, 2, "expected a string key, found '''"},
      {"['a']", 1, 2, "expected a value, found '''"},
      {"{a: 1}", 1, 2, "expected a string key, found 'a'"},
      {"{\"a\": 'b'}", 1, 7, "expected a value, found '''"},
      {"True", 1, 1, "expected a value, found 'T'"},
      {"tru", 1, 1, "expected a value, found 't'"},
      {"nul", 1, 1, "expected a value, found 'n'"},
      {"[truex]", 1, 6, "expected ',' or ']', found 'x'"},
      {"undefined", 1, 1, "expected a value, found 'u'"},
  });
}

TEST(JsonStrict, NanAndInfinity) {
  expect_all_bad({
      {"NaN", 1, 1, "expected a value, found 'N'"},
      {"[1, NaN]", 1, 5, "expected a value, found 'N'"},
      {"nan", 1, 1, "expected a value, found 'n'"},
      {"-NaN", 1, 2, "expected a digit, found 'N'"},
      {"Infinity", 1, 1, "expected a value, found 'I'"},
      {"-Infinity", 1, 2, "expected a digit, found 'I'"},
      {"{\"x\":\n  inf}", 2, 3, "expected a value, found 'i'"},
  });
}

TEST(JsonStrict, NumberGrammar) {
  expect_all_bad({
      {"01", 1, 2, "leading zero"},
      {"-01", 1, 3, "leading zero"},
      {"00", 1, 2, "leading zero"},
      {"[007]", 1, 3, "leading zero"},
      {"+1", 1, 1, "expected a value, found '+'"},
      {"[1, +5]", 1, 5, "expected a value, found '+'"},
      {".5", 1, 1, "expected a value, found '.'"},
      {"-.5", 1, 2, "expected a digit, found '.'"},
      {"5.", 1, 3, "expected a digit after the decimal point, found the end of the input"},
      {"[5.]", 1, 4, "expected a digit after the decimal point, found ']'"},
      {"5.e3", 1, 3, "expected a digit after the decimal point, found 'e'"},
      {"1e", 1, 3, "expected a digit in the exponent, found the end of the input"},
      {"1e+", 1, 4, "expected a digit in the exponent"},
      {"1E-x", 1, 4, "expected a digit in the exponent, found 'x'"},
      {"-", 1, 2, "expected a digit, found the end of the input"},
      {"- 1", 1, 2, "expected a digit, found ' '"},
      {"1.5.2", 1, 4, "unexpected data after the JSON value"},
      {"0x10", 1, 2, "unexpected data after the JSON value"},
      {"1_000", 1, 2, "unexpected data after the JSON value"},
  });
}

TEST(JsonStrict, NumbersOutOfDoubleRange) {
  expect_all_bad({
      {"1e400", 1, 1, "number out of double range"},
      {"-1e400", 1, 1, "number out of double range"},
      {"[0,\n -1e400]", 2, 2, "number out of double range"},
      {"1.7976931348623159e308", 1, 1, "number out of double range"},
      {"1e-400", 1, 1, "number out of double range"},  // a non-zero number that would be 0
      {"2e-324", 1, 1, "number out of double range"},
      {"{\"x\": 1e999999999999}", 1, 7, "number out of double range"},
  });
}

TEST(JsonStrict, UnterminatedStrings) {
  expect_all_bad({
      {"\"abc", 1, 5, "unterminated string"},
      {"[\"abc", 1, 6, "unterminated string"},
      {"{\"ab", 1, 5, "unterminated string"},
      {"\"", 1, 2, "unterminated string"},
      {"\"a\\", 1, 3, "unterminated escape"},
      {"\"\\u00", 1, 2, "\\u needs four hex digits"},
  });
}

TEST(JsonStrict, ControlCharactersInStrings) {
  expect_all_bad({
      {std::string("\"a\x01\""), 1, 3, "control character in string"},
      {std::string("\"\x1f\""), 1, 2, "control character in string"},
      {std::string("\"a\tb\""), 1, 3, "control character in string"},
      {std::string("\"a\nb\""), 1, 3, "control character in string"},
      {std::string("\"a\rb\""), 1, 3, "control character in string"},
      {std::string("[\"ok\",\n \"x\0y\"]", 14), 2, 4, "control character in string"},
      {std::string("{\"k\x02\": 1}"), 1, 4, "control character in string"},
  });
}

TEST(JsonStrict, InvalidEscapes) {
  // Escape errors point at the escape's backslash.
  expect_all_bad({
      {"\"\\x\"", 1, 2, "invalid escape"},
      {"\"ab\\a\"", 1, 4, "invalid escape"},
      {"\"\\U0041\"", 1, 2, "invalid escape"},
      {"\"\\'\"", 1, 2, "invalid escape"},
      {"\"\\0\"", 1, 2, "invalid escape"},
      {"\"\\ \"", 1, 2, "invalid escape"},
      {"\"\\u12\"", 1, 2, "\\u needs four hex digits"},
      {"\"\\u12G4\"", 1, 2, "\\u needs four hex digits"},
      {"\"\\u\"", 1, 2, "\\u needs four hex digits"},
      {"\"\\u+123\"", 1, 2, "\\u needs four hex digits"},
      {"\"x\\u0000\"", 1, 3, "\\u0000 is not allowed"},
      {"{\"\\q\": 1}", 1, 3, "invalid escape"},
  });
}

TEST(JsonStrict, LoneSurrogates) {
  expect_all_bad({
      {"\"\\udc00\"", 1, 2, "lone low surrogate"},
      {"\"\\uDFFF\"", 1, 2, "lone low surrogate"},
      {"\"ab\\ud800\"", 1, 4, "high surrogate without a low surrogate"},
      {"\"\\ud800x\"", 1, 2, "high surrogate without a low surrogate"},
      {"\"\\uDBFF\"", 1, 2, "high surrogate without a low surrogate"},
      {"\"\\ud800\\u0041\"", 1, 2, "high surrogate without a low surrogate"},
      {"\"\\ud800\\ud800\"", 1, 2, "high surrogate without a low surrogate"},
      {"\"\\ud800\\n\"", 1, 2, "high surrogate without a low surrogate"},
      {"\"\\ud800\\u12\"", 1, 2, "high surrogate without a low surrogate"},
      {"\"\\ud800", 1, 2, "high surrogate without a low surrogate"},
      {"\"\\udc00\\ud800\"", 1, 2, "lone low surrogate"},  // a pair in the wrong order
  });
}

TEST(JsonStrict, InvalidUtf8) {
  // Each error points at the first byte of the bad sequence.
  expect_all_bad({
      // Overlong forms.
      {"\"ab\xc0\xaf\"", 1, 4, "invalid UTF-8"},
      {"\"\xc1\xbf\"", 1, 2, "invalid UTF-8"},
      {"\"\xe0\x80\xaf\"", 1, 2, "invalid UTF-8"},
      {"\"\xe0\x9f\xbf\"", 1, 2, "invalid UTF-8"},
      {"\"\xf0\x80\x80\xaf\"", 1, 2, "invalid UTF-8"},
      {"\"\xf0\x8f\xbf\xbf\"", 1, 2, "invalid UTF-8"},
      // Surrogates encoded directly.
      {"\"\xed\xa0\x80\"", 1, 2, "invalid UTF-8"},
      {"\"\xed\xbf\xbf\"", 1, 2, "invalid UTF-8"},
      {"\"\xed\xa0\xbd\xed\xb8\x80\"", 1, 2, "invalid UTF-8"},  // CESU-8 of U+1F600
      // Beyond U+10FFFF.
      {"\"\xf4\x90\x80\x80\"", 1, 2, "invalid UTF-8"},
      {"\"\xf5\x80\x80\x80\"", 1, 2, "invalid UTF-8"},
      {"\"\xf7\xbf\xbf\xbf\"", 1, 2, "invalid UTF-8"},
      {"\"\xf8\x88\x80\x80\x80\"", 1, 2, "invalid UTF-8"},
      {"\"\xfc\x84\x80\x80\x80\x80\"", 1, 2, "invalid UTF-8"},
      // Truncated sequences: cut by the closing quote, by another lead byte, by the input's end.
      {"\"\xc3\"", 1, 2, "invalid UTF-8"},
      {"\"x\xe2\x82\"", 1, 3, "invalid UTF-8"},
      {"\"\xf0\x9f\x98\"", 1, 2, "invalid UTF-8"},
      {"\"\xe2\x82\xe2\x82\xac\"", 1, 2, "invalid UTF-8"},
      {"\"\xe2\x82", 1, 2, "invalid UTF-8"},
      {"\"\xf0\x9f\x98", 1, 2, "invalid UTF-8"},
      // Stray continuation bytes and bytes that never occur.
      {"\"\x80\"", 1, 2, "invalid UTF-8"},
      {"\"\xc3\xa9\xbf\"", 1, 4, "invalid UTF-8"},
      {"\"\xfe\"", 1, 2, "invalid UTF-8"},
      {"\"\xff\"", 1, 2, "invalid UTF-8"},
      // In a key, and outside any string.
      {"{\"\xff\": 1}", 1, 3, "invalid UTF-8"},
      {"\xff", 1, 1, "expected a value, found byte 255"},
      {"[1,\xc3\xa9]", 1, 4, "expected a value, found byte 195"},
  });
}

TEST(JsonStrict, DuplicateKeys) {
  // Reported at the value of the first member whose key repeats, naming where the first is.
  expect_all_bad({
      {"{\"a\":1,\"a\":2}", 1, 12, "duplicate key \"a\" (first given at line 1, column 6)"},
      {"{\"a\": 1, \"b\": 2, \"a\": 3}", 1, 23, "duplicate key \"a\""},
      {"{\n \"x\": [],\n \"x\": {}\n}", 3, 7,
       "duplicate key \"x\" (first given at line 2, column 7)"},
      // Escapes are compared decoded.
      {"{\"\\u0061\": 1, \"a\": 2}", 1, 20, "duplicate key \"a\""},
      {"{\"\": 1, \"\": 2}", 1, 13, "duplicate key \"\""},
      // Nested: the inner object's duplicate.
      {"{\"o\": {\"k\": 1, \"k\": 2}}", 1, 21, "duplicate key \"k\""},
      // Several repeated keys: the first repetition in document order is reported.
      {"{\"b\":1,\"a\":2,\"c\":3,\"a\":4,\"b\":5,\"b\":6}", 1, 24, "duplicate key \"a\""},
  });
  // Same key in different objects, keys that are prefixes of each other, case differences.
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  SPLINTCORE_EXPECT_OK(
      parse(a.arena, "{\"a\": {\"a\": 1}, \"b\": [{\"a\": 1}, {\"a\": 2}]}", &doc));
  SPLINTCORE_EXPECT_OK(parse(a.arena, "{\"a\": 1, \"ab\": 2, \"A\": 3, \"\": 4, \"a \": 5}", &doc));
}

TEST(JsonStrict, ManyKeysAreCheckedQuickly) {
  // Duplicate detection must not be quadratic: 100,000 distinct keys, then the same with one
  // repeat at the very end (a pairwise check took about 20 s on this).
  std::string text = "{";
  char key[32];
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    std::snprintf(key, sizeof(key), "%s\"k%07d\":%d", i > 0 ? "," : "", (i * 7919) % n, i % 10);
    text += key;
  }
  test::TestArena a(size_t{64} << 20);
  JsonDocument doc;
  SPLINTCORE_ASSERT_OK(parse(a.arena, text + "}", &doc));
  EXPECT_EQ(doc.root().child_count, static_cast<uint32_t>(n));
  // The check leaves the members in document order.
  int i = 0;
  for (uint32_t k = doc.root().first_child; k != kJsonNone; k = doc.at(k).next_sibling, ++i) {
    std::snprintf(key, sizeof(key), "k%07d", (i * 7919) % n);
    ASSERT_STREQ(doc.at(k).key, key) << i;
    ASSERT_EQ(doc.at(k).number, i % 10) << i;
  }
  EXPECT_EQ(i, n);
  EXPECT_EQ(doc.member(doc.root(), "k0000000")->number, 0.0);  // i = 0
  EXPECT_EQ(doc.member(doc.root(), "k0007919")->number, 1.0);  // i = 1
  a.arena.reset();
  const std::string dup = text + ",\"k0012345\":0}";
  Status s = parse(a.arena, dup, &doc);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_NE(std::strstr(s.message(), "duplicate key \"k0012345\""), nullptr) << format(s);
  EXPECT_EQ(s.column(), dup.size() - 1);
}

TEST(JsonStrict, DataAfterTheValue) {
  expect_all_bad({
      {"{} x", 1, 4, "unexpected data after the JSON value"},
      {"1 2", 1, 3, "unexpected data after the JSON value"},
      {"[]]", 1, 3, "unexpected data after the JSON value"},
      {"{}\n{}", 2, 1, "unexpected data after the JSON value"},
      {"\"a\"\"b\"", 1, 4, "unexpected data after the JSON value"},
      {std::string("1\0", 2), 1, 2, "unexpected data after the JSON value"},
      {"null,", 1, 5, "unexpected data after the JSON value"},
  });
}

TEST(JsonStrict, EmptyInputAndOtherStructure) {
  expect_all_bad({
      {"", 1, 1, "expected a value, found the end of the input"},
      {"   ", 1, 4, "expected a value, found the end of the input"},
      {"\n\n", 3, 1, "expected a value, found the end of the input"},
      {"\xef\xbb\xbf", 1, 1, "expected a value, found the end of the input"},
      {std::string("\xef\xbb\xbf\xef\xbb\xbf") + "1", 1, 1,
       "expected a value, found byte 239"},  // one BOM only
      {"\xef\xbb", 1, 1, "expected a value, found byte 239"},
      {"\f1", 1, 1, "expected a value, found byte 12"},  // not JSON whitespace
      {"\v1", 1, 1, "expected a value, found byte 11"},
      {std::string("\xc2\xa0") + "1", 1, 1, "expected a value, found byte 194"},  // no-break space
      {"{\"a\" 1}", 1, 6, "expected ':', found '1'"},
      {"{\"a\":}", 1, 6, "expected a value, found '}'"},
      {"{1: 2}", 1, 2, "expected a string key, found '1'"},
      {"[1 2]", 1, 4, "expected ',' or ']', found '2'"},
      {"{\"a\": 1 \"b\": 2}", 1, 9, "expected ',' or '}', found '\"'"},
      {"[1}", 1, 3, "expected ',' or ']', found '}'"},
      {"{\"a\": 1]", 1, 8, "expected ',' or '}', found ']'"},
      {"[1,2", 1, 5, "expected ',' or ']', found the end of the input"},
      {"{\"a\":", 1, 6, "expected a value, found the end of the input"},
      {"{", 1, 2, "expected a string key, found the end of the input"},
      {"]", 1, 1, "expected a value, found ']'"},
  });
}

// ---------------------------------------------------------------------------------------------
// Limits.

TEST(JsonLimit, MaxBytes) {
  JsonLimits limits;
  limits.max_bytes = 10;
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  SPLINTCORE_EXPECT_OK(parse(a.arena, "[1,2,3,45]", &doc, limits));  // exactly 10 bytes
  Status s = parse(a.arena, "[1,2,3,456]", &doc, limits);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
  EXPECT_NE(std::strstr(s.message(), "11 bytes"), nullptr) << format(s);
  EXPECT_NE(std::strstr(s.message(), "limit of 10"), nullptr) << format(s);
  EXPECT_STREQ(s.file(), "t.json");
  // Checked before anything is allocated.
  ExactArena tiny(0);
  s = parse(tiny.arena, "[1,2,3,456]", &doc, limits);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
}

TEST(JsonLimit, MaxDepth) {
  test::TestArena a(size_t{8} << 20);
  JsonDocument doc;
  auto nested = [](int depth, char open, char close) {
    return std::string(static_cast<size_t>(depth), open) +
           std::string(static_cast<size_t>(depth), close);
  };
  // The default limit is 32 levels.
  SPLINTCORE_EXPECT_OK(parse(a.arena, nested(32, '[', ']'), &doc));
  EXPECT_EQ(doc.values.size(), 32u);
  Status s = parse(a.arena, nested(33, '[', ']'), &doc);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
  EXPECT_EQ(s.line(), 1u);
  EXPECT_EQ(s.column(), 33u);  // the '[' that goes one level too deep
  EXPECT_NE(std::strstr(s.message(), "nesting deeper than 32"), nullptr) << format(s);
  EXPECT_STREQ(s.file(), "t.json");

  JsonLimits limits;
  limits.max_depth = 3;
  SPLINTCORE_EXPECT_OK(parse(a.arena, "{\"a\": [{}]}", &doc, limits));
  s = parse(a.arena, "{\"a\": [{\"b\": []}]}", &doc, limits);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
  EXPECT_EQ(s.column(), 14u);
  // Scalars do not count as a level.
  limits.max_depth = 1;
  SPLINTCORE_EXPECT_OK(parse(a.arena, "[1, \"x\", null]", &doc, limits));
  limits.max_depth = 0;
  SPLINTCORE_EXPECT_OK(parse(a.arena, "7", &doc, limits));
  EXPECT_EQ(parse(a.arena, "[]", &doc, limits).code(), StatusCode::kLimitExceeded);

  // 100,000 '[' (and '{"a":' chains) must not overflow the stack: the depth bounds the
  // recursion, and a caller's limit above the parser's ceiling (64) is held to the ceiling.
  const std::string deep(100000, '[');
  s = parse(a.arena, deep, &doc);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
  EXPECT_EQ(s.column(), 33u);
  limits.max_depth = 1000000;
  s = parse(a.arena, deep, &doc, limits);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
  EXPECT_EQ(s.column(), 65u);
  EXPECT_NE(std::strstr(s.message(), "nesting deeper than 64"), nullptr) << format(s);
  SPLINTCORE_EXPECT_OK(parse(a.arena, nested(64, '[', ']'), &doc, limits));
  std::string objects;
  for (int i = 0; i < 100000; ++i) objects += "{\"a\":";
  s = parse(a.arena, objects, &doc, limits);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
  EXPECT_EQ(s.column(), 64u * 5u + 1u);
}

TEST(JsonLimit, MaxValues) {
  test::TestArena a(size_t{1} << 20);
  JsonDocument doc;
  JsonLimits limits;
  limits.max_values = 4;  // [1,2,3] is four values: the array and three numbers
  SPLINTCORE_EXPECT_OK(parse(a.arena, "[1,2,3]", &doc, limits));
  limits.max_values = 3;
  Status s = parse(a.arena, "[1,2,3]", &doc, limits);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
  EXPECT_EQ(s.line(), 1u);
  EXPECT_EQ(s.column(), 6u);  // the fourth value
  EXPECT_NE(std::strstr(s.message(), "more than 3 values"), nullptr) << format(s);
  EXPECT_STREQ(s.file(), "t.json");
  // Object members count, their keys do not.
  limits.max_values = 2;
  SPLINTCORE_EXPECT_OK(parse(a.arena, "{\"a\": 1}", &doc, limits));
  s = parse(a.arena, "{\"a\": 1, \"b\": {}}", &doc, limits);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
  EXPECT_EQ(s.column(), 15u);
  limits.max_values = 0;
  EXPECT_EQ(parse(a.arena, "null", &doc, limits).code(), StatusCode::kLimitExceeded);
}

// ---------------------------------------------------------------------------------------------
// Truncation at every byte offset of a real case file.

// Runs every prefix of `text` through the parser in `arena` (reset between runs).
void truncate_everywhere(const std::string& text, Arena& arena, bool allow_exhaustion) {
  // The document is complete once its closing brace is in; only whitespace follows.
  const size_t complete = text.find_last_of('}') + 1;
  ASSERT_GT(complete, 1u);
  size_t ok = 0, exhausted = 0;
  for (size_t n = 0; n <= text.size(); ++n) {
    arena.reset();
    ExactText prefix(text.data(), n);
    Context ctx(&arena);
    JsonDocument doc;
    Status s = parse_json(ctx, prefix.bytes.get(), n, JsonLimits{}, "paper_scale.json", &doc);
    if (n >= complete) {
      ASSERT_TRUE(s.is_ok()) << n << ": " << format(s);
      ++ok;
      continue;
    }
    ASSERT_FALSE(s.is_ok()) << "prefix of " << n << " bytes parsed as a whole document";
    if (allow_exhaustion && s.code() == StatusCode::kArenaExhausted) {
      ++exhausted;
      continue;
    }
    ASSERT_EQ(s.code(), StatusCode::kParseError) << n << ": " << format(s);
    ASSERT_GT(std::strlen(s.message()), 0u);
    ASSERT_STREQ(s.file(), "paper_scale.json");
    // Every error is located, at most at the end of the prefix.
    ASSERT_NE(s.line(), kNoPosition) << n;
    ASSERT_GE(s.line(), 1u);
    ASSERT_GE(s.column(), 1u);
    ASSERT_LE(s.byte_offset(), n) << format(s);
  }
  EXPECT_EQ(ok, text.size() - complete + 1);
  if (!allow_exhaustion) {
    EXPECT_EQ(exhausted, 0u);
  }
}

TEST(JsonTruncation, EveryPrefixOfARealCaseFile) {
  const std::string text = fixture("paper_scale.json");
  ASSERT_GT(text.size(), 1000u);
  test::TestArena big(size_t{4} << 20);
  truncate_everywhere(text, big.arena, false);
}

TEST(JsonTruncation, EveryPrefixInASmallArena) {
  const std::string text = fixture("paper_scale.json");
  // Exactly the memory the whole file needs: no prefix needs more.
  size_t need = 0;
  {
    ExactArena probe(size_t{4} << 20);
    JsonDocument doc;
    SPLINTCORE_ASSERT_OK(parse(probe.arena, text, &doc));
    need = probe.arena.high_water();
  }
  ExactArena tight(need);
  truncate_everywhere(text, tight.arena, false);
  // Far too small: each prefix is then a parse error or a clean exhaustion.
  ExactArena tiny(2048);
  const std::string head = text.substr(0, 1500);
  for (size_t n = 0; n <= head.size(); ++n) {
    tiny.arena.reset();
    ExactText prefix(head.data(), n);
    Context ctx(&tiny.arena);
    JsonDocument doc;
    Status s = parse_json(ctx, prefix.bytes.get(), n, JsonLimits{}, "p.json", &doc);
    ASSERT_TRUE(s.code() == StatusCode::kParseError || s.code() == StatusCode::kArenaExhausted)
        << n << ": " << format(s);
  }
}

// ---------------------------------------------------------------------------------------------
// Arena exhaustion: every cap from 0 upward fails cleanly (kArenaExhausted, never a crash or a
// partial success) until the parse succeeds; from there on every cap succeeds with the same
// document as an unlimited run. (Growth falls back to the exact size when 1.5x does not fit, so
// the smallest cap that works is at most the high-water mark of an unlimited run.)

Status parse_with_cap(const std::string& text, size_t cap, JsonDocument* doc,
                      std::unique_ptr<ExactArena>* keep) {
  keep->reset(new ExactArena(cap));
  return parse((*keep)->arena, text, doc);
}

void exhaustion_sweep(const std::string& text, size_t step) {
  ExactArena unlimited(size_t{8} << 20);
  JsonDocument reference;
  SPLINTCORE_ASSERT_OK(parse(unlimited.arena, text, &reference));
  const size_t high_water = unlimited.arena.high_water();
  ASSERT_GT(high_water, text.size());

  auto expect_exhausted = [&](size_t cap) {
    std::unique_ptr<ExactArena> arena;
    JsonDocument doc;
    Status s = parse_with_cap(text, cap, &doc, &arena);
    if (s.is_ok()) return false;
    EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << "cap " << cap << ": " << format(s);
    EXPECT_NE(std::strstr(s.message(), "need"), nullptr) << format(s);
    EXPECT_GT(arena->arena.last_need(), cap) << format(s);  // it needed more than it had
    EXPECT_LE(arena->arena.used(), cap);
    return true;
  };
  // Coarse steps up to the first success, then single bytes back from there.
  size_t cap = 0;
  while (cap <= high_water && expect_exhausted(cap)) cap += step;
  ASSERT_LE(cap, high_water) << "no success up to the high-water mark";
  size_t smallest = cap;
  while (smallest > 0 && cap - smallest < step && !expect_exhausted(smallest - 1)) --smallest;
  if (::testing::Test::HasFailure()) return;
  EXPECT_GT(smallest, text.size());
  // From the smallest working cap up to the high-water mark (and beyond), always the reference.
  for (size_t c = smallest; c <= high_water + 64; c += (c == smallest ? 1 : step)) {
    std::unique_ptr<ExactArena> arena;
    JsonDocument doc;
    Status s = parse_with_cap(text, c, &doc, &arena);
    ASSERT_TRUE(s.is_ok()) << "cap " << c << " (smallest working " << smallest
                           << "): " << format(s);
    expect_same_document(reference, doc);
  }
}

TEST(JsonExhaustion, EveryCapOnASmallDocument) {
  exhaustion_sweep(
      R"({"n": null, "b": [true, false], "x": -1.25e-3, "s": "caf\u00e9 \ud83d\ude00",)"
      R"( "o": {"k": [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20]},)"
      R"( "e": {}, "a": [], "z": "last"})",
      1);
}

TEST(JsonExhaustion, CapsOnARealCaseFile) {
  // Every 7th cap, then every cap of the last step before the first success.
  exhaustion_sweep(fixture("paper_scale.json"), 7);
}

TEST(JsonExhaustion, HooksArenaGivesBackEveryBlock) {
  // The same parse over allocation hooks with small blocks and a cap: exhaustion is clean and
  // every block taken is given back.
  struct Counter {
    long live = 0;
  } counter;
  AllocatorHooks hooks;
  hooks.user = &counter;
  hooks.allocate = [](void* user, size_t bytes) -> void* {
    static_cast<Counter*>(user)->live += 1;
    return ::operator new (bytes, std::align_val_t{16});
  };
  hooks.release = [](void* user, void* p, size_t) {
    static_cast<Counter*>(user)->live -= 1;
    ::operator delete (p, std::align_val_t{16});
  };
  const std::string text = fixture("paper_scale.json");
  bool succeeded = false;
  for (size_t cap = 1024; cap <= (size_t{1} << 20) && !succeeded; cap += 1024) {
    {
      Arena arena(hooks, cap, 4096);
      JsonDocument doc;
      Status s = parse(arena, text, &doc);
      if (s.is_ok()) {
        succeeded = true;
        EXPECT_EQ(doc.root().child_count, 9u);
      } else {
        ASSERT_EQ(s.code(), StatusCode::kArenaExhausted) << format(s);
      }
    }
    ASSERT_EQ(counter.live, 0) << "cap " << cap;
  }
  EXPECT_TRUE(succeeded);
}

}  // namespace
}  // namespace splintcore
