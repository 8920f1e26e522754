// The helpers of the memory-contract tests (bound_exact_test.cpp, bound_inputs_test.cpp): the
// inputs every sizing function is tried on, a run in an arena of exactly a bound, and the
// two-step contract (a first run's high water, then exactly that).
#ifndef SPLINTCORE_TESTS_BOUND_UTIL_H
#define SPLINTCORE_TESTS_BOUND_UTIL_H

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "common/realcase.h"
#include "common/shapes.h"
#include "splintcore/mesh.h"
#include "support/test_util.h"

namespace splintcore {
namespace bound_test {

using test::format;
using test::TestArena;

struct Input {
  std::string name;
  std::vector<SoupTriangle> soup;
  bool large = false;  // the bound must be within 3x of the need
};

inline SoupTriangle tri(float ax, float ay, float az, float bx, float by, float bz, float cx,
                        float cy, float cz) {
  const float a[3] = {ax, ay, az}, b[3] = {bx, by, bz}, c[3] = {cx, cy, cz};
  return shapes::soup_triangle(a, b, c);
}

inline std::vector<SoupTriangle> tetrahedron() {
  return {tri(0, 0, 0, 0, 1, 0, 1, 0, 0), tri(0, 0, 0, 1, 0, 0, 0, 0, 1),
          tri(0, 0, 0, 0, 0, 1, 0, 1, 0), tri(1, 0, 0, 0, 1, 0, 0, 0, 1)};
}

// The triangles of an indexed mesh appended to a soup (float32 corners, as STL holds them).
inline void append_soup(const std::vector<Vec3>& vertices, const std::vector<Triangle>& triangles,
                        std::vector<SoupTriangle>* soup) {
  for (const Triangle& t : triangles) {
    SoupTriangle st;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = vertices[t.v[k]];
      for (int a = 0; a < 3; ++a) st.p[k][a] = static_cast<float>(p[a]);
    }
    soup->push_back(st);
  }
}

inline std::vector<Input> inputs() {
  std::vector<Input> out;
  out.push_back({"tetrahedron", tetrahedron()});
  {
    // Every fault check_mesh counts: a duplicate, a flat and a collapsed triangle, a fin on
    // an edge (non-manifold), a flipped copy (orientation conflict) and a loose triangle.
    std::vector<SoupTriangle> s = tetrahedron();
    s.push_back(s[1]);
    s.push_back(tri(0, 0, 0, 0.5f, 0, 0, 1, 0, 0));
    s.push_back(tri(2, 2, 2, 2, 2, 2, 2, 2, 2));
    s.push_back(tri(0, 0, 0, 1, 0, 0, 0.5f, -1, 0.5f));
    s.push_back(tri(0, 1, 0, 0, 0, 0, 1, 0, 0));
    s.push_back(tri(5, 5, 5, 6, 5, 5, 5, 6, 5));
    out.push_back({"degenerate", s});
  }
  out.push_back({"one_triangle", {tri(0, 0, 0, 1, 0, 0, 0, 1, 0)}});
  {
    std::vector<SoupTriangle> s = shapes::torus(40, 20, 10.0, 3.0);
    s.resize(s.size() - 37);  // open: a ragged hole
    out.push_back({"open_torus", s});
  }
  out.push_back({"torus_87k", shapes::torus(360, 121, 20.0, 6.0), true});
  {
    phantom::PhantomOptions po;
    po.target_triangles = 6000;
    phantom::JawMesh jaw;
    if (phantom::make_jaw(phantom::Jaw::kMaxilla, po, &jaw).is_ok()) {
      std::vector<SoupTriangle> s;
      append_soup(jaw.vertices, jaw.triangles, &s);
      out.push_back({"phantom_maxilla_6000", s, true});
    }
  }
#if !defined(SPLINTCORE_TEST_SANITIZED)
  // Not under the sanitizers (CI's asan job), which leave out the real dentition's tests for
  // their time (tools/test.sh: realdata_tests): there the 887k triangles made each of these
  // tests take 9-43 s. The g++ -O2 job runs them on it.
  realcase::RealCase rc;
  std::string error;
  if (realcase::load(SPLINTCORE_REALDATA_DIR, 0.0, 2.0, 8.0, &rc, &error)) {
    std::vector<SoupTriangle> s;
    for (const realcase::Tooth& t : rc.teeth) append_soup(t.vertices, t.triangles, &s);
    out.push_back({"real_dentition", s, true});
  }
#endif
  return out;
}

// Runs `run` in an arena of exactly `bound` bytes: it must not run out, and on a large input
// it must need at least a third of the bound.
template <class Run>
void expect_fits(const Input& in, const char* function, uint64_t bound, Run run) {
  SCOPED_TRACE(std::string(function) + " on " + in.name);
  ASSERT_GT(bound, 0u);
  TestArena ta(static_cast<size_t>(bound));
  const Status s = run(ta.arena);
  EXPECT_NE(s.code(), StatusCode::kArenaExhausted) << format(s) << " (bound " << bound << ")";
  EXPECT_EQ(ta.arena.cap(), bound);
  std::printf("%-22s %-28s bound %11llu need %11llu (%.2f)%s\n", function, in.name.c_str(),
              static_cast<unsigned long long>(bound),
              static_cast<unsigned long long>(ta.arena.high_water()),
              static_cast<double>(ta.arena.high_water()) / static_cast<double>(bound),
              s.is_ok() ? "" : (std::string("  [") + format(s) + "]").c_str());
  if (in.large && s.is_ok()) {
    EXPECT_GE(ta.arena.high_water() * 3, bound);
  }
}

// The welded mesh of an input, in its own arena (outside the one under test).
struct Welded {
  TestArena storage{size_t{512} << 20};
  Mesh mesh;
  explicit Welded(const Input& in) {
    mesh.bind(&storage.arena);
    Status s = weld_exact(Context(&storage.arena),
                          Span<const SoupTriangle>(in.soup.data(), in.soup.size()), &mesh);
    EXPECT_TRUE(s.is_ok()) << format(s);
  }
  uint64_t v() const { return mesh.vertices.size(); }
  uint64_t t() const { return mesh.triangles.size(); }
};

// The two-step contract of the functions without an a-priori bound (embedding.md): a first
// run in any arena large enough gives the need, the arena's high water; the same input then
// runs in exactly that many bytes, and fails cleanly in one byte less. Allocation depends on
// the input alone, so the need measured once (on a workstation) holds on the device.
// `minimal`: the need is also the least that works (one byte less fails). A reader whose arrays
// grow by half again when the arena has room (OBJ) can get by with less than a generous first
// run took: its need is then enough, and one byte less either works or fails cleanly.
// `result` (set by each run): for the functions whose self-intersection check goes in slabs
// when the whole pass does not fit (mesh.h), one byte less either fails cleanly or gives the
// same result.
template <class Run>
void expect_two_step(const char* function, const char* input, Run run, bool minimal = true,
                     const std::string* result = nullptr) {
  SCOPED_TRACE(std::string(function) + " on " + input);
  uint64_t need = 0;
  std::string want;
  {
    TestArena big(size_t{1} << 30);
    SPLINTCORE_ASSERT_OK(run(big.arena));
    need = big.arena.high_water();
    if (result != nullptr) want = *result;
  }
  {
    TestArena exact(static_cast<size_t>(need));
    SPLINTCORE_EXPECT_OK(run(exact.arena));
    EXPECT_EQ(exact.arena.high_water(), need);
    if (result != nullptr) {
      EXPECT_EQ(*result, want);
    }
  }
  bool less_works = false;
  {
    TestArena short_by_one(static_cast<size_t>(need - 1));
    const Status s = run(short_by_one.arena);
    less_works = s.is_ok();
    if (less_works && result != nullptr) {
      EXPECT_EQ(*result, want) << "one byte less: the same result";
    } else if (minimal || !less_works) {
      EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << format(s);
      EXPECT_EQ(short_by_one.arena.used(), 0u) << "the arena is as it was";
    }
  }
  std::printf("%-22s %-34s need %11llu bytes, %s\n", function, input,
              static_cast<unsigned long long>(need),
              less_works ? (result != nullptr ? "enough (less works: the same result)" : "enough")
                         : "exactly enough");
}

}  // namespace bound_test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_BOUND_UTIL_H
