#include <algorithm>
#include <random>

#include "support/test_util.h"

namespace splintcore {
namespace {

TEST(RadixSort, MatchesStableSortOnRandomKeys) {
  std::mt19937_64 rng(42);
  for (int round = 0; round < 20; ++round) {
    size_t n = static_cast<size_t>(rng() % 5000);
    int bits = static_cast<int>(rng() % 64) + 1;
    std::vector<KeyIndex> items(n);
    for (size_t i = 0; i < n; ++i) {
      uint64_t key = bits == 64 ? rng() : rng() & ((uint64_t{1} << bits) - 1);
      items[i] = KeyIndex{key, static_cast<uint32_t>(i), 0};
    }
    std::vector<KeyIndex> expected = items;
    std::stable_sort(expected.begin(), expected.end(),
                     [](const KeyIndex& a, const KeyIndex& b) { return a.key < b.key; });
    std::vector<KeyIndex> scratch(n);
    radix_sort(Span<KeyIndex>(items.data(), n), Span<KeyIndex>(scratch.data(), n));
    for (size_t i = 0; i < n; ++i) {
      ASSERT_EQ(items[i].key, expected[i].key);
      ASSERT_EQ(items[i].index, expected[i].index);  // stable: equal keys keep input order
    }
  }
}

TEST(RadixSort, PlainKeysMatchStdSort) {
  std::mt19937_64 rng(43);
  for (int round = 0; round < 20; ++round) {
    const size_t n = static_cast<size_t>(rng() % 5000);
    const int bits = static_cast<int>(rng() % 64) + 1;
    std::vector<uint64_t> items(n);
    for (uint64_t& k : items) k = bits == 64 ? rng() : rng() & ((uint64_t{1} << bits) - 1);
    std::vector<uint64_t> expected = items;
    std::sort(expected.begin(), expected.end());
    std::vector<uint64_t> scratch(n);
    radix_sort(Span<uint64_t>(items.data(), n), Span<uint64_t>(scratch.data(), n));
    ASSERT_EQ(items, expected);
  }
}

TEST(RadixSort, ArenaVariantReportsExhaustion) {
  std::vector<KeyIndex> items(100, KeyIndex{1, 0, 0});
  unsigned char buffer[64];
  Arena arena(buffer, sizeof(buffer));
  Status s = radix_sort(arena, Span<KeyIndex>(items.data(), items.size()));
  EXPECT_EQ(s.code(), StatusCode::kArenaExhausted);
  EXPECT_EQ(arena.used(), 0u);
}

}  // namespace
}  // namespace splintcore
