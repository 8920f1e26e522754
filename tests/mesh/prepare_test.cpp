// Scan preparation (prepare_scan, src/mesh/prepare.cpp): each step on a small planted case,
// the arena bound run at exactly its size, and the errors.
#include <cmath>
#include <vector>

#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

// A 6 x 6 grid of 2 mm cells in z = 0 (normals +z) and one of every defect.
struct Planted {
  std::vector<Vec3> v;
  std::vector<Triangle> t;
  Planted() {
    for (uint32_t j = 0; j <= 6; ++j) {
      for (uint32_t i = 0; i <= 6; ++i) v.push_back(Vec3{2.0 * i, 2.0 * j, 0});
    }
    for (uint32_t j = 0; j < 6; ++j) {
      for (uint32_t i = 0; i < 6; ++i) {
        if (i == 3 && j == 3) continue;  // a hole of 4 edges
        const uint32_t a = 7 * j + i;
        t.push_back(Triangle{{a, a + 1, a + 8}});
        t.push_back(Triangle{{a, a + 8, a + 7}});
      }
    }
    std::swap(t[20].v[1], t[20].v[2]);  // one triangle wound the other way
    t.push_back(t[0]);                  // a duplicate
    t.push_back(Triangle{{0, 1, 2}});   // zero area (collinear)
    v.push_back(Vec3{3, 3, 2});         // 49: a flap on the diagonal 8 - 16
    t.push_back(Triangle{{8, 16, 49}});
    v.push_back(Vec3{13, 12, 0});  // 50, 51: a triangle touching the grid at its corner 48 only
    v.push_back(Vec3{13, 13, 0});
    t.push_back(Triangle{{48, 50, 51}});
    v.push_back(Vec3{30, 0, 0});  // 52..54: a loose island
    v.push_back(Vec3{31, 0, 0});
    v.push_back(Vec3{30, 1, 0});
    t.push_back(Triangle{{52, 53, 54}});
  }
  Mesh mesh(Arena& arena) const {
    Mesh m(&arena);
    for (const Vec3& p : v) EXPECT_TRUE(m.vertices.push_back(p));
    for (const Triangle& x : t) EXPECT_TRUE(m.triangles.push_back(x));
    return m;
  }
};

TEST(PrepareScan, EveryStepCountsWhatWasPlanted) {
  TestArena ta;
  const Planted p;
  const Mesh in = p.mesh(ta.arena);
  PrepareOptions o;
  o.max_hole_edges = 8;  // the grid's border (24 edges) stays open
  Mesh out;
  PrepareReport r;
  SPLINTCORE_ASSERT_OK(prepare_scan(Context(&ta.arena), in, o, &out, &r));
  EXPECT_EQ(r.input_triangles, 75u);
  EXPECT_EQ(r.duplicate_triangles, 1u);
  EXPECT_EQ(r.degenerate_triangles, 1u);
  EXPECT_EQ(r.nonmanifold_edges, 1u);
  EXPECT_EQ(r.nonmanifold_triangles, 1u);
  EXPECT_EQ(r.nonmanifold_vertices, 1u);
  EXPECT_EQ(r.split_vertices_added, 1u);
  EXPECT_EQ(r.islands, 2u);
  EXPECT_EQ(r.island_triangles, 2u);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.flipped_triangles, 1u);
  EXPECT_EQ(r.orientation_conflicts, 0u);
  EXPECT_EQ(r.holes_filled, 1u);
  EXPECT_EQ(r.hole_triangles, 4u);
  EXPECT_EQ(r.holes_left, 1u);  // the grid's border
  EXPECT_EQ(r.unreferenced_vertices, 7u);
  EXPECT_EQ(r.output_triangles, 74u);
  EXPECT_EQ(r.output_vertices, 50u);
  MeshReport c;
  SPLINTCORE_ASSERT_OK(check_mesh(Context(&ta.arena), out, &c));
  EXPECT_EQ(c.boundary_edges, 24u);
  EXPECT_EQ(c.boundary_loops, 1u);
  EXPECT_EQ(c.shells, 1u);
  EXPECT_TRUE(c.edge_manifold() && c.oriented());
  EXPECT_EQ(c.degenerate_triangles + c.duplicate_triangles + c.unreferenced_vertices, 0u);
  // The input's majority winding (+z) is kept; vertices are copied, never moved.
  const Triangle& t0 = out.triangles[0];
  EXPECT_GT(cross(out.vertices[t0.v[1]] - out.vertices[t0.v[0]],
                  out.vertices[t0.v[2]] - out.vertices[t0.v[0]])
                .z,
            0.0);
  EXPECT_EQ(out.vertices[7], (Vec3{0, 2, 0}));
}

TEST(PrepareScan, OptionsChangeIslandsHolesAndFacing) {
  TestArena ta;
  const Planted p;
  const Mesh in = p.mesh(ta.arena);
  PrepareOptions o;
  o.min_island_triangles = 1;  // by count: nothing is smaller than one triangle
  o.max_hole_edges = 3;        // the 4-edge hole stays
  o.occlusal = Vec3{0, 0, -1};
  Mesh out;
  PrepareReport r;
  SPLINTCORE_ASSERT_OK(prepare_scan(Context(&ta.arena), in, o, &out, &r));
  EXPECT_EQ(r.islands, 0u);
  EXPECT_EQ(r.components, 3u);
  EXPECT_EQ(r.holes_filled, 0u);
  EXPECT_EQ(r.holes_left, 4u);          // the border, the hole, the two small pieces' borders
  EXPECT_GT(r.flipped_triangles, 60u);  // all turned to face -z
  const Triangle& t0 = out.triangles[0];
  EXPECT_LT(cross(out.vertices[t0.v[1]] - out.vertices[t0.v[0]],
                  out.vertices[t0.v[2]] - out.vertices[t0.v[0]])
                .z,
            0.0);
}

TEST(PrepareScan, RunsInExactlyItsBoundAndRewindsOnErrors) {
  TestArena ta;
  const Planted p;
  const Mesh in = p.mesh(ta.arena);
  const uint64_t bound = prepare_scan_bound(in.vertices.size(), in.triangles.size());
  std::vector<unsigned char> buffer(static_cast<size_t>(bound));
  Arena exact(buffer.data(), buffer.size());
  Mesh out;
  PrepareReport r;
  SPLINTCORE_ASSERT_OK(prepare_scan(Context(&exact), in, PrepareOptions{}, &out, &r));
  EXPECT_EQ(out.triangles.size(), 98u);  // by default the 24-edge border is filled too
  // Too small: a clean error, the arena as it was.
  Arena small(buffer.data(), static_cast<size_t>(bound / 4));
  Mesh none;
  Status s = prepare_scan(Context(&small), in, PrepareOptions{}, &none, &r);
  EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << test::format(s);
  EXPECT_EQ(small.used(), 0u);
  EXPECT_TRUE(none.triangles.empty());
  // Bad input: named.
  Mesh bad = p.mesh(ta.arena);
  bad.triangles[5].v[2] = 999;
  s = prepare_scan(Context(&ta.arena), bad, PrepareOptions{}, &none, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.index(), 5u);
  bad = p.mesh(ta.arena);
  bad.vertices[3].y = std::numeric_limits<double>::quiet_NaN();
  s = prepare_scan(Context(&ta.arena), bad, PrepareOptions{}, &none, &r);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_EQ(s.index(), 3u);
  s = prepare_scan(Context(&ta.arena), in, PrepareOptions{}, &out, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
}

// Step 6 and 7 on closed boxes (2 x 3 x 4 mm, 12 triangles): the seed triangle wound against
// the other eleven is the one turned (the input's majority wins, not the seed); a box wound
// inside out is turned whole, outward; a box missing one triangle gets it back as the fill of
// its 3-edge hole, with the loop's winding. Each output is a valid solid of volume 24.
TEST(PrepareScan, ClosedShellsAreTurnedOutwardAndAThreeEdgeHoleIsOneTriangle) {
  TestArena ta;
  const float lo[3] = {0, 0, 0}, hi[3] = {2, 3, 4};
  Mesh box;
  ASSERT_TRUE(test::mesh_from_soup(ta.arena, shapes::box(lo, hi), &box).is_ok());
  auto prepared = [&](const Mesh& in, PrepareReport* r) {
    Mesh out;
    const Status s = prepare_scan(Context(&ta.arena), in, PrepareOptions{}, &out, r);
    EXPECT_TRUE(s.is_ok()) << test::format(s);
    MeshReport c;
    EXPECT_TRUE(check_mesh(Context(&ta.arena), out, &c).is_ok());
    EXPECT_TRUE(require_valid_solid(c).is_ok()) << require_valid_solid(c).message();
    EXPECT_DOUBLE_EQ(c.volume, 24.0);
    return out;
  };
  auto copy = [&]() {
    Mesh m(&ta.arena);
    for (const Vec3& v : box.vertices) EXPECT_TRUE(m.vertices.push_back(v));
    for (const Triangle& t : box.triangles) EXPECT_TRUE(m.triangles.push_back(t));
    return m;
  };
  {
    Mesh seed_wrong = copy();
    std::swap(seed_wrong.triangles[0].v[1], seed_wrong.triangles[0].v[2]);
    PrepareReport r;
    const Mesh out = prepared(seed_wrong, &r);
    EXPECT_EQ(r.flipped_triangles, 1u);
    EXPECT_EQ(r.flipped_components, 0u);
    EXPECT_EQ(r.orientation_conflicts, 0u);
    for (size_t t = 0; t < box.triangles.size(); ++t) {
      EXPECT_EQ(out.triangles[t].v[0], box.triangles[t].v[0]) << t;  // as the box was
      EXPECT_EQ(out.triangles[t].v[1], box.triangles[t].v[1]) << t;
    }
  }
  {
    Mesh inside_out = copy();
    for (Triangle& t : inside_out.triangles) std::swap(t.v[1], t.v[2]);
    PrepareReport r;
    prepared(inside_out, &r);
    EXPECT_EQ(r.flipped_triangles, 12u);
    EXPECT_EQ(r.flipped_components, 1u);
  }
  {
    Mesh open = copy();
    const Triangle gone = open.triangles[7];
    ASSERT_TRUE(open.triangles.resize(11));  // the last triangle moved into the place of 7
    open.triangles[7] = box.triangles[11];
    PrepareReport r;
    const Mesh out = prepared(open, &r);
    EXPECT_EQ(r.holes_filled, 1u);
    EXPECT_EQ(r.hole_triangles, 1u);
    EXPECT_EQ(r.holes_left, 0u);
    ASSERT_EQ(out.triangles.size(), 12u);
    EXPECT_EQ(out.vertices.size(), 8u);  // no centroid vertex for three edges
    // The fill is the missing triangle, up to a rotation of its corners.
    const Triangle& fill = out.triangles[11];
    int turn = 0;
    while (turn < 3 && fill.v[turn] != gone.v[0]) ++turn;
    ASSERT_LT(turn, 3);
    EXPECT_EQ(fill.v[(turn + 1) % 3], gone.v[1]);
    EXPECT_EQ(fill.v[(turn + 2) % 3], gone.v[2]);
  }
}

// A Moebius strip (six quads, the last joined to the first with a half turn) cannot be
// oriented: the walk counts the edge it cannot make agree and guesses nothing; and the island
// area must be a number >= 0.
TEST(PrepareScan, ANonOrientableStripIsCountedAndABadIslandAreaRefused) {
  TestArena ta;
  Mesh strip(&ta.arena);
  const int n = 6;
  for (int i = 0; i < n; ++i) {
    // Corners i (inner) and n + i (outer) of a band around the z axis, twisted half a turn.
    const double a = 6.283185307179586 * i / n, c = std::cos(a), sn = std::sin(a);
    const double h = std::cos(a / 2), w = std::sin(a / 2);  // the band's cross direction
    ASSERT_TRUE(strip.vertices.push_back(Vec3{(10 - h) * c, (10 - h) * sn, -w}));
  }
  for (int i = 0; i < n; ++i) {
    const double a = 6.283185307179586 * i / n, c = std::cos(a), sn = std::sin(a);
    const double h = std::cos(a / 2), w = std::sin(a / 2);
    ASSERT_TRUE(strip.vertices.push_back(Vec3{(10 + h) * c, (10 + h) * sn, w}));
  }
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t j = (i + 1) % n;
    // At the seam (i = n - 1) the half turn swaps the band's sides.
    const uint32_t a = i, b = n + i, cj = i + 1 < n ? j : n + j, dj = i + 1 < n ? n + j : j;
    ASSERT_TRUE(strip.triangles.push_back(Triangle{{a, b, dj}}));
    ASSERT_TRUE(strip.triangles.push_back(Triangle{{a, dj, cj}}));
  }
  PrepareOptions o;
  o.max_hole_edges = 0;
  Mesh out;
  PrepareReport r;
  SPLINTCORE_ASSERT_OK(prepare_scan(Context(&ta.arena), strip, o, &out, &r));
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.orientation_conflicts, 1u);
  EXPECT_EQ(out.triangles.size(), 2u * n);

  for (double area : {-1.0, std::nan("")}) {
    o.min_island_area = area;
    Mesh none;
    const Status s = prepare_scan(Context(&ta.arena), strip, o, &none, &r);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_STREQ(s.message(), "prepare_scan: min_island_area must be a number >= 0");
  }
}

// A triangle with a repeated corner is degenerate wherever the repeat is: corners 0 = 1,
// 1 = 2 and 2 = 0 each, beside the planted collinear one.
TEST(PrepareScan, ARepeatedCornerIsDegenerateInEveryPlace) {
  TestArena ta;
  Planted p;
  p.t.push_back(Triangle{{30, 30, 31}});  // (distinct sets: not duplicates of each other)
  p.t.push_back(Triangle{{32, 33, 33}});
  p.t.push_back(Triangle{{35, 34, 35}});
  const Mesh in = p.mesh(ta.arena);
  PrepareOptions o;
  o.max_hole_edges = 8;
  Mesh out;
  PrepareReport r;
  SPLINTCORE_ASSERT_OK(prepare_scan(Context(&ta.arena), in, o, &out, &r));
  EXPECT_EQ(r.degenerate_triangles, 4u);
  EXPECT_EQ(r.output_triangles, 74u);  // as without them
}

// The occlusal direction along x or y (not only z) turns the mesh to face it: the planted grid
// (facing +z) turned by a rotation to face +x, then +y.
TEST(PrepareScan, TheOcclusalDirectionMayBeAnyAxis) {
  for (int axis = 0; axis < 2; ++axis) {
    SCOPED_TRACE(axis);
    TestArena ta;
    Planted p;
    for (Vec3& v : p.v) {
      // (x, y, z) -> (z, y, -x) takes +z to +x; (x, y, z) -> (x, z, -y) takes +z to +y.
      v = axis == 0 ? Vec3{v.z, v.y, -v.x} : Vec3{v.x, v.z, -v.y};
    }
    const Mesh in = p.mesh(ta.arena);
    const Vec3 facing = axis == 0 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    for (double sense : {1.0, -1.0}) {
      PrepareOptions o;
      o.max_hole_edges = 8;
      o.occlusal = facing * sense;
      Mesh out;
      PrepareReport r;
      SPLINTCORE_ASSERT_OK(prepare_scan(Context(&ta.arena), in, o, &out, &r));
      if (sense > 0) {
        EXPECT_EQ(r.flipped_triangles, 1u);  // the one planted the other way
      } else {
        EXPECT_GT(r.flipped_triangles, 60u);
      }
      const Triangle& t0 = out.triangles[0];
      const Vec3 n = cross(out.vertices[t0.v[1]] - out.vertices[t0.v[0]],
                           out.vertices[t0.v[2]] - out.vertices[t0.v[0]]);
      EXPECT_GT(dot(n, o.occlusal), 0.0);
    }
  }
}

// A crack, not a hole: a closed solid whose edge a-c has, on one side only, extra vertices on
// the segment (a T-junction, as scans have), leaves a boundary loop along one line. Its fill
// would have zero area, so it is left open: three collinear corners (no centroid), and four
// (their centroid on the line too).
TEST(PrepareScan, ACollinearLoopIsLeftOpen) {
  for (int extra = 1; extra <= 2; ++extra) {
    SCOPED_TRACE(extra);
    TestArena ta;
    Mesh m(&ta.arena);
    // 0 = a, 1 = c, 2 = r (the base triangle a c r), 3 = top, 4 = bottom, then the extra
    // vertices on a-c.
    for (const Vec3& v : {Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{1, 2, 0}, Vec3{1, 0.7, 1},
                          Vec3{1, 0.7, -1}, Vec3{0.5, 0, 0}, Vec3{1.25, 0, 0}}) {
      ASSERT_TRUE(m.vertices.push_back(v));
    }
    const uint32_t a = 0, c = 1, r = 2, top = 3, bottom = 4;
    // Above: a -> (extra vertices) -> c, each segment with the top apex; then c r and r a.
    uint32_t from = a;
    for (int k = 0; k < extra; ++k) {
      const uint32_t x = 5 + static_cast<uint32_t>(k);
      ASSERT_TRUE(m.triangles.push_back(Triangle{{from, x, top}}));
      from = x;
    }
    ASSERT_TRUE(m.triangles.push_back(Triangle{{from, c, top}}));
    ASSERT_TRUE(m.triangles.push_back(Triangle{{c, r, top}}));
    ASSERT_TRUE(m.triangles.push_back(Triangle{{r, a, top}}));
    // Below: the whole edge c -> a.
    ASSERT_TRUE(m.triangles.push_back(Triangle{{r, c, bottom}}));
    ASSERT_TRUE(m.triangles.push_back(Triangle{{a, r, bottom}}));
    ASSERT_TRUE(m.triangles.push_back(Triangle{{c, a, bottom}}));
    Mesh out;
    PrepareReport rep;
    SPLINTCORE_ASSERT_OK(prepare_scan(Context(&ta.arena), m, PrepareOptions{}, &out, &rep));
    EXPECT_EQ(rep.degenerate_triangles, 0u);
    EXPECT_EQ(rep.holes_filled, 0u);
    EXPECT_EQ(rep.holes_left, 1u);
    EXPECT_EQ(rep.hole_triangles, 0u);
    EXPECT_EQ(out.triangles.size(), m.triangles.size());
    EXPECT_EQ(out.vertices.size(), m.vertices.size() - 2 + static_cast<size_t>(extra));
  }
}

}  // namespace
}  // namespace splintcore
