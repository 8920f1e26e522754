// An independent, brute-force self-intersection count for tests: every pair of triangles,
// decided by the big-integer oracle (tests/geometry/triangle_test.cpp, linked into the same
// test binary), never by the library's predicates or its sweep.
#ifndef SPLINTCORE_TESTS_SELF_INTERSECTION_ORACLE_H
#define SPLINTCORE_TESTS_SELF_INTERSECTION_ORACLE_H

#include <utility>
#include <vector>

#include "splintcore/mesh.h"
#include "support/exact.h"

// The independent oracle, defined in tests/geometry/triangle_test.cpp (the same test binary):
// exact closed triangle-triangle and segment-triangle tests by separating axes in big-integer
// arithmetic, never the library's predicates. Triangles must be non-degenerate.
namespace splintcore_test {
namespace tri_oracle {
bool triangles_meet(const splintcore::Vec3& a, const splintcore::Vec3& b, const splintcore::Vec3& c,
                    const splintcore::Vec3& d, const splintcore::Vec3& e,
                    const splintcore::Vec3& f);
bool segment_meets_triangle(const splintcore::Vec3& p, const splintcore::Vec3& q,
                            const splintcore::Vec3& a, const splintcore::Vec3& b,
                            const splintcore::Vec3& c);
// For coplanar p, q, s, t with s, t off line pq: same side of the line?
bool same_side_of_line(const splintcore::Vec3& p, const splintcore::Vec3& q,
                       const splintcore::Vec3& s, const splintcore::Vec3& t);
}  // namespace tri_oracle
}  // namespace splintcore_test

namespace splintcore {
namespace brute {

using splintcore_test::exact_collinear3d;
using splintcore_test::exact_orient3d_sign;
namespace oracle = splintcore_test::tri_oracle;

// ---- the brute force -------------------------------------------------------------------------

inline bool skipped(const Vec3* v, const Triangle& t) {
  return t.v[0] == t.v[1] || t.v[1] == t.v[2] || t.v[0] == t.v[2] ||
         exact_collinear3d(v[t.v[0]], v[t.v[1]], v[t.v[2]]);
}

// Do the non-degenerate triangles s and t conflict: meet other than through the vertex ids
// they share (mesh.h)? Decided from the definitions with the oracle:
// - no shared id: they conflict iff the closed triangles meet.
// - all three shared: the same triangle twice, always a conflict.
// - two shared (edge pq, free vertices s' and t'): if the triangles are not coplanar their
//   planes meet in line pq, and each triangle meets that line in the segment pq, so pq is all
//   they share. If coplanar with s', t' on opposite sides of line pq, they lie in opposite
//   closed half-planes and again share only pq. If on the same side, both contain the points
//   just beside the middle of pq on that side: a conflict. So: conflict iff coplanar and on the
//   same side.
// - one shared (vertex o): S and T conflict iff S n T != {o}. If x != o is in both, the ray
//   from o through x stays in S up to the point where it leaves S, which is on the edge of S
//   opposite o (a ray from a vertex into a triangle exits through the opposite edge, its ends
//   included), and likewise for T. The nearer of the two exit points is in both triangles and on
//   the opposite edge of one of them. Conversely a point of an opposite edge is not o (S and T
//   are non-degenerate). So: conflict iff the edge of S opposite o meets T, or the edge of T
//   opposite o meets S.
inline bool brute_conflict(const Vec3* v, const Triangle& s, const Triangle& t) {
  int shared = 0, s_shared[3] = {0, 0, 0}, t_shared[3] = {0, 0, 0};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (s.v[i] == t.v[j]) {
        ++shared;
        s_shared[i] = 1;
        t_shared[j] = 1;
      }
    }
  }
  const Vec3 &a = v[s.v[0]], &b = v[s.v[1]], &c = v[s.v[2]];
  const Vec3 &d = v[t.v[0]], &e = v[t.v[1]], &f = v[t.v[2]];
  if (shared == 0) return oracle::triangles_meet(a, b, c, d, e, f);
  if (shared == 3) return true;
  if (shared == 2) {
    int sf = 0, tf = 0;  // the free corners
    while (s_shared[sf]) ++sf;
    while (t_shared[tf]) ++tf;
    const Vec3& p = v[s.v[(sf + 1) % 3]];
    const Vec3& q = v[s.v[(sf + 2) % 3]];
    return exact_orient3d_sign(p, q, v[s.v[sf]], v[t.v[tf]]) == 0 &&
           oracle::same_side_of_line(p, q, v[s.v[sf]], v[t.v[tf]]);
  }
  int so = 0, to = 0;  // the shared corner
  while (!s_shared[so]) ++so;
  while (!t_shared[to]) ++to;
  return oracle::segment_meets_triangle(v[s.v[(so + 1) % 3]], v[s.v[(so + 2) % 3]], d, e, f) ||
         oracle::segment_meets_triangle(v[t.v[(to + 1) % 3]], v[t.v[(to + 2) % 3]], a, b, c);
}

inline Aabb box_of(const Vec3* v, const Triangle& t) {
  Aabb b;
  for (uint32_t id : t.v) b.add(v[id]);
  return b;
}

struct Brute {
  uint64_t pairs = 0;
  uint64_t candidates = 0;  // non-degenerate pairs whose closed boxes overlap
  uint32_t first_a = 0, first_b = 0;
  std::vector<std::pair<uint32_t, uint32_t>> conflicts;
  bool is_conflict(uint32_t a, uint32_t b) const {
    for (const auto& c : conflicts) {
      if (c.first == a && c.second == b) return true;
    }
    return false;
  }
};

// Every pair a < b (boxes that do not overlap cannot meet: a sound shortcut).
inline Brute brute_force(const Mesh& mesh) {
  Brute r;
  const Vec3* v = mesh.vertices.data();
  const size_t n = mesh.triangles.size();
  std::vector<char> skip(n);
  std::vector<Aabb> boxes(n);
  for (size_t i = 0; i < n; ++i) {
    skip[i] = skipped(v, mesh.triangles[i]);
    boxes[i] = box_of(v, mesh.triangles[i]);
  }
  for (uint32_t a = 0; a < n; ++a) {
    if (skip[a]) continue;
    for (uint32_t b = a + 1; b < n; ++b) {
      if (skip[b] || !boxes[a].overlaps(boxes[b])) continue;
      ++r.candidates;
      if (!brute_conflict(v, mesh.triangles[a], mesh.triangles[b])) continue;
      if (r.pairs++ == 0) {
        r.first_a = a;
        r.first_b = b;
      }
      r.conflicts.push_back({a, b});
    }
  }
  return r;
}

}  // namespace brute
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_SELF_INTERSECTION_ORACLE_H
