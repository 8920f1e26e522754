#include "splintcore/splintcore.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

TEST(Status, DefaultIsOk) {
  Status s;
  EXPECT_TRUE(s.is_ok());
  EXPECT_STREQ(s.message(), "");
  EXPECT_STREQ(status_code_name(s.code()), "ok");
}

TEST(Status, MakeErrorJoinsPartsWithoutPrintf) {
  Status s = make_error(StatusCode::kParseError, "need ", uint64_t{12}, " got ", -3, " at ", 0.5,
                        " or ", 1e-7);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_STREQ(s.message(), "need 12 got -3 at 0.5 or 1e-07");
}

TEST(Status, FormatPutsLocationFirst) {
  Status s = make_error(StatusCode::kParseError, "expected 'vertex'");
  s.in_file("case.stl").at_line(7, 3);
  char out[256];
  s.format(out, sizeof(out));
  EXPECT_STREQ(out, "case.stl:7:3: expected 'vertex'");
  Status b = make_error(StatusCode::kTruncated, "ends early").at_byte(684).at_index(12);
  b.format(out, sizeof(out));
  EXPECT_STREQ(out, "byte 684: ends early");
  EXPECT_EQ(b.index(), 12u);
}

TEST(Status, LongMessagesAreTruncatedSafely) {
  Status s = Status::error(StatusCode::kInternal, "");
  std::string big(1000, 'x');
  s.append(big.c_str());
  EXPECT_EQ(std::strlen(s.message()), Status::kMessageCapacity - 1);
  char small[8];
  size_t n = s.format(small, sizeof(small));
  EXPECT_EQ(std::strlen(small), 7u);
  EXPECT_GT(n, 7u);
  std::string long_path(300, 'p');
  long_path += "/jaw.stl";
  s.in_file(long_path.c_str());
  EXPECT_EQ(std::strlen(s.file()), Status::kFileCapacity - 1);
  EXPECT_NE(std::strstr(s.file(), "jaw.stl"), nullptr);  // the end of the path is kept
}

TEST(Status, CancelledByProgressCallback) {
  test::TestArena t(1024);
  int calls = 0;
  Progress p;
  p.user = &calls;
  p.report = [](void* user, const char*, uint64_t, uint64_t) {
    return ++*static_cast<int*>(user) < 2;
  };
  Context ctx(&t.arena, nullptr, &p);
  EXPECT_TRUE(report_progress(ctx, "stage", 0, 1).is_ok());
  Status s = report_progress(ctx, "stage", 1, 1);
  EXPECT_EQ(s.code(), StatusCode::kCancelled);
  EXPECT_NE(std::strstr(s.message(), "stage"), nullptr);
}

// Without a file the position reads "line L, column C: " (a case text or JSON given as bytes);
// a line without a column, "line L: ".
TEST(Status, FormatWithoutAFileNamesTheLineAndColumn) {
  char out[256];
  Status s = make_error(StatusCode::kParseError, "expected ','");
  s.at_line(12, 5);
  s.format(out, sizeof(out));
  EXPECT_STREQ(out, "line 12, column 5: expected ','");
  s.at_line(12);
  s.format(out, sizeof(out));
  EXPECT_STREQ(out, "line 12: expected ','");
  s.in_file("case.json");
  s.format(out, sizeof(out));
  EXPECT_STREQ(out, "case.json:12: expected ','");
  Status b = make_error(StatusCode::kTruncated, "ends early").at_byte(9);
  b.at_line(3, 4);
  b.format(out, sizeof(out));
  EXPECT_STREQ(out, "line 3, column 4: byte 9: ends early");
}

// The codes' names are part of the outputs (report.json's "error", the C API's and the tools'
// messages): one distinct, fixed name each, and "unknown" for a value outside the enum.
TEST(Status, EveryCodeHasItsFixedName) {
  const std::pair<StatusCode, const char*> names[] = {
      {StatusCode::kOk, "ok"},
      {StatusCode::kInvalidArgument, "invalid_argument"},
      {StatusCode::kArenaExhausted, "arena_exhausted"},
      {StatusCode::kParseError, "parse_error"},
      {StatusCode::kTruncated, "truncated"},
      {StatusCode::kNonFinite, "non_finite"},
      {StatusCode::kLimitExceeded, "limit_exceeded"},
      {StatusCode::kIoError, "io_error"},
      {StatusCode::kInvalidMesh, "invalid_mesh"},
      {StatusCode::kCancelled, "cancelled"},
      {StatusCode::kUnsupported, "unsupported"},
      {StatusCode::kInternal, "internal"}};
  for (const auto& [code, name] : names) {
    EXPECT_STREQ(status_code_name(code), name) << static_cast<int>(code);
  }
  // The enum's values are 0..11 in this order: the next one is not a code.
  EXPECT_EQ(static_cast<int>(StatusCode::kInternal), 11);
  EXPECT_STREQ(status_code_name(static_cast<StatusCode>(12)), "unknown");
}

// A failed SPLINTCORE_ASSERT ends the process after telling the handler: the default one
// prints the expression and where it is; an embedder's handler is called instead (and the
// process still ends: the core never continues past a broken invariant); nullptr restores the
// default.
TEST(StatusDeathTest, AFailedAssertionTellsTheHandlerThenAborts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(assert_failed("count <= cap", "src/core/arena.cpp", 42),
               "splintcore: assertion failed: count <= cap \\(src/core/arena.cpp:42\\)");
  EXPECT_DEATH(
      {
        set_assert_handler([](const char* expression, const char* file, int line) {
          std::fprintf(stderr, "embedder saw %s at %s line %d\n", expression, file, line);
        });
        SPLINTCORE_ASSERT(1 + 1 == 3);
      },
      "embedder saw 1 \\+ 1 == 3 at .*status_test.cpp line [0-9]+");
  EXPECT_DEATH(
      {
        set_assert_handler([](const char*, const char*, int) { std::fputs("first\n", stderr); });
        set_assert_handler(nullptr);
        assert_failed("x", "y.cpp", 7);
      },
      "splintcore: assertion failed: x \\(y.cpp:7\\)");
  // The C API's setter (splintcore.h) installs the same handler.
  EXPECT_DEATH(
      {
        sc_set_assert_handler([](const char* expression, const char* file, int line) {
          std::fprintf(stderr, "C embedder saw %s at %s:%d\n", expression, file, line);
        });
        assert_failed("n != nullptr", "src/capi/capi.cpp", 201);
      },
      "C embedder saw n != nullptr at src/capi/capi.cpp:201");
}

}  // namespace
}  // namespace splintcore
