#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <utility>
#include <vector>

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

// Arrays of n values from `first` on, and whether one still holds them.
uint32_t* filled(Arena& arena, size_t n, uint32_t first) {
  uint32_t* a = arena.allocate_array<uint32_t>(n);
  if (a != nullptr)
    for (size_t i = 0; i < n; ++i) a[i] = first + static_cast<uint32_t>(i);
  return a;
}
bool holds(const uint32_t* a, size_t n, uint32_t first) {
  for (size_t i = 0; i < n; ++i)
    if (a[i] != first + static_cast<uint32_t>(i)) return false;
  return true;
}

TEST(ArenaMover, MovesArraysDownOverTheTemporariesInBufferMode) {
  alignas(Arena::kDefaultAlignment) unsigned char buffer[8192];
  Arena arena(buffer, sizeof(buffer));
  ASSERT_NE(arena.allocate(32), nullptr);  // below the start: kept
  const Arena::Marker start = arena.mark();
  ASSERT_NE(filled(arena, 500, 0), nullptr);  // temporaries
  uint32_t* a = filled(arena, 300, 1000);
  uint32_t* b = filled(arena, 200, 5000);
  ASSERT_NE(b, nullptr);
  uint32_t *moved_a = nullptr, *moved_b = nullptr, *absent = nullptr;
  {
    ArenaMover mover(arena, start);
    moved_a = mover.move(a, 300);
    EXPECT_EQ(mover.move(a, 0), nullptr);  // an empty array is nowhere
    moved_b = mover.move(b, 200);
    EXPECT_EQ(mover.move(absent, 7), nullptr);  // nor an absent one
  }
  EXPECT_EQ(static_cast<void*>(moved_a), static_cast<void*>(buffer + 32));
  EXPECT_TRUE(holds(moved_a, 300, 1000));
  EXPECT_EQ(moved_b, moved_a + 300);  // 1,200 bytes: a multiple of the alignment
  EXPECT_TRUE(holds(moved_b, 200, 5000));
  EXPECT_EQ(arena.used(), 32u + 2000u);  // the temporaries given back
}

// An arena of blocks: the first moved array needs a fresh block (the one below has no room,
// the cached one above is too small). Given, the arrays move; refused, both stay where they
// were, the top back above them, and nothing of either is overwritten.
TEST(ArenaMover, ArraysStayWhereTheyAreWhenTheAllocatorRefusesABlock) {
  for (const bool refuse : {false, true}) {
    SCOPED_TRACE(refuse ? "refused" : "given");
    struct Hook {
      int given = 0;
      int limit = 1 << 30;
    } hook;
    const auto allocate = [](void* user, size_t bytes) -> void* {
      auto* h = static_cast<Hook*>(user);
      return h->given++ < h->limit ? std::malloc(bytes) : nullptr;
    };
    const auto release = [](void*, void* p, size_t) { std::free(p); };
    Arena arena(AllocatorHooks{allocate, release, &hook}, 1 << 20, 4096);
    ASSERT_NE(arena.allocate(100), nullptr);  // the first block: 100 bytes kept
    const Arena::Marker start = arena.mark();
    ASSERT_NE(arena.allocate(4000), nullptr);  // a temporary: the second block (4,048 bytes)
    uint32_t* a = filled(arena, 1500, 7);      // 6,000 bytes: a third block, its own size
    uint32_t* b = filled(arena, 50, 90000);    // a fourth block
    ASSERT_NE(b, nullptr);
    const int blocks = hook.given;
    if (refuse) hook.limit = blocks;
    const size_t top = arena.used();
    uint32_t *moved_a = nullptr, *moved_b = nullptr;
    {
      ArenaMover mover(arena, start);
      moved_a = mover.move(a, 1500);
      moved_b = mover.move(b, 50);
    }
    EXPECT_EQ(hook.given, blocks + 1);  // one request for a block, given or refused
    EXPECT_TRUE(holds(moved_a, 1500, 7));
    EXPECT_TRUE(holds(moved_b, 50, 90000));
    if (refuse) {
      EXPECT_EQ(moved_a, a);
      EXPECT_EQ(moved_b, b);
      EXPECT_EQ(arena.used(), top);
      uint32_t* next = filled(arena, 10, 0);  // the next allocation lands above them
      ASSERT_NE(next, nullptr);
      EXPECT_TRUE(holds(a, 1500, 7));
      EXPECT_TRUE(holds(b, 50, 90000));
    } else {
      EXPECT_NE(moved_a, a);
      EXPECT_LT(arena.used(), top);
    }
  }
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

// The touch hook: the buffer told from its start on, in steps, before any of it is handed out;
// never past the buffer's end; the allocations exactly those of an arena without it.
struct Touches {
  std::vector<std::pair<size_t, size_t>> stretches;  // offset from the buffer's start, bytes
  const unsigned char* base = nullptr;
  static void note(void* user, void* begin, size_t bytes) {
    Touches* t = static_cast<Touches*>(user);
    t->stretches.emplace_back(static_cast<size_t>(static_cast<unsigned char*>(begin) - t->base),
                              bytes);
  }
  size_t end() const {
    return stretches.empty() ? 0 : stretches.back().first + stretches.back().second;
  }
};

TEST(Arena, TouchHookIsToldOfTheBufferAheadOfEveryAllocation) {
  constexpr size_t kCap = 10000, kStep = 1024;
  alignas(64) static unsigned char plain_buffer[kCap], touched_buffer[kCap];
  Arena plain(plain_buffer, kCap), touched(touched_buffer, kCap);
  Touches t;
  t.base = touched_buffer;
  TouchHook hook;
  hook.touch = &Touches::note;
  hook.user = &t;
  hook.step = kStep;
  touched.set_touch_hook(hook);
  EXPECT_TRUE(t.stretches.empty());  // nothing used yet
  const size_t sizes[] = {10, 1000, 3, 3000, 1, 2500, 16, 900, 5000};
  for (const size_t n : sizes) {
    unsigned char* a = static_cast<unsigned char*>(plain.allocate(n));
    unsigned char* b = static_cast<unsigned char*>(touched.allocate(n));
    ASSERT_EQ(a == nullptr, b == nullptr) << n;
    if (a != nullptr) {
      EXPECT_EQ(a - plain_buffer, b - touched_buffer) << n;
    }
    EXPECT_EQ(plain.used(), touched.used());
    EXPECT_GE(t.end(), touched.high_water()) << n;
    if (n == 1) {
      // A rewind and a smaller run under the high water tells nothing new.
      const size_t told = t.stretches.size();
      const Arena::Marker m = touched.mark();
      (void)touched.allocate(8);
      touched.rewind(m);
      EXPECT_EQ(t.stretches.size(), told);
    }
  }
  // Growing the top in place is a use too.
  void* top = touched.allocate(16);
  ASSERT_NE(top, nullptr);
  const size_t before = t.end();
  ASSERT_TRUE(touched.try_extend(top, 16, 16 + (before - touched.used()) + 100));
  EXPECT_GE(t.end(), touched.high_water());
  ASSERT_FALSE(t.stretches.empty());
  size_t at = 0;
  for (size_t i = 0; i < t.stretches.size(); ++i) {
    EXPECT_EQ(t.stretches[i].first, at) << i;  // from the start, no gap, no overlap
    at += t.stretches[i].second;
    if (at < kCap) {
      EXPECT_GE(t.stretches[i].second, kStep) << i;  // whole steps but the last
    }
  }
  EXPECT_LE(at, kCap);
  // A hook set on an arena in use is told of what is used at once.
  Arena later(plain_buffer, kCap);
  (void)later.allocate(3000);
  Touches t2;
  t2.base = plain_buffer;
  hook.user = &t2;
  later.set_touch_hook(hook);
  ASSERT_EQ(t2.stretches.size(), 1u);
  EXPECT_EQ(t2.stretches[0], std::make_pair(size_t{0}, size_t{3000}));
}

TEST(Arena, TouchHookIsNotCalledInHooksMode) {
  test::TestArena backing(size_t{1} << 20);
  AllocatorHooks h;
  h.allocate = [](void* user, size_t bytes) { return static_cast<Arena*>(user)->allocate(bytes); };
  h.release = [](void*, void*, size_t) {};
  h.user = &backing.arena;
  Arena arena(h, size_t{1} << 20, 4096);
  Touches t;
  TouchHook hook;
  hook.touch = &Touches::note;
  hook.user = &t;
  arena.set_touch_hook(hook);
  EXPECT_NE(arena.allocate(10000), nullptr);
  EXPECT_TRUE(t.stretches.empty());
}

// The pages of [from, to) (whole pages) of the mapping at p, `bytes` long, that are resident.
size_t resident_pages(void* p, uint64_t bytes, size_t from, size_t to) {
  const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
  std::vector<unsigned char> resident((bytes + page - 1) / page);
  EXPECT_EQ(::mincore(p, static_cast<size_t>(bytes), resident.data()), 0);
  size_t n = 0;
  for (size_t i = from / page; i < to / page; ++i) n += resident[i] & 1u;
  return n;
}

// The tools' hook prefaults: the pages the arena is about to hand out are resident (mincore)
// before anything is written to them, and those beyond the last stretch are not.
TEST(ArenaMemory, PrefaultHookMakesThePagesAheadResident) {
  const uint64_t bytes = uint64_t{16} << 20;
  void* p = acquire_arena_memory(bytes);
  ASSERT_NE(p, nullptr);
  const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
  const auto count = [&](size_t from, size_t to) { return resident_pages(p, bytes, from, to); };
  ASSERT_EQ(count(0, static_cast<size_t>(bytes)), 0u);
  // Is MADV_POPULATE_WRITE there (Linux 5.14 on)? Without it the hook does nothing.
#ifdef MADV_POPULATE_WRITE
  const bool populates = ::madvise(p, page, MADV_POPULATE_WRITE) == 0;
#else
  const bool populates = false;
#endif
  if (!populates) {
    release_arena_memory(p, bytes);
    GTEST_SKIP() << "no MADV_POPULATE_WRITE on this system";
  }
  Arena arena(p, static_cast<size_t>(bytes));
  arena.set_touch_hook(arena_prefault_hook());  // step: 4 MiB
  const size_t mib = size_t{1} << 20;
  ASSERT_NE(arena.allocate(5 * mib), nullptr);  // more than a step: told at once
  EXPECT_EQ(count(0, 5 * mib), 5 * mib / page);
  EXPECT_EQ(count(5 * mib, 16 * mib), 0u);
  ASSERT_NE(arena.allocate(1), nullptr);  // past it: a step more
  EXPECT_EQ(count(0, 9 * mib), 9 * mib / page);
  EXPECT_EQ(count(9 * mib, 16 * mib), 0u);
  release_arena_memory(p, bytes);
}

// The tools' toucher (two threads or more): what the arena hands out is resident when it is
// handed out, and the thread never goes past `ahead` beyond the furthest point the arena has
// reached (nor past the buffer); without memory it is the prefault hook, with no thread.
TEST(ArenaMemory, ToucherStaysAheadOfTheArenaAndNoFurther) {
  const uint64_t bytes = uint64_t{16} << 20;
  const size_t mib = size_t{1} << 20;
  EXPECT_EQ(ArenaToucher(nullptr, 0, mib).hook().touch, arena_prefault_hook().touch);
  alignas(64) static unsigned char idle[4096];  // (never written)
  for (int i = 0; i < 20; ++i) ArenaToucher started_and_stopped(idle, sizeof(idle), 1);
  void* p = acquire_arena_memory(bytes);
  ASSERT_NE(p, nullptr);
  const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
  const auto count = [&](size_t from, size_t to) { return resident_pages(p, bytes, from, to); };
  const size_t step = mib / 4;  // the hook's
  {
    ArenaToucher toucher(p, static_cast<size_t>(bytes), 2 * mib);
    Arena arena(p, static_cast<size_t>(bytes));
    ASSERT_EQ(toucher.hook().step, step);
    arena.set_touch_hook(toucher.hook());
    unsigned char* a = static_cast<unsigned char*>(arena.allocate(5 * mib));
    ASSERT_NE(a, nullptr);
    EXPECT_EQ(count(0, 5 * mib), 5 * mib / page);  // before any of it is written
    a[0] = 1;
    a[5 * mib - 1] = 2;
    ASSERT_NE(arena.allocate(1), nullptr);  // past it: a step more
    EXPECT_EQ(count(0, 5 * mib + step), (5 * mib + step) / page);
    EXPECT_EQ(a[0] + a[5 * mib - 1], 3);
  }  // the thread stopped
  // 5 MiB and a step reached, 2 MiB ahead: nothing from 7 MiB and a step on.
  EXPECT_EQ(count(7 * mib + step, 16 * mib), 0u);
  release_arena_memory(p, bytes);
  // Ahead of everything: the thread stops at the end of its bytes; an arena over more uses
  // the rest as it is (and does not wait for it).
  p = acquire_arena_memory(bytes);
  ASSERT_NE(p, nullptr);
  {
    ArenaToucher toucher(p, 2 * mib, 64 * mib);
    Arena arena(p, 3 * mib);
    arena.set_touch_hook(toucher.hook());
    EXPECT_NE(arena.allocate(3 * mib), nullptr);
    EXPECT_EQ(arena.allocate(1), nullptr);
  }
  EXPECT_EQ(count(0, 2 * mib), 2 * mib / page);
  EXPECT_EQ(count(2 * mib, 16 * mib), 0u);
  release_arena_memory(p, bytes);
}

#if defined(SPLINTCORE_TEST_ASAN)
// Under AddressSanitizer the alignment gap before an allocation is poisoned, so that an array
// overrun by an element into it is reported: in buffer and in hooks mode; a rewind unpoisons
// what it frees (rewound bytes stay readable) and the end of a buffer arena the whole buffer.
TEST(ArenaPoison, TheGapBeforeAnAllocationIsPoisonedUntilItIsFreed) {
  HookCounts counts;
  AllocatorHooks hooks{counting_allocate, counting_release, &counts};
  alignas(Arena::kDefaultAlignment) static unsigned char buffer[4096];
  for (int mode = 0; mode < 2; ++mode) {
    SCOPED_TRACE(mode);
    std::unique_ptr<Arena> owned(mode == 0 ? new Arena(buffer, sizeof buffer)
                                           : new Arena(hooks, 64 * 1024, 4096));
    Arena& arena = *owned;
    uint32_t* three = arena.allocate_array<uint32_t>(3);  // 12 bytes, a 4-byte gap after it
    ASSERT_NE(three, nullptr);
    const Arena::Marker after_three = arena.mark();
    uint8_t* next = arena.allocate_array<uint8_t>(5);
    ASSERT_EQ(next, reinterpret_cast<uint8_t*>(three) + 16);
    EXPECT_FALSE(__asan_address_is_poisoned(three + 2));
    EXPECT_TRUE(__asan_address_is_poisoned(three + 3));  // one element past the end
    EXPECT_FALSE(__asan_address_is_poisoned(next));
    EXPECT_FALSE(__asan_address_is_poisoned(next + 5));  // above the top: not poisoned
    uint64_t* wide = arena.allocate_array<uint64_t>(1);  // 11 bytes of gap after next
    ASSERT_EQ(reinterpret_cast<uint8_t*>(wide), next + 16);
    EXPECT_TRUE(__asan_address_is_poisoned(next + 5));
    EXPECT_TRUE(__asan_address_is_poisoned(next + 15));
    arena.rewind(after_three);
    EXPECT_FALSE(__asan_address_is_poisoned(three + 3));
    EXPECT_FALSE(__asan_address_is_poisoned(next + 5));
    EXPECT_FALSE(__asan_address_is_poisoned(next + 15));
    // Again, then the arena ends: its caller's buffer is left unpoisoned.
    ASSERT_EQ(arena.allocate_array<uint8_t>(5), next);
    ASSERT_NE(arena.allocate_array<uint64_t>(1), nullptr);
    EXPECT_TRUE(__asan_address_is_poisoned(next + 5));
    owned.reset();
    if (mode == 0) EXPECT_FALSE(__asan_address_is_poisoned(next + 5));  // (the buffer)
  }
  EXPECT_EQ(counts.live_bytes, 0u);
}
#endif

}  // namespace
}  // namespace splintcore
