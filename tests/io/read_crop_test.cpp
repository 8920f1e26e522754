// Reading cropped to a box (StlReadOptions::keep, MeshReadOptions::keep; issue 29): the
// triangles whose corners all lie beyond one side of the box are left out as they are read,
// as if they were not in the file. The reference is that definition itself: the same file
// written without them (filtered here by this file's own test, not the library's) and read
// whole. And a Boolean with B read cropped to boolean_region is the same solid as with B whole.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <tuple>
#include <vector>

#include "common/phantom.h"
#include "common/shapes.h"
#include "splintcore/boolean.h"
#include "splintcore/design.h"
#include "splintcore/io.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

// All three corners strictly beyond one side of the box (written out, not Aabb::outcode).
bool left_out(const SoupTriangle& t, const Aabb& box) {
  const double lo[3] = {box.lo.x, box.lo.y, box.lo.z}, hi[3] = {box.hi.x, box.hi.y, box.hi.z};
  for (int a = 0; a < 3; ++a) {
    bool below = true, above = true;
    for (int k = 0; k < 3; ++k) {
      below = below && static_cast<double>(t.p[k][a]) < lo[a];
      above = above && static_cast<double>(t.p[k][a]) > hi[a];
    }
    if (below || above) return true;
  }
  return false;
}

std::vector<SoupTriangle> kept_by(const std::vector<SoupTriangle>& soup, const Aabb& box) {
  std::vector<SoupTriangle> out;
  for (const SoupTriangle& t : soup) {
    if (!left_out(t, box)) out.push_back(t);
  }
  return out;
}

// The soup with exactly shared corners as PLY (ascii) or OBJ text: one vertex a corner, so
// the reader's weld (asked for) makes the mesh; the same floats as the STL.
std::string float_text(float f) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(f));
  return buf;
}

std::string soup_text(const std::vector<SoupTriangle>& soup, bool ply) {
  std::string s;
  if (ply) {
    s += "ply\nformat ascii 1.0\nelement vertex " + std::to_string(3 * soup.size()) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(soup.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  }
  for (const SoupTriangle& t : soup) {
    for (const auto& p : t.p) {
      s += (ply ? "" : "v ") + float_text(p[0]) + " " + float_text(p[1]) + " " + float_text(p[2]) +
           "\n";
    }
  }
  for (size_t i = 0; i < soup.size(); ++i) {
    const size_t b = 3 * i + (ply ? 0 : 1);
    s += (ply ? "3 " : "f ") + std::to_string(b) + " " + std::to_string(b + 1) + " " +
         std::to_string(b + 2) + "\n";
  }
  return s;
}

std::string ascii_stl(const std::vector<SoupTriangle>& soup) {
  std::string s = "solid crop\n";
  for (const SoupTriangle& t : soup) {
    s += "facet normal 0 0 0\nouter loop\n";
    for (const auto& p : t.p) {
      s += "vertex " + float_text(p[0]) + " " + float_text(p[1]) + " " + float_text(p[2]) + "\n";
    }
    s += "endloop\nendfacet\n";
  }
  return s + "endsolid crop\n";
}

struct Read {
  Status status;
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  MeshReadInfo info;
};

Read read(Arena& arena, const std::vector<uint8_t>& bytes, const char* name, const Aabb& keep,
          bool size_known = true, bool weld = true) {
  ArenaScope scope(arena);
  MemorySource ms{bytes.data(), bytes.size(), 0, 0};
  ByteSource source = memory_source(&ms, name);
  if (!size_known) source.size = kUnknownSize;
  MeshReadOptions o;
  o.weld = weld;
  o.keep = keep;
  Mesh m(&arena);
  Read r;
  r.status = read_mesh(Context(&arena), source, o, &m, &r.info);
  r.vertices.assign(m.vertices.begin(), m.vertices.end());
  r.triangles.assign(m.triangles.begin(), m.triangles.end());
  return r;
}

// The arena a binary read of known size leaves held (its mesh), `keep` its crop.
size_t held_after_read(Arena& arena, const std::vector<uint8_t>& bytes, const Aabb& keep) {
  ArenaScope scope(arena);
  const size_t before = arena.used();
  MemorySource ms{bytes.data(), bytes.size(), 0, 0};
  const ByteSource source = memory_source(&ms, "held.stl");
  MeshReadOptions o;
  o.weld = true;
  o.keep = keep;
  Mesh m(&arena);
  MeshReadInfo info;
  EXPECT_TRUE(read_mesh(Context(&arena), source, o, &m, &info).is_ok());
  return arena.used() - before;
}

void expect_same_mesh(const Read& got, const Read& want) {
  ASSERT_TRUE(got.status.is_ok()) << test::format(got.status);
  ASSERT_TRUE(want.status.is_ok()) << test::format(want.status);
  ASSERT_EQ(got.vertices.size(), want.vertices.size());
  ASSERT_EQ(got.triangles.size(), want.triangles.size());
  for (size_t i = 0; i < got.vertices.size(); ++i) {
    ASSERT_TRUE(got.vertices[i] == want.vertices[i]) << "vertex " << i;
  }
  for (size_t t = 0; t < got.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) ASSERT_EQ(got.triangles[t].v[k], want.triangles[t].v[k]);
  }
}

// Boxes that cut the torus (R 10, r 3, about the origin in the xy plane) in different ways,
// one that holds it all and one that misses it.
std::vector<Aabb> boxes() {
  return {Aabb{Vec3{-20, -20, -20}, Vec3{20, 20, 20}}, Aabb{Vec3{0, -20, -20}, Vec3{20, 20, 20}},
          Aabb{Vec3{-4, -13, -1}, Vec3{4, 13, 0.5}},   Aabb{Vec3{8.5, 1, 0}, Vec3{9, 30, 4}},
          Aabb{Vec3{-3, -3, -5}, Vec3{3, 3, 5}},       Aabb{Vec3{30, 30, 30}, Vec3{40, 40, 40}}};
}

TEST(ReadCrop, StlGivesTheFileWithoutTheTrianglesBeyondTheBox) {
  test::TestArena t(size_t{64} << 20);
  const std::vector<SoupTriangle> soup = shapes::torus(96, 48, 10, 3);
  const std::vector<uint8_t> binary = test::binary_stl(soup);
  const std::vector<uint8_t> ascii = test::to_bytes(ascii_stl(soup));
  size_t cases = 0;
  for (const Aabb& box : boxes()) {
    const std::vector<SoupTriangle> kept = kept_by(soup, box);
    SCOPED_TRACE("box " + std::to_string(cases++) + ": " + std::to_string(kept.size()) + " of " +
                 std::to_string(soup.size()) + " kept");
    const Read want = read(t.arena, test::binary_stl(kept), "want.stl", Aabb{});
    // Binary of known size (welded as read), a stream of unknown size, and ASCII (the soup,
    // then the weld): the same mesh.
    expect_same_mesh(read(t.arena, binary, "a.stl", box), want);
    expect_same_mesh(read(t.arena, binary, "a.stl", box, /*size_known=*/false), want);
    expect_same_mesh(read(t.arena, ascii, "a.stl", box), want);
    // The file's triangles are still counted as read.
    EXPECT_EQ(read(t.arena, binary, "a.stl", box).info.triangles, soup.size());
    // And the mesh holds no more of the arena than the file without them would: the room
    // reserved for the triangles left out is given back (the real dentition's files: 8.3 MB).
    if (!kept.empty()) {
      EXPECT_EQ(held_after_read(t.arena, binary, box),
                held_after_read(t.arena, test::binary_stl(kept), Aabb{}));
    }
  }
  // The box that holds everything and the empty default keep the whole file.
  expect_same_mesh(read(t.arena, binary, "a.stl", boxes()[0]),
                   read(t.arena, binary, "a.stl", Aabb{}));
  EXPECT_EQ(kept_by(soup, boxes().back()).size(), 0u);
}

// The binary reader tests its records' float corners against the box's sides rounded to
// float32 (lo up, hi down): sides exactly on a corner's float, a double's hair either side of
// it, halfway between two floats, and beyond float32's range (or infinite) must leave out
// the triangles the test in double does, no more and no fewer.
TEST(ReadCrop, SidesBetweenAndOnFloatsDecideAsInDouble) {
  test::TestArena t(size_t{16} << 20);
  // Small triangles whose x, y and z run over consecutive floats about 1.5 and -2.25.
  std::vector<SoupTriangle> soup;
  const float bases[2] = {1.5f, -2.25f};
  for (float base : bases) {
    float f = std::nextafter(std::nextafter(base, -HUGE_VALF), -HUGE_VALF);
    for (int i = 0; i < 5; ++i, f = std::nextafter(f, HUGE_VALF)) {
      const float g = std::nextafter(f, HUGE_VALF);
      // Each triangle with its corners turned twice, so that each corner (the record's first,
      // second or third) is in turn the one on a side with the others beyond it.
      for (const SoupTriangle& tri : {SoupTriangle{{{f, f, f}, {g, f, f}, {f, g, f}}},
                                      SoupTriangle{{{f, f, f}, {f, f, g}, {g, g, g}}},
                                      SoupTriangle{{{g, g, g}, {f, g, g}, {g, f, g}}}}) {
        for (int turn = 0; turn < 3; ++turn) {
          SoupTriangle turned;
          for (int k = 0; k < 3; ++k) {
            for (int a = 0; a < 3; ++a) turned.p[k][a] = tri.p[(k + turn) % 3][a];
          }
          soup.push_back(turned);
        }
      }
    }
  }
  std::vector<double> sides;
  for (float base : bases) {
    for (float f = std::nextafter(base, -HUGE_VALF); f <= std::nextafter(base, HUGE_VALF);
         f = std::nextafter(f, HUGE_VALF)) {
      const double d = static_cast<double>(f),
                   up = static_cast<double>(std::nextafter(f, HUGE_VALF));
      sides.insert(sides.end(), {d, std::nextafter(d, -HUGE_VAL), std::nextafter(d, HUGE_VAL),
                                 d + (up - d) / 2});
    }
  }
  const double far = 1e300;
  const std::vector<uint8_t> binary = test::binary_stl(soup);
  size_t cases = 0, left_out_any = 0, kept_any = 0;
  for (double side : sides) {
    // The side as lo (on each axis in turn, the others open) and as hi.
    for (int axis = 0; axis < 3; ++axis) {
      for (int as_hi = 0; as_hi < 2; ++as_hi) {
        double lo[3] = {-far, -HUGE_VAL, -far}, hi[3] = {far, HUGE_VAL, far};
        (as_hi != 0 ? hi : lo)[axis] = side;
        const Aabb box{Vec3{lo[0], lo[1], lo[2]}, Vec3{hi[0], hi[1], hi[2]}};
        const std::vector<SoupTriangle> kept = kept_by(soup, box);
        SCOPED_TRACE("case " + std::to_string(cases++));
        expect_same_mesh(read(t.arena, binary, "a.stl", box),
                         read(t.arena, test::binary_stl(kept), "want.stl", Aabb{}));
        left_out_any += kept.size() < soup.size() ? 1 : 0;
        kept_any += kept.empty() ? 0 : 1;
      }
    }
  }
  // The sides do cut between the triangles: some cases leave some out, some keep some.
  EXPECT_GT(left_out_any, cases / 4);
  EXPECT_GT(kept_any, cases / 4);
}

TEST(ReadCrop, PlyAndObjLeaveOutTheSameTriangles) {
  test::TestArena t(size_t{64} << 20);
  const std::vector<SoupTriangle> soup = shapes::torus(40, 20, 10, 3);
  for (int ply = 0; ply < 2; ++ply) {
    SCOPED_TRACE(ply ? "PLY" : "OBJ");
    const std::vector<uint8_t> text = test::to_bytes(soup_text(soup, ply != 0));
    const char* name = ply ? "a.ply" : "a.obj";
    for (const Aabb& box : boxes()) {
      const std::vector<SoupTriangle> kept = kept_by(soup, box);
      // Welded: the mesh the STL of the kept triangles gives.
      expect_same_mesh(read(t.arena, text, name, box),
                       read(t.arena, test::binary_stl(kept), "want.stl", Aabb{}));
      // Not welded: the file's vertices all stay, the kept faces keep their order.
      const Read whole = read(t.arena, text, name, Aabb{}, true, false);
      const Read cropped = read(t.arena, text, name, box, true, false);
      ASSERT_TRUE(cropped.status.is_ok()) << test::format(cropped.status);
      EXPECT_EQ(cropped.vertices.size(), whole.vertices.size());
      ASSERT_EQ(cropped.triangles.size(), kept.size());
      size_t k = 0;
      for (size_t i = 0; i < soup.size(); ++i) {
        if (left_out(soup[i], box)) continue;
        for (int c = 0; c < 3; ++c) EXPECT_EQ(cropped.triangles[k].v[c], whole.triangles[i].v[c]);
        ++k;
      }
    }
  }
}

TEST(ReadCrop, CornersOfLeftOutTrianglesAreStillChecked) {
  test::TestArena t(size_t{16} << 20);
  std::vector<SoupTriangle> soup = shapes::torus(24, 12, 10, 3);
  const Aabb box{Vec3{0, -20, -20}, Vec3{20, 20, 20}};
  // The last triangle wholly beyond the box's low x side, each of its nine coordinates in
  // turn then made NaN, huge or infinite: the same error (and place) as reading it whole.
  // (Every position is tried, each with the next coordinate at the limit exactly: however
  // the check of a left-out triangle groups the coordinates, one over the limit is found.)
  size_t far = soup.size();
  for (size_t i = 0; i < soup.size(); ++i) {
    if (left_out(soup[i], box)) far = i;
  }
  ASSERT_LT(far, soup.size());
  // A coordinate exactly at the limit is within it: the triangle is still left out.
  for (int c = 1; c < 9; ++c) {
    if (c % 3 == 0) continue;  // (its x keeps it beyond the low x side)
    std::vector<SoupTriangle> edge = soup;
    edge[far].p[c / 3][c % 3] = 1.0e6f;
    ASSERT_TRUE(left_out(edge[far], box));
    expect_same_mesh(read(t.arena, test::binary_stl(edge), "a.stl", box),
                     read(t.arena, test::binary_stl(kept_by(edge, box)), "want.stl", Aabb{}));
  }
  for (int c = 0; c < 9; ++c) {
    for (const float bad : {std::nanf(""), 1e30f, -1e30f, -INFINITY}) {
      std::vector<SoupTriangle> broken = soup;
      broken[far].p[c / 3][c % 3] = bad;
      // A bad y or z leaves it beyond the low x side; a bad x may not (a NaN corner is beyond
      // no side): then the triangle is read, and its corner checked there.
      if (c % 3 != 0) {
        ASSERT_TRUE(left_out(broken[far], box));
      }
      // The next coordinate at the limit exactly (max_abs_coordinate, 1e6 mm by default).
      if (c < 8) broken[far].p[(c + 1) / 3][(c + 1) % 3] = 1.0e6f;
      const std::vector<uint8_t> bytes = test::binary_stl(broken);
      const Read whole = read(t.arena, bytes, "a.stl", Aabb{});
      const Read cropped = read(t.arena, bytes, "a.stl", box);
      ASSERT_FALSE(whole.status.is_ok());
      EXPECT_EQ(cropped.status.code(), whole.status.code()) << c;
      EXPECT_EQ(test::format(cropped.status), test::format(whole.status)) << c;
    }
  }
}

// The paper-scale base minus both phantom jaws (the mandible 2 mm down), B read whole and read
// cropped to boolean_region: the same solid (the same triangles, in another order: the
// cropped weld numbers B's vertices by first use among the kept triangles), far fewer B
// triangles held.
TEST(ReadCrop, BooleanWithTheCroppedJawsIsTheSameSolid) {
  test::TestArena t(size_t{256} << 20);
  Context ctx(&t.arena);
  const std::vector<uint8_t> text =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
  CaseFile c;
  SPLINTCORE_ASSERT_OK(
      parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), "paper", &c));
  Mesh base(&t.arena);
  BaseReport br;
  SPLINTCORE_ASSERT_OK(build_case_base(ctx, c, &base, &br));
  std::vector<SoupTriangle> jaws;
  for (int j = 0; j < 2; ++j) {
    phantom::JawMesh m;
    phantom::PhantomOptions po;
    po.target_triangles = 20000;
    SPLINTCORE_ASSERT_OK(
        phantom::make_jaw(j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, po, &m));
    for (const Triangle& tr : m.triangles) {
      SoupTriangle s;
      for (int k = 0; k < 3; ++k) {
        Vec3 v = m.vertices[tr.v[k]];
        if (j == 1) v.z -= 2.0;
        s.p[k][0] = static_cast<float>(v.x);
        s.p[k][1] = static_cast<float>(v.y);
        s.p[k][2] = static_cast<float>(v.z);
      }
      jaws.push_back(s);
    }
  }
  const std::vector<uint8_t> stl = test::binary_stl(jaws);
  const BooleanOptions bo;
  const Aabb region = boolean_region(base, bo);
  std::vector<std::array<float, 9>> sets[2];
  double volume[2] = {0, 0};
  size_t held[2] = {0, 0};
  for (int cropped = 0; cropped < 2; ++cropped) {
    ArenaScope scope(t.arena);
    MemorySource ms{stl.data(), stl.size(), 0, 0};
    StlReadOptions so;
    if (cropped != 0) so.keep = region;
    Mesh b(&t.arena), out;
    SPLINTCORE_ASSERT_OK(read_stl_mesh(ctx, memory_source(&ms, "jaws.stl"), so, &b, nullptr));
    held[cropped] = b.triangles.size();
    BooleanStats st;
    SPLINTCORE_ASSERT_OK(mesh_boolean(ctx, base, b, bo, &out, &st));
    MeshReport report;
    SPLINTCORE_ASSERT_OK(check_mesh(ctx, out, &report));
    EXPECT_TRUE(report.is_valid_solid());
    volume[cropped] = report.volume;
    for (const Triangle& tr : out.triangles) {
      // Each triangle as its corners from the lowest, turning as it does.
      int first = 0;
      for (int k = 1; k < 3; ++k) {
        const Vec3 &p = out.vertices[tr.v[k]], &q = out.vertices[tr.v[first]];
        if (std::make_tuple(p.x, p.y, p.z) < std::make_tuple(q.x, q.y, q.z)) first = k;
      }
      std::array<float, 9> key;
      for (int k = 0; k < 3; ++k) {
        const Vec3& p = out.vertices[tr.v[(first + k) % 3]];
        key[3 * k] = static_cast<float>(p.x);
        key[3 * k + 1] = static_cast<float>(p.y);
        key[3 * k + 2] = static_cast<float>(p.z);
      }
      sets[cropped].push_back(key);
    }
    std::sort(sets[cropped].begin(), sets[cropped].end());
  }
  EXPECT_EQ(held[0], jaws.size());
  EXPECT_LT(held[1], held[0] / 2) << "the crop keeps most of the jaws";
  EXPECT_GT(held[1], 0u);
  EXPECT_EQ(sets[1], sets[0]);
  EXPECT_EQ(volume[1], volume[0]);
  std::printf("B triangles held: %zu whole, %zu cropped; result %zu triangles, %.6f mm^3\n",
              held[0], held[1], sets[0].size(), volume[0]);
}

}  // namespace
}  // namespace splintcore
