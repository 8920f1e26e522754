#include <cstdint>
#include <cstdlib>

#include "splintcore/platform.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

TEST(Arena, AllocatesAlignedWithinCapAndTracksHighWater) {
  alignas(64) unsigned char buffer[1024];
  Arena arena(buffer, sizeof(buffer));
  EXPECT_EQ(arena.cap(), 1024u);
  void* a = arena.allocate(3, 1);
  void* b = arena.allocate(8, 64);
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(b) % 64, 0u);
  EXPECT_EQ(arena.used(), 72u);
  EXPECT_EQ(arena.high_water(), 72u);
  Arena::Marker m = arena.mark();
  ASSERT_NE(arena.allocate(500, 16), nullptr);
  EXPECT_GE(arena.high_water(), 572u);
  arena.rewind(m);
  EXPECT_EQ(arena.used(), 72u);
  EXPECT_GE(arena.high_water(), 572u);  // the peak is remembered
  // Exactly the remaining bytes fit; one more does not.
  size_t left = 1024 - arena.used();
  Arena::Marker m2 = arena.mark();
  EXPECT_NE(arena.allocate(left, 1), nullptr);
  arena.rewind(m2);
  EXPECT_EQ(arena.allocate(left + 1, 1), nullptr);
  EXPECT_EQ(arena.last_need(), 1025u);
}

TEST(Arena, ExhaustedStatusNamesNeedAndCap) {
  unsigned char buffer[100];
  Arena arena(buffer, sizeof(buffer));
  EXPECT_EQ(arena.allocate(150, 1), nullptr);
  Status s = arena.exhausted_status();
  EXPECT_EQ(s.code(), StatusCode::kArenaExhausted);
  EXPECT_STREQ(s.message(),
               "arena exhausted: need 150 bytes, cap 100; increase the memory cap to at least "
               "150 bytes");
}

TEST(Arena, FailedRequestsInARowAddUpUntilASuccessOrRewind) {
  alignas(16) unsigned char buffer[256];
  Arena arena(buffer, sizeof(buffer));
  ASSERT_NE(arena.allocate(100, 16), nullptr);
  Arena::Marker m = arena.mark();
  EXPECT_EQ(arena.allocate(200, 16), nullptr);  // needs 112 + 200
  EXPECT_EQ(arena.last_need(), 312u);
  EXPECT_NE(arena.allocate(48, 16), nullptr);  // fits: a success starts a new count
  arena.rewind(m);
  EXPECT_EQ(arena.allocate(300, 16), nullptr);
  EXPECT_EQ(arena.last_need(), 112u + 300u);
  EXPECT_EQ(arena.allocate(400, 16), nullptr);
  // Both are needed (alignment padding may be counted once more: an upper bound).
  EXPECT_GE(arena.last_need(), 112u + 300u + 400u);
  EXPECT_LE(arena.last_need(), 112u + 300u + 400u + 32u);
  arena.rewind(m);
  EXPECT_EQ(arena.allocate(500, 16), nullptr);
  EXPECT_EQ(arena.last_need(), 112u + 500u);  // a rewind starts over
}

TEST(Arena, ZeroCapArenaFailsCleanly) {
  Arena arena(nullptr, 0);
  EXPECT_EQ(arena.allocate(1, 1), nullptr);
  EXPECT_EQ(arena.exhausted_status().code(), StatusCode::kArenaExhausted);
  // Overflowing size: 2^62 * 8 overflows 64 bits; on 32-bit targets 2^30 * 8 exceeds SIZE_MAX.
  EXPECT_EQ(arena.allocate_array<double>(SIZE_MAX / 4 + 1), nullptr);
}

TEST(Arena, ScopeRewinds) {
  // Aligned as the arena aligns (16): a plain char array is only 8-aligned on 32-bit ARM, and
  // the padding would count in used().
  alignas(Arena::kDefaultAlignment) unsigned char buffer[256];
  Arena arena(buffer, sizeof(buffer));
  ASSERT_NE(arena.allocate(16), nullptr);
  {
    ArenaScope scope(arena);
    ASSERT_NE(arena.allocate(100), nullptr);
    EXPECT_GE(arena.used(), 116u);
  }
  EXPECT_EQ(arena.used(), 16u);
}

TEST(Arena, ExtendGrowsOnlyTheTopAllocation) {
  alignas(16) unsigned char buffer[256];
  Arena arena(buffer, sizeof(buffer));
  void* a = arena.allocate(16);
  EXPECT_TRUE(arena.try_extend(a, 16, 64));
  EXPECT_EQ(arena.used(), 64u);
  void* b = arena.allocate(16);
  ASSERT_NE(b, nullptr);
  EXPECT_FALSE(arena.try_extend(a, 64, 80));       // a is no longer on top
  EXPECT_TRUE(arena.try_extend(b, 16, 256 - 64));  // exactly to the end of the buffer
  EXPECT_EQ(arena.used(), 256u);
  EXPECT_FALSE(arena.try_extend(b, 256 - 64, 256 - 63));
  EXPECT_EQ(arena.last_need(), 0u);  // an attempt to extend is not a failure
}

struct HookCounts {
  int allocations = 0;
  int releases = 0;
  size_t live_bytes = 0;
};
void* counting_allocate(void* user, size_t bytes) {
  auto* c = static_cast<HookCounts*>(user);
  ++c->allocations;
  c->live_bytes += bytes;
  return std::malloc(bytes);
}
void counting_release(void* user, void* p, size_t bytes) {
  auto* c = static_cast<HookCounts*>(user);
  ++c->releases;
  c->live_bytes -= bytes;
  std::free(p);
}

TEST(Arena, HooksModeTakesBlocksUnderTheCapAndReleasesThem) {
  HookCounts counts;
  AllocatorHooks hooks{counting_allocate, counting_release, &counts};
  {
    // Growth by copying leaves dead copies below (a stack arena never frees in the middle):
    // 24 KB of values need about 3 x 24 KB of blocks.
    Arena arena(hooks, 256 * 1024, 4096);
    ArenaArray<uint64_t> values(&arena);
    for (uint64_t i = 0; i < 3000; ++i) ASSERT_TRUE(values.push_back(i));
    for (uint64_t i = 0; i < 3000; ++i) ASSERT_EQ(values[i], i);
    EXPECT_LE(arena.reserved(), 256u * 1024u);
    EXPECT_GT(counts.allocations, 1);
    // Past the cap: a clean failure naming the need.
    EXPECT_EQ(arena.allocate(250 * 1024), nullptr);
    EXPECT_GT(arena.last_need(), 256u * 1024u);
    Arena::Marker m = arena.mark();
    ASSERT_NE(arena.allocate(10000), nullptr);
    arena.rewind(m);
    ASSERT_NE(arena.allocate(9000), nullptr);  // reuses the cached block
  }
  EXPECT_EQ(counts.allocations, counts.releases);
  EXPECT_EQ(counts.live_bytes, 0u);
}

TEST(ArenaArray, GrowsInPlaceAtTopAndCopiesOtherwise) {
  test::TestArena t(1 << 20);
  ArenaArray<int> a(&t.arena);
  for (int i = 0; i < 1000; ++i) ASSERT_TRUE(a.push_back(i));
  const int* before = a.data();
  ASSERT_TRUE(a.reserve(5000));
  EXPECT_EQ(a.data(), before);  // extended in place
  ArenaArray<int> b(&t.arena);
  ASSERT_TRUE(b.push_back(7));
  ASSERT_TRUE(a.reserve(20000));
  EXPECT_NE(a.data(), before);  // b sits on top now: a had to move
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(a[static_cast<size_t>(i)], i);
  ASSERT_TRUE(a.resize(1005));
  EXPECT_EQ(a[1004], 0);  // new elements are zeroed
}

TEST(ArenaArray, UsesTheCapToTheLastElementBeforeFailing) {
  alignas(16) unsigned char buffer[4096];
  Arena arena(buffer, sizeof(buffer));
  ArenaArray<uint32_t> a(&arena);
  size_t n = 0;
  while (a.push_back(static_cast<uint32_t>(n))) ++n;
  EXPECT_EQ(n, 1024u);  // growth falls back to the exact size when doubling does not fit
  EXPECT_EQ(arena.exhausted_status().code(), StatusCode::kArenaExhausted);
}

// A tool's arena memory (the hosted layer): 2 MiB aligned, every byte of the size asked for
// writable, given back by size; nothing for zero bytes or a size that cannot be mapped.
TEST(ArenaMemory, MappedAlignedWritableAndGivenBack) {
  for (uint64_t bytes : {uint64_t{1}, uint64_t{5} << 20, (uint64_t{6} << 20) + 1}) {
    void* p = acquire_arena_memory(bytes);
    ASSERT_NE(p, nullptr) << bytes;
    EXPECT_EQ(reinterpret_cast<uintptr_t>(p) % (uintptr_t{2} << 20), 0u) << bytes;
    unsigned char* b = static_cast<unsigned char*>(p);
    b[0] = 1;
    b[bytes - 1] = 2;
    Arena arena(p, static_cast<size_t>(bytes));
    EXPECT_NE(arena.allocate(static_cast<size_t>(bytes), 1), nullptr);
    release_arena_memory(p, bytes);
  }
  EXPECT_EQ(acquire_arena_memory(0), nullptr);
  EXPECT_EQ(acquire_arena_memory(UINT64_MAX), nullptr);
  release_arena_memory(nullptr, 1);  // nothing to give back
}

}  // namespace
}  // namespace splintcore
