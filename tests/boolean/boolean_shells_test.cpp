// Tests of B as the union of overlapping shells (src/boolean/boolean.cpp, issue 5): boxes with
// exact (dyadic) coordinates whose volumes are known by inclusion-exclusion, each result
// checked closed, manifold, outward and free of self-intersections, and compared with the
// same set computed a second way (the union of B's shells first); shells that overlap only
// where it does not matter; nesting; three shells; determinism; the arena at every cap; the
// real teeth when ../shared/realdata is present.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "common/realcase.h"
#include "splintcore/boolean.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "splintcore/platform.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

struct Box {
  Vec3 lo, hi;
};

double box_volume(const Box& b) {
  const double x = b.hi.x - b.lo.x, y = b.hi.y - b.lo.y, z = b.hi.z - b.lo.z;
  return x > 0 && y > 0 && z > 0 ? x * y * z : 0.0;
}

Box meet(const Box& a, const Box& b) { return Box{max_vec(a.lo, b.lo), min_vec(a.hi, b.hi)}; }

// |b0 u b1 u ... | by inclusion-exclusion over every subset.
double union_volume(const std::vector<Box>& boxes) {
  double total = 0;
  const size_t n = boxes.size();
  for (size_t mask = 1; mask < (size_t{1} << n); ++mask) {
    Box m{{-1e300, -1e300, -1e300}, {1e300, 1e300, 1e300}};
    int bits = 0;
    for (size_t i = 0; i < n; ++i) {
      if ((mask >> i & 1) == 0) continue;
      m = meet(m, boxes[i]);
      ++bits;
    }
    total += (bits % 2 == 1 ? 1.0 : -1.0) * box_volume(m);
  }
  return total;
}

// Appends a closed outward box shell to m.
void add_box(const Box& b, Mesh* m) {
  const uint32_t off = static_cast<uint32_t>(m->vertices.size());
  for (int i = 0; i < 8; ++i) {
    const Vec3 p{(i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z};
    ASSERT_TRUE(m->vertices.push_back(p));
  }
  const uint32_t f[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                             {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  for (const auto& t : f) {
    ASSERT_TRUE(m->triangles.push_back(Triangle{{t[0] + off, t[1] + off, t[2] + off}}));
  }
}

Mesh boxes_mesh(Arena& arena, const std::vector<Box>& boxes) {
  Mesh m(&arena);
  for (const Box& b : boxes) add_box(b, &m);
  return m;
}

struct Outcome {
  Status status;
  BooleanStats stats;
  double volume = 0;
  std::vector<uint8_t> bytes;  // vertices then triangles
};

// Runs the operation and checks what every result must be: a valid solid (closed,
// edge-manifold, oriented, outward, nothing degenerate), no self-intersection.
Outcome run(Arena& arena, const Mesh& a, const Mesh& b, BooleanOp op, bool float32 = false) {
  ArenaScope scope(arena);
  const size_t used = arena.used();
  Outcome r;
  BooleanOptions o;
  o.op = op;
  o.float32_output = float32;
  Mesh out;
  r.status = mesh_boolean(Context(&arena), a, b, o, &out, &r.stats);
  if (!r.status.is_ok()) {
    EXPECT_EQ(arena.used(), used) << "the arena is as it was after an error";
    EXPECT_TRUE(out.triangles.empty() && out.vertices.empty());
    return r;
  }
  MeshReport rep;
  EXPECT_TRUE(check_mesh(Context(&arena), out, &rep).is_ok());
  EXPECT_TRUE(rep.is_valid_solid()) << test::format(require_valid_solid(rep));
  SelfIntersectionReport si;
  EXPECT_TRUE(find_self_intersections(Context(&arena), out, 1, &si).is_ok());
  EXPECT_FALSE(si.self_intersecting()) << si.first_a << " " << si.first_b;
  r.volume = rep.volume;
  const uint8_t* v = reinterpret_cast<const uint8_t*>(out.vertices.data());
  const uint8_t* t = reinterpret_cast<const uint8_t*>(out.triangles.data());
  r.bytes.assign(v, v + out.vertices.size() * sizeof(Vec3));
  r.bytes.insert(r.bytes.end(), t, t + out.triangles.size() * sizeof(Triangle));
  return r;
}

// B's shells united first (one shell), then op with A: the second way to the same set.
Outcome second_way(Arena& arena, const Mesh& a, const std::vector<Box>& shells, BooleanOp op) {
  ArenaScope scope(arena);
  Mesh u(&arena);
  add_box(shells[0], &u);
  for (size_t i = 1; i < shells.size(); ++i) {
    Mesh next = boxes_mesh(arena, {shells[i]});
    BooleanOptions o;
    o.op = BooleanOp::kUnion;
    o.float32_output = false;
    Mesh joined;
    BooleanStats st;
    const Status s = mesh_boolean(Context(&arena), u, next, o, &joined, &st);
    EXPECT_TRUE(s.is_ok()) << test::format(s);
    if (!s.is_ok()) return Outcome{s, {}, 0, {}};
    EXPECT_EQ(st.passes, 1u);
    u = joined;
  }
  Outcome r = run(arena, a, u, op);
  EXPECT_EQ(r.stats.shells, 1u);
  return r;
}

void expect_volume(double got, double want) {
  EXPECT_NEAR(got / want, 1.0, 1e-9) << "got " << got << ", want " << want;
}

const Box kA{{0, 0, 0}, {4, 4, 4}};
// Two boxes inside A that overlap each other (no face of one in a plane of the other's, none
// in a plane of A's).
const Box kB1{{0.515625, 0.578125, 0.546875}, {2.453125, 1.609375, 1.484375}};
const Box kB2{{1.640625, 0.796875, 0.265625}, {3.421875, 1.734375, 1.203125}};

TEST(BooleanShells, DifferenceOfTwoOverlappingBoxes) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  const Mesh b = boxes_mesh(arena, {kB1, kB2});
  const Outcome r = run(arena, a, b, BooleanOp::kDifference);
  ASSERT_TRUE(r.status.is_ok()) << test::format(r.status);
  EXPECT_EQ(r.stats.shells, 2u);
  EXPECT_EQ(r.stats.shell_groups, 2u);
  EXPECT_EQ(r.stats.passes, 2u);
  EXPECT_EQ(r.stats.attempts, 2u) << "no nudge: every contact is generic";
  expect_volume(r.volume, 64.0 - union_volume({kB1, kB2}));
  const Outcome w = second_way(arena, a, {kB1, kB2}, BooleanOp::kDifference);
  ASSERT_TRUE(w.status.is_ok()) << test::format(w.status);
  expect_volume(r.volume, w.volume);
}

// The first group takes all of A: the difference is empty, and the passes stop there (a next
// pass would have nothing to take from; it used to fail, an empty mesh being no solid).
TEST(BooleanShells, DifferenceThatEmptiesAStopsEarly) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kB1});
  // Both shells hold A's box and overlap each other there.
  const Mesh b = boxes_mesh(arena, {kA, Box{{0.25, 0.25, 0.25}, {5, 5, 5}}});
  BooleanOptions o;
  o.float32_output = false;
  Mesh out;
  BooleanStats st;
  SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&arena), a, b, o, &out, &st));
  EXPECT_EQ(st.shell_groups, 2u);
  EXPECT_EQ(st.passes, 1u);
  EXPECT_EQ(out.triangles.size(), 0u);
}

TEST(BooleanShells, IntersectionOfTwoOverlappingBoxes) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  // B2 moved to cross A's face x = 4 (at y, z off A's face diagonals y = z, y = 4 - z).
  const Box b2{{1.640625, 0.796875, 0.265625}, {5.234375, 1.734375, 1.203125}};
  const Mesh b = boxes_mesh(arena, {kB1, b2});
  const Outcome r = run(arena, a, b, BooleanOp::kIntersection);
  ASSERT_TRUE(r.status.is_ok()) << test::format(r.status);
  EXPECT_EQ(r.stats.shell_groups, 2u);
  EXPECT_EQ(r.stats.passes, 2u);
  EXPECT_EQ(r.stats.attempts, 2u);
  expect_volume(r.volume, union_volume({kB1, meet(b2, kA)}));
  const Outcome w = second_way(arena, a, {kB1, b2}, BooleanOp::kIntersection);
  ASSERT_TRUE(w.status.is_ok()) << test::format(w.status);
  expect_volume(r.volume, w.volume);
  // |A - B| + |A * B| = |A|.
  const Outcome d = run(arena, a, b, BooleanOp::kDifference);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  expect_volume(d.volume + r.volume, 64.0);
}

TEST(BooleanShells, UnionOfTwoOverlappingBoxes) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  // Both cross A's face x = 4 and overlap each other inside and outside A.
  const Box b1{{3.265625, 1.140625, 1.640625}, {5.734375, 2.359375, 2.859375}};
  const Box b2{{2.765625, 1.890625, 2.109375}, {6.484375, 3.109375, 3.390625}};
  const Mesh b = boxes_mesh(arena, {b1, b2});
  const Outcome r = run(arena, a, b, BooleanOp::kUnion);
  ASSERT_TRUE(r.status.is_ok()) << test::format(r.status);
  EXPECT_EQ(r.stats.shell_groups, 2u);
  EXPECT_EQ(r.stats.passes, 2u);
  EXPECT_EQ(r.stats.attempts, 2u);
  expect_volume(r.volume, union_volume({kA, b1, b2}));
  const Outcome w = second_way(arena, a, {b1, b2}, BooleanOp::kUnion);
  ASSERT_TRUE(w.status.is_ok()) << test::format(w.status);
  expect_volume(r.volume, w.volume);
}

TEST(BooleanShells, OneShellInsideAnother) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  const Box outer{{0.5, 0.75, 0.625}, {3.25, 3.5, 3.375}};
  const Box inner{{1.125, 1.25, 1.375}, {2.25, 2.125, 2.625}};
  for (const std::vector<Box>& order :
       {std::vector<Box>{outer, inner}, std::vector<Box>{inner, outer}}) {
    const Mesh b = boxes_mesh(arena, order);
    const Outcome d = run(arena, a, b, BooleanOp::kDifference);
    ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
    EXPECT_EQ(d.stats.shell_groups, 2u) << "nesting is an overlap (winding number)";
    expect_volume(d.volume, 64.0 - box_volume(outer));
    const Outcome i = run(arena, a, b, BooleanOp::kIntersection);
    ASSERT_TRUE(i.status.is_ok()) << test::format(i.status);
    expect_volume(i.volume, box_volume(outer));
  }
}

TEST(BooleanShells, OverlapOnlyOutsideANeedsOnePassForTheDifference) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  const Box far1{{5.515625, 0.578125, 0.546875}, {7.453125, 1.609375, 1.484375}};
  const Box far2{{6.640625, 0.796875, 0.265625}, {8.421875, 1.734375, 1.203125}};
  const Mesh b = boxes_mesh(arena, {kB1, far1, far2});
  const Outcome d = run(arena, a, b, BooleanOp::kDifference);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  EXPECT_EQ(d.stats.shells, 3u);
  EXPECT_EQ(d.stats.shell_groups, 1u);
  EXPECT_EQ(d.stats.passes, 1u);
  expect_volume(d.volume, 64.0 - box_volume(kB1));
  // One group is the single run, which culls the far shells: the same bytes as B without them
  // (their vertices come after kB1's, so the output's numbering is the same).
  const Outcome alone = run(arena, a, boxes_mesh(arena, {kB1}), BooleanOp::kDifference);
  ASSERT_TRUE(alone.status.is_ok());
  EXPECT_EQ(alone.stats.shells, 1u);
  EXPECT_EQ(d.bytes, alone.bytes);
  const Outcome i = run(arena, a, b, BooleanOp::kIntersection);
  ASSERT_TRUE(i.status.is_ok()) << test::format(i.status);
  EXPECT_EQ(i.stats.passes, 1u);
  expect_volume(i.volume, box_volume(kB1));
  // The union sees them: two groups.
  const Outcome u = run(arena, a, b, BooleanOp::kUnion);
  ASSERT_TRUE(u.status.is_ok()) << test::format(u.status);
  EXPECT_EQ(u.stats.shell_groups, 2u);
  expect_volume(u.volume, 64.0 + union_volume({far1, far2}));
}

TEST(BooleanShells, ThreeMutuallyOverlappingShells) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  const Box b3{{1.109375, 0.390625, 0.859375}, {3.078125, 1.328125, 1.921875}};
  const Mesh b = boxes_mesh(arena, {kB1, kB2, b3});
  const double vb = union_volume({kB1, kB2, b3});
  const Outcome d = run(arena, a, b, BooleanOp::kDifference);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  EXPECT_EQ(d.stats.shell_groups, 3u);
  EXPECT_EQ(d.stats.passes, 3u);
  EXPECT_EQ(d.stats.attempts, 3u);
  expect_volume(d.volume, 64.0 - vb);
  const Outcome wd = second_way(arena, a, {kB1, kB2, b3}, BooleanOp::kDifference);
  ASSERT_TRUE(wd.status.is_ok()) << test::format(wd.status);
  expect_volume(d.volume, wd.volume);
  const Outcome i = run(arena, a, b, BooleanOp::kIntersection);
  ASSERT_TRUE(i.status.is_ok()) << test::format(i.status);
  EXPECT_EQ(i.stats.passes, 3u);
  expect_volume(i.volume, vb);
  // A fourth shell apart from the others joins the first group.
  const Box apart{{3.125, 3.125, 3.125}, {3.625, 3.375, 3.75}};
  const Mesh b4 = boxes_mesh(arena, {kB1, kB2, b3, apart});
  const Outcome d4 = run(arena, a, b4, BooleanOp::kDifference);
  ASSERT_TRUE(d4.status.is_ok()) << test::format(d4.status);
  EXPECT_EQ(d4.stats.shell_groups, 3u);
  expect_volume(d4.volume, 64.0 - vb - box_volume(apart));
}

// A UV sphere (closed, outward) appended to m.
void add_sphere(const Vec3& c, double r, int nlat, int nlon, Mesh* m) {
  const double pi = 3.14159265358979323846;
  const uint32_t off = static_cast<uint32_t>(m->vertices.size());
  ASSERT_TRUE(m->vertices.push_back(c + Vec3{0, 0, r}));
  for (int i = 1; i < nlat; ++i) {
    const double th = pi * i / nlat;
    for (int j = 0; j < nlon; ++j) {
      const double ph = 2 * pi * j / nlon + 0.1 * i;
      ASSERT_TRUE(
          m->vertices.push_back(c + Vec3{r * std::sin(th) * std::cos(ph),
                                         r * std::sin(th) * std::sin(ph), r * std::cos(th)}));
    }
  }
  const uint32_t south = off + static_cast<uint32_t>(1 + (nlat - 1) * nlon);
  ASSERT_TRUE(m->vertices.push_back(c + Vec3{0, 0, -r}));
  auto ring = [&](int i, int j) {
    return off + static_cast<uint32_t>(1 + (i - 1) * nlon + ((j % nlon) + nlon) % nlon);
  };
  for (int j = 0; j < nlon; ++j) {
    ASSERT_TRUE(m->triangles.push_back(Triangle{{off, ring(1, j), ring(1, j + 1)}}));
  }
  for (int i = 1; i + 1 < nlat; ++i) {
    for (int j = 0; j < nlon; ++j) {
      ASSERT_TRUE(
          m->triangles.push_back(Triangle{{ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)}}));
      ASSERT_TRUE(
          m->triangles.push_back(Triangle{{ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)}}));
    }
  }
  for (int j = 0; j < nlon; ++j) {
    ASSERT_TRUE(
        m->triangles.push_back(Triangle{{south, ring(nlat - 1, j + 1), ring(nlat - 1, j)}}));
  }
}

// Finely tessellated shells (their triangles are binned in a grid, not compared pair by pair):
// two spheres that overlap, a third apart from both (told apart by a plane).
TEST(BooleanShells, FineShellsOverlapAndApart) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  Mesh b(&arena);
  add_sphere(Vec3{1.3, 1.6, 1.7}, 0.9, 24, 48, &b);
  add_sphere(Vec3{2.4, 2.1, 2.2}, 0.8, 22, 44, &b);   // overlaps the first
  add_sphere(Vec3{3.2, 0.75, 0.8}, 0.6, 16, 32, &b);  // apart from both
  const Outcome d = run(arena, a, b, BooleanOp::kDifference);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  EXPECT_EQ(d.stats.shells, 3u);
  EXPECT_EQ(d.stats.shell_groups, 2u);
  // The second way: the two overlapping spheres united first, then the third appended.
  ArenaScope scope(arena);
  Mesh s1(&arena), s2(&arena), s3(&arena);
  add_sphere(Vec3{1.3, 1.6, 1.7}, 0.9, 24, 48, &s1);
  add_sphere(Vec3{2.4, 2.1, 2.2}, 0.8, 22, 44, &s2);
  BooleanOptions o;
  o.op = BooleanOp::kUnion;
  o.float32_output = false;
  Mesh u;
  SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&arena), s1, s2, o, &u, nullptr));
  Mesh joined(&arena);
  for (const Vec3& p : u.vertices) ASSERT_TRUE(joined.vertices.push_back(p));
  for (const Triangle& t : u.triangles) ASSERT_TRUE(joined.triangles.push_back(t));
  add_sphere(Vec3{3.2, 0.75, 0.8}, 0.6, 16, 32, &joined);
  const Outcome w = run(arena, a, joined, BooleanOp::kDifference);
  ASSERT_TRUE(w.status.is_ok()) << test::format(w.status);
  EXPECT_EQ(w.stats.shell_groups, 1u);
  expect_volume(d.volume, w.volume);
}

// The passes go fewest triangles first (each pass's A holds the imprints of the passes
// before): B's first shell, a fine sphere, is the greedy order's first group, the coarse box
// overlapping it the second, and the box is applied first. The same bytes as the two
// differences made one after the other in that order, and not the bytes of the other order
// (so the test can tell them apart); the same volume both ways.
TEST(BooleanShells, TheGroupWithFewerTrianglesPassesFirst) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  const Box small{{1.640625, 1.296875, 0.265625}, {3.421875, 2.234375, 1.703125}};
  Mesh sphere(&arena), b(&arena);
  add_sphere(Vec3{1.3, 1.6, 1.7}, 0.9, 24, 48, &sphere);
  add_sphere(Vec3{1.3, 1.6, 1.7}, 0.9, 24, 48, &b);
  add_box(small, &b);
  const Mesh box = boxes_mesh(arena, {small});
  const Outcome r = run(arena, a, b, BooleanOp::kDifference);
  ASSERT_TRUE(r.status.is_ok()) << test::format(r.status);
  EXPECT_EQ(r.stats.shell_groups, 2u);
  EXPECT_EQ(r.stats.passes, 2u);
  auto two_steps = [&](const Mesh& first, const Mesh& second) {
    BooleanOptions o;
    o.float32_output = false;
    Mesh cut;
    EXPECT_TRUE(mesh_boolean(Context(&arena), a, first, o, &cut, nullptr).is_ok());
    return run(arena, cut, second, BooleanOp::kDifference);
  };
  const Outcome box_first = two_steps(box, sphere);
  const Outcome sphere_first = two_steps(sphere, box);
  ASSERT_TRUE(box_first.status.is_ok() && sphere_first.status.is_ok());
  EXPECT_TRUE(r.bytes == box_first.bytes) << "not the box first";
  EXPECT_TRUE(r.bytes != sphere_first.bytes) << "the two orders give the same bytes";
  expect_volume(r.volume, sphere_first.volume);
}

// Appends to m two tetrahedra with the apex p in common (one shell, through p), each outward:
// bases q[0..2] and q[3..5].
void add_two_tetrahedra(const Vec3& p, const Vec3 (&q)[6], Mesh* m) {
  const uint32_t o = static_cast<uint32_t>(m->vertices.size());
  ASSERT_TRUE(m->vertices.push_back(p));
  for (const Vec3& v : q) ASSERT_TRUE(m->vertices.push_back(v));
  for (uint32_t k = 0; k < 2; ++k) {
    const uint32_t b = o + 1 + 3 * k;
    const bool flip = dot(cross(q[3 * k] - p, q[3 * k + 1] - p), q[3 * k + 2] - p) > 0;
    const uint32_t f[4][3] = {{o, b, b + 1}, {o, b + 1, b + 2}, {o, b + 2, b}, {b, b + 2, b + 1}};
    for (const auto& t : f) {
      ASSERT_TRUE(m->triangles.push_back(flip ? Triangle{{t[0], t[2], t[1]}}
                                              : Triangle{{t[0], t[1], t[2]}}));
    }
  }
}

// An order that fails is not the end: B's second shell (two tetrahedra that overlap each
// other, joined at their apex, inside a sphere through A's face x = 4) is applied first by
// size and breaks the re-triangulation of A there, with every nudge; the sphere first, the
// greedy order, cuts that part of A away and the tetrahedra then meet nothing of A. The
// greedy order's bytes, with the failed order's attempts counted.
TEST(BooleanShells, WhenTheOrderBySizeFailsTheGreedyOrderIsTried) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  const Vec3 c{4.1, 2.0, 2.0}, p{4.05, 2.0, 2.0};
  const Vec3 q[6] = {{3.3, 1.7, 1.75},  {3.3, 2.3, 1.8},    {3.3, 2.0, 2.3},
                     {3.35, 1.85, 1.6}, {3.35, 2.45, 1.95}, {3.37, 1.8, 2.2}};
  Mesh sphere(&arena), tetrahedra(&arena), b(&arena);
  add_sphere(c, 1.2, 24, 48, &sphere);
  add_two_tetrahedra(p, q, &tetrahedra);
  add_sphere(c, 1.2, 24, 48, &b);
  add_two_tetrahedra(p, q, &b);
  const Outcome r = run(arena, a, b, BooleanOp::kDifference);
  ASSERT_TRUE(r.status.is_ok()) << test::format(r.status);
  EXPECT_EQ(r.stats.shell_groups, 2u);
  EXPECT_GT(r.stats.attempts, 2u + BooleanOptions{}.max_nudges) << "the failed order's attempts";
  BooleanOptions o;
  o.float32_output = false;
  {
    ArenaScope scope(arena);
    Mesh cut;
    const Status s = mesh_boolean(Context(&arena), a, tetrahedra, o, &cut, nullptr);
    EXPECT_FALSE(s.is_ok()) << "the tetrahedra first no longer fail: this tests nothing";
  }
  Mesh cut;
  SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&arena), a, sphere, o, &cut, nullptr));
  const Outcome greedy = run(arena, cut, tetrahedra, BooleanOp::kDifference);
  ASSERT_TRUE(greedy.status.is_ok()) << test::format(greedy.status);
  EXPECT_TRUE(r.bytes == greedy.bytes);
}

// Every figure of two reports the same (the first offenders too): the topology as check_test
// compares it, and the rest.
void expect_same_report(const MeshReport& x, const MeshReport& y) {
  test::expect_same_topology(x, y);
  EXPECT_EQ(x.vertex_count, y.vertex_count);
  EXPECT_EQ(x.triangle_count, y.triangle_count);
  EXPECT_EQ(x.unreferenced_vertices, y.unreferenced_vertices);
  EXPECT_EQ(x.boundary_loops, y.boundary_loops);
  EXPECT_EQ(x.degenerate_triangles, y.degenerate_triangles);
  EXPECT_EQ(x.area, y.area);
  EXPECT_EQ(x.volume, y.volume);
  EXPECT_TRUE(x.bounds.lo == y.bounds.lo && x.bounds.hi == y.bounds.hi);
  EXPECT_EQ(x.first_degenerate_triangle, y.first_degenerate_triangle);
  EXPECT_EQ(x.first_duplicate_triangle, y.first_duplicate_triangle);
}

// BooleanOptions::result_report: check_mesh's report of the returned result, made by the
// result check itself (a fine sphere with a box cut off its side: the result is mostly A, so
// that check_mesh's memory, at the end, is the run's peak). At every arena cap that gives a
// result, the result is the same bytes as without the report, and the report, when made, is
// check_mesh's; some caps are too small for check_mesh's memory but not for the check's own
// edge pass: the result all the same, without the report. (Without the self-intersection
// check, whose memory would come after and hide check_mesh's.)
TEST(BooleanShells, TheResultCheckMakesTheResultsReport) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a(&arena);
  add_sphere(Vec3{2, 2, 2}, 1.5, 48, 96, &a);
  const Mesh b = boxes_mesh(arena, {Box{{3.2, 1.5, 1.5}, {4, 2.5, 2.5}}});
  const Outcome plain = run(arena, a, b, BooleanOp::kDifference);
  ASSERT_TRUE(plain.status.is_ok()) << test::format(plain.status);
  BooleanOptions o;
  o.float32_output = false;
  o.check_self_intersection = false;
  MeshReport report;
  o.result_report = &report;
  int made = 0, not_made = 0;
  for (size_t cap = 4096; cap <= (size_t{4} << 20); cap += 4096) {
    TestArena small(cap);
    Mesh ca, cb, out;
    if (!test::copy_mesh(small.arena, a, &ca) || !test::copy_mesh(small.arena, b, &cb)) continue;
    BooleanStats st;
    report = MeshReport{};
    if (!mesh_boolean(Context(&small.arena), ca, cb, o, &out, &st).is_ok()) continue;
    const uint8_t* v = reinterpret_cast<const uint8_t*>(out.vertices.data());
    const uint8_t* t = reinterpret_cast<const uint8_t*>(out.triangles.data());
    std::vector<uint8_t> bytes(v, v + out.vertices.size() * sizeof(Vec3));
    bytes.insert(bytes.end(), t, t + out.triangles.size() * sizeof(Triangle));
    EXPECT_TRUE(bytes == plain.bytes) << "cap " << cap;
    if (!st.result_report_made) {
      ++not_made;
      continue;
    }
    ++made;
    MeshReport again;
    SPLINTCORE_ASSERT_OK(check_mesh(Context(&arena), out, &again));
    expect_same_report(report, again);
    if (made > 1 && not_made > 0) break;
  }
  EXPECT_GT(made, 0);
  EXPECT_GT(not_made, 0) << "no cap left the report out";
}

// B without its triangles whose corners all lie beyond one side of `r` (strictly), and the
// vertices only they use; the rest in their order (written here, not taken from the design).
Mesh cropped(Arena& arena, const Mesh& b, const Aabb& r) {
  Mesh out(&arena);
  std::vector<int> side(b.vertices.size());
  std::vector<uint32_t> index(b.vertices.size(), UINT32_MAX);
  for (size_t v = 0; v < b.vertices.size(); ++v) {
    const Vec3& p = b.vertices[v];
    side[v] = (p.x < r.lo.x) | (p.x > r.hi.x) << 1 | (p.y < r.lo.y) << 2 | (p.y > r.hi.y) << 3 |
              (p.z < r.lo.z) << 4 | (p.z > r.hi.z) << 5;
  }
  auto kept = [&](const Triangle& t) { return (side[t.v[0]] & side[t.v[1]] & side[t.v[2]]) == 0; };
  for (const Triangle& t : b.triangles) {
    if (kept(t)) {
      for (uint32_t v : t.v) index[v] = 0;
    }
  }
  for (size_t v = 0; v < b.vertices.size(); ++v) {
    if (index[v] == UINT32_MAX) continue;
    index[v] = static_cast<uint32_t>(out.vertices.size());
    EXPECT_TRUE(out.vertices.push_back(b.vertices[v]));
  }
  for (const Triangle& t : b.triangles) {
    if (kept(t)) {
      EXPECT_TRUE(out.triangles.push_back(Triangle{{index[t.v[0]], index[t.v[1]], index[t.v[2]]}}));
    }
  }
  return out;
}

// A torus (closed, outward) about the axis through c along z: major radius R, minor r.
void add_torus(const Vec3& c, double R, double r, int n_major, int n_minor, Mesh* m) {
  const double pi = 3.14159265358979323846;
  const uint32_t off = static_cast<uint32_t>(m->vertices.size());
  for (int i = 0; i < n_major; ++i) {
    const double u = 2 * pi * i / n_major;
    for (int j = 0; j < n_minor; ++j) {
      const double w = 2 * pi * j / n_minor + 0.05 * i;
      const double d = R + r * std::cos(w);
      ASSERT_TRUE(
          m->vertices.push_back(c + Vec3{d * std::cos(u), d * std::sin(u), r * std::sin(w)}));
    }
  }
  auto at = [&](int i, int j) {
    return off + static_cast<uint32_t>((i % n_major) * n_minor + (j % n_minor));
  };
  for (int i = 0; i < n_major; ++i) {
    for (int j = 0; j < n_minor; ++j) {
      ASSERT_TRUE(m->triangles.push_back(Triangle{{at(i, j), at(i + 1, j), at(i + 1, j + 1)}}));
      ASSERT_TRUE(m->triangles.push_back(Triangle{{at(i, j), at(i + 1, j + 1), at(i, j + 1)}}));
    }
  }
}

// boolean_region: B's triangles beyond it can be left out (an open B whose border is outside A).
// B: a sphere inside A, one through A's face x = 4 (the cap outside cropped off), one apart from
// A (cropped whole), and a ring wider than A around its centre that the crop cuts into four
// pieces. None overlaps another near A (one group): the difference is the same bytes. Then a
// sphere overlapping the first: two groups, whose passes may divide the same solid otherwise
// (the ring's pieces are grouped one by one): the same volume, a valid solid. The union's
// region is everywhere.
TEST(BooleanShells, TrianglesBeyondTheRegionChangeNothing) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  Mesh b(&arena);
  add_sphere(Vec3{1.3, 1.6, 1.7}, 0.9, 24, 48, &b);        // inside A
  add_sphere(Vec3{4.1, 2.3, 1.0}, 1.2, 24, 48, &b);        // through A's face x = 4
  add_sphere(Vec3{9.0, 9.0, 9.0}, 1.0, 12, 24, &b);        // apart from A
  add_torus(Vec3{2.05, 1.95, 3.1}, 2.5, 0.3, 96, 12, &b);  // out through A's four side edges
  BooleanOptions o;
  o.float32_output = false;
  const Aabb region = boolean_region(a, o);
  EXPECT_LE(region.lo.x, 0.0);
  EXPECT_GE(region.hi.x, 4.0);
  EXPECT_LT(region.hi.x, 4.01);
  for (uint32_t overlapping = 0; overlapping < 2; ++overlapping) {
    if (overlapping == 1) add_sphere(Vec3{2.4, 2.1, 2.2}, 0.8, 22, 44, &b);
    const Mesh c = cropped(arena, b, region);
    EXPECT_LT(c.triangles.size(), b.triangles.size() * 4 / 5);
    const Outcome whole = run(arena, a, b, BooleanOp::kDifference);
    const Outcome crop = run(arena, a, c, BooleanOp::kDifference);
    ASSERT_TRUE(whole.status.is_ok()) << test::format(whole.status);
    ASSERT_TRUE(crop.status.is_ok()) << test::format(crop.status);
    EXPECT_EQ(whole.stats.shells, 4u + overlapping);
    EXPECT_EQ(crop.stats.shells, 2u + 4u + overlapping);  // the far sphere gone, the ring in 4
    EXPECT_EQ(crop.stats.shell_groups, 1u + overlapping);
    if (overlapping == 0) {
      EXPECT_FALSE(whole.bytes.empty());
      EXPECT_EQ(whole.bytes, crop.bytes);
    } else {
      EXPECT_NEAR(crop.volume, whole.volume, 1e-12 * whole.volume);
    }
  }
  o.op = BooleanOp::kUnion;
  const Aabb everywhere = boolean_region(a, o);
  EXPECT_EQ(cropped(arena, b, everywhere).triangles.size(), b.triangles.size());
}

TEST(BooleanShells, SameBytesEveryRunAndFloat32) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  const Box b3{{1.109375, 0.390625, 0.859375}, {3.078125, 1.328125, 1.921875}};
  const Mesh b = boxes_mesh(arena, {kB1, kB2, b3});
  for (BooleanOp op : {BooleanOp::kDifference, BooleanOp::kUnion, BooleanOp::kIntersection}) {
    const Outcome first = run(arena, a, b, op, true);
    ASSERT_TRUE(first.status.is_ok()) << test::format(first.status);
    const Outcome again = run(arena, a, b, op, true);
    ASSERT_TRUE(again.status.is_ok());
    EXPECT_FALSE(first.bytes.empty());
    EXPECT_EQ(first.bytes, again.bytes) << boolean_op_name(op);
  }
}

// With float32 output, B's vertices must be float32 values where they matter (near A's
// region), checked on B itself before the passes so that the error names B's own triangle: a
// vertex nudged off the float32 grid in a shell apart from A changes nothing, in a shell that
// overlaps another near A it is refused at the first triangle of B that uses it.
TEST(BooleanShells, AVertexThatIsNotFloat32MattersOnlyNearA) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  const Box far{{10, 10, 10}, {11, 11, 11}};
  for (uint32_t nudged : {17u, 9u}) {  // of the far box; of kB2
    SCOPED_TRACE("vertex " + std::to_string(nudged));
    Mesh b = boxes_mesh(arena, {kB1, kB2, far});
    b.vertices[nudged].x += 0x1p-40;
    const Outcome r = run(arena, a, b, BooleanOp::kDifference, true);
    if (nudged == 17) {
      ASSERT_TRUE(r.status.is_ok()) << test::format(r.status);
      EXPECT_EQ(r.stats.shell_groups, 2u);
      continue;
    }
    uint32_t first = 0;
    while (first < b.triangles.size() && b.triangles[first].v[0] != nudged &&
           b.triangles[first].v[1] != nudged && b.triangles[first].v[2] != nudged) {
      ++first;
    }
    EXPECT_EQ(r.status.code(), StatusCode::kInvalidArgument) << test::format(r.status);
    EXPECT_EQ(r.status.index(), first);
    EXPECT_NE(std::string(r.status.message()).find("not a float32 value"), std::string::npos);
  }
}

// Every cap from nothing to enough: a clean kArenaExhausted (arena as at entry, output empty)
// or the same bytes as with room to spare.
TEST(BooleanShells, ArenaExhaustionIsCleanAtEveryCap) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  const Mesh b = boxes_mesh(arena, {kB1, kB2});
  for (BooleanOp op : {BooleanOp::kDifference, BooleanOp::kIntersection}) {
    const Outcome full = run(arena, a, b, op);
    ASSERT_TRUE(full.status.is_ok());
    std::vector<unsigned char> buffer(size_t{1} << 20);
    size_t need = 0;
    {
      Arena probe(buffer.data(), buffer.size());
      BooleanOptions o;
      o.op = op;
      o.float32_output = false;
      Mesh out;
      ASSERT_TRUE(mesh_boolean(Context(&probe), a, b, o, &out, nullptr).is_ok());
      need = probe.high_water();
    }
    int exhausted = 0;
    for (size_t cap = 0; cap <= need; cap += need / 97 + 1) {
      Arena small(buffer.data(), cap);
      BooleanOptions o;
      o.op = op;
      o.float32_output = false;
      Mesh out;
      BooleanStats st;
      const Status s = mesh_boolean(Context(&small), a, b, o, &out, &st);
      if (s.is_ok()) {
        const Outcome r = run(arena, a, b, op);
        EXPECT_EQ(r.bytes, full.bytes);
        continue;
      }
      ++exhausted;
      EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << test::format(s);
      EXPECT_EQ(small.used(), 0u) << "cap " << cap;
      EXPECT_TRUE(out.triangles.empty() && out.vertices.empty());
    }
    EXPECT_GT(exhausted, 50);
  }
}

TEST(BooleanShells, AnErrorNamesThePass) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = boxes_mesh(arena, {kA});
  // The first shell reaches beyond A (x up to 5) and is opened there: its border lies outside
  // A (an open B whose border meets A is refused before any pass), but the union of the
  // shells (the intersection's first step) needs it closed.
  Box b1 = kB1;
  b1.hi.x = 5;
  Mesh b = boxes_mesh(arena, {b1, kB2});
  Mesh open(&arena);
  for (const Vec3& v : b.vertices) ASSERT_TRUE(open.vertices.push_back(v));
  size_t dropped = b.triangles.size();
  for (size_t t = 0; t < b.triangles.size(); ++t) {
    const uint32_t* v = b.triangles[t].v;
    const bool far = b.vertices[v[0]].x == 5 && b.vertices[v[1]].x == 5 && b.vertices[v[2]].x == 5;
    if (far && dropped == b.triangles.size()) {
      dropped = t;
    } else {
      ASSERT_TRUE(open.triangles.push_back(b.triangles[t]));
    }
  }
  ASSERT_LT(dropped, b.triangles.size());
  const Outcome r = run(arena, a, open, BooleanOp::kIntersection);
  ASSERT_FALSE(r.status.is_ok());
  EXPECT_EQ(r.status.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(std::string(r.status.message()).find("pass 1 of 2"), std::string::npos)
      << r.status.message();
  EXPECT_EQ(r.stats.shell_groups, 2u);
}

// The real teeth: 31 closed shells against the wafer (as the benchmark: bite opened 2 mm,
// crowns 1.5 mm into the wafer). Reports whether neighbouring teeth overlap near the wafer.
TEST(BooleanShells, RealTeeth) {
  const std::string dir = SPLINTCORE_REALDATA_DIR;
  if (!test::file_exists(dir + "/maxilla/tooth_1.stl")) GTEST_SKIP() << "realdata not found";
  realcase::RealCase rc;
  std::string error;
  ASSERT_TRUE(realcase::load(dir, 2.0, 1.5, 6.0, &rc, &error)) << error;
  TestArena ta(size_t{1024} << 20);  // the union takes about 560 MB (untouched pages cost nothing)
  Arena& arena = ta.arena;
  Mesh teeth, wafer;
  BaseReport br;
  SPLINTCORE_ASSERT_OK(realcase::teeth_mesh(arena, rc, &teeth));
  SPLINTCORE_ASSERT_OK(realcase::wafer_mesh(arena, rc, 0.5, &wafer, &br));
  for (BooleanOp op : {BooleanOp::kDifference, BooleanOp::kUnion}) {
    ArenaScope scope(arena);
    BooleanOptions o;
    o.op = op;
    Mesh out;
    BooleanStats st;
    const Status s = mesh_boolean(Context(&arena), wafer, teeth, o, &out, &st);
    ASSERT_TRUE(s.is_ok()) << test::format(s);
    EXPECT_EQ(st.shells, 31u);
    std::cout << "[ real     ] " << boolean_op_name(op) << ": " << st.shells << " shells, "
              << st.shell_groups << " group(s), " << st.passes << " pass(es), "
              << out.triangles.size() << " triangles\n";
    MeshReport rep;
    SPLINTCORE_ASSERT_OK(check_mesh(Context(&arena), out, &rep));
    EXPECT_TRUE(rep.is_valid_solid()) << test::format(require_valid_solid(rep));
  }
}

// The pair from Manifold's bug reports (realdata/manifold-bugreports, about 20k and 12k
// triangles, coordinates near 20,000 mm: long thin CAD triangles lying over dense ones). Their
// union tested about 48 M candidate pairs per attempt, nine attempts, 45-130 s, before failing
// on a float32 coincidence. It must answer, either way, within the default work bound: a
// valid solid whose volume lies between the larger input's and the sum, or kLimitExceeded
// naming the bound.
TEST(BooleanShells, RealManifoldTwinAnswersWithinTheWorkBound) {
  const std::string dir = std::string(SPLINTCORE_REALDATA_DIR) + "/../manifold-bugreports/";
  const char* names[2] = {"Generic_Twin_7081.1.t0_left.obj", "Generic_Twin_7081.1.t0_right.obj"};
  if (!test::file_exists(dir + names[0])) GTEST_SKIP() << "realdata not found";
  TestArena ta(size_t{1024} << 20);
  Arena& arena = ta.arena;
  const Context ctx(&arena);
  Mesh m[2];
  double volume[2] = {0, 0};
  for (int i = 0; i < 2; ++i) {
    FileSource file;
    SPLINTCORE_ASSERT_OK(file.open((dir + names[i]).c_str()));
    MeshReadInfo info;
    SPLINTCORE_ASSERT_OK(read_mesh(ctx, file.source(), MeshReadOptions{}, &m[i], &info));
    MeshReport rep;
    SPLINTCORE_ASSERT_OK(check_mesh(ctx, m[i], &rep));
    ASSERT_TRUE(rep.is_valid_solid()) << names[i];
    volume[i] = rep.volume;
  }
  BooleanOptions o;
  o.op = BooleanOp::kUnion;
  Mesh out;
  BooleanStats st;
  const Status s = mesh_boolean(ctx, m[0], m[1], o, &out, &st);
  const uint64_t bound = 64 * (m[0].triangles.size() + m[1].triangles.size()) + (uint64_t{1} << 22);
  std::cout << "[ twin     ] " << test::format(s) << "; " << st.candidate_pairs
            << " candidate pairs (bound " << bound << ")\n";
  // The bound is checked after each triangle of B: it may be passed by one B triangle's pairs.
  EXPECT_LE(st.candidate_pairs, bound + m[0].triangles.size());
  if (s.is_ok()) {
    MeshReport rep;
    SPLINTCORE_ASSERT_OK(check_mesh(ctx, out, &rep));
    EXPECT_TRUE(rep.is_valid_solid()) << test::format(require_valid_solid(rep));
    EXPECT_GE(rep.volume, std::max(volume[0], volume[1]) * (1 - 1e-9));
    EXPECT_LE(rep.volume, (volume[0] + volume[1]) * (1 + 1e-9));
  } else {
    EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << test::format(s);
    const std::string text = s.message();
    EXPECT_NE(text.find("max_candidate_pairs"), std::string::npos) << text;
    EXPECT_NE(text.find("raise the bound"), std::string::npos) << text;
  }
}

}  // namespace
}  // namespace splintcore
