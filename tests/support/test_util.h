// Helpers for the tests (test code may use the standard containers; the core may not).
#ifndef SPLINTCORE_TESTS_TEST_UTIL_H
#define SPLINTCORE_TESTS_TEST_UTIL_H

#include <gtest/gtest.h>

// AddressSanitizer (g++ defines __SANITIZE_ADDRESS__, clang++ has the feature).
#if defined(__SANITIZE_ADDRESS__)
#define SPLINTCORE_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SPLINTCORE_TEST_ASAN 1
#endif
#endif
#if defined(SPLINTCORE_TEST_ASAN)
#include <sanitizer/asan_interface.h>
#include <sys/mman.h>

#include <cstdlib>
#endif

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "common/shapes.h"
#include "splintcore/core.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"

#include <sys/resource.h>
#include <unistd.h>

#include <csignal>

namespace splintcore {
namespace test {

// Allocator hooks (an arena of blocks) that refuse the block request numbered fail_at
// (0-based; -1: none) and count the requests and the bytes still out (0 once the arena is
// gone: every block given back).
struct FailNthBlock {
  int64_t calls = 0;
  int64_t fail_at = -1;
  int64_t outstanding = 0;
  static void* allocate(void* user, size_t bytes) {
    FailNthBlock* f = static_cast<FailNthBlock*>(user);
    if (f->calls++ == f->fail_at) return nullptr;
    f->outstanding += static_cast<int64_t>(bytes);
    return ::operator new (bytes, std::align_val_t{16});
  }
  static void release(void* user, void* pointer, size_t bytes) {
    static_cast<FailNthBlock*>(user)->outstanding -= static_cast<int64_t>(bytes);
    ::operator delete (pointer, std::align_val_t{16});
  }
  AllocatorHooks hooks() {
    AllocatorHooks h;
    h.allocate = &FailNthBlock::allocate;
    h.release = &FailNthBlock::release;
    h.user = this;
    return h;
  }
};

// For its lifetime, files this process writes are limited to `bytes` (RLIMIT_FSIZE, as a
// full disk: a write past it fails with EFBIG) and SIGXFSZ is ignored, as
// remove_temporary_outputs_on_signals() has the tools do; both as they were afterwards.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) : previous_(std::signal(SIGXFSZ, SIG_IGN)) {
    EXPECT_EQ(getrlimit(RLIMIT_FSIZE, &saved_), 0);
    rlimit small = saved_;
    small.rlim_cur = bytes;
    EXPECT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  }
  ~FileSizeLimit() {
    EXPECT_EQ(setrlimit(RLIMIT_FSIZE, &saved_), 0);
    std::signal(SIGXFSZ, previous_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  void (*previous_)(int);
  rlimit saved_{};
};

// A fresh folder in the system's temporary folder (splintcore_PREFIX_NAME_PID), removed with
// everything in it when the test is done.
struct TempDir {
  std::filesystem::path path;
  TempDir(const char* prefix, const char* name) {
    path = std::filesystem::temp_directory_path() /
           (std::string("splintcore_") + prefix + "_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

// Sweeps over every cut or cap of an input, and long random properties, take every
// kSweepStep-th point under the sanitizers (CI's asan job, SPLINTCORE_TEST_SANITIZED): the
// instrumented runs are 5-10x slower, and every other job runs each point. The first and last
// points are always among those taken where a test says so.
#if defined(SPLINTCORE_TEST_SANITIZED)
constexpr size_t kSweepStep = 5;
#else
constexpr size_t kSweepStep = 1;
#endif

// An arena over a heap buffer owned by the test.
// The buffer is not zeroed (nothing may depend on arena contents), so a large cap costs
// nothing until it is touched. Nor is it left as the system hands it out, which for a large
// buffer is a fresh mapping, all zeros: the first time the arena reaches a stretch of it, the
// stretch is filled with 0xA5 bytes (a touch hook, scribble()), so that code reading memory it
// never wrote (a count it did not clear) fails here as it would for an embedder whose arena
// still holds the last job's data. It is 16-byte aligned (Arena::kDefaultAlignment): plain new[]
// gives only 8 on 32-bit ARM (glibc armhf), which would add padding to used()/high_water()
// and make the exact-accounting tests differ from x86-64.
// The buffer is aligned to a cache line, the largest alignment any allocation asks for
// (alignas(64) in decimate.cpp): then the padding, and so high_water(), is the same wherever
// the buffer lands, and a cap taken from one arena's high water fits another's exactly.
struct TestArena {
  static constexpr size_t kAlign = Arena::kDefaultAlignment > 64 ? Arena::kDefaultAlignment : 64;
#if defined(SPLINTCORE_TEST_ASAN)
  // Under AddressSanitizer the buffer is mapped, not taken from the heap: ASan writes the shadow
  // of a whole heap block when it is allocated and again when it is freed (a 1 GiB arena: 256 MB
  // of shadow), which made BoundTwoStep.ReadPlyObj take 43 s of CPU for 1.3 s of work. A
  // poisoned page after the buffer still catches a write past its end.
  static constexpr size_t kGuard = 4096;
  struct Free {
    size_t bytes = 0;
    void operator()(unsigned char* p) const {
      ASAN_UNPOISON_MEMORY_REGION(p + bytes, kGuard);
      munmap(p, bytes + kGuard);
    }
  };
  static unsigned char* allocate(size_t bytes) {
    void* p = mmap(nullptr, bytes + kGuard, PROT_READ | PROT_WRITE,
                   MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (p == MAP_FAILED) std::abort();
    unsigned char* b = static_cast<unsigned char*>(p);
    ASAN_POISON_MEMORY_REGION(b + bytes, kGuard);
    return b;
  }
#else
  struct Free {
    size_t bytes = 0;
    void operator()(unsigned char* p) const { ::operator delete[](p, std::align_val_t{kAlign}); }
  };
  static unsigned char* allocate(size_t bytes) {
    return static_cast<unsigned char*>(::operator new[](bytes, std::align_val_t{kAlign}));
  }
#endif
  std::unique_ptr<unsigned char[], Free> buffer;
  Arena arena;
  explicit TestArena(size_t bytes = size_t{256} << 20)
      : buffer(allocate(bytes > 0 ? bytes : 1), Free{bytes > 0 ? bytes : 1}),
        arena(buffer.get(), bytes) {
    TouchHook hook;
    hook.touch = &scribble;
    hook.step = 4096;
    arena.set_touch_hook(hook);
  }
  // The touch hook: arena memory never handed out before, about to be.
  static void scribble(void*, void* begin, size_t bytes) { std::memset(begin, 0xA5, bytes); }
};

inline std::string format(const Status& s) {
  char text[1024];
  s.format(text, sizeof(text));
  return text;
}

#define SPLINTCORE_EXPECT_OK(expr)                               \
  do {                                                           \
    ::splintcore::Status st_ = (expr);                           \
    EXPECT_TRUE(st_.is_ok()) << ::splintcore::test::format(st_); \
  } while (0)
#define SPLINTCORE_ASSERT_OK(expr)                               \
  do {                                                           \
    ::splintcore::Status st_ = (expr);                           \
    ASSERT_TRUE(st_.is_ok()) << ::splintcore::test::format(st_); \
  } while (0)

inline void put_u32(std::vector<uint8_t>& out, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) out[at + static_cast<size_t>(i)] = static_cast<uint8_t>(v >> (8 * i));
}
inline void put_f32(std::vector<uint8_t>& out, size_t at, float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  put_u32(out, at, bits);
}

// A binary STL of the soup (zero normals), header text as given (may begin with "solid").
inline std::vector<uint8_t> binary_stl(const std::vector<SoupTriangle>& soup,
                                       const char* header = "test binary") {
  std::vector<uint8_t> out(84 + 50 * soup.size(), 0);
  std::memcpy(out.data(), header, std::strlen(header) < 80 ? std::strlen(header) : 80);
  put_u32(out, 80, static_cast<uint32_t>(soup.size()));
  for (size_t t = 0; t < soup.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) {
        put_f32(out, 84 + 50 * t + 12 + 12 * static_cast<size_t>(k) + 4 * static_cast<size_t>(a),
                soup[t].p[k][a]);
      }
    }
  }
  return out;
}

inline std::vector<uint8_t> to_bytes(const std::string& s) {
  return std::vector<uint8_t>(s.begin(), s.end());
}

// Reads STL bytes into a mesh (welded) in `arena`.
inline Status mesh_from_bytes(Arena& arena, const std::vector<uint8_t>& bytes, Mesh* mesh,
                              StlInfo* info = nullptr, size_t max_chunk = 0) {
  MemorySource ms{bytes.data(), bytes.size(), 0, max_chunk};
  Context ctx(&arena);
  mesh->bind(&arena);
  return read_stl_mesh(ctx, memory_source(&ms), StlReadOptions{}, mesh, info);
}

inline Status mesh_from_soup(Arena& arena, const std::vector<SoupTriangle>& soup, Mesh* mesh) {
  Context ctx(&arena);
  mesh->bind(&arena);
  return weld_exact(ctx, Span<const SoupTriangle>(soup.data(), soup.size()), mesh);
}

// Writes a mesh to bytes in memory.
inline Status mesh_to_bytes(Arena& arena, const Mesh& mesh, StlFormat format,
                            std::vector<uint8_t>* out) {
  out->assign(84 + 400 * mesh.triangles.size() + 4096, 0);
  MemorySink sink{out->data(), out->size(), 0, 0};
  Context ctx(&arena);
  StlWriteOptions wo;
  wo.format = format;
  Status s = write_stl(ctx, mesh, memory_sink(&sink), wo);
  out->resize(static_cast<size_t>(sink.size));
  return s;
}

// A sink that appends what it is given to *out.
inline ByteSink string_sink(std::string* out) {
  ByteSink sink;
  sink.user = out;
  sink.write = [](void* user, const uint8_t* data, size_t n) {
    static_cast<std::string*>(user)->append(reinterpret_cast<const char*>(data), n);
    return true;
  };
  return sink;
}

inline std::string sha256_hex(const void* data, size_t n) {
  Sha256 sha;
  sha.update(data, n);
  uint8_t digest[32];
  sha.finish(digest);
  char hex[65];
  Sha256::to_hex(digest, hex);
  return hex;
}

// A mesh's bytes, vertices then triangles, as two digests (for "the same result" checks).
inline std::string mesh_sha256(const Mesh& m) {
  return sha256_hex(m.vertices.data(), m.vertices.size() * sizeof(Vec3)) +
         sha256_hex(m.triangles.data(), m.triangles.size() * sizeof(Triangle));
}

// A copy of `from` in `arena` (e.g. the real jaws moved into a small arena that must also hold
// them); false when the arena is exhausted.
inline bool copy_mesh(Arena& arena, const Mesh& from, Mesh* to) {
  to->bind(&arena);
  if (!to->vertices.resize(from.vertices.size()) || !to->triangles.resize(from.triangles.size())) {
    return false;
  }
  std::copy(from.vertices.begin(), from.vertices.end(), to->vertices.begin());
  std::copy(from.triangles.begin(), from.triangles.end(), to->triangles.begin());
  return true;
}

// `from`'s vertices and triangles appended to `to` (its vertex ids moved past `to`'s
// vertices): several meshes as one; false when `to`'s arena is exhausted.
inline bool append_mesh_to(const Mesh& from, Mesh* to) {
  const uint32_t base = static_cast<uint32_t>(to->vertices.size());
  for (const Vec3& p : from.vertices) {
    if (!to->vertices.push_back(p)) return false;
  }
  for (const Triangle& t : from.triangles) {
    if (!to->triangles.push_back(Triangle{{t.v[0] + base, t.v[1] + base, t.v[2] + base}})) {
      return false;
    }
  }
  return true;
}

// The bytes a kArenaExhausted status in an arena of `cap` bytes names as its need: the
// remedy's "to at least N bytes" (the arena's and marching cubes' messages end with "increase
// the memory cap to at least N bytes"), else "need N bytes" -> N; marching cubes' id pool names
// the increase instead ("increase the memory cap by at least N bytes") -> cap + N. 0 when the
// message names none.
inline uint64_t need_of(const Status& s, uint64_t cap) {
  const std::string m = s.message();
  for (const std::string tag : {"to at least ", "need "}) {
    const size_t at = m.rfind(tag);
    if (at != std::string::npos) return std::strtoull(m.c_str() + at + tag.size(), nullptr, 10);
  }
  const size_t by = m.rfind("by at least ");
  if (by != std::string::npos) return cap + std::strtoull(m.c_str() + by + 12, nullptr, 10);
  return 0;
}

// What a run at caps below its ample peak did (expect_clean_or_same).
struct CapsTried {
  int tried = 0;
  int failed = 0;
  size_t first_success = 0;  // the first cap that worked, 0 if none did
};

// Runs `run(arena, &mesh)` in an arena of each cap of `caps` (ascending, each below the ample
// run's peak). Each run must fail cleanly (kArenaExhausted, the arena as it was, no triangles)
// or, where a stage works in less when it must (the self-intersection check in slabs, the
// Boolean's hits in batches), give the ample run's mesh (mesh_sha256 `want`); once a cap works,
// every larger one must.
template <class Run>
CapsTried expect_clean_or_same(const std::vector<size_t>& caps, const std::string& want, Run run) {
  CapsTried c;
  for (const size_t cap : caps) {
    std::vector<unsigned char> buf(cap + 1);
    Arena small(buf.data(), cap);
    Mesh out;
    const Status s = run(small, &out);
    ++c.tried;
    if (s.is_ok()) {
      if (c.first_success == 0) c.first_success = cap;
      EXPECT_EQ(mesh_sha256(out), want) << "cap " << cap;
      continue;
    }
    ++c.failed;
    EXPECT_EQ(c.first_success, 0u)
        << "failed at " << cap << " after working at " << c.first_success;
    EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << "cap " << cap << ": " << format(s);
    EXPECT_EQ(small.used(), 0u) << "cap " << cap;
    EXPECT_TRUE(out.triangles.empty()) << "cap " << cap;
  }
  return c;
}

// A run with room to spare: its arena peak and its mesh's mesh_sha256 (what the runs at the
// caps below the peak are held to by expect_clean_or_same); `ok` false if it failed.
struct AmpleRun {
  bool ok = false;
  size_t peak = 0;
  std::string sha;
};
template <class Run>
AmpleRun ample_run(size_t bytes, Run run) {
  std::vector<unsigned char> big(bytes);
  Arena probe(big.data(), big.size());
  Mesh out;
  AmpleRun a;
  const Status s = run(probe, &out);
  EXPECT_TRUE(s.is_ok()) << format(s);
  a.ok = s.is_ok();
  a.peak = probe.high_water();
  a.sha = mesh_sha256(out);
  return a;
}

// 0, step, 2 step... up to but not including `end`.
inline std::vector<size_t> caps_below(size_t end, size_t step) {
  std::vector<size_t> caps;
  for (size_t cap = 0; cap < end; cap += step) caps.push_back(cap);
  return caps;
}

inline std::vector<uint8_t> read_file_bytes(const std::string& path) {
  std::vector<uint8_t> out;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return out;
  uint8_t buf[65536];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof(buf), f)) > 0) out.insert(out.end(), buf, buf + n);
  std::fclose(f);
  return out;
}

inline bool file_exists(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return false;
  std::fclose(f);
  return true;
}

#ifdef SPLINTCORE_FIXTURES_DIR
// fixtures/golden.sha256 as key -> hash (lines "HASH  KEY"; '#' lines and blank lines skipped).
inline std::map<std::string, std::string> golden_hashes() {
  std::map<std::string, std::string> out;
  std::ifstream in(std::string(SPLINTCORE_FIXTURES_DIR) + "/golden.sha256");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string hash, key;
    fields >> hash >> key;
    out[key] = hash;
  }
  return out;
}

// The committed hash of one key ("" when the key is not there).
inline std::string golden_hash(const std::string& key) {
  const std::map<std::string, std::string> all = golden_hashes();
  const auto it = all.find(key);
  return it == all.end() ? std::string() : it->second;
}
#endif

// Two mesh reports' topology the same: edges, borders, shells, Euler characteristic, genus, and
// the first offending edges (and the first duplicate, when there is one).
inline void expect_same_topology(const MeshReport& got, const MeshReport& want) {
  EXPECT_EQ(got.edge_count, want.edge_count);
  EXPECT_EQ(got.boundary_edges, want.boundary_edges);
  EXPECT_EQ(got.nonmanifold_edges, want.nonmanifold_edges);
  EXPECT_EQ(got.orientation_conflicts, want.orientation_conflicts);
  EXPECT_EQ(got.duplicate_triangles, want.duplicate_triangles);
  EXPECT_EQ(got.shells, want.shells);
  EXPECT_EQ(got.euler_characteristic, want.euler_characteristic);
  EXPECT_EQ(got.genus, want.genus);
  const EdgeRef* g[3] = {&got.first_boundary_edge, &got.first_nonmanifold_edge,
                         &got.first_orientation_conflict};
  const EdgeRef* w[3] = {&want.first_boundary_edge, &want.first_nonmanifold_edge,
                         &want.first_orientation_conflict};
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(g[i]->v0, w[i]->v0) << i;
    EXPECT_EQ(g[i]->v1, w[i]->v1) << i;
    EXPECT_EQ(g[i]->triangle, w[i]->triangle) << i;
  }
  if (want.duplicate_triangles > 0) {
    EXPECT_EQ(got.first_duplicate_triangle, want.first_duplicate_triangle);
  }
}

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_TEST_UTIL_H
