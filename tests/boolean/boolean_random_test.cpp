// The randomised proof the Boolean owes the splint (src/boolean/boolean_run.h and its stage files):
// more than 1,000 random rigid motions of the paper_scale base (A, 2,612 triangles) against both
// phantom jaws (B, tools/common/phantom.h, the mandible moved by the case's -2 mm), and 300 more of
// the real patient's wafer against two of the real CBCT teeth when ../shared/realdata is present.
// About 40% of the cases are exact contacts: a base face plane through a jaw vertex, or a base
// vertex on a jaw vertex, where the Boolean must nudge A and still succeed, or answer
// kUnsupported naming the triangles (at most 2% of the cases).
//
// Every successful case proves, for A - B and A * B:
//   - closed, edge-manifold, consistently oriented, outward, nothing degenerate (check_mesh);
//   - |vol(A - B) + vol(A * B) - vol(A')| <= 1e-9 vol(A'), A' the base as used (A + nudge);
//   - every output vertex is a vertex of A', bit for bit a vertex of B (jaw vertices are never
//     moved), or one of the stats.intersection_points: exactly that many others;
//   - no self-intersection (find_self_intersections, exact) on every 10th case and on every
//     nudged result of every 3rd case (it costs about half the operation).
// The identity is exact up to the rounding of the volume sums only for double output
// (float32_output = false: intersection points are the rounded doubles of the exact points),
// so that is how every case runs. Every 10th case also runs as the tool does (float32 output,
// the library's own self-intersection check): there the intersection points move by up to half
// a float32 ulp off the surfaces, which changes the volume of A's re-triangulated surface by up
// to (1/3) * area * displacement per triangle corner (a few 1e-9 of the wafer's volume on the
// real teeth), so the identity is checked against 1e-9 vol(A') plus that first-order bound.
//
// Cases run on two threads (each its own arena); each case draws from its own
// std::mt19937_64 seeded by (test seed, case index), so a case replays alone and the summary
// does not depend on scheduling. One summary line per TEST.

#include <gtest/gtest.h>

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "common/phantom.h"
#include "common/realcase.h"
#include "splintcore/boolean.h"
#include "splintcore/design.h"
#include "splintcore/mesh.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

#if defined(NDEBUG) && !defined(__SANITIZE_ADDRESS__)
constexpr uint32_t kCaseDivisor = 1;
#else
constexpr uint32_t kCaseDivisor = 4;
#endif

using test::TestArena;

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxAngle = 3.0 * kPi / 180.0;  // generic motions: up to 3 degrees
constexpr double kMaxShift = 0.5;                // and up to 0.5 mm
constexpr double kMaxContactShift = 1.5;         // a base vertex moved onto a jaw vertex
constexpr double kVolumeTolerance = 1e-9;        // relative
constexpr double kMaxUnsupportedShare = 0.02;
constexpr uint32_t kThreads = 2;

// ---- vertex sets --------------------------------------------------------------------------------

// Exact membership by bit pattern (an open-addressing hash set: cheap at -O0 too, where the
// standard containers are slow).
class VertexSet {
 public:
  void assign(const Mesh& m, const Vec3& shift) {
    size_t capacity = 16;
    while (capacity < 2 * m.vertices.size()) capacity *= 2;
    slots_.assign(capacity, Key{0, 0, 0, false});
    for (const Vec3& v : m.vertices) {
      const Key k = key_of(v + shift);
      size_t i = hash(k) & (capacity - 1);
      while (slots_[i].used && !same(slots_[i], k)) i = (i + 1) & (capacity - 1);
      slots_[i] = k;
    }
  }
  bool contains(const Vec3& v) const {
    const Key k = key_of(v);
    const size_t mask = slots_.size() - 1;
    for (size_t i = hash(k) & mask;; i = (i + 1) & mask) {
      if (!slots_[i].used) return false;
      if (same(slots_[i], k)) return true;
    }
  }

 private:
  struct Key {
    uint64_t x, y, z;
    bool used;
  };
  static Key key_of(const Vec3& v) {
    Key k{0, 0, 0, true};
    std::memcpy(&k.x, &v.x, 8);
    std::memcpy(&k.y, &v.y, 8);
    std::memcpy(&k.z, &v.z, 8);
    return k;
  }
  static bool same(const Key& a, const Key& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
  static size_t hash(const Key& k) {
    uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
    h = (h ^ (h >> 29) ^ k.y) * 0xBF58476D1CE4E5B9ull;
    h = (h ^ (h >> 31) ^ k.z) * 0x94D049BB133111EBull;
    return static_cast<size_t>(h ^ (h >> 32));
  }
  std::vector<Key> slots_;
};

bool float32_exact(const Vec3& v) {
  Vec3 r = v;
  return round_to_float32(&r) && r == v;
}

// ---- the scene: A before any motion, B, and where exact contacts can be made --------------------

struct Scene {
  const char* name = "";
  const Mesh* base = nullptr;  // float32-exact, valid solid
  const Mesh* jaws = nullptr;  // float32-exact
  VertexSet jaw_set;
  Vec3 centre;  // rotations are about the arch's centre (the base's box centre)
  // Face-plane contacts (only when every base vertex lies on one of two planes z = top, z =
  // bottom): jaw vertices whose z is within kMaxShift of a face.
  bool flat_faces = false;
  double top = 0, bottom = 0;
  std::vector<uint32_t> near_top, near_bottom;
  // Vertex-on-vertex contacts: jaw vertices within 2 mm of a base vertex (before the motion).
  std::vector<uint32_t> near_base;
};

void prepare_scene(const Mesh& base, const Mesh& jaws, Scene* s) {
  s->base = &base;
  s->jaws = &jaws;
  s->jaw_set.assign(jaws, Vec3{});
  const Aabb box = mesh_bounds(base);
  s->centre = box.center();
  s->top = box.hi.z;
  s->bottom = box.lo.z;
  s->flat_faces = true;
  for (const Vec3& v : base.vertices) {
    s->flat_faces = s->flat_faces && (v.z == s->top || v.z == s->bottom);
  }
  Aabb grown = box;
  grown.lo = grown.lo - Vec3{kMaxShift, kMaxShift, kMaxShift};
  grown.hi = grown.hi + Vec3{kMaxShift, kMaxShift, kMaxShift};
  for (uint32_t i = 0; i < jaws.vertices.size(); ++i) {
    const Vec3& v = jaws.vertices[i];
    if (!grown.contains(v)) continue;
    double nearest = HUGE_VAL;
    for (const Vec3& w : base.vertices) nearest = std::min(nearest, length_squared(w - v));
    if (nearest <= 4.0) s->near_base.push_back(i);
    if (s->flat_faces && std::abs(v.z - s->top) <= kMaxShift) s->near_top.push_back(i);
    if (s->flat_faces && std::abs(v.z - s->bottom) <= kMaxShift) s->near_bottom.push_back(i);
  }
}

// ---- motions ------------------------------------------------------------------------------------

enum class Contact : uint8_t { kNone, kFacePlane, kVertexOnVertex };

const char* contact_name(Contact c) {
  return c == Contact::kNone ? "generic"
                             : (c == Contact::kFacePlane ? "face-plane" : "vertex-on-vertex");
}

struct Motion {
  Contact contact = Contact::kNone;
  RigidTransform x;   // applied to the base, then every coordinate rounded to float32
  Vec3 second_shift;  // vertex-on-vertex: the exact shift applied after the rounding
  uint32_t jaw_vertex = 0;
};

std::string describe(const Motion& m) {
  char text[512];
  std::snprintf(text, sizeof(text),
                "%s, R = [%.17g %.17g %.17g; %.17g %.17g %.17g; %.17g %.17g %.17g], t = (%.17g, "
                "%.17g, %.17g), then + (%.17g, %.17g, %.17g), jaw vertex %u",
                contact_name(m.contact), m.x.r[0][0], m.x.r[0][1], m.x.r[0][2], m.x.r[1][0],
                m.x.r[1][1], m.x.r[1][2], m.x.r[2][0], m.x.r[2][1], m.x.r[2][2], m.x.t.x, m.x.t.y,
                m.x.t.z, m.second_shift.x, m.second_shift.y, m.second_shift.z, m.jaw_vertex);
  return text;
}

// Rotation by `angle` about the unit `axis` through `centre`, then translation by `shift`.
RigidTransform rotation_about(const Vec3& axis, double angle, const Vec3& centre,
                              const Vec3& shift) {
  const double c = std::cos(angle), s = std::sin(angle), k = 1.0 - c;
  RigidTransform x;
  x.r[0][0] = c + axis.x * axis.x * k;
  x.r[0][1] = axis.x * axis.y * k - axis.z * s;
  x.r[0][2] = axis.x * axis.z * k + axis.y * s;
  x.r[1][0] = axis.y * axis.x * k + axis.z * s;
  x.r[1][1] = c + axis.y * axis.y * k;
  x.r[1][2] = axis.y * axis.z * k - axis.x * s;
  x.r[2][0] = axis.z * axis.x * k - axis.y * s;
  x.r[2][1] = axis.z * axis.y * k + axis.x * s;
  x.r[2][2] = c + axis.z * axis.z * k;
  x.t = centre - x.apply_vector(centre) + shift;
  return x;
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  for (;;) {
    const Vec3 v{n(rng), n(rng), n(rng)};
    const double l = length(v);
    if (l > 1e-3) return v * (1.0 / l);
  }
}

Vec3 random_shift(std::mt19937_64& rng, double max_length) {
  std::uniform_real_distribution<double> u(0.0, max_length);
  return random_unit(rng) * u(rng);
}

// out = round_to_float32(x(base)) + second_shift (exact: the shift is a difference of two
// float32 values near the vertex it moves, and the others are rounded again).
bool apply_motion(const Mesh& base, const Motion& m, Mesh* out) {
  out->vertices.clear();
  out->triangles.clear();
  if (!out->vertices.reserve(base.vertices.size()) ||
      !out->triangles.reserve(base.triangles.size())) {
    return false;
  }
  for (const Vec3& v : base.vertices) {
    Vec3 p = m.x.apply_point(v);
    if (!round_to_float32(&p)) return false;
    if (m.contact == Contact::kVertexOnVertex) {
      p = p + m.second_shift;
      if (!round_to_float32(&p)) return false;
    }
    (void)out->vertices.push_back(p);
  }
  for (const Triangle& t : base.triangles) (void)out->triangles.push_back(t);
  return true;
}

// The element at fraction u in [0, 1) of a non-empty list.
uint32_t pick(const std::vector<uint32_t>& list, double u) {
  return list[static_cast<size_t>(u * static_cast<double>(list.size())) % list.size()];
}

// Draws a motion of the kind asked for and applies it: false when this draw does not work
// (no contact vertex in reach, or the rounded base is not a valid solid); the caller draws again.
bool draw_motion(const Context& ctx, const Scene& s, Contact contact, std::mt19937_64& rng,
                 Motion* m, Mesh* a) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  m->contact = contact;
  m->second_shift = Vec3{};
  m->jaw_vertex = 0;
  const Mesh& jaws = *s.jaws;
  if (contact == Contact::kFacePlane) {
    // About the vertical axis only, so the faces stay planes z = const, and then exactly
    // through a jaw vertex: z' = 1 * z + (z_j - z_face) = z_j for the face's vertices (both
    // float32, their difference and the sum exact in double).
    const bool top = unit(rng) < 0.5;
    const std::vector<uint32_t>& pool = top ? s.near_top : s.near_bottom;
    if (pool.empty()) return false;
    m->jaw_vertex = pick(pool, unit(rng));
    const double face = top ? s.top : s.bottom;
    const double zj = jaws.vertices[m->jaw_vertex].z;
    Vec3 shift = random_shift(rng, kMaxShift);
    shift.z = 0;
    m->x = rotation_about(Vec3{0, 0, 1}, (2.0 * unit(rng) - 1.0) * kMaxAngle, s.centre, shift);
    m->x.t.z = zj - face;
    if (!apply_motion(*s.base, *m, a)) return false;
    bool hit = false;
    for (const Vec3& v : a->vertices) hit = hit || v.z == zj;
    if (!hit) return false;
  } else {
    m->x = rotation_about(random_unit(rng), unit(rng) * kMaxAngle, s.centre,
                          random_shift(rng, kMaxShift));
    if (contact == Contact::kVertexOnVertex) {
      // A random jaw vertex near the base, and the moved base's vertex nearest to it: shift
      // the base so that vertex lands on it exactly.
      Motion plain = *m;
      plain.contact = Contact::kNone;
      if (!apply_motion(*s.base, plain, a) || s.near_base.empty()) return false;
      // Several tries per motion: most jaw vertices near the base are not near a base vertex
      // (the base has vertices only along its four edges).
      bool found = false;
      uint32_t best = 0;
      for (int tries = 0; tries < 64 && !found; ++tries) {
        m->jaw_vertex = pick(s.near_base, unit(rng));
        const Vec3 j = jaws.vertices[m->jaw_vertex];
        double best_d2 = HUGE_VAL;
        for (uint32_t i = 0; i < a->vertices.size(); ++i) {
          const double d2 = length_squared(a->vertices[i] - j);
          if (d2 < best_d2) {
            best_d2 = d2;
            best = i;
          }
        }
        found = best_d2 <= kMaxContactShift * kMaxContactShift;
      }
      if (!found) return false;
      const Vec3 j = jaws.vertices[m->jaw_vertex];
      m->second_shift = j - a->vertices[best];
      if (!apply_motion(*s.base, *m, a) || a->vertices[best] != j) return false;
    } else if (!apply_motion(*s.base, *m, a)) {
      return false;
    }
  }
  MeshReport r;
  if (!check_mesh(ctx, *a, &r).is_ok()) return false;
  return r.is_valid_solid();
}

// ---- one case -----------------------------------------------------------------------------------

struct Tally {
  uint64_t cases = 0;
  uint64_t contacts = 0;
  uint64_t unsupported = 0;
  uint64_t nudged = 0;  // cases where an operation needed attempts > 1
  uint64_t self_checked = 0;
  uint64_t redraws = 0;  // motions drawn again (contact out of reach, invalid base)
  uint64_t float32_cases = 0;
  uint64_t float32_unsupported = 0;
  uint64_t float32_nudged = 0;
  uint64_t float32_different_nudges = 0;  // identity not comparable: A moved differently
  uint64_t intersection_points = 0;
  double min_rel = HUGE_VAL, max_rel = -HUGE_VAL;  // (vd + vi - va) / va, double output
  double float32_max_rel = 0;                      // |...| with float32 output
  double float32_max_bound_use = 0;                // |error| / allowed, float32 output

  void add(const Tally& o) {
    cases += o.cases;
    contacts += o.contacts;
    unsupported += o.unsupported;
    nudged += o.nudged;
    self_checked += o.self_checked;
    redraws += o.redraws;
    float32_cases += o.float32_cases;
    float32_unsupported += o.float32_unsupported;
    float32_nudged += o.float32_nudged;
    float32_different_nudges += o.float32_different_nudges;
    intersection_points += o.intersection_points;
    min_rel = std::min(min_rel, o.min_rel);
    max_rel = std::max(max_rel, o.max_rel);
    float32_max_rel = std::max(float32_max_rel, o.float32_max_rel);
    float32_max_bound_use = std::max(float32_max_bound_use, o.float32_max_bound_use);
  }
};

struct OpResult {
  bool ok = false;
  bool unsupported = false;
  double volume = 0;
  // Sum over triangles of (area / 3) * (corners that are intersection points): the volume
  // moves by at most this times the largest displacement of an intersection point.
  double moved_area = 0;
  bool self_checked = false;
  BooleanStats stats;
};

double triangle_area(const Mesh& m, const Triangle& t) {
  return 0.5 * length(cross(m.vertices[t.v[1]] - m.vertices[t.v[0]],
                            m.vertices[t.v[2]] - m.vertices[t.v[0]]));
}

// A as the library used it: A + nudge, rounded to float32 for float32 output (the library
// rounds it so, as the STL will hold it: a nudge can carry a coordinate into a coarser binade).
void used_base(const Mesh& a, const Vec3& nudge, bool float32, Mesh* out) {
  out->vertices.clear();
  out->triangles.clear();
  for (const Vec3& v : a.vertices) {
    Vec3 p = v + nudge;
    if (float32) {
      EXPECT_TRUE(round_to_float32(&p));
    }
    EXPECT_TRUE(out->vertices.push_back(p));
  }
  for (const Triangle& t : a.triangles) EXPECT_TRUE(out->triangles.push_back(t));
}

// Runs one operation and checks everything a result must be; `where` names the case.
// The exact self-intersection check runs when `self_check`, or when `self_check_if_nudged` and
// the library moved A or resolved a degenerate contact exactly.
OpResult run_op(const Context& ctx, const Scene& s, const Mesh& a, const BooleanOptions& options,
                bool self_check, bool self_check_if_nudged, const std::string& where) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  const std::string what = where + ", " + boolean_op_name(options.op) +
                           (options.float32_output ? " (float32 output)" : "");
  OpResult res;
  Mesh out;
  const Status status = mesh_boolean(ctx, a, *s.jaws, options, &out, &res.stats);
  if (!status.is_ok()) {
    const std::string message = test::format(status);
    if (status.code() == StatusCode::kUnsupported) {
      res.unsupported = true;
      EXPECT_NE(message.find("triangle"), std::string::npos) << what << ": " << message;
    } else {
      ADD_FAILURE() << what << ": " << message;
    }
    return res;
  }
  if (out.triangles.size() == 0) {
    // Only the intersection may be empty (the base cut no crown), never the difference.
    EXPECT_TRUE(options.op == BooleanOp::kIntersection) << what << ": empty result";
    res.ok = true;
    return res;
  }
  MeshReport r;
  const Status checked = check_mesh(ctx, out, &r);
  EXPECT_TRUE(checked.is_ok()) << what << ": " << test::format(checked);
  EXPECT_TRUE(r.is_valid_solid()) << what << ": " << test::format(require_valid_solid(r));
  EXPECT_EQ(r.unreferenced_vertices, 0u) << what;
  if (!r.is_valid_solid()) return res;

  // Output vertices: A' (A as the library used it), B bit for bit, or intersection points,
  // exactly stats.intersection_points of them.
  Mesh used(&arena);
  used_base(a, res.stats.nudge, options.float32_output, &used);
  VertexSet moved_a;
  moved_a.assign(used, Vec3{});
  std::vector<uint8_t> is_point(out.vertices.size(), 0);
  std::vector<uint8_t> referenced(out.vertices.size(), 0);
  for (const Triangle& t : out.triangles) {
    for (uint32_t v : t.v) referenced[v] = 1;
  }
  uint64_t points = 0, not_float32 = 0;
  std::string first_not_float32;
  for (uint32_t i = 0; i < out.vertices.size(); ++i) {
    if (referenced[i] == 0) continue;
    const Vec3& v = out.vertices[i];
    const bool of_a = moved_a.contains(v), of_b = s.jaw_set.contains(v);
    if (options.float32_output && !float32_exact(v) && not_float32++ == 0) {
      char text[256];
      std::snprintf(text, sizeof(text), " (the first: vertex %u at (%.17g, %.17g, %.17g), %s)", i,
                    v.x, v.y, v.z, of_a ? "of A" : (of_b ? "of B" : "an intersection point"));
      first_not_float32 = text;
    }
    if (of_a || of_b) continue;
    is_point[i] = 1;
    ++points;
  }
  EXPECT_EQ(points, res.stats.intersection_points)
      << what << ": output vertices that are neither A's nor B's (a jaw vertex moved?)";
  EXPECT_EQ(not_float32, 0u) << what << ": output vertices that are not float32"
                             << first_not_float32 << ", attempts " << res.stats.attempts;
  for (const Triangle& t : out.triangles) {
    const int corners = is_point[t.v[0]] + is_point[t.v[1]] + is_point[t.v[2]];
    if (corners > 0) res.moved_area += triangle_area(out, t) * corners / 3.0;
  }

  res.self_checked = self_check || (self_check_if_nudged &&
                                    (res.stats.attempts > 1 || res.stats.degenerate_pairs > 0));
  if (res.self_checked) {
    SelfIntersectionReport si;
    const Status found = find_self_intersections(ctx, out, 1, &si);
    EXPECT_TRUE(found.is_ok()) << what << ": " << test::format(found);
    EXPECT_FALSE(si.self_intersecting())
        << what << ": triangles " << si.first_a << " and " << si.first_b << " intersect";
  }
  res.volume = mesh_volume(out);
  res.ok = true;
  return res;
}

struct Plan {
  const char* name = "";
  uint64_t seed = 0;
  uint32_t cases = 0;
  double contact_share = 0;       // of the cases, drawn per case
  double face_plane_share = 0.5;  // of the contacts, when the base has flat faces
};

void run_case(const Context& ctx, const Scene& s, const Plan& plan, uint32_t index, Tally* tally) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  std::mt19937_64 rng(plan.seed ^ (0x9E3779B97F4A7C15ull * (uint64_t{index} + 1)));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Contact contact = Contact::kNone;
  if (unit(rng) < plan.contact_share) {
    contact = (s.flat_faces && unit(rng) < plan.face_plane_share) ? Contact::kFacePlane
                                                                  : Contact::kVertexOnVertex;
  }
  Mesh a(&arena);
  Motion m;
  bool drawn = false;
  for (int draw = 0; draw < 200 && !drawn; ++draw) {
    drawn = draw_motion(ctx, s, contact, rng, &m, &a);
    if (!drawn) ++tally->redraws;
  }
  const std::string where =
      std::string(s.name) + " seed " + std::to_string(plan.seed) + " case " + std::to_string(index);
  ASSERT_TRUE(drawn) << where << ": no valid " << contact_name(contact) << " motion in 200 draws";
  const std::string full = where + " (" + describe(m) + ")";
  ++tally->cases;
  if (contact != Contact::kNone) ++tally->contacts;

  // As proved: double output; the exact self-intersection check on every 10th case and on the
  // nudged results of every 3rd.
  const bool every_tenth = index % 10 == 0, every_third = index % 3 == 0;
  BooleanOptions o;
  o.float32_output = false;
  o.check_self_intersection = false;
  o.op = BooleanOp::kDifference;
  OpResult d = run_op(ctx, s, a, o, every_tenth, every_third, full);
  o.op = BooleanOp::kIntersection;
  OpResult i = run_op(ctx, s, a, o, every_tenth, every_third, full);
  if (d.unsupported || i.unsupported) {
    ++tally->unsupported;
  } else if (d.ok && i.ok) {
    const bool nudged = d.stats.attempts > 1 || i.stats.attempts > 1;
    if (nudged) ++tally->nudged;
    if (d.self_checked && i.self_checked) ++tally->self_checked;
    tally->intersection_points += d.stats.intersection_points;
    // Both operations corefine the same way, so they must have moved A alike.
    EXPECT_TRUE(d.stats.nudge == i.stats.nudge)
        << full << ": nudges differ, (" << d.stats.nudge.x << ", " << d.stats.nudge.y << ", "
        << d.stats.nudge.z << ") and (" << i.stats.nudge.x << ", " << i.stats.nudge.y << ", "
        << i.stats.nudge.z << ")";
    Mesh moved(&arena);
    used_base(a, d.stats.nudge, false, &moved);
    const double va = mesh_volume(moved);
    const double rel = (d.volume + i.volume - va) / va;
    EXPECT_LE(std::abs(rel), kVolumeTolerance)
        << full << ": vol(A-B) " << d.volume << " + vol(A*B) " << i.volume << " != vol(A) " << va;
    tally->min_rel = std::min(tally->min_rel, rel);
    tally->max_rel = std::max(tally->max_rel, rel);
  }

  // As the tool runs it, on every 10th case (not those checked above): float32 output and the
  // library's own self-intersection check.
  if (index % 10 != 5) return;
  BooleanOptions f;
  f.op = BooleanOp::kDifference;
  OpResult fd = run_op(ctx, s, a, f, false, false, full);
  f.op = BooleanOp::kIntersection;
  OpResult fi = run_op(ctx, s, a, f, false, false, full);
  ++tally->float32_cases;
  if (fd.unsupported || fi.unsupported) {
    ++tally->float32_unsupported;
    return;
  }
  if (!fd.ok || !fi.ok) return;
  if (fd.stats.attempts > 1 || fi.stats.attempts > 1) ++tally->float32_nudged;
  if (fd.stats.nudge != fi.stats.nudge) {
    // Rounding broke one result and not the other: the two are of differently placed bases.
    ++tally->float32_different_nudges;
    return;
  }
  Mesh moved(&arena);
  used_base(a, fd.stats.nudge, true, &moved);
  const double va = mesh_volume(moved);
  // An intersection point moves by at most half a float32 ulp per coordinate off its exact
  // place: ulp(c) <= 2^-23 |c|.
  const Aabb box = mesh_bounds(moved);
  const double reach = std::max({std::abs(box.lo.x), std::abs(box.lo.y), std::abs(box.lo.z),
                                 std::abs(box.hi.x), std::abs(box.hi.y), std::abs(box.hi.z)});
  const double displacement = std::sqrt(3.0) * std::ldexp(reach, -24) * 1.01;
  const double allowed = kVolumeTolerance * va + displacement * (fd.moved_area + fi.moved_area);
  const double error = std::abs(fd.volume + fi.volume - va);
  EXPECT_LE(error, allowed) << full << ": float32 output, vol(A-B) " << fd.volume << " + vol(A*B) "
                            << fi.volume << " != vol(A) " << va;
  tally->float32_max_rel = std::max(tally->float32_max_rel, error / va);
  tally->float32_max_bound_use = std::max(tally->float32_max_bound_use, error / allowed);
}

// Runs the plan's cases on kThreads threads (case k on thread k % kThreads), then checks the
// totals and prints the summary.
void run_plan(const Scene& s, const Plan& plan) {
  std::vector<Tally> tallies(kThreads);
  std::vector<std::thread> threads;
  for (uint32_t t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      TestArena ta(size_t{512} << 20);
      const Context ctx(&ta.arena);
      for (uint32_t k = t; k < plan.cases; k += kThreads) run_case(ctx, s, plan, k, &tallies[t]);
    });
  }
  for (std::thread& t : threads) t.join();
  Tally all;
  for (const Tally& t : tallies) all.add(t);
  std::printf(
      "[ summary  ] %s: %" PRIu64 " cases (%" PRIu64 " exact contacts, %" PRIu64
      " redraws), %" PRIu64 " unsupported, %" PRIu64 " nudged, %" PRIu64 " self-checked, %" PRIu64
      " intersection points; relative volume error min %.3g max %.3g; "
      "float32 output: %" PRIu64 " cases, %" PRIu64 " unsupported, %" PRIu64 " nudged, %" PRIu64
      " nudged differently, max relative error %.3g (%.3g of its bound)\n",
      plan.name, all.cases, all.contacts, all.redraws, all.unsupported, all.nudged,
      all.self_checked, all.intersection_points, all.min_rel, all.max_rel, all.float32_cases,
      all.float32_unsupported, all.float32_nudged, all.float32_different_nudges,
      all.float32_max_rel, all.float32_max_bound_use);
  std::fflush(stdout);
  EXPECT_EQ(all.cases, plan.cases);
  EXPECT_LE(static_cast<double>(all.unsupported), kMaxUnsupportedShare * plan.cases)
      << "more than 2% of the cases unsupported";
  EXPECT_LE(static_cast<double>(all.float32_unsupported),
            kMaxUnsupportedShare * static_cast<double>(all.float32_cases) + 1.0);
}

// ---- the phantom scene --------------------------------------------------------------------------

struct PhantomScene {
  TestArena ta{size_t{64} << 20};
  Mesh base;
  Mesh jaws;
  Scene scene;
};

// The paper_scale base and both phantom jaws (`triangles` each), the mandible moved as the
// case says and rounded to float32 (as an STL of the moved jaw holds it).
void build_phantom_scene(uint64_t triangles, PhantomScene* p) {
  Arena& arena = p->ta.arena;
  const Context ctx(&arena);
  const std::vector<uint8_t> text =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
  ASSERT_FALSE(text.empty());
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(),
                                  "paper_scale.json", &c));
  p->base.bind(&arena);
  BaseReport report;
  SPLINTCORE_ASSERT_OK(build_case_base(ctx, c, &p->base, &report));
  ASSERT_EQ(p->base.triangles.size(), 2612u);
  for (const Vec3& v : p->base.vertices) ASSERT_TRUE(float32_exact(v));

  p->jaws.bind(&arena);
  for (phantom::Jaw jaw : {phantom::Jaw::kMaxilla, phantom::Jaw::kMandible}) {
    const char* role = jaw == phantom::Jaw::kMaxilla ? "maxilla" : "mandible";
    RigidTransform x;
    bool found = false;
    for (const CaseJaw& j : c.jaws) {
      if (std::string(j.role) == role) {
        x = j.transform;
        found = true;
      }
    }
    ASSERT_TRUE(found) << role;
    phantom::JawMesh m;
    phantom::PhantomOptions po;
    po.target_triangles = triangles;
    SPLINTCORE_ASSERT_OK(phantom::make_jaw(jaw, po, &m));
    const size_t first = p->jaws.vertices.size();
    SPLINTCORE_ASSERT_OK(phantom::to_mesh(m, &p->jaws));
    for (size_t i = first; i < p->jaws.vertices.size(); ++i) {
      Vec3 v = x.apply_point(p->jaws.vertices[i]);
      ASSERT_TRUE(round_to_float32(&v));
      p->jaws.vertices[i] = v;
    }
  }
  MeshReport r;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, p->jaws, &r));
  ASSERT_TRUE(r.is_valid_solid()) << test::format(require_valid_solid(r));
  ASSERT_EQ(r.shells, 2u);
  p->scene.name = "phantom";
  prepare_scene(p->base, p->jaws, &p->scene);
  ASSERT_TRUE(p->scene.flat_faces);  // the paper_scale base's faces are the planes z = +-1.6
  ASSERT_FALSE(p->scene.near_top.empty());
  ASSERT_FALSE(p->scene.near_bottom.empty());
}

// 400 + 300 + 300 = 1,000 cases on the phantom alone in optimised builds (the g++ and clang++
// -O2 CI jobs run them all); unoptimised and sanitizer builds run a quarter of each plan
// (kCaseDivisor), which keeps the suite's time there near the optimised one.
TEST(BooleanRandom, PhantomCoarseJaws) {
  PhantomScene p;
  build_phantom_scene(6000, &p);
  if (HasFatalFailure()) return;
  Plan plan;
  plan.name = "BooleanRandom.PhantomCoarseJaws (2 x 6,000-triangle jaws)";
  plan.seed = 20261121001;
  plan.cases = 400 / kCaseDivisor;
  plan.contact_share = 0.2;
  run_plan(p.scene, plan);
}

TEST(BooleanRandom, PhantomFineJaws) {
  PhantomScene p;
  build_phantom_scene(14000, &p);
  if (HasFatalFailure()) return;
  Plan plan;
  plan.name = "BooleanRandom.PhantomFineJaws (2 x 14,000-triangle jaws)";
  plan.seed = 20261121002;
  plan.cases = 300 / kCaseDivisor;
  plan.contact_share = 0.2;
  run_plan(p.scene, plan);
}

TEST(BooleanRandom, PhantomExactContacts) {
  PhantomScene p;
  build_phantom_scene(6000, &p);
  if (HasFatalFailure()) return;
  Plan plan;
  plan.name = "BooleanRandom.PhantomExactContacts (2 x 6,000-triangle jaws)";
  plan.seed = 20261121003;
  plan.cases = 300 / kCaseDivisor;
  plan.contact_share = 1.0;
  plan.face_plane_share = 0.5;
  run_plan(p.scene, plan);
}

// ---- regressions found by the suite -------------------------------------------------------------

// How many output vertices are not float32 (the first three listed).
uint64_t count_not_float32(const Mesh& out, std::string* listed) {
  uint64_t count = 0;
  for (uint32_t i = 0; i < out.vertices.size(); ++i) {
    if (float32_exact(out.vertices[i])) continue;
    if (count++ < 3) {
      char text[160];
      const Vec3& v = out.vertices[i];
      std::snprintf(text, sizeof(text), " vertex %u (%.17g, %.17g, %.17g);", i, v.x, v.y, v.z);
      *listed += text;
    }
  }
  return count;
}

// Found by PhantomFineJaws when it ran 2 x 20,000-triangle jaws (seed 20261121002, case 110, a
// face-plane contact; every 5th case then ran with float32 output): the degenerate contact was
// nudged (attempt 2, A + 2^-16 (1, 3, 7)), and a base vertex at y = 0.4999798 (float32, an odd
// multiple of 2^-25) landed at y = 0.5000256, past 0.5 where float32 has only multiples of
// 2^-24: the float32 result held a vertex that is not float32, so the STL written from it was
// not the mesh that was checked. (mesh_boolean then learnt to round the nudged A to float32;
// the contact is now resolved exactly, with no nudge, and the result must still be float32.)
TEST(BooleanRandom, RegressionNudgedPhantomBaseStaysFloat32) {
  PhantomScene p;
  build_phantom_scene(20000, &p);
  if (HasFatalFailure()) return;
  Arena& arena = p.ta.arena;
  const Context ctx(&arena);
  Motion m;
  m.contact = Contact::kFacePlane;
  const double r[3][3] = {{0.99987056243542882, 0.016089076264943422, 0},
                          {-0.016089076264943422, 0.99987056243542882, 0},
                          {0, 0, 1}};
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) m.x.r[i][k] = r[i][k];
  }
  m.x.t = Vec3{-0.081225556740331883, -0.098746897487950888, 0.11591517925262451};
  Mesh a(&arena);
  ASSERT_TRUE(apply_motion(p.base, m, &a));
  MeshReport r0;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, a, &r0));
  ASSERT_TRUE(r0.is_valid_solid());
  for (const Vec3& v : a.vertices) ASSERT_TRUE(float32_exact(v));
  BooleanOptions o;  // as the tool runs it: float32 output
  Mesh out;
  BooleanStats st;
  SPLINTCORE_ASSERT_OK(mesh_boolean(ctx, a, p.jaws, o, &out, &st));
  EXPECT_EQ(st.attempts, 1u);
  EXPECT_GT(st.degenerate_pairs, 0u);
  std::string listed;
  EXPECT_EQ(count_not_float32(out, &listed), 0u)
      << "difference with float32 output after " << st.attempts << " attempts, nudge ("
      << st.nudge.x << ", " << st.nudge.y << ", " << st.nudge.z << "):" << listed;
}

// The same in eight vertices: a box whose top y is the float32 just below 0.5, and a box that
// touches it along one edge only, whose union is not an edge-manifold solid (so A is nudged by
// 2^-16 (1, 3, 7), and its top y crosses 0.5).
TEST(BooleanRandom, RegressionNudgeAcrossAPowerOfTwoStaysFloat32) {
  TestArena ta(size_t{64} << 20);
  Arena& arena = ta.arena;
  const Context ctx(&arena);
  auto box = [&](const Vec3& lo, const Vec3& hi, Mesh* m) {
    m->bind(&arena);
    for (int i = 0; i < 8; ++i) {
      ASSERT_TRUE(m->vertices.push_back(
          Vec3{(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z}));
    }
    const uint32_t f[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                               {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    for (const auto& t : f) ASSERT_TRUE(m->triangles.push_back(Triangle{{t[0], t[1], t[2]}}));
  };
  const double below_half = 0.5 - std::ldexp(1.0, -25);  // float32, odd multiple of 2^-25
  Mesh a, b;
  box(Vec3{0, 0, 0}, Vec3{1, below_half, 1}, &a);
  box(Vec3{1, below_half, 0}, Vec3{2, 1, 1}, &b);
  for (const Vec3& v : a.vertices) ASSERT_TRUE(float32_exact(v));
  BooleanOptions o;  // float32 output
  o.op = BooleanOp::kUnion;
  Mesh out;
  BooleanStats st;
  SPLINTCORE_ASSERT_OK(mesh_boolean(ctx, a, b, o, &out, &st));
  EXPECT_GT(st.attempts, 1u);
  std::string listed;
  EXPECT_EQ(count_not_float32(out, &listed), 0u)
      << "after " << st.attempts << " attempts, nudge (" << st.nudge.x << ", " << st.nudge.y << ", "
      << st.nudge.z << "):" << listed;
}

// ---- the real teeth -----------------------------------------------------------------------------

// Two teeth, one per jaw (an upper premolar and a lower incisor): 40,712 triangles. The
// operation's cost grows with B's triangles near A, and every tooth is near the wafer.
constexpr int kRealTeeth[] = {5, 24};

TEST(BooleanRandom, RealTeeth) {
  const std::string dir = SPLINTCORE_REALDATA_DIR;
  if (!test::file_exists(dir + "/maxilla/tooth_1.stl")) GTEST_SKIP() << "realdata not found";
  realcase::RealCase rc;
  std::string error;
  // As the benchmark: the bite opened 2 mm, crowns 1.5 mm into the wafer, 6 mm lines.
  ASSERT_TRUE(realcase::load(dir, 2.0, 1.5, 6.0, &rc, &error)) << error;
  TestArena ta(size_t{256} << 20);
  Arena& arena = ta.arena;
  const Context ctx(&arena);
  Mesh wafer;
  BaseReport report;
  SPLINTCORE_ASSERT_OK(realcase::wafer_mesh(arena, rc, 0.5, &wafer, &report));
  Mesh base(&arena);
  for (Vec3 v : wafer.vertices) {
    ASSERT_TRUE(round_to_float32(&v));
    ASSERT_TRUE(base.vertices.push_back(v));
  }
  for (const Triangle& t : wafer.triangles) ASSERT_TRUE(base.triangles.push_back(t));
  MeshReport r;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, base, &r));
  ASSERT_TRUE(r.is_valid_solid()) << test::format(require_valid_solid(r));
  Mesh teeth(&arena);
  for (const realcase::Tooth& t : rc.teeth) {
    if (std::find(std::begin(kRealTeeth), std::end(kRealTeeth), t.number) == std::end(kRealTeeth)) {
      continue;
    }
    const uint32_t off = static_cast<uint32_t>(teeth.vertices.size());
    for (Vec3 v : t.vertices) {
      ASSERT_TRUE(round_to_float32(&v));  // the opened mandible's z - 2 is not always float32
      ASSERT_TRUE(teeth.vertices.push_back(v));
    }
    for (const Triangle& tr : t.triangles) {
      const Triangle shifted{{tr.v[0] + off, tr.v[1] + off, tr.v[2] + off}};
      ASSERT_TRUE(teeth.triangles.push_back(shifted));
    }
  }
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, teeth, &r));
  ASSERT_TRUE(r.is_valid_solid()) << test::format(require_valid_solid(r));
  ASSERT_EQ(r.shells, 2u);
  Scene scene;
  scene.name = "real teeth";
  prepare_scene(base, teeth, &scene);
  Plan plan;
  plan.name = "BooleanRandom.RealTeeth (wafer vs teeth 5 and 24)";
  plan.seed = 20261121004;
  plan.cases = 300 / kCaseDivisor;
  plan.contact_share = 0.25;  // vertex on vertex (the wafer's faces are not planes z = const)
  run_plan(scene, plan);
}

}  // namespace
}  // namespace splintcore
