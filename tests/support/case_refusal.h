// A case file that parse_case must refuse (the case tests share it).
#ifndef SPLINTCORE_TESTS_SUPPORT_CASE_REFUSAL_H
#define SPLINTCORE_TESTS_SUPPORT_CASE_REFUSAL_H

#include <gtest/gtest.h>

#include <string>

#include "splintcore/design.h"
#include "support/test_util.h"

namespace splintcore {
namespace test {

// `text` refused with `code` and a message holding `fragment`, naming the file (and, when
// `located`, the line and column of the value); the arena as it was and the CaseFile empty.
inline void expect_case_refused(const std::string& text, StatusCode code, const char* fragment,
                                bool located = false) {
  TestArena t(size_t{1} << 20);
  ASSERT_NE(t.arena.allocate(16), nullptr);
  const size_t used = t.arena.used();
  CaseFile out;
  Status s = parse_case(Context(&t.arena), text.data(), text.size(), "case.json", &out);
  EXPECT_EQ(s.code(), code) << format(s) << "\n" << text;
  EXPECT_NE(std::string(s.message()).find(fragment), std::string::npos) << s.message() << "\n"
                                                                        << text;
  EXPECT_STREQ(s.file(), "case.json");
  if (located) {
    EXPECT_GT(s.line(), 0u);
    EXPECT_GT(s.column(), 0u);
  }
  EXPECT_EQ(t.arena.used(), used) << "a failed parse left memory in the arena";
  EXPECT_TRUE(out.jaws.empty() && out.upper.empty() && out.lower.empty());
  EXPECT_EQ(out.version, 0u);
  EXPECT_FALSE(out.has_plan);
}

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_SUPPORT_CASE_REFUSAL_H
