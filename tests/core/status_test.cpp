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

}  // namespace
}  // namespace splintcore
