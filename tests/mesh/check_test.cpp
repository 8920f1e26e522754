#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

MeshReport check(TestArena& t, const std::vector<SoupTriangle>& soup) {
  Mesh mesh;
  Status s = test::mesh_from_soup(t.arena, soup, &mesh);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  MeshReport r;
  Context ctx(&t.arena);
  s = check_mesh(ctx, mesh, &r);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return r;
}

std::vector<SoupTriangle> unit_box() {
  const float lo[3] = {0, 0, 0}, hi[3] = {2, 3, 4};
  return shapes::box(lo, hi);
}

TEST(CheckMesh, BoxIsAValidGenusZeroSolidWithExactMeasures) {
  TestArena t;
  MeshReport r = check(t, unit_box());
  EXPECT_TRUE(r.is_valid_solid());
  EXPECT_EQ(r.vertex_count, 8u);
  EXPECT_EQ(r.edge_count, 18u);
  EXPECT_EQ(r.shells, 1u);
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_EQ(r.genus, 0);
  EXPECT_DOUBLE_EQ(r.volume, 24.0);
  EXPECT_DOUBLE_EQ(r.area, 2 * (6.0 + 8.0 + 12.0));
  EXPECT_EQ(r.bounds.hi, (Vec3{2, 3, 4}));
  EXPECT_TRUE(require_valid_solid(r).is_ok());
}

TEST(CheckMesh, TorusHasGenusOne) {
  TestArena t;
  MeshReport r = check(t, shapes::torus(32, 16, 10, 3));
  EXPECT_TRUE(r.is_valid_solid());
  EXPECT_EQ(r.genus, 1);
  EXPECT_EQ(r.euler_characteristic, 0);
  // Volume of the polyhedral torus converges to 2 pi^2 R r^2 from below.
  const double exact = 2 * 9.869604401089358 * 10 * 9;
  EXPECT_LT(r.volume, exact);
  EXPECT_GT(r.volume, 0.95 * exact);
}

TEST(CheckMesh, OpenMeshReportsFirstBoundaryEdge) {
  TestArena t;
  auto soup = unit_box();
  soup.erase(soup.begin() + 5);
  MeshReport r = check(t, soup);
  EXPECT_FALSE(r.closed());
  EXPECT_EQ(r.boundary_edges, 3u);
  EXPECT_EQ(r.boundary_loops, 1u);
  EXPECT_EQ(r.genus, -1);
  Status s = require_valid_solid(r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(std::strstr(s.message(), "not closed: 3 boundary edges"), nullptr) << s.message();
}

// Boundary loops are the components of the boundary edges: one per hole, holes that share a
// vertex counting once, none for a closed mesh.
TEST(CheckMesh, BoundaryLoopsCountHoles) {
  TestArena t;
  EXPECT_EQ(check(t, unit_box()).boundary_loops, 0u);
  auto soup = unit_box();
  // Triangles far apart on the box: find two that share no corner, drop both.
  auto shares_corner = [](const SoupTriangle& a, const SoupTriangle& b) {
    for (const auto& p : a.p) {
      for (const auto& q : b.p) {
        if (p[0] == q[0] && p[1] == q[1] && p[2] == q[2]) return true;
      }
    }
    return false;
  };
  size_t far = 1;
  while (far < soup.size() && shares_corner(soup[0], soup[far])) ++far;
  ASSERT_LT(far, soup.size());
  auto two_holes = soup;
  two_holes.erase(two_holes.begin() + static_cast<std::ptrdiff_t>(far));
  two_holes.erase(two_holes.begin());
  MeshReport r = check(t, two_holes);
  EXPECT_EQ(r.boundary_edges, 6u);
  EXPECT_EQ(r.boundary_loops, 2u);
  // Two triangles that share a corner (or an edge) removed: one loop.
  size_t touching = 1;
  while (touching < soup.size() && !shares_corner(soup[0], soup[touching])) ++touching;
  ASSERT_LT(touching, soup.size());
  auto joined = soup;
  joined.erase(joined.begin() + static_cast<std::ptrdiff_t>(touching));
  joined.erase(joined.begin());
  r = check(t, joined);
  EXPECT_GT(r.boundary_edges, 0u);
  EXPECT_EQ(r.boundary_loops, 1u);
}

TEST(CheckMesh, FlippedTriangleIsAnOrientationConflict) {
  TestArena t;
  auto soup = unit_box();
  std::swap(soup[3].p[1], soup[3].p[2]);
  MeshReport r = check(t, soup);
  EXPECT_TRUE(r.closed());
  EXPECT_EQ(r.orientation_conflicts, 3u);
  // Triangle 3 (top face) conflicts with its three neighbours; the first reported edge is the
  // one with the smallest triangle: top-face partner 2.
  EXPECT_EQ(r.first_orientation_conflict.triangle, 2u);
  EXPECT_FALSE(r.is_valid_solid());
}

TEST(CheckMesh, InsideOutBoxHasNegativeVolume) {
  TestArena t;
  auto soup = unit_box();
  for (auto& tri : soup) std::swap(tri.p[1], tri.p[2]);
  MeshReport r = check(t, soup);
  EXPECT_TRUE(r.oriented());
  EXPECT_DOUBLE_EQ(r.volume, -24.0);
  Status s = require_valid_solid(r);
  EXPECT_NE(std::strstr(s.message(), "inside out"), nullptr);
}

TEST(CheckMesh, NonManifoldEdgeDegenerateAndDuplicateTriangles) {
  TestArena t;
  auto soup = unit_box();
  // A fin sharing the box edge (0,0,0)-(2,0,0) with two box triangles.
  float a[3] = {0, 0, 0}, b[3] = {2, 0, 0}, c[3] = {1, -5, 0};
  soup.push_back(shapes::soup_triangle(a, b, c));
  // A zero-area sliver (collinear corners) and a repeated triangle.
  float m[3] = {1, 0, 0};
  soup.push_back(shapes::soup_triangle(a, m, b));
  soup.push_back(soup[0]);
  MeshReport r = check(t, soup);
  EXPECT_GE(r.nonmanifold_edges, 1u);
  EXPECT_EQ(r.degenerate_triangles, 1u);
  EXPECT_EQ(r.first_degenerate_triangle, 13u);
  EXPECT_EQ(r.duplicate_triangles, 1u);
  EXPECT_EQ(r.first_duplicate_triangle, 14u);
}

// require_valid_solid names the first defect in a fixed order (empty, open, non-manifold,
// misoriented, degenerate, duplicate, inside out), with its count, where it is (vertices and
// triangle) and the triangle as the status's index. The reports are a valid box's with one
// defect each written in, then one from a real mesh: two closed tetrahedra on one edge.
TEST(CheckMesh, RequireValidSolidNamesTheFirstDefectAndWhereItIs) {
  TestArena t;
  const MeshReport box = check(t, unit_box());
  ASSERT_TRUE(require_valid_solid(box).is_ok());
  struct Case {
    const char* text;
    uint64_t index;
    void (*set)(MeshReport*);
  };
  const Case cases[] = {
      {"mesh is empty: no triangles", kNoPosition,
       [](MeshReport* r) {
         r->triangle_count = 0;
         r->nonmanifold_edges = 1;  // the first check wins
       }},
      {"mesh is not closed: 1 boundary edge, first between vertices 1 and 2 (triangle 4)", 4,
       [](MeshReport* r) {
         r->boundary_edges = 1;
         r->first_boundary_edge = EdgeRef{1, 2, 4};
         r->nonmanifold_edges = 1;
       }},
      {"mesh is not edge-manifold: 2 edges shared by 3 or more triangles, first between "
       "vertices 3 and 7 (triangle 11)",
       11,
       [](MeshReport* r) {
         r->nonmanifold_edges = 2;
         r->first_nonmanifold_edge = EdgeRef{3, 7, 11};
         r->orientation_conflicts = 1;
       }},
      {"mesh is not consistently oriented: 3 edges used twice in the same direction, first "
       "between vertices 0 and 5 (triangle 2)",
       2,
       [](MeshReport* r) {
         r->orientation_conflicts = 3;
         r->first_orientation_conflict = EdgeRef{0, 5, 2};
         r->degenerate_triangles = 4;
       }},
      {"mesh has 4 degenerate (zero-area) triangles, first is triangle 9", 9,
       [](MeshReport* r) {
         r->degenerate_triangles = 4;
         r->first_degenerate_triangle = 9;
         r->duplicate_triangles = 1;
       }},
      {"mesh has 1 duplicate triangle, first is triangle 10", 10,
       [](MeshReport* r) {
         r->duplicate_triangles = 1;
         r->first_duplicate_triangle = 10;
         r->volume = -1;
       }},
  };
  for (const Case& c : cases) {
    MeshReport r = box;
    c.set(&r);
    const Status s = require_valid_solid(r);
    EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << c.text;
    EXPECT_STREQ(s.message(), c.text);
    EXPECT_EQ(s.index(), c.index) << c.text;
  }

  // Two tetrahedra (each closed and outward) on the edge (0,0,0)-(0,0,1): four triangles
  // use it, two each way, so it is neither a boundary nor an orientation conflict.
  const float o[3] = {0, 0, 0}, z[3] = {0, 0, 1}, a[3] = {1, 0, 0}, b[3] = {0, 1, 0};
  const float c[3] = {-1, 0, 0}, d[3] = {0, -1, 0};
  auto tetra = [](const float* p0, const float* p1, const float* p2, const float* p3) {
    // Outward when p3 is on the negative side of (p0, p1, p2).
    return std::vector<SoupTriangle>{
        shapes::soup_triangle(p0, p1, p2), shapes::soup_triangle(p0, p3, p1),
        shapes::soup_triangle(p1, p3, p2), shapes::soup_triangle(p2, p3, p0)};
  };
  std::vector<SoupTriangle> soup = tetra(o, b, a, z);
  for (const SoupTriangle& tri : tetra(o, d, c, z)) soup.push_back(tri);
  const MeshReport r = check(t, soup);
  EXPECT_EQ(r.boundary_edges, 0u);
  EXPECT_EQ(r.orientation_conflicts, 0u);
  EXPECT_EQ(r.nonmanifold_edges, 1u);
  EXPECT_GT(r.volume, 0.0);
  const Status s = require_valid_solid(r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(std::strstr(s.message(), "not edge-manifold: 1 edge shared by 3 or more"), nullptr)
      << s.message();
  EXPECT_NE(std::strstr(s.message(), "between vertices 0 and 3"), nullptr) << s.message();
}

// The check decides most triangles with orient2d's first stage (on the area's cross product,
// two triangles at a time) before collinear3d: the degenerate count must be collinear3d's on
// triangles flat in x-y but not in 3D (vertical), nearly flat ones (filter undecided), exactly
// collinear ones off the axes, and random ones; an odd count (the last triangle alone); the
// area and volume the bits of mesh_area() and mesh_volume().
TEST(CheckMesh, DegenerateCountIsCollinear3dOnEveryTriangle) {
  TestArena t;
  std::mt19937 rng(29);
  std::uniform_real_distribution<float> coord(-20.0f, 20.0f);
  Mesh mesh(&t.arena);
  std::vector<Vec3> v;
  std::vector<Triangle> tris;
  for (uint32_t i = 0; i < 4001; ++i) {
    const Vec3 a{coord(rng), coord(rng), coord(rng)};
    Vec3 b{coord(rng), coord(rng), coord(rng)};
    Vec3 c{coord(rng), coord(rng), coord(rng)};
    switch (i % 5) {
      case 0:  // vertical: the x-y orientation is exactly zero, the triangle is not flat
        b = Vec3{a.x, a.y, b.z};
        break;
      case 1:  // exactly collinear, off the axes (a + 2 (b - a) in small integers)
        b = Vec3{a.x + 1.0, a.y + 2.0, a.z + 3.0};
        c = Vec3{a.x + 2.0, a.y + 4.0, a.z + 6.0};
        break;
      case 2:  // nearly collinear: the midpoint nudged by one ulp
        c = Vec3{0.5 * (a.x + b.x), 0.5 * (a.y + b.y), std::nextafter(0.5 * (a.z + b.z), 1e9)};
        break;
      case 3:  // collinear in x-y only
        c = Vec3{0.5 * (a.x + b.x), 0.5 * (a.y + b.y), c.z};
        break;
      default: break;
    }
    const uint32_t base = static_cast<uint32_t>(v.size());
    v.push_back(a);
    v.push_back(b);
    v.push_back(c);
    tris.push_back(Triangle{{base, base + 1, base + 2}});
  }
  ASSERT_TRUE(mesh.vertices.resize(v.size()));
  ASSERT_TRUE(mesh.triangles.resize(tris.size()));
  std::copy(v.begin(), v.end(), mesh.vertices.data());
  std::copy(tris.begin(), tris.end(), mesh.triangles.data());
  uint64_t expected = 0;
  uint32_t first = 0;
  for (uint32_t i = 0; i < tris.size(); ++i) {
    const uint32_t* k = tris[i].v;
    if (collinear3d(v[k[0]], v[k[1]], v[k[2]])) {
      if (expected == 0) first = i;
      ++expected;
    }
  }
  EXPECT_GE(expected, 800u);  // the exactly collinear fifth at least
  MeshReport r;
  Context ctx(&t.arena);
  ASSERT_TRUE(check_mesh(ctx, mesh, &r).is_ok());
  EXPECT_EQ(r.degenerate_triangles, expected);
  EXPECT_EQ(r.first_degenerate_triangle, first);
  EXPECT_EQ(r.area, mesh_area(mesh));
  EXPECT_EQ(r.volume, mesh_volume(mesh));
  // The last triangle (alone in its pair) counts: made flat, it is the last one found.
  mesh.vertices[mesh.triangles[4000].v[2]] = mesh.vertices[mesh.triangles[4000].v[0]];
  MeshReport flat;
  ASSERT_TRUE(check_mesh(ctx, mesh, &flat).is_ok());
  EXPECT_EQ(flat.degenerate_triangles,
            expected + (collinear3d(v[12000], v[12001], v[12002]) ? 0u : 1u));
}

TEST(CheckMesh, TwoShellsAndOutOfRangeIndex) {
  TestArena t;
  auto soup = unit_box();
  const float lo[3] = {5, 5, 5}, hi[3] = {6, 6, 6};
  auto second = shapes::box(lo, hi);
  soup.insert(soup.end(), second.begin(), second.end());
  MeshReport r = check(t, soup);
  EXPECT_EQ(r.shells, 2u);
  EXPECT_EQ(r.genus, 0);
  EXPECT_DOUBLE_EQ(r.volume, 25.0);

  Mesh bad(&t.arena);
  ASSERT_TRUE(bad.vertices.push_back(Vec3{}));
  ASSERT_TRUE(bad.triangles.push_back(Triangle{{0, 0, 3}}));
  Context ctx(&t.arena);
  Status s = check_mesh(ctx, bad, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.index(), 0u);
}

// Property: random rigid motions of closed meshes keep them valid solids with the same
// topology, and the volume agrees with the analytic box volume.
TEST(CheckMesh, PropertyRandomBoxesStayValid) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<float> u(-50, 50), s(0.5f, 20);
  for (int i = 0; i < 200; ++i) {
    TestArena t(1 << 20);
    float lo[3] = {u(rng), u(rng), u(rng)};
    float hi[3] = {lo[0] + s(rng), lo[1] + s(rng), lo[2] + s(rng)};
    MeshReport r = check(t, shapes::box(lo, hi));
    ASSERT_TRUE(r.is_valid_solid());
    double exact = (double{hi[0]} - lo[0]) * (double{hi[1]} - lo[1]) * (double{hi[2]} - lo[2]);
    ASSERT_NEAR(r.volume, exact, 1e-12 * exact);
  }
}

// The report as a plain model computes it: every undirected edge's uses gathered in a map
// (ordered by key), shells by repeated flood fill, duplicates by comparing sorted id triples.
// The check's linear edge pass must give exactly these figures and first offenders.
MeshReport model_report(const Mesh& mesh) {
  MeshReport r;
  const uint32_t nt = static_cast<uint32_t>(mesh.triangles.size());
  const Triangle* tris = mesh.triangles.data();
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> uses;  // edge -> 3 t + k
  for (uint32_t t = 0; t < nt; ++t) {
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t a = tris[t].v[k], b = tris[t].v[(k + 1) % 3];
      uses[{std::min(a, b), std::max(a, b)}].push_back(3 * t + k);
    }
  }
  std::vector<uint32_t> shell(nt);
  for (uint32_t t = 0; t < nt; ++t) shell[t] = t;
  for (bool changed = true; changed;) {  // labels: the smallest triangle reachable
    changed = false;
    for (const auto& e : uses) {
      uint32_t m = UINT32_MAX;
      for (uint32_t u : e.second) m = std::min(m, shell[u / 3]);
      for (uint32_t u : e.second) {
        if (shell[u / 3] != m) shell[u / 3] = m, changed = true;
      }
    }
  }
  auto note = [](EdgeRef* ref, uint64_t* count, uint32_t a, uint32_t b, uint32_t t) {
    if (*count == 0 || t < ref->triangle) *ref = EdgeRef{a, b, t};
    ++*count;
  };
  std::set<std::pair<uint32_t, uint32_t>> shell_vertex, shell_edge;
  for (const auto& e : uses) {
    const uint32_t a = e.first.first, b = e.first.second;
    uint32_t min_t = UINT32_MAX, forward = 0;
    for (uint32_t u : e.second) {
      min_t = std::min(min_t, u / 3);
      forward += tris[u / 3].v[u % 3] == a ? 1u : 0u;
    }
    ++r.edge_count;
    shell_edge.insert({shell[min_t], r.edge_count});
    const size_t n = e.second.size();
    if (n == 1) note(&r.first_boundary_edge, &r.boundary_edges, a, b, min_t);
    if (n > 2) note(&r.first_nonmanifold_edge, &r.nonmanifold_edges, a, b, min_t);
    if (n == 2 && forward != 1) {
      note(&r.first_orientation_conflict, &r.orientation_conflicts, a, b, min_t);
    }
  }
  std::map<std::array<uint32_t, 3>, std::vector<uint32_t>> sets;
  std::map<uint32_t, std::array<int64_t, 3>> per_shell;  // V, E, F
  for (uint32_t t = 0; t < nt; ++t) {
    std::array<uint32_t, 3> v = {tris[t].v[0], tris[t].v[1], tris[t].v[2]};
    for (uint32_t x : v) {
      if (shell_vertex.insert({shell[t], x}).second) ++per_shell[shell[t]][0];
    }
    ++per_shell[shell[t]][2];
    std::sort(v.begin(), v.end());
    sets[v].push_back(t);
  }
  for (const auto& se : shell_edge) ++per_shell[se.first][1];
  for (const auto& s : sets) {
    if (s.second.size() < 2) continue;
    if (r.duplicate_triangles == 0 || s.second[1] < r.first_duplicate_triangle) {
      r.first_duplicate_triangle = s.second[1];
    }
    r.duplicate_triangles += s.second.size() - 1;
  }
  bool genus_defined =
      r.boundary_edges == 0 && r.nonmanifold_edges == 0 && r.orientation_conflicts == 0 && nt > 0;
  int64_t genus = 0, total_v = 0;
  for (const auto& s : per_shell) {
    const int64_t chi = s.second[0] - s.second[1] + s.second[2];
    total_v += s.second[0];
    if (chi > 2 || (2 - chi) % 2 != 0) genus_defined = false;
    genus += (2 - chi) / 2;
  }
  r.shells = per_shell.size();
  r.euler_characteristic = total_v - static_cast<int64_t>(r.edge_count) + nt;
  r.genus = genus_defined ? genus : -1;
  return r;
}

// Random index triples over few vertices: non-manifold edges, repeated ids, duplicates in any
// order, shells touching at a vertex, conflicts; and closed meshes with triangles appended.
TEST(CheckMesh, PropertyEdgePassAgreesWithAPlainModel) {
  std::mt19937_64 rng(2029);
  for (int round = 0; round < 400; ++round) {
    TestArena t(1 << 22);
    Mesh mesh(&t.arena);
    if (round % 4 == 0) {
      const float lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3};
      ASSERT_TRUE(test::mesh_from_soup(t.arena, shapes::box(lo, hi), &mesh).is_ok());
    } else {
      mesh.bind(&t.arena);
    }
    const uint32_t nv = 3 + static_cast<uint32_t>(rng() % (round % 3 == 0 ? 6 : 40));
    while (mesh.vertices.size() < nv) {
      ASSERT_TRUE(mesh.vertices.push_back(
          Vec3{static_cast<double>(rng() % 7), static_cast<double>(rng() % 5), 0.5}));
    }
    const uint32_t extra = static_cast<uint32_t>(rng() % 60);
    for (uint32_t i = 0; i < extra; ++i) {
      Triangle tri{{static_cast<uint32_t>(rng() % nv), static_cast<uint32_t>(rng() % nv),
                    static_cast<uint32_t>(rng() % nv)}};
      if (i > 0 && rng() % 5 == 0) {  // an earlier triangle again, rotated or flipped
        const Triangle& o = mesh.triangles[rng() % mesh.triangles.size()];
        tri = rng() % 2 ? Triangle{{o.v[1], o.v[2], o.v[0]}} : Triangle{{o.v[0], o.v[2], o.v[1]}};
      }
      ASSERT_TRUE(mesh.triangles.push_back(tri));
    }
    MeshReport got;
    ASSERT_TRUE(check_mesh(Context(&t.arena), mesh, &got).is_ok());
    SCOPED_TRACE(round);
    test::expect_same_topology(got, model_report(mesh));
    // The measures are taken in the check's own pass: the same bits as the functions.
    EXPECT_EQ(got.area, mesh_area(mesh));
    EXPECT_EQ(got.volume, mesh_volume(mesh));
  }
}

// A closed surface pinched at a vertex (a torus with two far-apart vertices made one) is still
// closed, edge-manifold and oriented, but not a surface at that vertex: its Euler
// characteristic is odd (-1), so it has no genus (-1), as in the plain model.
TEST(CheckMesh, APinchedTorusHasNoGenus) {
  TestArena t;
  Mesh mesh;
  ASSERT_TRUE(test::mesh_from_soup(t.arena, shapes::torus(32, 16, 10, 3), &mesh).is_ok());
  // Vertex 0 and the vertex nearest its mirror image through the torus' centre: no common
  // neighbour, so making them one adds no edge and leaves every edge with two uses.
  const Vec3 mirror = mesh.vertices[0] * -1.0;
  uint32_t far = 1;
  for (uint32_t v = 1; v < mesh.vertices.size(); ++v) {
    if (length(mesh.vertices[v] - mirror) < length(mesh.vertices[far] - mirror)) far = v;
  }
  ASSERT_GT(length(mesh.vertices[far] - mesh.vertices[0]), 20.0);
  for (Triangle& tri : mesh.triangles) {
    for (uint32_t& v : tri.v) v = v == far ? 0 : v;
  }
  MeshReport r;
  ASSERT_TRUE(check_mesh(Context(&t.arena), mesh, &r).is_ok());
  EXPECT_TRUE(r.closed() && r.edge_manifold() && r.oriented());
  EXPECT_EQ(r.shells, 1u);
  EXPECT_EQ(r.unreferenced_vertices, 1u);
  EXPECT_EQ(r.euler_characteristic, -1);
  EXPECT_EQ(r.genus, -1);
  test::expect_same_topology(r, model_report(mesh));
}

// check_closed_oriented is linear however many triangles share a vertex: a bipyramid whose
// apex (vertex 0, the first bucket) is in 100,000 triangles. Bucket-local pair counting took
// (2 * 10^5)^2 steps there. Also: the first bad edge is the one named.
TEST(CheckClosedOriented, HubVertexOfAHundredThousandTrianglesAndFirstBadEdge) {
  const int n = 100000;
  std::vector<SoupTriangle> soup;
  const float apex[3] = {0, 0, 5}, bottom[3] = {0, 0, -5};
  auto ring = [&](int i, float p[3]) {
    // The ring's corners on a circle of radius 10 (angles from a fixed table, not libm).
    const double t = 6.283185307179586 * static_cast<double>(i % n) / n;
    // cos/sin by their Taylor series in double: only needs to be the same every run.
    double c = 1, s = 0, term = 1;
    for (int k = 1; k < 40; ++k) {
      term *= t / k;
      if (k % 4 == 1) s += term;
      if (k % 4 == 2) c -= term;
      if (k % 4 == 3) s -= term;
      if (k % 4 == 0) c += term;
    }
    p[0] = static_cast<float>(10 * c);
    p[1] = static_cast<float>(10 * s);
    p[2] = 0;
  };
  for (int i = 0; i < n; ++i) {
    float a[3], b[3];
    ring(i, a);
    ring(i + 1, b);
    soup.push_back(shapes::soup_triangle(apex, a, b));
    soup.push_back(shapes::soup_triangle(bottom, b, a));
  }
  TestArena t(size_t{256} << 20);
  Mesh mesh;
  ASSERT_TRUE(test::mesh_from_soup(t.arena, soup, &mesh).is_ok());
  ASSERT_EQ(mesh.triangles.size(), size_t{2} * n);
  Context ctx(&t.arena);
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, mesh, &volume));
  EXPECT_NEAR(volume, 2.0 / 3.0 * 3.14159265358979 * 100 * 5, 0.01);

  // Flipping top triangle 6 (apex, r3, r4) breaks its three edges; the one named is in the
  // apex's bucket (vertex 0: the smallest), and the triangle named is the first (in triangle
  // order) that uses it, as the quadratic version reported.
  std::swap(mesh.triangles[6].v[1], mesh.triangles[6].v[2]);
  ASSERT_EQ(mesh.triangles[6].v[0], 0u);
  const Status s = check_closed_oriented(ctx, mesh, &volume);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(std::strstr(s.message(), "not consistently oriented"), nullptr) << s.message();
  const char* at = std::strstr(s.message(), "between vertices");
  ASSERT_NE(at, nullptr) << s.message();
  unsigned lo = 0, hi = 0, tri = 0;
  ASSERT_EQ(std::sscanf(at, "between vertices %u and %u (triangle %u)", &lo, &hi, &tri), 3);
  EXPECT_EQ(lo, 0u);
  EXPECT_TRUE(hi == mesh.triangles[6].v[1] || hi == mesh.triangles[6].v[2]) << hi;
  uint32_t first_user = ~0u;
  for (uint32_t t = 0; t < mesh.triangles.size() && first_user == ~0u; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.triangles[t].v[k], b = mesh.triangles[t].v[(k + 1) % 3];
      if (std::min(a, b) == lo && std::max(a, b) == hi) first_user = t;
    }
  }
  EXPECT_EQ(tri, first_user);
}

// check_closed_oriented (the Boolean's and the printer's quick gate) names an index out of
// range (the triangle as the status's index), an inside-out solid and an empty mesh.
TEST(CheckClosedOriented, NamesABadIndexAnInsideOutSolidAndAnEmptyMesh) {
  TestArena t;
  Mesh mesh;
  ASSERT_TRUE(test::mesh_from_soup(t.arena, unit_box(), &mesh).is_ok());
  Context ctx(&t.arena);
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, mesh, &volume));
  EXPECT_EQ(volume, 24.0);

  const uint32_t saved = mesh.triangles[4].v[1];
  mesh.triangles[4].v[1] = 8;  // one past the last vertex
  Status s = check_closed_oriented(ctx, mesh, &volume);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_STREQ(s.message(), "triangle 4 refers to vertex 8 but the mesh has 8 vertices");
  EXPECT_EQ(s.index(), 4u);
  mesh.triangles[4].v[1] = saved;

  for (Triangle& tri : mesh.triangles) std::swap(tri.v[1], tri.v[2]);
  volume = 0;
  s = check_closed_oriented(ctx, mesh, &volume);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_STREQ(s.message(), "mesh is inside out: volume -24 mm^3");
  EXPECT_EQ(volume, -24.0);  // reported even when it fails

  Mesh empty(&t.arena);
  s = check_closed_oriented(ctx, empty, &volume);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_STREQ(s.message(), "mesh is empty");
}

// remove_small_shells: a 2 x 3 x 4 box with a crumb (a 0.1 mm cube) beside it and a void (an
// inside-out 0.2 mm cube) inside it, the crumb's triangles first (so its vertices have the
// first ids and the box's are renumbered).
std::vector<SoupTriangle> box_with_crumbs() {
  const float clo[3] = {5, 5, 5}, chi[3] = {5.1f, 5.1f, 5.1f};
  const float vlo[3] = {1, 1, 1}, vhi[3] = {1.2f, 1.2f, 1.2f};
  std::vector<SoupTriangle> soup = shapes::box(clo, chi);
  for (const SoupTriangle& t : unit_box()) soup.push_back(t);
  for (SoupTriangle t : shapes::box(vlo, vhi)) {
    for (int k = 0; k < 3; ++k) std::swap(t.p[1][k], t.p[2][k]);
    soup.push_back(t);
  }
  return soup;
}

TEST(SmallShells, CrumbAndVoidGoTheBoxStaysBitForBit) {
  TestArena t;
  Context ctx(&t.arena);
  Mesh mesh, alone;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, box_with_crumbs(), &mesh));
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, unit_box(), &alone));
  ASSERT_EQ(mesh.triangles.size(), 36u);
  SmallShells removed;
  SPLINTCORE_ASSERT_OK(remove_small_shells(ctx, 0.01, &mesh, &removed));
  EXPECT_EQ(removed.removed, 2u);
  EXPECT_EQ(removed.triangles, 24u);
  EXPECT_NEAR(removed.volume_mm3, 0.001 + 0.008, 1e-6);
  EXPECT_DOUBLE_EQ(removed.largest_kept_mm3, 24.0);
  // What is left is the box as welded alone: the same vertices, ids and triangle order.
  EXPECT_EQ(test::mesh_sha256(mesh), test::mesh_sha256(alone));
  MeshReport r;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, mesh, &r));
  EXPECT_TRUE(r.is_valid_solid());
}

TEST(SmallShells, NothingBelowTheBoundLeavesTheMeshAlone) {
  TestArena t;
  Context ctx(&t.arena);
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, box_with_crumbs(), &mesh));
  const std::string before = test::mesh_sha256(mesh);
  SmallShells removed;
  SPLINTCORE_ASSERT_OK(remove_small_shells(ctx, 1e-4, &mesh, &removed));  // under 0.001 mm^3
  EXPECT_EQ(removed.removed, 0u);
  EXPECT_EQ(test::mesh_sha256(mesh), before);
  // The largest shell stays whatever the bound: here the crumb alone.
  Mesh crumb;
  const float lo[3] = {5, 5, 5}, hi[3] = {5.1f, 5.1f, 5.1f};
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, shapes::box(lo, hi), &crumb));
  SPLINTCORE_ASSERT_OK(remove_small_shells(ctx, 1e9, &crumb, &removed));
  EXPECT_EQ(removed.removed, 0u);
  EXPECT_EQ(crumb.triangles.size(), 12u);
}

TEST(SmallShells, RunsInItsBoundAndLessIsACleanError) {
  TestArena t;
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, box_with_crumbs(), &mesh));
  const std::string before = test::mesh_sha256(mesh);
  const uint64_t bound = remove_small_shells_bound(mesh.vertices.size());
  SmallShells removed;
  {
    // A byte short of the three arrays themselves (the bound adds their alignment slack).
    TestArena tight(16 * mesh.vertices.size() - 1);
    const Status s = remove_small_shells(Context(&tight.arena), 0.01, &mesh, &removed);
    EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << test::format(s);
    EXPECT_EQ(test::mesh_sha256(mesh), before);
  }
  TestArena exact(static_cast<size_t>(bound));
  SPLINTCORE_ASSERT_OK(remove_small_shells(Context(&exact.arena), 0.01, &mesh, &removed));
  EXPECT_EQ(removed.removed, 2u);
  EXPECT_EQ(exact.arena.used(), 0u);  // all given back
}

TEST(SmallShells, AnIndexOutOfRangeIsNamed) {
  TestArena t;
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, unit_box(), &mesh));
  mesh.triangles[7].v[2] = 99;
  SmallShells removed;
  const Status s = remove_small_shells(Context(&t.arena), 0.01, &mesh, &removed);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(test::format(s).find("triangle 7 refers to vertex 99"), std::string::npos)
      << test::format(s);
}

// A box 2.2 x 2.2 x 2.4 mm at float32 corners that are not round in binary (welded).
Status odd_box(Arena& arena, Mesh* mesh) {
  const float lo[3] = {0.1f, -0.3f, 1.7f}, hi[3] = {2.3f, 1.9f, 4.1f};
  return test::mesh_from_soup(arena, shapes::box(lo, hi), mesh);
}

// transform_mesh (the plan's repositioning of a jaw, segment.h): every vertex is the
// transform's apply_point of the one before, the triangles as they were; the volume kept and
// the inverse bringing the box back within rounding.
TEST(TransformMesh, MovesEveryVertexAndKeepsTheTriangles) {
  TestArena t;
  Context ctx(&t.arena);
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(odd_box(t.arena, &mesh));
  const std::vector<Vec3> before(mesh.vertices.begin(), mesh.vertices.end());
  const std::vector<Triangle> triangles(mesh.triangles.begin(), mesh.triangles.end());
  RigidTransform x = rotation_about_axis(Vec3{1, 2, 3}, Vec3{1.0 / 3, -2.0 / 3, 2.0 / 3}, 0.7);
  x.t[0] += 5;
  transform_mesh(x, &mesh);
  ASSERT_EQ(mesh.vertices.size(), before.size());
  for (size_t i = 0; i < before.size(); ++i) {
    EXPECT_TRUE(mesh.vertices[i] == x.apply_point(before[i])) << i;
  }
  ASSERT_EQ(mesh.triangles.size(), triangles.size());
  EXPECT_EQ(
      std::memcmp(mesh.triangles.data(), triangles.data(), triangles.size() * sizeof(Triangle)), 0);
  MeshReport r;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, mesh, &r));
  EXPECT_NEAR(r.volume, 2.2 * 2.2 * 2.4, 1e-5);
  transform_mesh(inverse(x), &mesh);
  for (size_t i = 0; i < before.size(); ++i) {
    EXPECT_LT(length(mesh.vertices[i] - before[i]), 1e-12) << i;
  }
}

// scale_mesh: the box from inches to mm, each coordinate the float32 nearest the double
// product (computed here apart); 1/1000 from micrometres; and the refusals, the mesh unchanged.
TEST(ScaleMesh, EachCoordinateIsTheFloat32NearestTheProduct) {
  TestArena t;
  Context ctx(&t.arena);
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(odd_box(t.arena, &mesh));
  std::vector<Vec3> before(mesh.vertices.begin(), mesh.vertices.end());
  SPLINTCORE_ASSERT_OK(scale_mesh(25.4, &mesh));
  ASSERT_EQ(mesh.vertices.size(), before.size());
  for (size_t i = 0; i < before.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      const float expected = static_cast<float>(before[i][a] * 25.4);
      EXPECT_EQ(mesh.vertices[i][a], static_cast<double>(expected)) << i << " " << a;
    }
  }
  MeshReport r;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, mesh, &r));
  EXPECT_TRUE(r.is_valid_solid());
  const double mm3 = 2.2 * 2.2 * 2.4 * 25.4 * 25.4 * 25.4;
  EXPECT_NEAR(r.volume, mm3, 1e-6 * mm3);  // the float32 sides are not 2.2 and 2.4 exactly
  SPLINTCORE_ASSERT_OK(scale_mesh(0.001, &mesh));
  EXPECT_EQ(mesh.vertices[0][0],
            static_cast<double>(static_cast<float>(
                static_cast<double>(static_cast<float>(before[0][0] * 25.4)) * 0.001)));
  // Refused, nothing changed: a factor that is no scale, a vertex that is not finite, a vertex
  // that would leave float32 range (named).
  const std::string kept = test::mesh_sha256(mesh);
  for (double bad : {0.0, -1.0, std::nan(""), HUGE_VAL}) {
    const Status s = scale_mesh(bad, &mesh);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << bad;
    EXPECT_NE(std::string(s.message()).find("finite number above 0"), std::string::npos);
  }
  mesh.vertices[5].y = 1e38;
  const std::string with_big = test::mesh_sha256(mesh);
  Status s = scale_mesh(10, &mesh);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded);
  EXPECT_EQ(std::string(s.message()), "vertex 5 scaled by 10 is beyond float32 range");
  EXPECT_EQ(test::mesh_sha256(mesh), with_big);
  mesh.vertices[3].z = std::nan("");
  s = scale_mesh(2, &mesh);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_EQ(s.index(), 3u);
  EXPECT_NE(kept, with_big);
}

}  // namespace
}  // namespace splintcore
