// The arena exhaustion loop (after SQLite's allocation-failure tests and Jolt's fixed-budget
// allocator): read + check + write a small mesh with every memory cap from 0 upward. Each cap
// too small must give kArenaExhausted with a message naming the need and the cap, never a
// crash; once the cap is big enough the output bytes must be those of an unlimited run; and
// the need a failure reports must be enough to get past it. Run over a caller buffer and over
// allocation hooks (whose every block must be given back).

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "common/shapes.h"
#include "splintcore/core.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "support/test_util.h"

namespace {

using splintcore::AllocatorHooks;
using splintcore::Arena;
using splintcore::Context;
using splintcore::MemorySink;
using splintcore::MemorySource;
using splintcore::Mesh;
using splintcore::MeshReport;
using splintcore::Status;
using splintcore::StatusCode;
using splintcore::StlFormat;
using splintcore::StlReadOptions;
using splintcore::StlWriteOptions;
using splintcore::test::format;

// Room for the output (the ASCII torus is about 50 KB).
constexpr size_t kOutputBytes = size_t{256} << 10;

struct Input {
  const char* name;
  std::vector<uint8_t> bytes;
  StlFormat format;
  StlReadOptions read_options;
  StlWriteOptions write_options;
};

std::vector<uint8_t> ascii_of(const std::vector<uint8_t>& binary) {
  // Write the binary file's mesh as ASCII with the library itself (the bytes are only input).
  splintcore::test::TestArena arena(size_t{16} << 20);
  Mesh mesh;
  Status s = splintcore::test::mesh_from_bytes(arena.arena, binary, &mesh);
  EXPECT_TRUE(s.is_ok()) << format(s);
  std::vector<uint8_t> out;
  s = splintcore::test::mesh_to_bytes(arena.arena, mesh, StlFormat::kAscii, &out);
  EXPECT_TRUE(s.is_ok()) << format(s);
  return out;
}

std::vector<Input> inputs() {
  const std::vector<uint8_t> binary =
      splintcore::test::binary_stl(splintcore::shapes::torus(12, 8, 10, 3), "torus");
  const std::vector<uint8_t> ascii = ascii_of(binary);
  std::vector<Input> list;
  list.push_back({"binary", binary, StlFormat::kBinary, {}, {}});
  list.push_back({"ascii", ascii, StlFormat::kAscii, {}, {}});
  // The same with the smallest buffers, so that the read refills and the writer flushes.
  Input small_binary{"binary, small buffers", binary, StlFormat::kBinary, {}, {}};
  small_binary.read_options.chunk_bytes = 4096;
  small_binary.write_options.buffer_bytes = 4096;
  Input small_ascii = small_binary;
  small_ascii.name = "ascii, small buffers";
  small_ascii.bytes = ascii;
  small_ascii.format = StlFormat::kAscii;
  list.push_back(small_binary);
  list.push_back(small_ascii);
  for (Input& in : list) in.write_options.format = in.format;
  return list;
}

// read_stl_mesh + check_mesh + write_stl, everything from `arena`. The output goes to `out`
// (a caller buffer: sinks are the caller's business, not the arena's).
Status pipeline(Arena& arena, const Input& in, std::vector<uint8_t>* out) {
  Context ctx(&arena);
  MemorySource ms{in.bytes.data(), in.bytes.size(), 0, 0};
  Mesh mesh;
  splintcore::StlInfo info;
  SPLINTCORE_RETURN_IF_ERROR(splintcore::read_stl_mesh(
      ctx, splintcore::memory_source(&ms, "torus.stl"), in.read_options, &mesh, &info));
  MeshReport report;
  SPLINTCORE_RETURN_IF_ERROR(splintcore::check_mesh(ctx, mesh, &report));
  if (!report.is_valid_solid() || report.genus != 1 || report.triangle_count != 192) {
    return Status::error(StatusCode::kInternal, "the torus did not check as a genus-1 solid");
  }
  MemorySink sink{out->data(), out->size(), 0, 0};
  Status s = splintcore::write_stl(ctx, mesh, splintcore::memory_sink(&sink), in.write_options);
  if (s.is_ok()) out->resize(static_cast<size_t>(sink.size));
  return s;
}

// Parses "arena exhausted: need N bytes, cap C" and checks the cap is the one given and the
// need exceeds it. Returns N, or 0 when anything is wrong (after recording the failure).
uint64_t check_exhausted(const Status& s, uint64_t cap) {
  EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << "cap " << cap << ": " << format(s);
  const std::string message = s.message();
  const std::string need_tag = "arena exhausted: need ";
  const size_t at = message.find(need_tag);
  const bool cap_named = message.find(", cap " + std::to_string(cap) + ";") != std::string::npos;
  EXPECT_NE(at, std::string::npos) << "cap " << cap << ": " << message;
  EXPECT_TRUE(cap_named) << "cap " << cap << ": " << message;
  if (s.code() != StatusCode::kArenaExhausted || at == std::string::npos || !cap_named) return 0;
  const uint64_t need = std::strtoull(message.c_str() + at + need_tag.size(), nullptr, 10);
  // A need within the cap would not have failed: the message would send the user nowhere.
  EXPECT_GT(need, cap) << message;
  return need > cap ? need : 0;
}

struct SweepResult {
  uint64_t first_success = 0;  // the smallest cap that worked
  uint64_t last_need = 0;      // the need reported at first_success - 1
  uint64_t runs = 0;
};

// Runs `run_with_cap(cap, &out)` with caps 0, step, 2 step... until it succeeds, then byte by
// byte between the last failure and that success to find the exact smallest cap, then at a
// few caps above it. Stops early after a few bad failures (to keep the log readable).
template <class RunWithCap>
SweepResult sweep(const std::vector<uint8_t>& expected, uint64_t step, uint64_t limit,
                  RunWithCap run_with_cap) {
  SweepResult r;
  int bad = 0;
  uint64_t cap = 0;
  uint64_t last_failed = 0;
  bool found = false;
  for (; cap <= limit && bad < 5; cap += step) {
    std::vector<uint8_t> out;
    Status s = run_with_cap(cap, &out);
    ++r.runs;
    if (s.is_ok()) {
      EXPECT_EQ(out, expected) << "cap " << cap;
      found = true;
      break;
    }
    if (check_exhausted(s, cap) == 0) ++bad;
    last_failed = cap;
  }
  EXPECT_TRUE(found) << "no success up to cap " << limit;
  if (!found) return r;
  uint64_t success = cap;
  uint64_t last_need = 0;
  for (uint64_t c = last_failed; c < cap && bad < 5; ++c) {
    std::vector<uint8_t> out;
    Status s = run_with_cap(c, &out);
    ++r.runs;
    if (s.is_ok()) {
      EXPECT_EQ(out, expected) << "cap " << c;
      success = c;
      break;
    }
    last_need = check_exhausted(s, c);
    if (last_need == 0) ++bad;
  }
  r.first_success = success;
  r.last_need = last_need;
  // Once big enough, always enough.
  for (uint64_t c = success; c < success + 64 * step && c <= limit; c += step / 4 + 1) {
    std::vector<uint8_t> out;
    Status s = run_with_cap(c, &out);
    ++r.runs;
    EXPECT_TRUE(s.is_ok()) << "cap " << c << ": " << format(s);
    EXPECT_EQ(out, expected) << "cap " << c;
  }
  return r;
}

// The output of an unlimited run, and the arena's high water.
std::vector<uint8_t> reference_output(const Input& in, size_t* high_water) {
  splintcore::test::TestArena big(size_t{8} << 20);
  std::vector<uint8_t> out(kOutputBytes);
  Status s = pipeline(big.arena, in, &out);
  EXPECT_TRUE(s.is_ok()) << format(s);
  *high_water = big.arena.high_water();
  return out;
}

TEST(IoExhaustionTest, BufferArenaSweep) {
  for (const Input& in : inputs()) {
    SCOPED_TRACE(in.name);
    size_t high_water = 0;
    const std::vector<uint8_t> expected = reference_output(in, &high_water);
    ASSERT_FALSE(expected.empty());
    ASSERT_LT(high_water, size_t{1} << 20);
    // One buffer for every cap (64-byte aligned start, so padding is the same for all caps).
    std::vector<unsigned char> memory(high_water + 4096 + 64);
    unsigned char* base = memory.data();
    base += (64 - reinterpret_cast<uintptr_t>(base) % 64) % 64;
    auto run = [&](uint64_t cap, std::vector<uint8_t>* out) {
      Arena arena(base, static_cast<size_t>(cap));
      out->resize(kOutputBytes);
      Status s = pipeline(arena, in, out);
      EXPECT_LE(arena.high_water(), cap);
      if (!s.is_ok()) {
        // The arena's own record agrees with the message.
        EXPECT_EQ(arena.exhausted_status().code(), StatusCode::kArenaExhausted);
      }
      return s;
    };
    // Every 16 bytes (the arena's alignment); ASCII parses are slower, so every 48 there.
    const uint64_t coarse_step =
        (in.format == StlFormat::kAscii ? 48 : 16) * splintcore::test::kSweepStep;
    SweepResult r = sweep(expected, coarse_step, high_water + 4096, run);
    ASSERT_GT(r.first_success, 0u);
    EXPECT_LE(r.first_success, r.last_need)
        << "a failure at cap " << r.first_success - 1 << " reported a need of " << r.last_need
        << " but " << r.first_success << " bytes were needed";
    EXPECT_EQ(r.first_success, high_water);  // the reference run's high water is the need
    // The need reported at every failing cap is actionable: running with it gets further
    // (a larger need) or succeeds.
    for (uint64_t cap = 0; cap < r.first_success; cap += r.first_success / 40 + 1) {
      std::vector<uint8_t> out;
      Status s = run(cap, &out);
      const uint64_t need = check_exhausted(s, cap);
      if (need == 0 || need > high_water + 4096) continue;
      Status again = run(need, &out);
      if (!again.is_ok()) {
        EXPECT_GT(check_exhausted(again, need), need);
      }
    }
  }
}

// ---- hooks ------------------------------------------------------------------------------------

struct HookCounts {
  uint64_t allocations = 0;
  uint64_t releases = 0;
  uint64_t outstanding_bytes = 0;
  uint64_t peak_bytes = 0;
  uint64_t fail_after = ~uint64_t{0};  // allocations allowed before the hook returns nullptr
  bool size_mismatch = false;
  std::vector<std::pair<void*, size_t>> live;
};

void* counting_allocate(void* user, size_t bytes) {
  HookCounts* c = static_cast<HookCounts*>(user);
  if (c->allocations >= c->fail_after) return nullptr;
  void* p = std::malloc(bytes);  // 16-byte aligned on the platforms we test
  if (p == nullptr) return nullptr;
  ++c->allocations;
  c->outstanding_bytes += bytes;
  if (c->outstanding_bytes > c->peak_bytes) c->peak_bytes = c->outstanding_bytes;
  c->live.push_back({p, bytes});
  return p;
}

void counting_release(void* user, void* pointer, size_t bytes) {
  HookCounts* c = static_cast<HookCounts*>(user);
  ++c->releases;
  bool found = false;
  for (size_t i = 0; i < c->live.size(); ++i) {
    if (c->live[i].first == pointer) {
      if (c->live[i].second != bytes) c->size_mismatch = true;
      c->live.erase(c->live.begin() + static_cast<std::ptrdiff_t>(i));
      found = true;
      break;
    }
  }
  if (!found) c->size_mismatch = true;  // released something never allocated
  c->outstanding_bytes -= bytes;
  std::memset(pointer, 0xAB, bytes);  // so reading a released block shows without sanitizers
  std::free(pointer);
}

TEST(IoExhaustionTest, HooksArenaSweep) {
  for (const Input& in : inputs()) {
    SCOPED_TRACE(in.name);
    size_t high_water = 0;
    const std::vector<uint8_t> expected = reference_output(in, &high_water);
    uint64_t total_allocations = 0;
    auto run = [&](uint64_t cap, std::vector<uint8_t>* out) {
      HookCounts counts;
      AllocatorHooks hooks;
      hooks.allocate = counting_allocate;
      hooks.release = counting_release;
      hooks.user = &counts;
      out->resize(kOutputBytes);
      Status s;
      {
        Arena arena(hooks, static_cast<size_t>(cap), 4096);
        s = pipeline(arena, in, out);
        EXPECT_LE(arena.reserved(), cap);
      }
      // Every block given back, with the size it was taken with; never over the cap.
      EXPECT_EQ(counts.allocations, counts.releases) << "cap " << cap;
      EXPECT_EQ(counts.outstanding_bytes, 0u) << "cap " << cap;
      EXPECT_TRUE(counts.live.empty()) << "cap " << cap;
      EXPECT_FALSE(counts.size_mismatch) << "cap " << cap;
      EXPECT_LE(counts.peak_bytes, cap) << "cap " << cap;
      total_allocations += counts.allocations;
      return s;
    };
    // The need with hooks (block headers and block tails count against the cap).
    HookCounts unlimited;
    {
      AllocatorHooks hooks;
      hooks.allocate = counting_allocate;
      hooks.release = counting_release;
      hooks.user = &unlimited;
      Arena arena(hooks, size_t{64} << 20, 4096);
      std::vector<uint8_t> out(kOutputBytes);
      SPLINTCORE_ASSERT_OK(pipeline(arena, in, &out));
      EXPECT_EQ(out, expected);
    }
    EXPECT_EQ(unlimited.allocations, unlimited.releases);
    const uint64_t limit = unlimited.peak_bytes + 4096;
    const uint64_t step = (in.format == StlFormat::kAscii ? 96 : 32) * splintcore::test::kSweepStep;
    SweepResult r = sweep(expected, step, limit, run);
    ASSERT_GT(r.first_success, 0u);
    EXPECT_LE(r.first_success, r.last_need)
        << "a failure at cap " << r.first_success - 1 << " reported a need of " << r.last_need
        << " but " << r.first_success << " bytes were needed";
    EXPECT_GT(total_allocations, 0u);
  }
}

TEST(IoExhaustionTest, HooksThatFailAreReportedAsExhaustion) {
  // The hooks themselves run out (SQLite style: fail the Nth allocation, N = 0, 1, 2...).
  for (const Input& in : inputs()) {
    SCOPED_TRACE(in.name);
    size_t high_water = 0;
    const std::vector<uint8_t> expected = reference_output(in, &high_water);
    bool succeeded = false;
    for (uint64_t n = 0; n < 64 && !succeeded; ++n) {
      HookCounts counts;
      counts.fail_after = n;
      AllocatorHooks hooks;
      hooks.allocate = counting_allocate;
      hooks.release = counting_release;
      hooks.user = &counts;
      std::vector<uint8_t> out(kOutputBytes);
      Status s;
      {
        Arena arena(hooks, size_t{64} << 20, 4096);
        s = pipeline(arena, in, &out);
      }
      EXPECT_EQ(counts.allocations, counts.releases);
      EXPECT_EQ(counts.outstanding_bytes, 0u);
      if (s.is_ok()) {
        succeeded = true;
        EXPECT_EQ(out, expected) << "n " << n;
      } else {
        EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << "n " << n << ": " << format(s);
        EXPECT_EQ(counts.allocations, n);
      }
    }
    EXPECT_TRUE(succeeded);
  }
}

TEST(IoExhaustionTest, HooksArenaGivesTheSameMeshAsABuffer) {
  // read_stl_mesh() with hooks: the mesh must survive the arena handing blocks back (with small
  // blocks and a small read buffer, the blocks after the start are too small to reuse).
  const std::vector<uint8_t> binary =
      splintcore::test::binary_stl(splintcore::shapes::torus(24, 16, 10, 3), "torus");
  const std::vector<std::vector<uint8_t>> files = {binary, ascii_of(binary)};
  for (const std::vector<uint8_t>& bytes : files) {
    splintcore::test::TestArena buffer(size_t{8} << 20);
    Mesh reference;
    SPLINTCORE_ASSERT_OK(splintcore::test::mesh_from_bytes(buffer.arena, bytes, &reference));
    std::vector<uint8_t> reference_out;
    SPLINTCORE_ASSERT_OK(splintcore::test::mesh_to_bytes(buffer.arena, reference,
                                                         StlFormat::kBinary, &reference_out));
    for (size_t block_bytes : {size_t{4096}, size_t{65536}, size_t{4} << 20}) {
      for (size_t chunk_bytes : {size_t{4096}, size_t{65536}}) {
        SCOPED_TRACE("block " + std::to_string(block_bytes) + " chunk " +
                     std::to_string(chunk_bytes));
        HookCounts counts;
        AllocatorHooks hooks;
        hooks.allocate = counting_allocate;
        hooks.release = counting_release;
        hooks.user = &counts;
        {
          Arena arena(hooks, size_t{64} << 20, block_bytes);
          Context ctx(&arena);
          MemorySource ms{bytes.data(), bytes.size(), 0, 0};
          StlReadOptions options;
          options.chunk_bytes = chunk_bytes;
          Mesh mesh;
          SPLINTCORE_ASSERT_OK(splintcore::read_stl_mesh(ctx, splintcore::memory_source(&ms),
                                                         options, &mesh, nullptr));
          ASSERT_EQ(mesh.vertices.size(), reference.vertices.size());
          ASSERT_EQ(mesh.triangles.size(), reference.triangles.size());
          EXPECT_EQ(std::memcmp(mesh.vertices.data(), reference.vertices.data(),
                                reference.vertices.size() * sizeof(splintcore::Vec3)),
                    0);
          EXPECT_EQ(std::memcmp(mesh.triangles.data(), reference.triangles.data(),
                                reference.triangles.size() * sizeof(splintcore::Triangle)),
                    0);
          std::vector<uint8_t> out;
          SPLINTCORE_ASSERT_OK(
              splintcore::test::mesh_to_bytes(arena, mesh, StlFormat::kBinary, &out));
          EXPECT_EQ(out, reference_out);
        }
        EXPECT_EQ(counts.allocations, counts.releases);
        EXPECT_EQ(counts.outstanding_bytes, 0u);
      }
    }
  }
}

}  // namespace
