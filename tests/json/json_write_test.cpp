// The JSON writer (json.h): exact bytes for small documents, every misuse and a failing sink
// reported by finish(), and what it writes read back by the library's own strict parser.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "splintcore/json.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::format;
using test::TestArena;

struct StringSink {
  std::string text;
  size_t fail_after = SIZE_MAX;  // bytes accepted before the sink fails
  static bool write(void* user, const uint8_t* data, size_t bytes) {
    StringSink* s = static_cast<StringSink*>(user);
    if (s->text.size() + bytes > s->fail_after) return false;
    s->text.append(reinterpret_cast<const char*>(data), bytes);
    return true;
  }
  ByteSink sink() {
    ByteSink b;
    b.write = &StringSink::write;
    b.user = this;
    b.name = "test sink";
    return b;
  }
};

TEST(JsonWriter, WritesCompactJson) {
  StringSink s;
  JsonWriter w(s.sink());
  w.begin_object();
  w.add("text", "a\"b\\c\n\x01 \xc3\xa9");
  w.add("yes", true);
  w.add("no", false);
  w.add("big", uint64_t{18446744073709551615u});
  w.add("negative", int64_t{-9223372036854775807 - 1});
  w.add("small", 3u);
  w.add("tenth", 0.1);
  w.add("third", 1.0 / 3.0);
  w.add("nan", std::numeric_limits<double>::quiet_NaN());
  w.add("inf", -std::numeric_limits<double>::infinity());
  w.add("point", Vec3{1, -0.5, 1e300});
  w.add("nothing", static_cast<const char*>(nullptr));
  w.begin_array("list");
  w.add(nullptr, 1);
  w.begin_object();
  w.end_object();
  w.begin_array();
  w.end_array();
  w.end_array();
  w.end_object();
  SPLINTCORE_ASSERT_OK(w.finish());
  EXPECT_EQ(s.text,
            "{\"text\":\"a\\\"b\\\\c\\u000a\\u0001 \xc3\xa9\",\"yes\":true,\"no\":false,"
            "\"big\":18446744073709551615,\"negative\":-9223372036854775808,\"small\":3,"
            "\"tenth\":0.1,\"third\":0.3333333333333333,\"nan\":null,\"inf\":null,"
            "\"point\":[1,-0.5,1e+300],\"nothing\":null,\"list\":[1,{},[]]}");
  // The library's strict parser reads it back, numbers to the same bits.
  TestArena ta(1 << 20);
  JsonDocument doc;
  SPLINTCORE_ASSERT_OK(
      parse_json(Context(&ta.arena), s.text.data(), s.text.size(), JsonLimits{}, "written", &doc));
  EXPECT_EQ(doc.member(doc.root(), "third")->number, 1.0 / 3.0);
  EXPECT_STREQ(doc.member(doc.root(), "text")->string, "a\"b\\c\n\x01 \xc3\xa9");
}

TEST(JsonWriter, LongOutputPassesThroughTheBuffer) {
  StringSink s;
  JsonWriter w(s.sink());
  w.begin_array();
  std::string expected = "[";
  for (int i = 0; i < 1000; ++i) {
    w.add(nullptr, int64_t{i} * 7919);
    expected += (i > 0 ? "," : "") + std::to_string(int64_t{i} * 7919);
  }
  w.end_array();
  SPLINTCORE_ASSERT_OK(w.finish());
  EXPECT_EQ(s.text, expected + "]");
}

TEST(JsonWriter, MisuseIsReportedByFinish) {
  const auto expect_error = [](void (*misuse)(JsonWriter&), const char* what) {
    StringSink s;
    JsonWriter w(s.sink());
    misuse(w);
    const Status st = w.finish();
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << what;
    EXPECT_NE(format(st).find(what), std::string::npos) << format(st);
  };
  expect_error([](JsonWriter& w) { w.begin_object(); }, "left open");
  expect_error([](JsonWriter&) {}, "nothing written");
  expect_error([](JsonWriter& w) { w.end_array(); }, "close without an open");
  expect_error([](JsonWriter& w) { w.add("k", 1); }, "key at the top level");
  expect_error(
      [](JsonWriter& w) {
        w.add(nullptr, 1);
        w.add(nullptr, 2);
      },
      "second value");
  expect_error(
      [](JsonWriter& w) {
        w.begin_object();
        w.add(nullptr, 1);
      },
      "without a key");
  expect_error(
      [](JsonWriter& w) {
        w.begin_array();
        w.add("k", 1);
      },
      "key in an array");
  expect_error(
      [](JsonWriter& w) {
        w.begin_array();
        w.end_object();
      },
      "out of order");
  expect_error(
      [](JsonWriter& w) {
        for (int i = 0; i < 65; ++i) w.begin_array();
      },
      "deeper than 64");
}

TEST(JsonWriter, FailingSinkIsAnIoError) {
  for (size_t accept : {size_t{0}, size_t{255}, size_t{256}, size_t{300}}) {
    StringSink s;
    s.fail_after = accept;
    JsonWriter w(s.sink());
    w.begin_array();
    for (int i = 0; i < 200; ++i) w.add(nullptr, "twelve bytes");
    w.end_array();
    const Status st = w.finish();
    EXPECT_EQ(st.code(), StatusCode::kIoError) << accept;
    EXPECT_NE(format(st).find("test sink"), std::string::npos);
    EXPECT_LE(s.text.size(), accept);
  }
}

}  // namespace
}  // namespace splintcore
