// The height field's offset (module-private, blockout.h says what and why): a polytope Q around
// the lower half of the ball of radius r, and the planar pieces of T + Q (Minkowski sum) for a
// jaw triangle T whose lowest points make the lower surface of T + Q.
//
// Q is a lathe of 12 sides: a profile circumscribed about the quarter circle, tangent at 0, 30,
// 60 and 90 degrees from the bottom, turned in 12 flat sides circumscribed about the circle, so
// every face plane lies at distance r(1 + 1e-9) from the centre: Q holds the lower half ball,
// and its vertices lie within r / cos^2(15 degrees) = 1.0718 r of the centre. Every value is
// built from square roots (no transcendental function: the same bits everywhere).
//
// Why the pieces: the lowest point of T + Q in a column is a vertex of a linear program over
// T x Q, so it lies in T + q (q Q's vertex furthest along T's outward normal), in an edge of T
// plus an edge of Q (a parallelogram), or in a vertex of T plus a face of Q; those that are
// faces of the sum are enough (with ties taken both ways), and only those that do not face
// along w (+d) can hold a lowest point. Each piece lies in T + Q, so the least of their heights
// is the lower surface of T + Q, at most that of T + the ball.
#ifndef SPLINTCORE_BLOCKOUT_OFFSET_BALL_H
#define SPLINTCORE_BLOCKOUT_OFFSET_BALL_H

#include <cmath>
#include <cstdint>

#include "splintcore/geometry.h"

namespace splintcore {

struct OffsetBall {
  static constexpr int kSides = 12;
  static constexpr int kRings = 4;   // profile vertices: bottom ring .. equator ring
  static constexpr int kFaces = 25;  // faces not along w: the bottom, two rings of kSides
  static constexpr int kEdges = 60;  // edges with a face not along w on a side
  static constexpr int kFaceTriangles = 10 + 4 * kSides;  // the bottom's fan and the quads
  Vec3 vertex[kRings * kSides];
  struct Face {
    Vec3 normal;       // outward, unit
    int first, count;  // its triangles in `triangle`
  };
  Face face[kFaces];
  Vec3 triangle[kFaceTriangles][3];
  struct Edge {
    int a, b;       // vertices
    Vec3 n1, n2;    // the outward normals of the faces on its sides (unit)
    Vec3 along;     // vertex b - vertex a
    double length;  // |along|
    double turn;    // (n1 x n2) . along: the wedge's sense
  };
  Edge edge[kEdges];
  double reach = 0;  // the largest |vertex|
};

// Q for radius r > 0 (local frame: w is d; Q lies in w <= 0).
void make_offset_ball(double r, OffsetBall* q);

// Calls emit(p0, p1, p2) for each planar piece (triangles) of T + Q on T and its edges:
// T + q (q Q's vertex furthest along T's outward normal, ties all), and the parallelograms
// e + f (e an edge of T, f an edge of Q) that are faces of T + Q not facing along w; T = (t0,
// t1, t2) counter-clockwise seen from its outside with its outward normal against w (a front
// triangle). Serial, deterministic order.
template <typename Emit>
void triangle_pieces(const OffsetBall& q, const Vec3 t[3], Emit emit);

// The faces of Q (bits 0 .. kFaces - 1) along whose normal corner k of T lies furthest (ties
// all): where F + t_k is a face of T + Q. A face F + a is part of the lower surface of the
// union of the sums only where a is furthest along F's normal on every front triangle around
// it (elsewhere F's inside lies inside a neighbour's sum), so a vertex's faces are the AND of
// this over its front triangles (vertex_pieces).
uint32_t support_faces(const OffsetBall& q, const Vec3 t[3], int k);

// Calls emit for the triangles of F + a, for each face F of Q in `faces` (bits as above).
template <typename Emit>
void vertex_pieces(const OffsetBall& q, const Vec3& a, uint32_t faces, Emit emit);

// ---- implementation

namespace offset_detail {

// Relative slack of the tie and cone tests: a piece near a boundary is taken (taking more is
// never wrong, every piece lies in T + Q).
constexpr double kSlack = 1e-9;

// x (perpendicular to edge f, of length xl) within the wedge of f's faces' outward normals
// (less than a half turn), with slack.
inline bool in_wedge(const Vec3& x, double xl, const OffsetBall::Edge& f) {
  const double scale = kSlack * xl * f.length;
  const double s1 = dot(cross(f.n1, x), f.along), s2 = dot(cross(x, f.n2), f.along);
  return f.turn >= 0 ? (s1 >= -scale && s2 >= -scale) : (s1 <= scale && s2 <= scale);
}

}  // namespace offset_detail

template <typename Emit>
void triangle_pieces(const OffsetBall& q, const Vec3 t[3], Emit emit) {
  using offset_detail::kSlack;
  const Vec3 n = cross(t[1] - t[0], t[2] - t[0]);
  const double nl = length(n);
  double best = -HUGE_VAL;
  for (const Vec3& v : q.vertex) {
    const double d = dot(n, v);
    best = d > best ? d : best;
  }
  for (const Vec3& v : q.vertex) {
    if (dot(n, v) >= best - kSlack * nl * q.reach) emit(t[0] + v, t[1] + v, t[2] + v);
  }
  // An edge of T plus an edge of Q where their normal N = e x f, turned away from T's third
  // vertex, lies in the wedge of f's faces (both ways when T's plane holds N).
  for (int k = 0; k < 3; ++k) {
    const Vec3& a = t[k];
    const Vec3& b = t[k == 2 ? 0 : k + 1];
    const Vec3& c = t[k == 0 ? 2 : k - 1];
    const Vec3 e = b - a;
    const double el = length(e), cl = length(c - a);
    for (const OffsetBall::Edge& f : q.edge) {
      const Vec3 normal = cross(e, f.along);
      const double nn2 = dot(normal, normal);
      const double floor = kSlack * el * f.length;
      if (!(nn2 > floor * floor)) continue;  // parallel: no area
      const double nn = std::sqrt(nn2);
      const double side = dot(normal, c - a);
      const double tie = kSlack * nn * cl;
      for (int sign = -1; sign <= 1; sign += 2) {
        if (sign * side > tie) continue;  // turned towards T's third vertex
        const Vec3 x = normal * static_cast<double>(sign);
        if (x.z > kSlack * nn) continue;  // faces along w: holds no lowest point
        if (!offset_detail::in_wedge(x, nn, f)) continue;
        const Vec3& qa = q.vertex[f.a];
        const Vec3& qb = q.vertex[f.b];
        emit(a + qa, b + qa, b + qb);
        emit(a + qa, b + qb, a + qb);
      }
    }
  }
}

template <typename Emit>
void vertex_pieces(const OffsetBall& q, const Vec3& a, uint32_t faces, Emit emit) {
  for (int i = 0; i < OffsetBall::kFaces; ++i) {
    if ((faces >> i & 1u) == 0) continue;
    const OffsetBall::Face& f = q.face[i];
    for (int k = f.first; k < f.first + f.count; ++k) {
      emit(a + q.triangle[k][0], a + q.triangle[k][1], a + q.triangle[k][2]);
    }
  }
}

}  // namespace splintcore

#endif  // SPLINTCORE_BLOCKOUT_OFFSET_BALL_H
