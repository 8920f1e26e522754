// The arena-exhaustion sweep over every public operation that takes an arena (issue 9; the
// model is SQLite's "every allocation failure point is tried" and Jolt's fixed budget).
//
// For each operation, on a small input:
// 1. an unlimited run gives the reference output (serialised to bytes) and the arena's need;
// 2. buffer mode, every cap from 0 to 256 bytes, then the chain of failure points: a failing
//    run at cap C reports "need N bytes"; N > C, and the run at cap N gets past that
//    allocation (it fails later, at a larger need, or succeeds). In buffer mode an allocation
//    can fail only when it raises the arena's high water, so this chain visits every
//    allocation that can fail there, one run each (and the cap just below each need is run
//    too, to see it fail at the same point);
// 3. hooks mode with small blocks, the hooks failing the Nth block request (N = 0, 1, 2...,
//    until the run succeeds): failures inside code that reuses memory below the high water;
//    every block taken is given back, with its size (no leak, also under ASan).
// Each failure must be kArenaExhausted with "need N bytes" text, leave the arena's top where
// it was (arena.used() equal to its value before the call: every public operation promises
// "on an error the arena is as it was") and leave the outputs empty; the success at the end
// must give the reference output. Operations that need an index (the distance queries) are
// checked against the arena's top after the index was built.
// The counts of failure points tried are printed (and checked to be > 0) per operation, with
// the running total over the operations swept so far.

#include <gtest/gtest.h>

#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "common/shapes.h"
#include "splintcore/boolean.h"
#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "splintcore/io.h"
#include "splintcore/json.h"
#include "splintcore/mesh.h"
#include "splintcore/platform.h"
#include "splintcore/printer.h"
#include "splintcore/spline.h"
#include "splintcore/volume.h"
#include "support/phantom_jaws.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::format;

// What one run of an operation gives: its status, its output as bytes (only read on success)
// and whether every output it has is empty (read on failure).
struct OpRun {
  Status status;
  std::vector<uint8_t> output;
  bool outputs_empty = true;
};

using Operation = std::function<OpRun(Arena&)>;

template <class T>
void append_bytes(std::vector<uint8_t>* out, const T* data, size_t count) {
  const uint8_t* p = reinterpret_cast<const uint8_t*>(data);
  out->insert(out->end(), p, p + count * sizeof(T));
}
void append_mesh(std::vector<uint8_t>* out, const Mesh& m) {
  append_bytes(out, m.vertices.data(), m.vertices.size());
  append_bytes(out, m.triangles.data(), m.triangles.size());
}
bool mesh_empty(const Mesh& m) { return m.vertices.empty() && m.triangles.empty(); }

struct Counts {
  uint64_t buffer_points = 0;  // distinct failure points in buffer mode (the chain)
  uint64_t hook_points = 0;    // distinct N for which the Nth block request failed
  uint64_t small_caps = 0;     // caps 0..256 run byte by byte
};

// The failure's checks; returns the need (0 when the failure is not clean).
uint64_t check_failure(const char* name, const OpRun& r, const Arena& arena, size_t used_before,
                       const std::string& where) {
  EXPECT_EQ(r.status.code(), StatusCode::kArenaExhausted)
      << name << " " << where << ": " << format(r.status);
  const uint64_t need = test::need_of(r.status, arena.cap());
  EXPECT_NE(std::string(r.status.message()).find(" bytes"), std::string::npos)
      << name << " " << where << ": " << r.status.message();
  EXPECT_GT(need, 0u) << name << " " << where << ": " << r.status.message();
  EXPECT_EQ(arena.used(), used_before) << name << " " << where << ": the top moved";
  EXPECT_TRUE(r.outputs_empty) << name << " " << where << ": partial output";
  if (r.status.code() != StatusCode::kArenaExhausted) return 0;
  return need;
}

// 16-byte aligned heap memory for buffer-mode arenas.
struct Buffer {
  std::vector<unsigned char> bytes;
  unsigned char* base = nullptr;
  explicit Buffer(size_t n) : bytes(n + 64) {
    base = bytes.data() + (64 - reinterpret_cast<uintptr_t>(bytes.data()) % 64) % 64;
  }
};

struct HookState {
  uint64_t requests = 0;
  uint64_t allocations = 0;
  uint64_t releases = 0;
  uint64_t outstanding = 0;
  uint64_t fail_at = ~uint64_t{0};  // the request number (0-based) that returns nullptr
  bool mismatch = false;
  std::vector<std::pair<void*, size_t>> live;
};

void* hook_allocate(void* user, size_t bytes) {
  HookState* h = static_cast<HookState*>(user);
  const uint64_t n = h->requests++;
  if (n == h->fail_at) return nullptr;
  void* p = std::malloc(bytes);
  if (p == nullptr) return nullptr;
  ++h->allocations;
  h->outstanding += bytes;
  h->live.push_back({p, bytes});
  return p;
}

void hook_release(void* user, void* pointer, size_t bytes) {
  HookState* h = static_cast<HookState*>(user);
  ++h->releases;
  bool found = false;
  for (size_t i = 0; i < h->live.size(); ++i) {
    if (h->live[i].first == pointer) {
      h->mismatch = h->mismatch || h->live[i].second != bytes;
      h->live.erase(h->live.begin() + static_cast<std::ptrdiff_t>(i));
      found = true;
      break;
    }
  }
  h->mismatch = h->mismatch || !found;
  h->outstanding -= bytes;
  std::memset(pointer, 0xAB, bytes);
  std::free(pointer);
}

// `op` in an arena of `block_bytes` blocks whose allocator refuses the Nth block request the
// operation makes (N = refuse, 0-based), after a first allocation of `first` bytes (so that
// "the top is back" is tested above a non-empty arena too; none when 0). A failure must be clean
// (check_failure); every block must go back with its size. *requests: the operation's block
// requests (more than `refuse` when the refused one was reached).
OpRun run_refusing_block(const char* name, const Operation& op, size_t block_bytes, size_t first,
                         uint64_t refuse, uint64_t* requests) {
  HookState h;
  AllocatorHooks hooks;
  hooks.allocate = hook_allocate;
  hooks.release = hook_release;
  hooks.user = &h;
  const std::string where = "block " + std::to_string(refuse);
  OpRun r;
  uint64_t before = 0;
  {
    Arena arena(hooks, size_t{1} << 30, block_bytes);
    if (first > 0) {
      EXPECT_NE(arena.allocate(first), nullptr);
    }
    before = h.requests;
    h.fail_at = before + refuse;
    r = op(arena);
    if (!r.status.is_ok()) check_failure(name, r, arena, first, where);
  }
  EXPECT_EQ(h.allocations, h.releases) << name << " " << where;
  EXPECT_EQ(h.outstanding, 0u) << name << " " << where;
  EXPECT_FALSE(h.mismatch) << name << " " << where;
  *requests = h.requests - before;
  return r;
}

// Refuses the Nth block request of `op` in an arena of `block_bytes` blocks, for N = 0, 1, 2...
// until a run asks for fewer blocks than that (at most 10,000 runs). Every run must fail
// cleanly (kArenaExhausted, the arena's top back where it was, empty outputs, every block given
// back with its size) or, where the operation has another way, give the output of the run with
// none refused. `first`: bytes allocated before the operation (see run_refusing_block).
// Returns the number of runs that failed (*refused: the requests refused); prints the counts.
uint64_t refuse_each_block_request(const char* name, size_t block_bytes, const Operation& op,
                                   size_t first = 0, uint64_t* refused = nullptr) {
  auto run = [&](uint64_t fail_at, bool* reached) {
    uint64_t requests = 0;
    const OpRun r = run_refusing_block(name, op, block_bytes, first, fail_at, &requests);
    *reached = requests > fail_at;
    return r;
  };
  bool reached = false;
  const OpRun want = run(~uint64_t{0}, &reached);
  EXPECT_TRUE(want.status.is_ok()) << name << ": " << format(want.status);
  uint64_t n = 0, failed = 0, other_way = 0;
  for (; n < 10000; ++n) {
    const OpRun r = run(n, &reached);
    if (!reached) {
      EXPECT_TRUE(r.status.is_ok() && r.output == want.output) << name;
      break;
    }
    if (r.status.is_ok()) {
      ++other_way;
      EXPECT_TRUE(r.output == want.output) << name << ": block " << n << " refused: other bytes";
    } else {
      ++failed;
    }
  }
  std::printf(
      "[ refuse   ] %s, %zu-byte blocks: %llu requests refused one at a time, %llu clean "
      "failures, %llu the same output another way\n",
      name, block_bytes, static_cast<unsigned long long>(n),
      static_cast<unsigned long long>(failed), static_cast<unsigned long long>(other_way));
  if (refused != nullptr) *refused = n;
  return failed;
}

// Failure points tried by every sweep run so far in this process (printed after each).
Counts g_total;
uint64_t g_operations = 0;

Counts sweep(const char* name, const Operation& op, size_t reference_cap = size_t{256} << 20) {
  Counts counts;
  uint64_t overstated = 0;  // failures whose need exceeded the reference run's high water
  // 1. The reference.
  std::vector<uint8_t> expected;
  size_t need = 0;
  {
    test::TestArena big(reference_cap);
    OpRun r = op(big.arena);
    EXPECT_TRUE(r.status.is_ok()) << name << ": " << format(r.status);
    if (!r.status.is_ok()) return counts;
    expected = r.output;
    need = big.arena.high_water();
  }
  Buffer buffer(need + 4096);
  auto run_buffer = [&](uint64_t cap) {
    Arena arena(buffer.base, static_cast<size_t>(cap));
    OpRun r = op(arena);
    EXPECT_LE(arena.high_water(), cap);
    if (r.status.is_ok()) {
      EXPECT_EQ(r.output, expected) << name << " cap " << cap << ": output differs";
      return uint64_t{0};
    }
    const uint64_t n = check_failure(name, r, arena, 0, "cap " + std::to_string(cap));
    EXPECT_GT(n, cap) << name << " cap " << cap << ": a need within the cap";
    return n;
  };
  // 2a. Every cap near the small end.
  for (uint64_t cap = 0; cap <= 256 && cap < need; ++cap, ++counts.small_caps) {
    run_buffer(cap);
  }
  // 2b. The chain of failure points.
  uint64_t cap = 0;
  int bad = 0;
  for (;;) {
    const uint64_t n = run_buffer(cap);
    if (n == 0) break;  // success (or a broken failure, already reported)
    ++counts.buffer_points;
    if (n - 1 > cap) {
      // Just below the need: the same point fails again, naming the same need.
      Arena arena(buffer.base, static_cast<size_t>(n - 1));
      OpRun r = op(arena);
      if (r.status.is_ok()) {
        // Growth that falls back to the exact size can fit below the unconstrained high water.
        EXPECT_EQ(r.output, expected) << name << " cap " << n - 1;
      } else {
        const uint64_t again = check_failure(name, r, arena, 0, "cap " + std::to_string(n - 1));
        EXPECT_GE(again, n) << name << " cap " << n - 1 << ": " << r.status.message();
      }
    }
    if (n <= cap) {
      ADD_FAILURE() << name << ": need " << n << " at cap " << cap << " (reference need " << need
                    << ")";
      if (++bad > 3) break;
      cap = need;
      continue;
    }
    if (n > need) {
      // The need named is more than an unconstrained run uses (a growth that wanted more than
      // it needed): the remedy still works. Continue from the reference need.
      ++overstated;
      cap = need;
      continue;
    }
    cap = n;
  }
  EXPECT_LE(cap, need) << name;
  {
    Arena arena(buffer.base, need);
    OpRun r = op(arena);
    EXPECT_TRUE(r.status.is_ok()) << name << " at the reference need " << need << ": "
                                  << format(r.status);
    EXPECT_EQ(r.output, expected) << name;
  }
  // 3. Hooks: fail the Nth block request. Blocks of 4 KiB, larger for the big operations
  // (at most a few hundred blocks per run).
  const size_t block_bytes = need / 256 > 4096 ? (need / 256 + 4095) / 4096 * 4096 : 4096;
  // Every request, not only up to the first run that succeeds: a refused request can be
  // survived (a growth that falls back to the exact size) and a later one not.
  refuse_each_block_request(name, block_bytes, op, 16, &counts.hook_points);
  EXPECT_GT(counts.buffer_points + counts.small_caps, 0u) << name;
  std::printf(
      "[ sweep    ] %-34s need %9zu B  buffer points %4llu  hook points %4llu  "
      "small caps %3llu%s%s\n",
      name, need, static_cast<unsigned long long>(counts.buffer_points),
      static_cast<unsigned long long>(counts.hook_points),
      static_cast<unsigned long long>(counts.small_caps),
      overstated > 0 ? "  (need overstated " : "",
      overstated > 0 ? (std::to_string(overstated) + "x)").c_str() : "");
  g_total.buffer_points += counts.buffer_points;
  g_total.hook_points += counts.hook_points;
  g_total.small_caps += counts.small_caps;
  ++g_operations;
  std::printf(
      "[ sweep    ] total over %llu operations: buffer points %llu  hook points %llu  "
      "small caps %llu\n",
      static_cast<unsigned long long>(g_operations),
      static_cast<unsigned long long>(g_total.buffer_points),
      static_cast<unsigned long long>(g_total.hook_points),
      static_cast<unsigned long long>(g_total.small_caps));
  return counts;
}

// check_mesh of `mesh` as an operation for sweep(): its output the report's counts, genus
// and volume; `expect` checks a report that came out.
Operation check_mesh_of(const Mesh& mesh, std::function<void(const MeshReport&)> expect) {
  return [&mesh, expect](Arena& a) {
    OpRun r;
    MeshReport report;
    r.status = check_mesh(Context(&a), mesh, &report);
    if (r.status.is_ok()) {
      expect(report);
      const uint64_t f[] = {report.edge_count,
                            report.boundary_edges,
                            report.boundary_loops,
                            report.nonmanifold_edges,
                            report.duplicate_triangles,
                            report.shells,
                            static_cast<uint64_t>(report.genus)};
      append_bytes(&r.output, f, 7);
      append_bytes(&r.output, &report.volume, 1);
    }
    return r;
  };
}

// ---- inputs (outside any arena under test) -------------------------------------------------

std::vector<SoupTriangle> torus_soup() { return shapes::torus(12, 8, 10, 3); }

std::vector<SoupTriangle> box_soup(float lo, float hi) {
  const float a[3] = {lo, lo, lo}, b[3] = {hi, hi, hi};
  return shapes::box(a, b);
}

// Thirteen tetrahedra on thirteen points, any two sharing exactly one corner: the blocks
// {0, 1, 3, 9} + i mod 13 of the projective plane of order 3, on points of the moment curve
// (i, i^2, i^3) (no four coplanar), each turned outward.
std::vector<SoupTriangle> tetrahedra_of_the_plane_of_order_3() {
  std::vector<SoupTriangle> plane;
  float pt[13][3];
  for (int i = 0; i < 13; ++i) {
    pt[i][0] = static_cast<float>(i);
    pt[i][1] = static_cast<float>(i * i);
    pt[i][2] = static_cast<float>(i * i * i);
  }
  const int kBlock[4] = {0, 1, 3, 9};
  for (int i = 0; i < 13; ++i) {
    int c[4];
    for (int k = 0; k < 4; ++k) c[k] = (kBlock[k] + i) % 13;
    // Turned so that c[3] lies behind face (c[0], c[1], c[2]) (their volume negative): that
    // face and the three others then face outward.
    const auto vol = [&](int a, int b, int d, int e) {
      double u[3], v[3], w[3];
      for (int x = 0; x < 3; ++x) {
        u[x] = double{pt[b][x]} - pt[a][x];
        v[x] = double{pt[d][x]} - pt[a][x];
        w[x] = double{pt[e][x]} - pt[a][x];
      }
      return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
             u[2] * (v[0] * w[1] - v[1] * w[0]);
    };
    if (vol(c[0], c[1], c[2], c[3]) > 0) std::swap(c[1], c[2]);
    const int faces[4][3] = {
        {c[0], c[1], c[2]}, {c[0], c[3], c[1]}, {c[1], c[3], c[2]}, {c[0], c[2], c[3]}};
    for (const auto& f : faces) {
      SoupTriangle t;
      for (int k = 0; k < 3; ++k) {
        for (int x = 0; x < 3; ++x) t.p[k][x] = pt[f[k]][x];
      }
      plane.push_back(t);
    }
  }
  return plane;
}

// A mesh held in its own arena (the input of an operation under test).
struct HeldMesh {
  test::TestArena t{size_t{64} << 20};
  Mesh mesh;
  explicit HeldMesh(const std::vector<SoupTriangle>& soup) {
    Status s = test::mesh_from_soup(t.arena, soup, &mesh);
    EXPECT_TRUE(s.is_ok()) << format(s);
  }
  HeldMesh() = default;
};

std::vector<uint8_t> fixture(const char* path) {
  return test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/" + path);
}

// ---- the sweeps ----------------------------------------------------------------------------

TEST(ExhaustionSweep, Mesh) {
  const std::vector<SoupTriangle> soup = torus_soup();
  const Span<const SoupTriangle> s(soup.data(), soup.size());
  sweep("weld_exact", [&](Arena& a) {
    OpRun r;
    Mesh m(&a);
    r.status = weld_exact(Context(&a), s, &m);
    r.outputs_empty = mesh_empty(m);
    if (r.status.is_ok()) append_mesh(&r.output, m);
    return r;
  });
  sweep("weld_tolerance", [&](Arena& a) {
    OpRun r;
    Mesh m(&a);
    r.status = weld_tolerance(Context(&a), s, 0.01, &m);
    r.outputs_empty = mesh_empty(m);
    if (r.status.is_ok()) append_mesh(&r.output, m);
    return r;
  });
  HeldMesh torus(soup);
  sweep("check_mesh", check_mesh_of(torus.mesh, [](const MeshReport& report) {
          EXPECT_TRUE(report.is_valid_solid());
          EXPECT_EQ(report.genus, 1);
        }));
  // With a hole (a boundary loop) and a triangle twice (edges of 3 uses, a duplicate): the
  // check takes the boundary's union-find and the collected triangles only when it meets them.
  std::vector<SoupTriangle> faulty(soup.begin() + 1, soup.end());
  faulty.push_back(soup[40]);
  HeldMesh flawed(faulty);
  sweep("check_mesh (a hole, a duplicate)",
        check_mesh_of(flawed.mesh, [](const MeshReport& report) {
          EXPECT_EQ(report.boundary_loops, 1u);
          EXPECT_EQ(report.duplicate_triangles, 1u);
          EXPECT_GT(report.nonmanifold_edges, 0u);
        }));
  // Thirteen tetrahedra any two of which share one corner: 13 shells, every vertex in four.
  // The (vertex, shell) pairs of the shells' vertex counts then outgrow the edge pass, so
  // their allocations raise the high water.
  HeldMesh shared(tetrahedra_of_the_plane_of_order_3());
  sweep("check_mesh (shells sharing vertices)",
        check_mesh_of(shared.mesh, [](const MeshReport& report) {
          EXPECT_EQ(report.shells, 13u);
          EXPECT_EQ(report.vertex_count, 13u);
          EXPECT_TRUE(report.is_valid_solid()) << test::format(require_valid_solid(report));
        }));
  // The scan preparation's passes on the flawed torus and a small box beside it (an island).
  std::vector<SoupTriangle> scan = faulty;
  for (const SoupTriangle& t : box_soup(40, 40.5f)) scan.push_back(t);
  HeldMesh scanned(scan);
  sweep("prepare_scan (hole, duplicate, island)", [&](Arena& a) {
    OpRun r;
    Mesh out;
    PrepareReport report;
    r.status = prepare_scan(Context(&a), scanned.mesh, PrepareOptions{}, &out, &report);
    r.outputs_empty = mesh_empty(out);
    if (r.status.is_ok()) {
      EXPECT_EQ(report.duplicate_triangles, 1u);
      EXPECT_EQ(report.holes_filled, 1u);
      append_mesh(&r.output, out);
    }
    return r;
  });
  sweep("check_closed_oriented", [&](Arena& a) {
    OpRun r;
    double volume = 0;
    r.status = check_closed_oriented(Context(&a), torus.mesh, &volume);
    if (r.status.is_ok()) append_bytes(&r.output, &volume, 1);
    return r;
  });
  sweep("find_self_intersections", [&](Arena& a) {
    OpRun r;
    SelfIntersectionReport report;
    r.status = find_self_intersections(Context(&a), torus.mesh, 10, &report);
    if (r.status.is_ok()) {
      append_bytes(&r.output, &report.intersecting_pairs, 1);
      append_bytes(&r.output, &report.candidate_pairs, 1);
    }
    return r;
  });
  // A self-intersecting input (two overlapping boxes in one mesh): the pairs are collected.
  std::vector<SoupTriangle> two = box_soup(0, 2);
  for (const SoupTriangle& t : box_soup(1, 3)) two.push_back(t);
  HeldMesh crossing(two);
  sweep("find_self_intersections (crossing)", [&](Arena& a) {
    OpRun r;
    SelfIntersectionReport report;
    r.status = find_self_intersections(Context(&a), crossing.mesh, 1000, &report);
    if (r.status.is_ok()) {
      EXPECT_TRUE(report.self_intersecting());
      append_bytes(&r.output, &report.intersecting_pairs, 1);
      append_bytes(&r.output, &report.first_a, 1);
      append_bytes(&r.output, &report.first_b, 1);
    }
    return r;
  });
}

TEST(ExhaustionSweep, Stl) {
  const std::vector<uint8_t> binary = test::binary_stl(torus_soup(), "torus");
  std::vector<uint8_t> ascii;
  {
    test::TestArena t(size_t{16} << 20);
    Mesh m;
    SPLINTCORE_ASSERT_OK(test::mesh_from_bytes(t.arena, binary, &m));
    SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, m, StlFormat::kAscii, &ascii));
  }
  const std::vector<const std::vector<uint8_t>*> files = {&binary, &ascii};
  for (const std::vector<uint8_t>* file : files) {
    const bool is_binary = file == &binary;
    StlReadOptions options;
    options.chunk_bytes = 4096;  // refills
    sweep(is_binary ? "read_stl_mesh (binary)" : "read_stl_mesh (ASCII)", [&](Arena& a) {
      OpRun r;
      MemorySource ms{file->data(), file->size(), 0, 0};
      Mesh m(&a);
      StlInfo info;
      r.status = read_stl_mesh(Context(&a), memory_source(&ms), options, &m, &info);
      r.outputs_empty = mesh_empty(m);
      if (r.status.is_ok()) append_mesh(&r.output, m);
      return r;
    });
    sweep(is_binary ? "read_stl (binary soup)" : "read_stl (ASCII soup)", [&](Arena& a) {
      OpRun r;
      MemorySource ms{file->data(), file->size(), 0, 0};
      ArenaArray<SoupTriangle> soup(&a);
      r.status = read_stl(Context(&a), memory_source(&ms), options, &soup, nullptr);
      r.outputs_empty = soup.empty();
      if (r.status.is_ok()) append_bytes(&r.output, soup.data(), soup.size());
      return r;
    });
  }
  HeldMesh torus(torus_soup());
  for (StlFormat format : {StlFormat::kBinary, StlFormat::kAscii}) {
    sweep(format == StlFormat::kBinary ? "write_stl (binary)" : "write_stl (ASCII)", [&](Arena& a) {
      OpRun r;
      std::vector<uint8_t> out(size_t{256} << 10);
      MemorySink sink{out.data(), out.size(), 0, 0};
      StlWriteOptions wo;
      wo.format = format;
      wo.buffer_bytes = 4096;
      r.status = write_stl(Context(&a), torus.mesh, memory_sink(&sink), wo);
      // A failed writer has written nothing (the buffer is taken before any byte).
      r.outputs_empty = sink.size == 0;
      out.resize(static_cast<size_t>(sink.size));
      r.output = out;
      return r;
    });
  }
}

// Shortest round-trip text of a double (the torus's vertices are float32 values).
std::string shortest(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

TEST(ExhaustionSweep, PlyAndObj) {
  // The torus as an ASCII PLY and as an OBJ, read and welded (read_mesh: detection, then
  // read_ply or read_obj).
  HeldMesh torus(torus_soup());
  std::string ply = "ply\nformat ascii 1.0\nelement vertex " +
                    std::to_string(torus.mesh.vertices.size()) +
                    "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                    std::to_string(torus.mesh.triangles.size()) +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
  std::string obj = "# torus\n";
  for (const Vec3& v : torus.mesh.vertices) {
    const std::string xyz = shortest(v.x) + " " + shortest(v.y) + " " + shortest(v.z);
    ply += xyz + "\n";
    obj += "v " + xyz + "\n";
  }
  for (const Triangle& t : torus.mesh.triangles) {
    ply += "3 " + std::to_string(t.v[0]) + " " + std::to_string(t.v[1]) + " " +
           std::to_string(t.v[2]) + "\n";
    obj += "f " + std::to_string(t.v[0] + 1) + " " + std::to_string(t.v[1] + 1) + " " +
           std::to_string(t.v[2] + 1) + "\n";
  }
  const std::vector<std::pair<const char*, const std::string*>> files = {
      {"read_mesh (ASCII PLY, welded)", &ply}, {"read_mesh (OBJ, welded)", &obj}};
  for (const auto& f : files) {
    sweep(f.first, [&](Arena& a) {
      OpRun r;
      MemorySource ms{reinterpret_cast<const uint8_t*>(f.second->data()), f.second->size(), 0, 0};
      MeshReadOptions options;
      options.weld = true;
      options.chunk_bytes = 4096;  // refills
      Mesh m(&a);
      r.status = read_mesh(Context(&a), memory_source(&ms), options, &m, nullptr);
      r.outputs_empty = mesh_empty(m);
      if (r.status.is_ok()) append_mesh(&r.output, m);
      return r;
    });
  }
}

TEST(ExhaustionSweep, JsonAndCase) {
  const std::vector<uint8_t> text = fixture("cases/paper_scale.json");
  ASSERT_FALSE(text.empty());
  const char* chars = reinterpret_cast<const char*>(text.data());
  sweep("parse_json", [&](Arena& a) {
    OpRun r;
    JsonDocument doc;
    r.status = parse_json(Context(&a), chars, text.size(), JsonLimits{}, "paper_scale", &doc);
    r.outputs_empty = doc.values.empty();
    if (r.status.is_ok()) {
      for (const JsonValue& v : doc.values) {
        append_bytes(&r.output, &v.type, 1);
        append_bytes(&r.output, &v.number, 1);
        append_bytes(&r.output, &v.child_count, 1);
      }
    }
    return r;
  });
  sweep("parse_case", [&](Arena& a) {
    OpRun r;
    CaseFile c;
    r.status = parse_case(Context(&a), chars, text.size(), "paper_scale", &c);
    r.outputs_empty = c.upper.empty() && c.lower.empty() && c.jaws.empty();
    if (r.status.is_ok()) {
      append_bytes(&r.output, c.upper.data(), c.upper.size());
      append_bytes(&r.output, c.lower.data(), c.lower.size());
      append_bytes(&r.output, &c.base.spacing_mm, 1);
    }
    return r;
  });
  test::TestArena held(size_t{16} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(Context(&held.arena), chars, text.size(), "paper_scale", &c));
  sweep("build_case_base", [&](Arena& a) {
    OpRun r;
    Mesh m(&a);
    BaseReport report;
    r.status = build_case_base(Context(&a), c, &m, &report);
    r.outputs_empty = mesh_empty(m);
    if (r.status.is_ok()) append_mesh(&r.output, m);
    return r;
  });
  sweep("make_lines", [&](Arena& a) {
    OpRun r;
    ArenaArray<Line> up(&a);
    r.status = make_lines(Context(&a), c.upper, c.occlusal_normal, "upper", &up);
    r.outputs_empty = up.empty();
    if (r.status.is_ok()) append_bytes(&r.output, up.data(), up.size());
    return r;
  });
  // The lines held outside the arena under test.
  ArenaArray<Line> held_up(&held.arena), held_lo(&held.arena);
  SPLINTCORE_ASSERT_OK(
      make_lines(Context(&held.arena), c.upper, c.occlusal_normal, "upper", &held_up));
  SPLINTCORE_ASSERT_OK(
      make_lines(Context(&held.arena), c.lower, c.occlusal_normal, "lower", &held_lo));
  sweep("build_splint_base (rounded corners)", [&](Arena& a) {
    OpRun r;
    Mesh m(&a);
    BaseReport report;
    BaseParams p = c.base;
    p.corner_radius_mm = 0.5;  // the rounded-corner path too
    r.status = build_splint_base(Context(&a), held_up.span(), held_lo.span(), p, &m, &report);
    r.outputs_empty = mesh_empty(m);
    if (r.status.is_ok()) append_mesh(&r.output, m);
    return r;
  });
}

TEST(ExhaustionSweep, DistanceAndVolume) {
  HeldMesh torus(torus_soup());
  const Span<const Vec3> none;
  std::vector<Vec3> queries;
  for (int i = 0; i < 40; ++i) {
    queries.push_back(Vec3{-15.0 + 0.75 * i, 0.3 * (i % 7) - 1.0, 0.25 * (i % 5) - 0.5});
  }
  sweep("build_distance_index", [&](Arena& a) {
    OpRun r;
    DistanceIndex index;
    r.status = build_distance_index(Context(&a), torus.mesh, DistanceIndexOptions{}, &index);
    r.outputs_empty = index.nodes.empty();
    if (r.status.is_ok()) {
      append_bytes(&r.output, index.nodes.data(), index.nodes.size());
      append_bytes(&r.output, index.order.data(), index.order.size());
    }
    return r;
  });
  // Queries on an index that lives below the arena's top (built in the run, kept).
  // A failed query must leave the arena's top where the index left it (checked here, since
  // the sweep's own check sees the top after the test's rewind of the index).
  size_t after_index = 0;
  auto with_index = [&](Arena& a, OpRun* r, DistanceIndex* index) {
    r->status = build_distance_index(Context(&a), torus.mesh, DistanceIndexOptions{}, index);
    after_index = a.used();
    return r->status.is_ok();
  };
  auto query_failed = [&](Arena& a, const Arena::Marker& start, const char* name) {
    EXPECT_EQ(a.used(), after_index) << name << ": the failed query moved the top";
    a.rewind(start);
  };
  sweep("index + triangles_in_box", [&](Arena& a) {
    OpRun r;
    const Arena::Marker start = a.mark();
    DistanceIndex index;
    if (!with_index(a, &r, &index)) return r;
    ArenaArray<uint32_t> out(&a);
    Aabb box;
    box.lo = Vec3{-4, -4, -4};
    box.hi = Vec3{12, 4, 4};
    r.status = triangles_in_box(Context(&a), index, box, &out);
    r.outputs_empty = out.empty();
    if (r.status.is_ok()) {
      append_bytes(&r.output, out.data(), out.size());
    } else {
      query_failed(a, start, "index + triangles_in_box");
    }
    return r;
  });
  sweep("index + batch_closest_points", [&](Arena& a) {
    OpRun r;
    const Arena::Marker start = a.mark();
    DistanceIndex index;
    if (!with_index(a, &r, &index)) return r;
    std::vector<ClosestPoint> results(queries.size());
    r.status =
        batch_closest_points(Context(&a), index, Span<const Vec3>(queries.data(), queries.size()),
                             Span<ClosestPoint>(results.data(), results.size()));
    if (r.status.is_ok()) {
      for (const ClosestPoint& p : results) append_bytes(&r.output, &p.distance, 1);
    } else {
      query_failed(a, start, "index + batch_closest_points");
    }
    return r;
  });
  sweep("index + batch_signed_distances", [&](Arena& a) {
    OpRun r;
    const Arena::Marker start = a.mark();
    DistanceIndex index;
    if (!with_index(a, &r, &index)) return r;
    std::vector<double> results(queries.size());
    r.status = batch_signed_distances(
        Context(&a), index, Span<const Vec3>(queries.data(), queries.size()),
        SignMethod::kWindingNumber, Span<double>(results.data(), results.size()));
    if (r.status.is_ok()) {
      append_bytes(&r.output, results.data(), results.size());
    } else {
      query_failed(a, start, "index + batch_signed_distances");
    }
    return r;
  });
  (void)none;
  SdfGrid grid;
  grid.origin = Vec3{-14, -14, -4};
  grid.spacing = 1.0;
  grid.nx = grid.ny = 29;
  grid.nz = 9;
  grid.band = 2.0;
  sweep("index + sample_sdf", [&](Arena& a) {
    OpRun r;
    const Arena::Marker start = a.mark();
    DistanceIndex index;
    if (!with_index(a, &r, &index)) return r;
    std::vector<float> values(size_t{grid.nx} * grid.ny * grid.nz);
    r.status = sample_sdf(Context(&a), index, grid, SignMethod::kAuto, 0, grid.nz,
                          Span<float>(values.data(), values.size()));
    if (r.status.is_ok()) {
      append_bytes(&r.output, values.data(), values.size());
    } else {
      query_failed(a, start, "index + sample_sdf");
    }
    return r;
  });

  // Marching cubes over a sphere field (fill from a table: the source is the caller's).
  struct Field {
    VolumeGrid grid;
    std::vector<float> values;
  };
  static Field field;
  field.grid.origin = Vec3{0, 0, 0};
  field.grid.spacing = Vec3{1, 1, 1};
  field.grid.nx = 14;
  field.grid.ny = 13;
  field.grid.nz = 12;
  field.values.clear();
  for (uint32_t z = 0; z < field.grid.nz; ++z) {
    for (uint32_t y = 0; y < field.grid.ny; ++y) {
      for (uint32_t x = 0; x < field.grid.nx; ++x) {
        const Vec3 p{x - 6.6, y - 6.2, z - 5.7};
        field.values.push_back(static_cast<float>(length(p) - 4.3));
      }
    }
  }
  LayerSource source;
  source.user = &field;
  source.fill = [](void* user, uint32_t z0, uint32_t z1, Span<float> out) {
    const Field& f = *static_cast<Field*>(user);
    const size_t layer = size_t{f.grid.nx} * f.grid.ny;
    std::memcpy(out.data(), f.values.data() + layer * z0, layer * (z1 - z0) * sizeof(float));
    return Status::ok();
  };
  MarchingCubesOptions mco;
  mco.layers_per_tile = 3;  // several tiles
  sweep("marching_cubes_mesh", [&](Arena& a) {
    OpRun r;
    Mesh m(&a);
    r.status = marching_cubes_mesh(Context(&a), field.grid, source, mco, &m);
    r.outputs_empty = mesh_empty(m);
    if (r.status.is_ok()) append_mesh(&r.output, m);
    return r;
  });
  sweep("marching_cubes (visitor)", [&](Arena& a) {
    OpRun r;
    std::vector<Triangle> triangles;
    MarchingCubesVisitor visitor;
    visitor.user = &triangles;
    visitor.triangle = [](void* user, const Triangle& t, const Vec3&, const Vec3&, const Vec3&) {
      static_cast<std::vector<Triangle>*>(user)->push_back(t);
      return Status::ok();
    };
    r.status = marching_cubes(Context(&a), field.grid, source, mco, visitor);
    if (r.status.is_ok()) append_bytes(&r.output, triangles.data(), triangles.size());
    return r;
  });
}

TEST(ExhaustionSweep, BooleanPrinterAndDesign) {
  HeldMesh a_box(box_soup(0, 2));
  HeldMesh b_box(box_soup(1, 3));
  HeldMesh torus(torus_soup());
  for (BooleanOp op : {BooleanOp::kDifference, BooleanOp::kUnion, BooleanOp::kIntersection}) {
    const std::string name = std::string("mesh_boolean cube ") + boolean_op_name(op) + " cube";
    sweep(name.c_str(), [&](Arena& a) {
      OpRun r;
      Mesh out;
      BooleanOptions bo;
      bo.op = op;
      BooleanStats stats;
      r.status = mesh_boolean(Context(&a), a_box.mesh, b_box.mesh, bo, &out, &stats);
      r.outputs_empty = mesh_empty(out);
      if (r.status.is_ok()) append_mesh(&r.output, out);
      return r;
    });
  }
  // A slab minus the torus: the tube (radius 3 around the ring of radius 10 in z = 0) crosses
  // the slab's faces z = -1, z = 1, x = 4 and y = 4 (many cut triangles). (Until 2026-12-08
  // the box was the cube [4, 14]^3, clear of the torus: no triangle was cut.)
  const float slab_lo[3] = {4, 4, -1}, slab_hi[3] = {14, 14, 1};
  HeldMesh big_box(shapes::box(slab_lo, slab_hi));
  sweep("mesh_boolean slab - torus", [&](Arena& a) {
    OpRun r;
    Mesh out;
    BooleanStats stats;
    r.status = mesh_boolean(Context(&a), big_box.mesh, torus.mesh, BooleanOptions{}, &out, &stats);
    EXPECT_TRUE(!r.status.is_ok() || (stats.cut_triangles_a > 0 && stats.cut_triangles_b > 0))
        << "the torus cuts no triangle";
    r.outputs_empty = mesh_empty(out);
    if (r.status.is_ok()) append_mesh(&r.output, out);
    return r;
  });
  sweep("check_printable", [&](Arena& a) {
    OpRun r;
    PrintCheck check;
    r.status =
        check_printable(Context(&a), torus.mesh, eden260_profile(), PrintCheckOptions{}, &check);
    if (r.status.is_ok()) {
      append_bytes(&r.output, &check.layers, 1);
      append_bytes(&r.output, &check.extent, 1);
    }
    return r;
  });
  {
    std::vector<KeyIndex> items;
    for (uint32_t i = 0; i < 300; ++i) {
      items.push_back(KeyIndex{hash_mix(i % 37), i, 0});
    }
    sweep("radix_sort", [&](Arena& a) {
      OpRun r;
      std::vector<KeyIndex> copy = items;
      r.status = radix_sort(a, Span<KeyIndex>(copy.data(), copy.size()));
      if (r.status.is_ok()) append_bytes(&r.output, copy.data(), copy.size());
      return r;
    });
  }
  {
    const std::string path = std::string(SPLINTCORE_FIXTURES_DIR) + "/stl/tetra_ascii.stl";
    sweep("read_file", [&](Arena& a) {
      OpRun r;
      Span<uint8_t> bytes;
      r.status = read_file(a, path.c_str(), 1 << 20, &bytes);
      r.outputs_empty = bytes.empty();
      if (r.status.is_ok()) append_bytes(&r.output, bytes.data(), bytes.size());
      return r;
    });
  }
}

// fixtures/cases/paper_scale.json with the phantom's jaws of 2,000 triangles each.
struct PaperScaleCase {
  test::TestArena held{size_t{64} << 20};
  CaseFile c;
  Mesh jaws[2];
  PaperScaleCase() {
    const std::vector<uint8_t> text = fixture("cases/paper_scale.json");
    static std::vector<uint8_t> kept;  // the case's strings point into its text
    kept = text;
    SPLINTCORE_EXPECT_OK(parse_case(Context(&held.arena),
                                    reinterpret_cast<const char*>(kept.data()), kept.size(),
                                    "paper_scale", &c));
    EXPECT_TRUE(test::phantom_jaw_meshes(held.arena, phantom::kMinTriangles, jaws));
  }
  OpRun design(Arena& a, const CaseFile& with, DesignReport* report) const {
    OpRun r;
    Mesh splint;
    r.status = design_splint(Context(&a), with, Span<const Mesh>(jaws, 2), &splint, report);
    r.outputs_empty = mesh_empty(splint);
    if (r.status.is_ok()) append_mesh(&r.output, splint);
    return r;
  }
};

TEST(ExhaustionSweep, DesignSplintPaperScaleSmallPhantom) {
  const PaperScaleCase p;
  sweep("design_splint (paper_scale, 2x2000)", [&](Arena& a) {
    DesignReport report;
    return p.design(a, p.c, &report);
  });
}

// The height-field design of the phantom (its base sunk 2.5 mm, so that the blockout cuts and
// its Boolean checks itself), and its spacer (a 0.3 mm clearance), in 64 KiB blocks, each
// request refused in turn; where the design has another way it is the swept surface not kept
// for a second run or the Boolean's batches. (It found move_mesh_down copying into a block the
// allocator had refused: a crash.)
TEST(ExhaustionSweep, HeightfieldDesignWithEachBlockRequestRefused) {
  const PaperScaleCase p;
  CaseFile c = p.c;
  std::vector<Pick> up(c.upper.begin(), c.upper.end()), lo(c.lower.begin(), c.lower.end());
  for (Pick& k : up) k.position = k.position + c.occlusal_normal * 2.5;
  for (Pick& k : lo) k.position = k.position - c.occlusal_normal * 2.5;
  c.upper = Span<const Pick>(up.data(), up.size());
  c.lower = Span<const Pick>(lo.data(), lo.size());
  c.has_blockout = true;
  c.blockout_method = BlockoutMethod::kHeightfield;
  c.blockout.voxel = 0.3;
  c.blockout.inset = 0;
  for (double offset : {0.0, 0.3}) {  // the blockout, then the spacer (a clearance)
    c.blockout.offset = offset;
    DesignReport report;
    const auto design = [&](Arena& a) { return p.design(a, c, &report); };
    {
      test::TestArena once(size_t{256} << 20);
      SPLINTCORE_ASSERT_OK(design(once.arena).status);
    }
    ASSERT_GT(report.blockout[0].swept_triangles + report.blockout[1].swept_triangles, 0u);
    ASSERT_TRUE(report.blockout[0].boolean.self_intersection_checked ||
                report.blockout[1].boolean.self_intersection_checked);
    EXPECT_GT(
        refuse_each_block_request(offset > 0 ? "height-field spacer design" : "height-field design",
                                  size_t{64} << 10, design),
        0u);
  }
}

// The weld of a file whose corners are all distinct: its positions outgrow their reserve and
// move down over the table at the end, a move that in 4 KiB blocks needs a block of its own
// (before 2026-12-06 a refused one was an assertion: the process ended).
TEST(ExhaustionSweep, WeldOfScatteredCornersWithEachBlockRequestRefused) {
  std::vector<SoupTriangle> apart;
  for (int copy = 0; copy < 8; ++copy) {
    for (SoupTriangle t : torus_soup()) {
      for (auto& corner : t.p) corner[0] += 64.0f * static_cast<float>(apart.size());
      apart.push_back(t);
    }
  }
  const std::vector<uint8_t> file = test::binary_stl(apart, "apart");
  EXPECT_GT(refuse_each_block_request("read_stl_mesh (no shared corner)", 4096,
                                      [&](Arena& a) {
                                        OpRun r;
                                        MemorySource ms{file.data(), file.size(), 0, 0};
                                        Mesh m(&a);
                                        r.status = read_stl_mesh(Context(&a), memory_source(&ms),
                                                                 StlReadOptions{}, &m, nullptr);
                                        r.outputs_empty = mesh_empty(m);
                                        if (r.status.is_ok()) append_mesh(&r.output, m);
                                        return r;
                                      }),
            0u);
}

}  // namespace
}  // namespace splintcore
