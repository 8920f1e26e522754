// The lathe around the lower half ball (offset_ball.h).
#include "blockout/offset_ball.h"
#include "core/fminmax.h"

#include <cmath>

namespace splintcore {

namespace {

Vec3 unit(const Vec3& v) { return v * (1.0 / length(v)); }

// Outward unit normal of the planar polygon (a, b, c, ...) counter-clockwise from outside.
Vec3 face_normal(const Vec3& a, const Vec3& b, const Vec3& c) { return unit(cross(b - a, c - a)); }

}  // namespace

void make_offset_ball(double r, OffsetBall* q) {
  constexpr int n = OffsetBall::kSides;
  const double s2 = std::sqrt(2.0), s3 = std::sqrt(3.0), s6 = std::sqrt(6.0);
  const double c15 = (s6 + s2) / 4, s15 = (s6 - s2) / 4;
  // cos and sin of 30 j degrees.
  const double cs[n][2] = {{1, 0},          {s3 / 2, 0.5},  {0.5, s3 / 2},  {0, 1},
                           {-0.5, s3 / 2},  {-s3 / 2, 0.5}, {-1, 0},        {-s3 / 2, -0.5},
                           {-0.5, -s3 / 2}, {0, -1},        {0.5, -s3 / 2}, {s3 / 2, -0.5}};
  // The profile (radius across, w), tangent to the circle of radius rr at 0, 30, 60, 90
  // degrees from the bottom: its corners at 15, 45, 75 degrees (radius rr / cos 15), then the
  // equator; the radius across divided by cos 15 for the 12 flat sides.
  const double rr = r * (1 + 1e-9);
  const double k = rr / c15;
  const double profile[OffsetBall::kRings][2] = {
      {k * s15, -rr}, {k * s2 / 2, -k * s2 / 2}, {rr, -k * s15}, {rr, 0}};
  q->reach = 0;
  for (int ring = 0; ring < OffsetBall::kRings; ++ring) {
    const double across = profile[ring][0] / c15;
    for (int j = 0; j < n; ++j) {
      const Vec3 v{across * cs[j][0], across * cs[j][1], profile[ring][1]};
      q->vertex[ring * n + j] = v;
      q->reach = max_of(q->reach, length(v));
    }
  }
  auto at = [](int ring, int j) { return ring * n + (j % n); };
  // Faces: the bottom (a fan from vertex 0, counter-clockwise seen from below), then the quads
  // of the two rings (ring, ring + 1) between sides j and j + 1; the equator's vertical quads
  // only give normals (their pieces are vertical).
  int tri = 0;
  q->face[0] = {Vec3{0, 0, -1}, 0, n - 2};
  for (int j = 1; j + 1 < n; ++j, ++tri) {
    q->triangle[tri][0] = q->vertex[at(0, 0)];
    q->triangle[tri][1] = q->vertex[at(0, j + 1)];
    q->triangle[tri][2] = q->vertex[at(0, j)];
  }
  Vec3 side_normal[3][n];  // ring quads 0-1, 1-2, 2-3
  for (int ring = 0; ring < 3; ++ring) {
    for (int j = 0; j < n; ++j) {
      const Vec3& a = q->vertex[at(ring, j)];
      const Vec3& b = q->vertex[at(ring, j + 1)];
      const Vec3& c = q->vertex[at(ring + 1, j + 1)];
      const Vec3& d = q->vertex[at(ring + 1, j)];
      side_normal[ring][j] = face_normal(a, b, c);
      if (ring == 2) continue;
      q->face[1 + ring * n + j] = {side_normal[ring][j], tri, 2};
      q->triangle[tri][0] = a, q->triangle[tri][1] = b, q->triangle[tri++][2] = c;
      q->triangle[tri][0] = a, q->triangle[tri][1] = c, q->triangle[tri++][2] = d;
    }
  }
  // Edges: the rings 0, 1, 2 (below, above), the meridians 0-1 and 1-2 (sides j - 1, j).
  int e = 0;
  const Vec3 bottom{0, 0, -1};
  for (int ring = 0; ring < 3; ++ring) {
    for (int j = 0; j < n; ++j) {
      const Vec3& below = ring == 0 ? bottom : side_normal[ring - 1][j];
      q->edge[e++] = {at(ring, j), at(ring, j + 1), below, side_normal[ring][j], Vec3{}, 0, 0};
    }
  }
  for (int ring = 0; ring < 2; ++ring) {
    for (int j = 0; j < n; ++j) {
      q->edge[e++] = {at(ring, j),
                      at(ring + 1, j),
                      side_normal[ring][(j + n - 1) % n],
                      side_normal[ring][j],
                      Vec3{},
                      0,
                      0};
    }
  }
  for (OffsetBall::Edge& f : q->edge) {
    f.along = q->vertex[f.b] - q->vertex[f.a];
    f.length = length(f.along);
    f.turn = dot(cross(f.n1, f.n2), f.along);
  }
}

uint32_t support_faces(const OffsetBall& q, const Vec3 t[3], int k) {
  double size = 0;
  for (int i = 1; i < 3; ++i) size = max_of(size, length(t[i] - t[0]));
  const double tie = offset_detail::kSlack * (size + 1);
  uint32_t faces = 0;
  for (int i = 0; i < OffsetBall::kFaces; ++i) {
    const Vec3& n = q.face[i].normal;
    const double mine = dot(n, t[k]);
    bool furthest = true;
    for (int j = 0; j < 3; ++j) {
      if (j != k && dot(n, t[j]) > mine + tie) furthest = false;
    }
    if (furthest) faces |= 1u << i;
  }
  return faces;
}

}  // namespace splintcore
