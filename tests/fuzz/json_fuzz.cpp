// libFuzzer target: arbitrary bytes through the strict JSON parser with the default limits
// (JsonLimits{}), under a small arena. Any crash or sanitizer report is a bug; so is a parsed
// document whose tree is inconsistent (a child index out of range, counts that disagree, a
// string whose stated length is not its NUL position for key lookups).
//   build/fuzz/tests/splintcore_fuzz_json -max_total_time=60 fixtures/fuzz/json
#include <cstdlib>
#include <cstring>

#include "splintcore/json.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace splintcore;
  static unsigned char memory[16 << 20];
  Arena arena(memory, sizeof(memory));
  Context ctx(&arena);
  JsonDocument doc;
  Status s = parse_json(ctx, reinterpret_cast<const char*>(data), size, JsonLimits{}, "fuzz", &doc);
  if (!s.is_ok()) {
    if (s.code() == StatusCode::kOk || s.message()[0] == '\0') std::abort();  // an error says what
    return 0;
  }
  const size_t n = doc.values.size();
  if (n == 0) std::abort();
  // Walk the tree without recursion: every child in range, child_count agrees, members keyed.
  for (size_t i = 0; i < n; ++i) {
    const JsonValue& v = doc.values[i];
    uint32_t count = 0;
    for (uint32_t k = v.first_child; k != kJsonNone; k = doc.at(k).next_sibling) {
      if (k <= i || k >= n) std::abort();
      if (v.type == JsonType::kObject && doc.at(k).key == nullptr) std::abort();
      if (++count > n) std::abort();
    }
    if (count != v.child_count) std::abort();
    if (v.type == JsonType::kString && v.string == nullptr) std::abort();
    if (v.type == JsonType::kObject) {
      for (uint32_t k = v.first_child; k != kJsonNone; k = doc.at(k).next_sibling) {
        // member() finds the first member with a key (no duplicates are allowed).
        const JsonValue* m = doc.member(v, doc.at(k).key);
        if (m == nullptr) std::abort();
      }
    }
  }
  char text[512];
  (void)json_error(doc, doc.root(), StatusCode::kInvalidArgument, "fuzz")
      .format(text, sizeof(text));
  return 0;
}
