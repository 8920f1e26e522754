// The core never touches the heap: this binary replaces the global allocator (operator new and
// delete in every form, and the malloc family, all forwarding to glibc's __libc_* entry points)
// with versions that count calls while a flag is on, then runs reading, checking, welding,
// sorting, hashing and writing with the flag on and expects zero. A positive control shows the
// counter does see allocations. Its own binary (and main) because replacing the allocator is
// global; not built with sanitizers, which replace the allocator themselves.

#include <gtest/gtest.h>

#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "common/shapes.h"
#include "splintcore/core.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "support/test_util.h"

// ---- the counting allocator -------------------------------------------------------------------

extern "C" {
void* __libc_malloc(size_t size);
void* __libc_calloc(size_t count, size_t size);
void* __libc_realloc(void* pointer, size_t size);
void __libc_free(void* pointer);
void* __libc_memalign(size_t alignment, size_t size);
}

namespace {

std::atomic<bool> g_counting{false};
std::atomic<uint64_t> g_allocations{0};
std::atomic<uint64_t> g_frees{0};

inline void note_allocation() {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
}

inline void note_free(void* pointer) {
  if (pointer != nullptr && g_counting.load(std::memory_order_relaxed)) {
    g_frees.fetch_add(1, std::memory_order_relaxed);
  }
}

void* counted_malloc(size_t size) {
  note_allocation();
  return __libc_malloc(size);
}

void* counted_aligned(size_t alignment, size_t size) {
  note_allocation();
  if (alignment < sizeof(void*)) alignment = sizeof(void*);
  return __libc_memalign(alignment, size);
}

void counted_free(void* pointer) {
  note_free(pointer);
  __libc_free(pointer);
}

void* new_or_throw(size_t size) {
  if (size == 0) size = 1;
  void* p = counted_malloc(size);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}

void* aligned_new_or_throw(size_t size, std::align_val_t alignment) {
  if (size == 0) size = 1;
  void* p = counted_aligned(static_cast<size_t>(alignment), size);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}

}  // namespace

extern "C" {
void* malloc(size_t size) noexcept { return counted_malloc(size); }
void* calloc(size_t count, size_t size) noexcept {
  note_allocation();
  return __libc_calloc(count, size);
}
void* realloc(void* pointer, size_t size) noexcept {
  note_allocation();
  return __libc_realloc(pointer, size);
}
void free(void* pointer) noexcept { counted_free(pointer); }
void* aligned_alloc(size_t alignment, size_t size) noexcept {
  return counted_aligned(alignment, size);
}
void* memalign(size_t alignment, size_t size) noexcept { return counted_aligned(alignment, size); }
int posix_memalign(void** out, size_t alignment, size_t size) noexcept {
  if (alignment < sizeof(void*) || (alignment & (alignment - 1)) != 0) return EINVAL;
  void* p = counted_aligned(alignment, size);
  if (p == nullptr) return ENOMEM;
  *out = p;
  return 0;
}
}

void* operator new(size_t size) { return new_or_throw(size); }
void* operator new[](size_t size) { return new_or_throw(size); }
void* operator new(size_t size, const std::nothrow_t&) noexcept {
  return counted_malloc(size == 0 ? 1 : size);
}
void* operator new[](size_t size, const std::nothrow_t&) noexcept {
  return counted_malloc(size == 0 ? 1 : size);
}
void* operator new(size_t size, std::align_val_t alignment) {
  return aligned_new_or_throw(size, alignment);
}
void* operator new[](size_t size, std::align_val_t alignment) {
  return aligned_new_or_throw(size, alignment);
}
void* operator new(size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  return counted_aligned(static_cast<size_t>(alignment), size == 0 ? 1 : size);
}
void* operator new[](size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  return counted_aligned(static_cast<size_t>(alignment), size == 0 ? 1 : size);
}
void operator delete(void* p) noexcept { counted_free(p); }
void operator delete[](void* p) noexcept { counted_free(p); }
void operator delete(void* p, size_t) noexcept { counted_free(p); }
void operator delete[](void* p, size_t) noexcept { counted_free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { counted_free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { counted_free(p); }
void operator delete(void* p, std::align_val_t) noexcept { counted_free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { counted_free(p); }
void operator delete(void* p, size_t, std::align_val_t) noexcept { counted_free(p); }
void operator delete[](void* p, size_t, std::align_val_t) noexcept { counted_free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { counted_free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  counted_free(p);
}

// ---- the tests --------------------------------------------------------------------------------

namespace {

using splintcore::Arena;
using splintcore::ArenaArray;
using splintcore::Context;
using splintcore::KeyIndex;
using splintcore::MemorySink;
using splintcore::MemorySource;
using splintcore::Mesh;
using splintcore::MeshReport;
using splintcore::SoupTriangle;
using splintcore::Span;
using splintcore::Status;
using splintcore::StatusCode;
using splintcore::StlFormat;
using splintcore::StlReadOptions;
using splintcore::StlWriteOptions;

// Counts what happens between start() and stop(). Nothing between may use gtest macros (they
// may allocate): record results in plain variables and assert after stop().
struct Counting {
  uint64_t allocations = 0;
  uint64_t frees = 0;
  void start() {
    g_allocations.store(0);
    g_frees.store(0);
    g_counting.store(true);
  }
  void stop() {
    g_counting.store(false);
    allocations = g_allocations.load();
    frees = g_frees.load();
  }
};

struct Data {
  std::vector<SoupTriangle> soup;
  std::vector<uint8_t> binary;
  std::vector<uint8_t> ascii;
  std::vector<uint8_t> truncated;
};

Data make_data() {
  Data d;
  d.soup = splintcore::shapes::torus(24, 16, 10, 3);
  d.binary = splintcore::test::binary_stl(d.soup, "alloc test");
  splintcore::test::TestArena arena(size_t{16} << 20);
  Mesh mesh;
  Status s = splintcore::test::mesh_from_bytes(arena.arena, d.binary, &mesh);
  EXPECT_TRUE(s.is_ok());
  s = splintcore::test::mesh_to_bytes(arena.arena, mesh, StlFormat::kAscii, &d.ascii);
  EXPECT_TRUE(s.is_ok());
  d.truncated.assign(d.ascii.begin(),
                     d.ascii.begin() + static_cast<std::ptrdiff_t>(d.ascii.size() / 2));
  return d;
}

void* volatile g_escape = nullptr;
int* volatile g_escape_int = nullptr;
char* volatile g_escape_text = nullptr;

TEST(AllocFreeTest, CounterSeesAllocations) {
  // Positive control: the replacement is in use and counts.
  Counting c;
  std::vector<int> v;
  // The pointers escape through volatile globals: otherwise -O2 may elide malloc/free and
  // new/delete pairs altogether (which is allowed) and the control would count nothing.
  c.start();
  v.push_back(1);
  g_escape = std::malloc(24);
  std::free(g_escape);
  g_escape_int = new int(3);
  delete g_escape_int;
  c.stop();
  EXPECT_GE(c.allocations, 3u);
  EXPECT_GE(c.frees, 2u);
  EXPECT_EQ(v.size(), 1u);
  // Allocations made inside shared libraries reach the replacement too (strdup is in libc).
  c.start();
  g_escape_text = strdup("splintcore");
  std::free(g_escape_text);
  c.stop();
  EXPECT_EQ(c.allocations, 1u);
  EXPECT_EQ(c.frees, 1u);
  // And nothing is counted while off.
  c.start();
  c.stop();
  EXPECT_EQ(c.allocations, 0u);
}

TEST(AllocFreeTest, CoreCallsDoNotAllocate) {
  const Data d = make_data();
  ASSERT_FALSE(d.ascii.empty());
  // Everything the core will touch is set up before counting starts.
  std::vector<unsigned char> memory(size_t{32} << 20);
  Arena arena(memory.data(), memory.size());
  Context ctx(&arena);
  std::vector<uint8_t> binary_out(d.binary.size() + 4096);
  std::vector<uint8_t> ascii_out(d.ascii.size() + 4096);
  std::vector<KeyIndex> items(5000);
  std::vector<KeyIndex> scratch(items.size());
  for (size_t i = 0; i < items.size(); ++i) {
    items[i] = KeyIndex{splintcore::hash_mix(i % 777), static_cast<uint32_t>(i), 0};
  }
  Status results[16];
  MeshReport report;
  splintcore::StlInfo binary_info;
  splintcore::StlInfo ascii_info;
  uint8_t digest[32] = {};
  char hex[65] = {};
  char formatted[512] = {};
  size_t binary_written = 0;
  size_t ascii_written = 0;
  size_t tolerance_vertices = 0;
  size_t soup_triangles = 0;

  Counting c;
  c.start();
  {
    MemorySource bin_src{d.binary.data(), d.binary.size(), 0, 0};
    Mesh mesh;
    results[0] = splintcore::read_stl_mesh(ctx, splintcore::memory_source(&bin_src, "a.stl"),
                                           StlReadOptions{}, &mesh, &binary_info);
    results[1] = splintcore::check_mesh(ctx, mesh, &report);
    MemorySink bin_sink{binary_out.data(), binary_out.size(), 0, 0};
    StlWriteOptions wb;
    wb.format = StlFormat::kBinary;
    results[2] = splintcore::write_stl(ctx, mesh, splintcore::memory_sink(&bin_sink), wb);
    binary_written = static_cast<size_t>(bin_sink.size);
    MemorySink ascii_sink{ascii_out.data(), ascii_out.size(), 0, 0};
    StlWriteOptions wa;
    wa.format = StlFormat::kAscii;
    results[3] = splintcore::write_stl(ctx, mesh, splintcore::memory_sink(&ascii_sink), wa);
    ascii_written = static_cast<size_t>(ascii_sink.size);

    MemorySource ascii_src{d.ascii.data(), d.ascii.size(), 0, 7};
    Mesh mesh2;
    results[4] = splintcore::read_stl_mesh(ctx, splintcore::memory_source(&ascii_src, "b.stl"),
                                           StlReadOptions{}, &mesh2, &ascii_info);

    // Soup, tolerance welding and exact welding straight from a read.
    MemorySource soup_src{d.binary.data(), d.binary.size(), 0, 0};
    ArenaArray<SoupTriangle> soup(&arena);
    results[5] = splintcore::read_stl(ctx, splintcore::memory_source(&soup_src), StlReadOptions{},
                                      &soup, nullptr);
    soup_triangles = soup.size();
    Mesh welded;
    welded.bind(&arena);
    results[6] = splintcore::weld_tolerance(ctx, soup.span(), 1e-3, &welded);
    tolerance_vertices = welded.vertices.size();
    Mesh exact;
    exact.bind(&arena);
    results[7] = splintcore::weld_exact(ctx, soup.span(), &exact);

    // Sorting, both forms; hashing.
    splintcore::radix_sort(Span<KeyIndex>(items.data(), items.size()),
                           Span<KeyIndex>(scratch.data(), scratch.size()));
    results[8] = splintcore::radix_sort(arena, Span<KeyIndex>(items.data(), items.size()));
    splintcore::Sha256 sha;
    sha.update(binary_out.data(), binary_written);
    sha.finish(digest);
    splintcore::Sha256::to_hex(digest, hex);
    splintcore::HashSink hs;
    results[9] = splintcore::write_stl(ctx, mesh, splintcore::hash_sink(&hs), wa);

    // Error paths build their messages without the heap too.
    MemorySource bad_src{d.truncated.data(), d.truncated.size(), 0, 0};
    Mesh bad;
    results[10] = splintcore::read_stl_mesh(ctx, splintcore::memory_source(&bad_src, "cut.stl"),
                                            StlReadOptions{}, &bad, nullptr);
    results[10].format(formatted, sizeof(formatted));
    unsigned char tiny_memory[64];
    Arena tiny(tiny_memory, sizeof(tiny_memory));
    Context tiny_ctx(&tiny);
    MemorySource tiny_src{d.binary.data(), d.binary.size(), 0, 0};
    Mesh tiny_mesh;
    results[11] = splintcore::read_stl_mesh(tiny_ctx, splintcore::memory_source(&tiny_src),
                                            StlReadOptions{}, &tiny_mesh, nullptr);
  }
  c.stop();

  EXPECT_EQ(c.allocations, 0u) << "heap allocations inside core calls";
  EXPECT_EQ(c.frees, 0u) << "heap frees inside core calls";
  for (int i = 0; i < 10; ++i) {
    EXPECT_TRUE(results[i].is_ok()) << i << ": " << splintcore::test::format(results[i]);
  }
  EXPECT_EQ(results[10].code(), StatusCode::kTruncated);
  EXPECT_NE(std::string(formatted).find("cut.stl:"), std::string::npos) << formatted;
  EXPECT_EQ(results[11].code(), StatusCode::kArenaExhausted);
  // The work was real.
  EXPECT_EQ(binary_info.triangles, d.soup.size());
  EXPECT_EQ(ascii_info.triangles, d.soup.size());
  EXPECT_EQ(ascii_info.format, StlFormat::kAscii);
  EXPECT_TRUE(report.is_valid_solid());
  EXPECT_EQ(binary_written, d.binary.size());
  EXPECT_EQ(ascii_written, d.ascii.size());
  EXPECT_TRUE(std::equal(ascii_out.begin(),
                         ascii_out.begin() + static_cast<std::ptrdiff_t>(ascii_written),
                         d.ascii.begin()));
  EXPECT_EQ(soup_triangles, d.soup.size());
  EXPECT_EQ(tolerance_vertices, 24u * 16u);
  EXPECT_EQ(std::string(hex), splintcore::test::sha256_hex(binary_out.data(), binary_written));
  for (size_t i = 1; i < items.size(); ++i) ASSERT_LE(items[i - 1].key, items[i].key);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
