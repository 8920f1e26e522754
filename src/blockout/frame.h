// The sweeps' local frame (module-private): an orthonormal right-handed frame (u, v, w) with w
// along the direction, shared by the sampled sweep and the height field (blockout.h).
#ifndef SPLINTCORE_BLOCKOUT_FRAME_H
#define SPLINTCORE_BLOCKOUT_FRAME_H

#include <cmath>

#include "splintcore/blockout.h"
#include "splintcore/core.h"
#include "splintcore/geometry.h"

namespace splintcore {

struct Frame {
  Vec3 u, v, w;
};

// An orthonormal right-handed frame (u x v = w) with w along d. Axis directions get an exact
// permutation frame, so local coordinates are the input bits.
inline Status make_frame(const Vec3& d, Frame* f) {
  if (!is_finite(d)) {
    return make_error(StatusCode::kInvalidArgument, "sweep: the direction is not finite");
  }
  const double n2 = dot(d, d);
  if (!(n2 > 0)) {
    return make_error(StatusCode::kInvalidArgument, "sweep: the direction is zero");
  }
  const int nonzero = (d.x != 0) + (d.y != 0) + (d.z != 0);
  if (nonzero == 1) {
    const Vec3 x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
    if (d.x > 0)
      *f = {y, z, x};
    else if (d.x < 0)
      *f = {z, y, -x};
    else if (d.y > 0)
      *f = {z, x, y};
    else if (d.y < 0)
      *f = {x, z, -y};
    else if (d.z > 0)
      *f = {x, y, z};
    else
      *f = {x, -y, -z};
    return Status::ok();
  }
  const Vec3 w = d * (1.0 / std::sqrt(n2));
  const double ax = std::fabs(w.x), ay = std::fabs(w.y), az = std::fabs(w.z);
  const Vec3 helper = (ax <= ay && ax <= az) ? Vec3{1, 0, 0}
                      : (ay <= az)           ? Vec3{0, 1, 0}
                                             : Vec3{0, 0, 1};
  Vec3 u = cross(helper, w);
  u = u * (1.0 / std::sqrt(dot(u, u)));
  f->u = u;
  f->v = cross(w, u);
  f->w = w;
  return Status::ok();
}

inline Vec3 to_local(const Frame& f, const Vec3& p) {
  return {dot(f.u, p), dot(f.v, p), dot(f.w, p)};
}
inline Vec3 to_world(const Frame& f, const Vec3& p) {
  const Vec3 a = f.u * p.x;
  const Vec3 b = f.v * p.y;
  const Vec3 c = f.w * p.z;
  return (a + b) + c;
}

// Vertex i of jaw j where the sweep takes it (SweepOptions::jaw_vertex, else the jaw's own).
inline Vec3 jaw_point(const SweepOptions& o, Span<const Mesh> jaws, size_t j, size_t i) {
  return o.jaw_vertex != nullptr ? o.jaw_vertex(o.jaw_vertex_user, j, i) : jaws[j].vertices[i];
}

}  // namespace splintcore

#endif  // SPLINTCORE_BLOCKOUT_FRAME_H
