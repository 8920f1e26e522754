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

// radix_sort_bits: a stable sort by a bit range alone. Small arrays take the LSD passes, large
// ones with a wide range (n >= 65536, at least 28 bits) the top-digit pass first; both must
// equal std::stable_sort by the range's value, with bits outside the range left random so
// that only stability decides their order.
TEST(RadixSort, BitRangeMatchesStableSortByThoseBits) {
  std::mt19937_64 rng(44);
  struct Case {
    size_t n;
    unsigned lo, hi;
    unsigned used;  // random bits in the range, from its bottom (few: many equal keys)
  };
  const Case cases[] = {
      {0, 0, 64, 64},      {1, 3, 9, 6},         {2, 0, 1, 1},         {1000, 20, 62, 42},
      {5000, 0, 64, 64},   {5000, 7, 19, 5},     {70000, 20, 62, 42},  {70000, 20, 62, 30},
      {70000, 0, 64, 64},  {100000, 17, 45, 28}, {100000, 17, 44, 27}, {100000, 32, 64, 3},
      {131072, 1, 64, 63}, {66000, 30, 63, 33},
  };
  for (const Case& c : cases) {
    std::vector<uint64_t> items(c.n);
    const uint64_t range_mask =
        (c.hi - c.lo == 64 ? ~uint64_t{0} : ((uint64_t{1} << (c.hi - c.lo)) - 1)) << c.lo;
    const uint64_t used_mask = (c.used == 64 ? ~uint64_t{0} : ((uint64_t{1} << c.used) - 1))
                               << c.lo;
    for (uint64_t& k : items) {
      const uint64_t r = rng();
      k = (rng() & ~range_mask) | (r & used_mask);
    }
    std::vector<uint64_t> expected = items;
    std::stable_sort(expected.begin(), expected.end(),
                     [&](uint64_t a, uint64_t b) { return (a & range_mask) < (b & range_mask); });
    std::vector<uint64_t> scratch(c.n);
    radix_sort_bits(Span<uint64_t>(items.data(), c.n), Span<uint64_t>(scratch.data(), c.n), c.lo,
                    c.hi);
    ASSERT_EQ(items, expected) << "n " << c.n << ", bits " << c.lo << ".." << c.hi;
  }
}

// The index build's use: ids rising under a code sort as the whole key would.
TEST(RadixSort, BitRangeOverCodesGivesTheWholeKeyOrder) {
  std::mt19937_64 rng(45);
  const size_t n = 200000;
  const unsigned id_bits = 18;
  std::vector<uint64_t> items(n);
  for (size_t i = 0; i < n; ++i) {
    const uint64_t code = rng() % 50000;  // many ties
    items[i] = (code << id_bits) | (i & ((uint64_t{1} << id_bits) - 1));
  }
  // Ids must rise in input order: keep the first 2^18 only.
  items.resize(size_t{1} << 17);
  std::vector<uint64_t> expected = items;
  std::sort(expected.begin(), expected.end());
  std::vector<uint64_t> scratch(items.size());
  radix_sort_bits(Span<uint64_t>(items.data(), items.size()),
                  Span<uint64_t>(scratch.data(), scratch.size()), id_bits, 64);
  EXPECT_EQ(items, expected);
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
