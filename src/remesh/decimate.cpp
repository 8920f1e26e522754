// Quadric error metric decimation by half-edge collapse.
//
// Sources: M. Garland and P. S. Heckbert, "Surface simplification using quadric error metrics",
// SIGGRAPH 1997 (sections 4-5: plane quadrics summed per vertex, edge pairs in a heap keyed by
// the error at the optimal position, the 3x3 solve with the endpoints and the midpoint as the
// fallback); T. K. Dey, H. Edelsbrunner, S. Guha and D. V. Nekhayev, "Topology preserving edge
// contraction", Publ. Inst. Math. (Beograd) 66, 1999 (the link condition); the triangle flip
// test as in meshoptimizer's simplifier (A. Kapoulkine, src/simplifier.cpp, hasTriangleFlip).
//
// Data: the working triangles and, per half-edge h = 3 t + k (side k of triangle t, from
// corner k to corner k + 1), its twin (closed mesh: every half-edge has exactly one), plus one
// outgoing half-edge per vertex. The fan of a vertex is walked with next_out(h) =
// twin[prev(h)]. Collapsing h = (u, v) keeps u (moved to the new position), kills h's and its
// twin's triangles, relabels v's corners to u and pairs up the twins of the dead triangles'
// other sides; nothing is allocated during the loop. An edge is known by the smaller of its
// two half-edges; the heap holds (error, edge) pairs and a position per half-edge, so an
// edge's entry is found, moved and removed in O(log E) and ties break by edge id.
//
// Speed: the loop is bound by cache misses (a collapse touches about 20 vertices and 20
// triangles anywhere in the mesh), so the layout is chosen for it: all a vertex's data in two
// cache lines, a triangle's corners, twins and heap slots in 36 bytes, an 8-ary heap of 8-byte
// entries whose children share a cache line, the neighbours' quadrics prefetched during the
// link test. Measured against separate arrays and a binary heap of 16-byte entries: about a
// third less time. Deferring key rises until an entry reaches the top was slower.
//
// Quadrics are built relative to the input's bounding-box centre (well conditioned far from
// the origin); positions stay in input coordinates, so a vertex that never moves keeps its
// input bits.
#include "splintcore/distance.h"
#include "splintcore/remesh.h"

namespace splintcore {

namespace {

constexpr uint32_t kNone = ~uint32_t{0};
constexpr uint32_t kParked = kNone - 1;  // heap position of an edge refused for now
constexpr uint32_t kProgressEvery = 65536;

inline uint32_t next_of(uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }
inline uint32_t prev_of(uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; }

bool add_alloc(uint64_t* total, uint64_t count, uint64_t size) {
  uint64_t bytes = 0;
  return checked_mul(count, size, &bytes) && checked_add(bytes, 16, &bytes) &&
         checked_add(*total, bytes, total);
}

// Symmetric 4x4 quadric [A b; b^T c] and the total area of the planes in it.
struct Quadric {
  double a00, a01, a02, a11, a12, a22, b0, b1, b2, c, w;
};

inline void add_to(Quadric* q, const Quadric& r) {
  q->a00 += r.a00;
  q->a01 += r.a01;
  q->a02 += r.a02;
  q->a11 += r.a11;
  q->a12 += r.a12;
  q->a22 += r.a22;
  q->b0 += r.b0;
  q->b1 += r.b1;
  q->b2 += r.b2;
  q->c += r.c;
  q->w += r.w;
}

inline Quadric sum_of(const Quadric& q, const Quadric& r) {
  Quadric s = q;
  add_to(&s, r);
  return s;
}

// p^T A p + 2 b.p + c, at least 0 (rounding can make it slightly negative).
inline double evaluate(const Quadric& q, const Vec3& p) {
  const double ax = q.a00 * p.x + q.a01 * p.y + q.a02 * p.z;
  const double ay = q.a01 * p.x + q.a11 * p.y + q.a12 * p.z;
  const double az = q.a02 * p.x + q.a12 * p.y + q.a22 * p.z;
  const double e =
      (p.x * ax + p.y * ay + p.z * az) + 2.0 * (q.b0 * p.x + q.b1 * p.y + q.b2 * p.z) + q.c;
  return e > 0.0 ? e : 0.0;
}

// Solves A p = -b by the adjugate when A is well conditioned (|det| > 1e-10 trace^3; A is
// positive semi-definite, so det <= (trace / 3)^3).
inline bool optimal_point(const Quadric& q, Vec3* p) {
  const double c00 = q.a11 * q.a22 - q.a12 * q.a12;
  const double c01 = q.a02 * q.a12 - q.a01 * q.a22;
  const double c02 = q.a01 * q.a12 - q.a02 * q.a11;
  const double det = q.a00 * c00 + q.a01 * c01 + q.a02 * c02;
  const double trace = q.a00 + q.a11 + q.a22;
  if (!(trace > 0.0) || !(det > 1e-10 * trace * trace * trace)) return false;
  const double c11 = q.a00 * q.a22 - q.a02 * q.a02;
  const double c12 = q.a01 * q.a02 - q.a00 * q.a12;
  const double c22 = q.a00 * q.a11 - q.a01 * q.a01;
  const double inv = 1.0 / det;
  *p = Vec3{-(c00 * q.b0 + c01 * q.b1 + c02 * q.b2) * inv,
            -(c01 * q.b0 + c11 * q.b1 + c12 * q.b2) * inv,
            -(c02 * q.b0 + c12 * q.b1 + c22 * q.b2) * inv};
  return is_finite(*p);
}

// The heap key of an error: its float32 bits, rounded toward zero by integer operations
// only (the same on every platform; monotone, so the order is the errors' order up to ties
// within float precision, which the edge id breaks), in the high half; the edge id in the low.
inline uint64_t heap_entry(double error, uint32_t id) {
  uint64_t bits;
  std::memcpy(&bits, &error, sizeof(bits));
  uint64_t key = 0;
  const int exponent = static_cast<int>((bits >> 52) & 0x7ff) - 1023;
  if ((bits >> 63) != 0 || exponent < -126) {
    key = 0;  // negative (never), zero or below float32's normal range: ties broken by id
  } else if (exponent > 127) {
    key = 0x7f800000u;
  } else {
    key = (static_cast<uint64_t>(exponent + 127) << 23) | ((bits >> 29) & 0x7fffffu);
  }
  return (key << 32) | id;
}
inline uint32_t entry_id(uint64_t entry) { return static_cast<uint32_t>(entry); }

// A triangle's corners, the twins of its three half-edges and their heap positions (the
// slots of the edges they name, kNone when not an edge's name or not in the heap), together
// because the loop reads them together.
struct Face {
  uint32_t v[3];
  uint32_t twin[3];
  uint32_t slot[3];
};

// 8-ary min-heap of packed (key, id) entries with the position of every id (kNone: absent).
// The children of node i are 8 i + 1 .. 8 i + 8: one cache line when the array is placed so
// that index 1 starts a line (a matter of speed only: the order never depends on addresses).
struct Heap {
  static constexpr uint32_t kArity = 8;
  uint64_t* items = nullptr;
  Face* faces = nullptr;  // positions live in Face::slot
  uint32_t size = 0;

  uint32_t& pos(uint32_t id) { return faces[id / 3].slot[id % 3]; }
  uint32_t pos(uint32_t id) const { return faces[id / 3].slot[id % 3]; }

  void place(uint32_t i, uint64_t e) {
    items[i] = e;
    pos(entry_id(e)) = i;
  }
  void sift_up(uint32_t i) {
    const uint64_t e = items[i];
    while (i > 0) {
      const uint32_t parent = (i - 1) / kArity;
      if (e >= items[parent]) break;
      place(i, items[parent]);
      i = parent;
    }
    place(i, e);
  }
  void sift_down(uint32_t i) {
    const uint64_t e = items[i];
    for (;;) {
      const uint32_t first = kArity * i + 1;
      if (first >= size) break;
      const uint32_t last = size - first < kArity ? size : first + kArity;
      uint32_t best = first;
      uint64_t best_entry = items[first];
      for (uint32_t c = first + 1; c < last; ++c) {
        if (items[c] < best_entry) {
          best_entry = items[c];
          best = c;
        }
      }
      if (best_entry >= e) break;
      place(i, best_entry);
      i = best;
    }
    place(i, e);
  }
  void heapify() {
    for (uint32_t i = size / kArity + 1; i > 0; --i) {
      if (i - 1 < size) sift_down(i - 1);
    }
  }
  bool contains(uint32_t id) const { return pos(id) < size; }
  void push(uint64_t e) {
    place(size, e);
    sift_up(size++);
  }
  void remove(uint32_t id) {
    const uint32_t i = pos(id);
    pos(id) = kNone;
    --size;
    if (i == size) return;
    place(i, items[size]);
    if (i > 0 && items[i] < items[(i - 1) / kArity]) {
      sift_up(i);
    } else {
      sift_down(i);
    }
  }
  void update(uint32_t id, uint64_t e) {
    const uint32_t i = pos(id);
    const uint64_t old = items[i];
    items[i] = e;
    if (e < old) {
      sift_up(i);
    } else {
      sift_down(i);
    }
  }
};

// Everything the loop reads about a vertex, in two cache lines.
struct alignas(64) VertexData {
  Quadric quadric;
  Vec3 pos;
  uint32_t head;     // one outgoing half-edge, kNone when unused or gone
  uint32_t valence;  // neighbours
  uint32_t stamp;    // link condition marks
  uint32_t flags;    // kLocked, kBoundary
};
constexpr uint32_t kLocked = 1;    // stays (options.locked)
constexpr uint32_t kBoundary = 2;  // on a boundary edge: stays, and its edges never collapse
static_assert(sizeof(VertexData) == 128, "two cache lines per vertex");

struct Decimator {
  uint32_t nv = 0, nt = 0;
  Face* tri = nullptr;  // corners and twins of every triangle
  VertexData* vx = nullptr;
  uint32_t generation = 0;
  Vec3 center{};
  Heap heap;
  bool keep = false;  // options.keep_positions
  // max_distance: samples of the input surface, each in the list of the live triangle it is
  // assigned to (given samples 0 .. n_given - 1, then input vertex i as n_given + i), and the
  // scratch of one collapse: the new fan's corners and the samples' new triangles.
  double reach2 = 0.0;  // max_distance^2; 0: off
  uint32_t n_given = 0;
  const Vec3* given = nullptr;
  uint32_t* first_sample = nullptr;  // per triangle, kNone: none
  uint32_t* next_sample = nullptr;   // per sample
  struct FanTriangle {
    uint32_t t;
    uint32_t corner[3];  // vertex ids (v read as u)
    Vec3 a, b, c;
  };
  FanTriangle* fan = nullptr;  // kDecimateFanTriangles
  uint32_t fan_size = 0;
  uint32_t fan_changed = 0;  // fan[fan_changed ..]: the triangles that move (v's)
  // The surface the result is measured against: the input triangles (not `approximate`), the
  // one each sample lies on (given: sample_sources; a vertex: its first such triangle).
  const Triangle* surface_tris = nullptr;
  const Vec3* surface_verts = nullptr;
  const uint32_t* given_source = nullptr;  // null: none known
  uint32_t* around_first = nullptr;        // per vertex + 1: where its input triangles start
  uint32_t* around = nullptr;              // the input triangles (not approximate) by vertex
  uint64_t* moved = nullptr;               // kDecimateMovedSamples: sample << 32 | triangle
  uint32_t moved_count = 0;

  uint32_t origin(uint32_t h) const { return tri[h / 3].v[h % 3]; }
  uint32_t dest(uint32_t h) const { return tri[h / 3].v[(h % 3 + 1) % 3]; }
  uint32_t& twin(uint32_t h) { return tri[h / 3].twin[h % 3]; }
  uint32_t twin(uint32_t h) const { return tri[h / 3].twin[h % 3]; }
  uint32_t next_out(uint32_t h) const { return twin(prev_of(h)); }

  // The error key (mm^2) of collapsing edge `h` (origin kept) and where the vertex goes.
  double cost(uint32_t h, Vec3* target) const {
    const uint32_t u = origin(h), v = dest(h);
    const Quadric q = sum_of(vx[u].quadric, vx[v].quadric);
    const Vec3 pu = vx[u].pos - center, pv = vx[v].pos - center;
    if (keep) {
      // Into the endpoint that may stay and gives the smaller error (u on a tie).
      const bool may_keep_u = (vx[v].flags & kLocked) == 0;
      const bool may_keep_v = (vx[u].flags & kLocked) == 0;
      const double eu = may_keep_u ? evaluate(q, pu) : HUGE_VAL;
      const double ev = may_keep_v ? evaluate(q, pv) : HUGE_VAL;
      *target = ev < eu ? vx[v].pos : vx[u].pos;
      const double e = ev < eu ? ev : eu;
      return q.w > 0.0 ? e / q.w : 0.0;
    }
    const Vec3 mid = (pu + pv) * 0.5;
    Vec3 best = pu;
    double best_error = evaluate(q, pu);
    const double ev = evaluate(q, pv);
    if (ev < best_error) {
      best = pv;
      best_error = ev;
    }
    const double em = evaluate(q, mid);
    if (em < best_error) {
      best = mid;
      best_error = em;
    }
    Vec3 opt;
    if (optimal_point(q, &opt) && length_squared(opt - mid) <= length_squared(pv - pu)) {
      const double eo = evaluate(q, opt);
      if (eo < best_error) {
        best = opt;
        best_error = eo;
      }
    }
    // Endpoints keep their input bits (no round trip through the centre).
    if (best == pu) {
      *target = vx[u].pos;
    } else if (best == pv) {
      *target = vx[v].pos;
    } else {
      *target = best + center;
    }
    return q.w > 0.0 ? best_error / q.w : 0.0;
  }

  uint32_t edge_of(uint32_t h) const { return h < twin(h) ? h : twin(h); }

  // Whether edge h may ever collapse: both endpoints inside (closed fans, which check() and
  // collapse() walk) and, keeping positions, not both locked.
  bool collapsible(uint32_t h) const {
    if (twin(h) == kNone) return false;
    const uint32_t fu = vx[origin(h)].flags, fv = vx[dest(h)].flags;
    if (((fu | fv) & kBoundary) != 0) return false;
    return (fu & fv & kLocked) == 0;
  }

  // Takes an edge out of the heap (or the parked set).
  void detach(uint32_t h, uint32_t* parked) {
    if (heap.contains(h)) {
      heap.remove(h);
    } else if (heap.pos(h) == kParked) {
      heap.pos(h) = kNone;
      --*parked;
    }
  }

  // 0: ok; 1: link condition; 2: flip; 3: flat; 4: a sample out of reach (max_distance).
  int check(uint32_t h, const Vec3& p) {
    const uint32_t g = twin(h);
    const uint32_t u = origin(h), v = dest(h);
    const uint32_t a = origin(prev_of(h)), b = origin(prev_of(g));
    if (vx[a].valence <= 3 || vx[b].valence <= 3 || vx[u].valence + vx[v].valence < 7) return 1;
    if (++generation == 0) {
      for (uint32_t i = 0; i < nv; ++i) vx[i].stamp = 0;
      generation = 1;
    }
    const uint32_t start_u = vx[u].head;
    uint32_t e = start_u;
    do {
      // Hints only (no effect on results): the neighbours' quadrics are read next if the
      // collapse is made.
      __builtin_prefetch(&vx[dest(e)].quadric);
      vx[dest(e)].stamp = generation;
      e = next_out(e);
    } while (e != start_u);
    uint32_t common = 0;
    const uint32_t start_v = vx[v].head;
    e = start_v;
    do {
      __builtin_prefetch(&vx[dest(e)].quadric);
      common += vx[dest(e)].stamp == generation ? 1u : 0u;
      e = next_out(e);
    } while (e != start_v);
    if (common != 2) return 1;
    const uint32_t t0 = h / 3, t1 = g / 3;
    for (int side = 0; side < 2; ++side) {
      const uint32_t start = side == 0 ? start_u : start_v;
      const Vec3 pc = vx[side == 0 ? u : v].pos;
      if (pc == p) continue;  // these triangles do not move
      e = start;
      do {
        const uint32_t t = e / 3;
        if (t != t0 && t != t1) {
          const Vec3& px = vx[dest(e)].pos;
          const Vec3& py = vx[origin(prev_of(e))].pos;
          const Vec3 old_n = cross(px - pc, py - pc);
          const Vec3 new_n = cross(px - p, py - p);
          const double d = dot(old_n, new_n);
          if (!(d > 0.25 * std::sqrt(length_squared(old_n) * length_squared(new_n)))) return 2;
          if (collinear3d(p, px, py)) return 3;
        }
        e = next_out(e);
      } while (e != start);
    }
    if (reach2 > 0.0 && !place_samples(h)) return 4;
    return 0;
  }

  Vec3 sample_at(uint32_t s) const { return s < n_given ? given[s] : vx[s - n_given].pos; }

  // max_distance: the samples that collapsing h = (u, v) (u stays where it is) would move, v
  // and those of v's triangles, each placed on the first triangle of the new fan within reach
  // (u's triangles, then v's with v read as u, without h's and its twin's), in `moved`; false
  // when one is out of reach or the scratch is too small.
  bool place_samples(uint32_t h) {
    const uint32_t g = twin(h), u = origin(h), v = dest(h), t0 = h / 3, t1 = g / 3;
    fan_size = 0;
    for (int side = 0; side < 2; ++side) {
      const uint32_t start = vx[side == 0 ? u : v].head;
      uint32_t e = start;
      do {
        const uint32_t t = e / 3;
        if (side == 1 && e == start) fan_changed = fan_size;
        if (t != t0 && t != t1) {
          if (fan_size == kDecimateFanTriangles) return false;
          // Corners in the triangle's order, the moving one at u.
          Vec3 c[3];
          uint32_t id[3];
          for (int k = 0; k < 3; ++k) {
            const uint32_t w = tri[t].v[k];
            id[k] = w == v ? u : w;
            c[k] = vx[id[k]].pos;
          }
          fan[fan_size++] = FanTriangle{t, {id[0], id[1], id[2]}, c[0], c[1], c[2]};
        }
        e = next_out(e);
      } while (e != start);
    }
    moved_count = 0;
    if (!place(n_given + v, kNone)) return false;
    const uint32_t start = vx[v].head;
    uint32_t e = start;
    do {
      for (uint32_t s = first_sample[e / 3]; s != kNone; s = next_sample[s]) {
        if (!place(s, e / 3)) return false;
      }
      e = next_out(e);
    } while (e != start);
    return fan_near_input(u);
  }

  bool near_triangle(const Vec3& x, uint32_t src) const {
    const Triangle& t = surface_tris[src];
    return within(x, surface_verts[t.v[0]], surface_verts[t.v[1]], surface_verts[t.v[2]]);
  }
  // x within reach of the closed triangle abc (a predicate, not a closest point): refused by
  // the triangle's box or its plane; then accepted when x projects inside the triangle (the
  // three edge planes through the normal) or lies within reach of one of its sides.
  bool within(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c) const {
    double box2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double lo = std::min(a[k], std::min(b[k], c[k]));
      const double hi = std::max(a[k], std::max(b[k], c[k]));
      const double d = x[k] < lo ? lo - x[k] : (x[k] > hi ? x[k] - hi : 0.0);
      box2 += d * d;
    }
    if (box2 > reach2) return false;
    const Vec3 ab = b - a, bc = c - b, ca = a - c;
    const Vec3 n = cross(ab, c - a);
    const double n2 = length_squared(n);
    const Vec3 ax = x - a, bx = x - b, cx = x - c;
    const double h = dot(ax, n);
    if (h * h > reach2 * n2) return false;
    if (n2 > 0 && dot(cross(ab, ax), n) >= 0 && dot(cross(bc, bx), n) >= 0 &&
        dot(cross(ca, cx), n) >= 0) {
      return true;  // over the triangle, and within reach of its plane
    }
    return side_within(ax, ab) || side_within(bx, bc) || side_within(cx, ca);
  }
  // The point at offset `from` from a side's start within reach of the side (its vector `side`).
  bool side_within(const Vec3& from, const Vec3& side) const {
    const double len2 = length_squared(side);
    const double t = dot(from, side);
    if (!(len2 > 0) || t <= 0) return length_squared(from) <= reach2;
    if (t >= len2) return length_squared(from - side) <= reach2;
    // |from|^2 - t^2 / len2 <= reach2, multiplied through by len2.
    return length_squared(from) * len2 - t * t <= reach2 * len2;
  }

  // Within reach of an input triangle around input vertex w.
  bool near_around(const Vec3& x, uint32_t w) const {
    for (uint32_t i = around_first[w]; i < around_first[w + 1]; ++i) {
      if (near_triangle(x, around[i])) return true;
    }
    return false;
  }

  // The triangles that move within reach of the input surface (near_input: a conservative
  // test, the nearest input triangle may be another), each at its centroid and the midpoint
  // of its side that starts at u: every new side once (the fan is consistently oriented: a
  // side between two moved triangles runs from u in one of them; one shared with an unmoved
  // triangle did not move).
  bool fan_near_input(uint32_t u) const {
    for (uint32_t i = fan_changed; i < fan_size; ++i) {
      const FanTriangle& f = fan[i];
      const Vec3& from_u = f.corner[0] == u ? f.b : (f.corner[1] == u ? f.c : f.a);
      const Vec3& at_u = f.corner[0] == u ? f.a : (f.corner[1] == u ? f.b : f.c);
      const Vec3 points[2] = {(at_u + from_u) * 0.5, ((f.a + f.b) + f.c) * (1.0 / 3.0)};
      for (const Vec3& x : points) {
        if (!near_input(x, f)) return false;
      }
    }
    return true;
  }

  // Candidates in order: the input triangles around f's corners, then those under (or around)
  // the samples placed on f, then those of the other moved samples (consecutive repeats of a
  // triangle tested once).
  bool near_input(const Vec3& x, const FanTriangle& f) const {
    for (uint32_t w : f.corner) {
      if (near_around(x, w)) return true;
    }
    for (int pass = 0; pass < 2; ++pass) {
      uint32_t last = kNone;
      for (uint32_t i = 0; i < moved_count; ++i) {
        const uint32_t s = static_cast<uint32_t>(moved[i] >> 32);
        if ((static_cast<uint32_t>(moved[i]) == f.t) != (pass == 0)) continue;
        if (s >= n_given) {
          if (near_around(x, s - n_given)) return true;
        } else if (given_source != nullptr && given_source[s] != kNone && given_source[s] != last) {
          last = given_source[s];
          if (near_triangle(x, last)) return true;
        }
      }
    }
    return false;
  }

  // Places sample s on a fan triangle within reach (into `moved`): the one that replaces
  // triangle `was` (its triangle so far) if that is within reach, else the first.
  bool place(uint32_t s, uint32_t was) {
    if (moved_count == kDecimateMovedSamples) return false;
    const Vec3 q = sample_at(s);
    for (uint32_t i = fan_changed; i < fan_size; ++i) {
      const FanTriangle& f = fan[i];
      if (f.t != was) continue;
      if (within(q, f.a, f.b, f.c)) {
        moved[moved_count++] = uint64_t{s} << 32 | f.t;
        return true;
      }
      break;
    }
    for (uint32_t i = 0; i < fan_size; ++i) {
      const FanTriangle& f = fan[i];
      if (f.t != was && within(q, f.a, f.b, f.c)) {
        moved[moved_count++] = uint64_t{s} << 32 | f.t;
        return true;
      }
    }
    return false;
  }

  // After place_samples(h) passed: v's triangles lose their samples, which go where `moved`
  // says (before the collapse changes the fans).
  void move_samples(uint32_t h) {
    const uint32_t v = dest(h);
    const uint32_t start = vx[v].head;
    uint32_t e = start;
    do {
      first_sample[e / 3] = kNone;
      e = next_out(e);
    } while (e != start);
    for (uint32_t i = 0; i < moved_count; ++i) {
      const uint32_t s = static_cast<uint32_t>(moved[i] >> 32), t = static_cast<uint32_t>(moved[i]);
      next_sample[s] = first_sample[t];
      first_sample[t] = s;
    }
  }

  // Collapses edge h (origin u kept at p, destination v removed).
  void collapse(uint32_t h, const Vec3& p, uint32_t* parked) {
    if (reach2 > 0.0) move_samples(h);
    const uint32_t g = twin(h);
    const uint32_t n0 = next_of(h), p0 = prev_of(h), n1 = next_of(g), p1 = prev_of(g);
    const uint32_t u = origin(h), v = dest(h), a = origin(p0), b = origin(p1);
    const uint32_t x0 = twin(n0), y0 = twin(p0), x1 = twin(n1), y1 = twin(p1);
    const uint32_t gone[10] = {h, g, n0, p0, n1, p1, x0, y0, x1, y1};
    for (uint32_t k : gone) detach(k, parked);
    // v's corners become u (walked before the twins change).
    const uint32_t start_v = vx[v].head;
    uint32_t e = start_v;
    do {
      tri[e / 3].v[e % 3] = u;
      e = next_out(e);
    } while (e != start_v);
    twin(x0) = y0;
    twin(y0) = x0;
    twin(x1) = y1;
    twin(y1) = x1;
    tri[h / 3].v[0] = tri[h / 3].v[1] = tri[h / 3].v[2] = kNone;
    tri[g / 3].v[0] = tri[g / 3].v[1] = tri[g / 3].v[2] = kNone;
    vx[u].head = y0;
    vx[a].head = x0;
    vx[b].head = x1;
    vx[v].head = kNone;
    vx[u].valence = vx[u].valence + vx[v].valence - 4;
    vx[v].valence = 0;
    --vx[a].valence;
    --vx[b].valence;
    vx[u].pos = p;
    add_to(&vx[u].quadric, vx[v].quadric);
    // Every edge around u has a new error.
    e = y0;
    do {
      const uint32_t id = edge_of(e);
      if (!collapsible(id)) {
        // E.g. v's edge to a locked vertex when u is locked too: it can no longer collapse,
        // and its key (now infinite) must not stay in the heap.
        detach(id, parked);
        e = next_out(e);
        continue;
      }
      Vec3 unused;
      const double key = cost(id, &unused);
      if (heap.contains(id)) {
        heap.update(id, heap_entry(key, id));
      } else {
        if (heap.pos(id) == kParked) --*parked;
        heap.push(heap_entry(key, id));
      }
      e = next_out(e);
    } while (e != y0);
  }

  // Twins: half-edges bucketed by origin; a -> b pairs with the one b -> a. The buckets are
  // temporaries.
  Status link_twins(Arena& arena, bool allow_boundary) {
    ArenaScope buckets(arena);
    const uint32_t half = 3 * nt;
    uint32_t* first = arena.allocate_array<uint32_t>(size_t{nv} + 1);
    uint32_t* out_edges = arena.allocate_array<uint32_t>(half);
    if (first == nullptr || out_edges == nullptr) return arena.exhausted_status();
    std::memset(first, 0, (size_t{nv} + 1) * sizeof(uint32_t));
    for (uint32_t h = 0; h < half; ++h) ++first[origin(h) + 1];
    for (uint32_t i = 0; i < nv; ++i) first[i + 1] += first[i];
    for (uint32_t h = 0; h < half; ++h) out_edges[first[origin(h)]++] = h;
    for (uint32_t i = nv; i > 0; --i) first[i] = first[i - 1];
    first[0] = 0;
    for (uint32_t h = 0; h < half; ++h) {
      const uint32_t a = origin(h), b = dest(h);
      uint32_t same = 0, opposite = 0, match = kNone;
      for (uint32_t i = first[a]; i < first[a + 1]; ++i) same += dest(out_edges[i]) == b;
      for (uint32_t i = first[b]; i < first[b + 1]; ++i) {
        if (dest(out_edges[i]) == a) {
          ++opposite;
          match = out_edges[i];
        }
      }
      if (allow_boundary && same == 1 && opposite == 0) {
        twin(h) = kNone;  // a boundary edge: both ends stay
        vx[a].flags |= kBoundary;
        vx[b].flags |= kBoundary;
        continue;
      }
      if (same != 1 || opposite != 1) {
        const char* what = opposite == 0 ? "is not closed: a boundary edge (open meshes are "
                                           "not supported)"
                           : same + opposite > 2 ? "is not edge-manifold or not consistently "
                                                   "oriented: an edge used by more than two "
                                                   "triangles or twice in one direction"
                                                 : "is not consistently oriented";
        return make_error(StatusCode::kInvalidMesh, "decimate_qem: mesh ", what,
                          " between vertices ", a, " and ", b, " (triangle ", h / 3, ")")
            .at_index(h / 3);
      }
      twin(h) = match;
    }
    return link_fans(first, out_edges);
  }

  // One fan per vertex: its head, one of the half-edges out of it (first[i] .. first[i + 1]
  // in out_edges), whose next_out walk must come round through all of them.
  Status link_fans(const uint32_t* first, const uint32_t* out_edges) {
    for (uint32_t i = 0; i < nv; ++i) {
      const uint32_t degree = first[i + 1] - first[i];
      if (degree == 0) {
        vx[i].head = kNone;
        continue;
      }
      const uint32_t h0 = out_edges[first[i]];
      vx[i].head = h0;
      if ((vx[i].flags & kBoundary) != 0) continue;  // never walked
      uint32_t steps = 0, e = h0;
      do {
        e = next_out(e);
        ++steps;
      } while (e != h0 && steps <= degree);
      if (steps != degree) {
        return make_error(StatusCode::kInvalidMesh,
                          "decimate_qem: mesh is not "
                          "vertex-manifold: the triangles around vertex ",
                          i, " form more than one fan (triangle ", h0 / 3, ")")
            .at_index(h0 / 3);
      }
    }
    return Status::ok();
  }

  // Positions, valences, the centre and the plane quadrics.
  void init_vertices(const Vec3* in_verts) {
    for (uint32_t i = 0; i < nv; ++i) {
      VertexData& x = vx[i];
      std::memset(static_cast<void*>(&x.quadric), 0, sizeof(Quadric));
      x.pos = in_verts[i];
      x.valence = 0;
      x.stamp = 0;
    }
    for (uint32_t h = 0; h < 3 * nt; ++h) ++vx[origin(h)].valence;
    {
      Aabb box;
      for (uint32_t t = 0; t < nt; ++t) {
        for (uint32_t k : tri[t].v) box.add(in_verts[k]);
      }
      center = box.center();
    }
    // Plane quadrics, weighted by area, summed in triangle order.
    for (uint32_t t = 0; t < nt; ++t) {
      const Vec3 a = in_verts[tri[t].v[0]] - center;
      const Vec3 b = in_verts[tri[t].v[1]] - center;
      const Vec3 c = in_verts[tri[t].v[2]] - center;
      const Vec3 n = cross(b - a, c - a);
      const double len = length(n);
      if (!(len > 0.0)) continue;
      const double area = 0.5 * len;
      const Vec3 un{n.x / len, n.y / len, n.z / len};
      const double off = -dot(un, a);
      const Quadric q{area * un.x * un.x,
                      area * un.x * un.y,
                      area * un.x * un.z,
                      area * un.y * un.y,
                      area * un.y * un.z,
                      area * un.z * un.z,
                      area * un.x * off,
                      area * un.y * off,
                      area * un.z * off,
                      area * off * off,
                      area};
      for (uint32_t k : tri[t].v) add_to(&vx[k].quadric, q);
    }
  }

  // max_distance: the sample lists (the given samples in their triangles, in order) and the
  // scratch of one collapse.
  Status init_samples(Arena& arena, const Mesh& mesh, const DecimateOptions& options) {
    if (!(options.max_distance > 0.0)) return Status::ok();
    reach2 = options.max_distance * options.max_distance;
    n_given = static_cast<uint32_t>(options.samples.size());
    given = options.samples.data();
    first_sample = arena.allocate_array<uint32_t>(nt);
    next_sample = arena.allocate_array<uint32_t>(size_t{n_given} + nv);
    fan = arena.allocate_array<FanTriangle>(kDecimateFanTriangles);
    moved = arena.allocate_array<uint64_t>(kDecimateMovedSamples);
    if (first_sample == nullptr || next_sample == nullptr || fan == nullptr || moved == nullptr) {
      return arena.exhausted_status();
    }
    surface_tris = mesh.triangles.data();
    surface_verts = mesh.vertices.data();
    given_source = options.sample_sources.empty() ? nullptr : options.sample_sources.data();
    around_first = arena.allocate_array<uint32_t>(size_t{nv} + 1);
    around = arena.allocate_array<uint32_t>(size_t{3} * nt);
    if (around_first == nullptr || around == nullptr) return arena.exhausted_status();
    auto surface = [&options](uint32_t t) {
      return options.approximate.empty() || options.approximate[t] == 0;
    };
    std::memset(around_first, 0, (size_t{nv} + 1) * sizeof(uint32_t));
    for (uint32_t t = 0; t < nt; ++t) {
      if (!surface(t)) continue;
      for (uint32_t k : mesh.triangles[t].v) ++around_first[k + 1];
    }
    for (uint32_t i = 0; i < nv; ++i) around_first[i + 1] += around_first[i];
    for (uint32_t t = 0; t < nt; ++t) {  // in triangle order within a vertex
      if (!surface(t)) continue;
      for (uint32_t k : mesh.triangles[t].v) around[around_first[k]++] = t;
    }
    for (uint32_t i = nv; i > 0; --i) around_first[i] = around_first[i - 1];
    around_first[0] = 0;
    for (uint32_t t = 0; t < nt; ++t) first_sample[t] = kNone;
    for (uint32_t i = n_given; i > 0; --i) {  // prepended last first: lists in sample order
      const uint32_t t = options.sample_triangles[i - 1];
      next_sample[i - 1] = first_sample[t];
      first_sample[t] = i - 1;
    }
    return Status::ok();
  }

  // Every edge in the heap (by its smaller half-edge), then heapified.
  void fill_heap() {
    for (uint32_t h = 0; h < 3 * nt; ++h) {
      if (h < twin(h) && collapsible(h)) {
        Vec3 unused;
        heap.items[heap.size] = heap_entry(cost(h, &unused), h);
        heap.pos(h) = heap.size++;
      } else {
        heap.pos(h) = kNone;
      }
    }
    heap.heapify();
  }

  // The greedy loop: the cheapest edge that passes check() collapses, until at most
  // options.target_triangles are left, the cheapest error is above options.max_error or no
  // edge passes. *live: the triangles left; the counters go to *stats.
  Status collapse_edges(const Context& ctx, const DecimateOptions& options, uint64_t* live_left,
                        DecimateStats* stats) {
    DecimateStats local = *stats;
    const uint32_t half = 3 * nt;
    const uint64_t target = options.target_triangles;
    const double limit = options.max_error * options.max_error;
    uint64_t live = nt;
    uint32_t parked = 0;
    uint64_t collapses_at_round = 0;
    double max_key = 0.0;
    // Puts the refused edges back (with fresh keys) when there has been a collapse since the
    // last time; false when there is nothing new to try.
    auto another_round = [&]() {
      if (parked == 0 || local.collapses == collapses_at_round) return false;
      collapses_at_round = local.collapses;
      ++local.rounds;
      for (uint32_t e = 0; e < half; ++e) {
        if (heap.pos(e) != kParked) continue;
        Vec3 unused;
        heap.place(heap.size++, heap_entry(cost(e, &unused), e));
      }
      parked = 0;
      heap.heapify();
      return true;
    };
    while (live > target) {
      if (heap.size == 0) {
        if (another_round()) continue;
        local.stop = DecimateStop::kNoValidCollapse;
        break;
      }
      const uint32_t h = entry_id(heap.items[0]);
      Vec3 p;
      const double key = cost(h, &p);
      SPLINTCORE_ASSERT(heap_entry(key, h) == heap.items[0]);  // keys are kept exact
      if (limit > 0.0 && key > limit) {  // the smallest error left is too large
        if (another_round()) continue;
        local.stop = DecimateStop::kErrorLimit;
        break;
      }
      heap.remove(h);
      // Keeping positions, the edge collapses into the endpoint cost() chose.
      const uint32_t into = keep && !(p == vx[origin(h)].pos) ? twin(h) : h;
      const int verdict = check(into, p);
      if (verdict != 0) {
        heap.pos(h) = kParked;
        ++parked;
        if (verdict == 1) ++local.rejected_link;
        if (verdict == 2) ++local.rejected_flip;
        if (verdict == 3) ++local.rejected_degenerate;
        if (verdict == 4) ++local.rejected_distance;
        continue;
      }
      collapse(into, p, &parked);
      live -= 2;
      ++local.collapses;
      if (key > max_key) max_key = key;
      if (local.collapses % kProgressEvery == 0) {
        SPLINTCORE_RETURN_IF_ERROR(
            report_progress(ctx, "decimate", 2 * local.collapses, nt - target));
      }
    }
    local.max_error = std::sqrt(max_key);
    *stats = local;
    *live_left = live;
    return report_progress(ctx, "decimate", nt - live, nt - live);
  }

  // The compact output above the work: the live triangles in order, their vertices numbered
  // by first use (triangles allocated first, as move_mesh_down needs).
  Status compact(Arena& arena, uint64_t live, const DecimateOptions& options, Mesh* result) const {
    const Span<uint32_t> vertex_map = options.vertex_map;
    uint32_t* remap = arena.allocate_array<uint32_t>(nv);
    if (remap == nullptr) return arena.exhausted_status();
    for (uint32_t i = 0; i < nv; ++i) remap[i] = kNone;
    uint32_t out_v = 0;
    for (uint32_t t = 0; t < nt; ++t) {
      if (tri[t].v[0] == kNone) continue;
      for (uint32_t k : tri[t].v) {
        if (remap[k] == kNone) remap[k] = out_v++;
      }
    }
    for (size_t i = 0; i < vertex_map.size(); ++i) vertex_map[i] = remap[i];
    for (uint32_t& m : options.sample_map) m = kNone;
    for (uint32_t& m : options.removed_map) m = kNone;
    const uint32_t out_t = static_cast<uint32_t>(live);
    Triangle* res_t = arena.allocate_array<Triangle>(out_t);
    Vec3* res_v = arena.allocate_array<Vec3>(out_v);
    if (res_t == nullptr || res_v == nullptr) return arena.exhausted_status();
    uint32_t w = 0;
    for (uint32_t t = 0; t < nt; ++t) {
      if (tri[t].v[0] == kNone) continue;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = tri[t].v[k];
        res_t[w].v[k] = remap[v];
        res_v[remap[v]] = vx[v].pos;
      }
      if (reach2 > 0.0) {
        for (uint32_t q = first_sample[t]; q != kNone; q = next_sample[q]) {
          if (q < n_given) {
            if (!options.sample_map.empty()) options.sample_map[q] = w;
          } else if (!options.removed_map.empty()) {
            options.removed_map[q - n_given] = w;
          }
        }
      }
      ++w;
    }
    SPLINTCORE_ASSERT(w == out_t);
    result->triangles.adopt(res_t, out_t, out_t);
    result->vertices.adopt(res_v, out_v, out_v);
    return Status::ok();
  }
};

// The checks of decimate_qem's arguments (no memory needed).
Status check_decimate_input(const Mesh& mesh, const DecimateOptions& options, const Mesh& out) {
  if (!out.vertices.empty() || !out.triangles.empty()) {
    return make_error(StatusCode::kInvalidArgument, "decimate_qem: the output mesh must be empty");
  }
  if (!is_finite(options.max_error) || !(options.max_error >= 0.0)) {
    return make_error(StatusCode::kInvalidArgument,
                      "decimate_qem: max_error must be a finite distance >= 0 mm, not ",
                      options.max_error);
  }
  if ((!options.locked.empty() &&
       (!options.keep_positions || options.locked.size() != mesh.vertices.size())) ||
      (!options.vertex_map.empty() && options.vertex_map.size() != mesh.vertices.size())) {
    return make_error(StatusCode::kInvalidArgument,
                      "decimate_qem: `locked` needs keep_positions, and it and `vertex_map` "
                      "need one entry per vertex (",
                      mesh.vertices.size(), ")");
  }
  if (!is_finite(options.max_distance) || !(options.max_distance >= 0.0) ||
      (options.max_distance > 0.0 && !options.keep_positions)) {
    return make_error(StatusCode::kInvalidArgument,
                      "decimate_qem: max_distance must be a finite distance >= 0 mm (and > 0 "
                      "only with keep_positions), not ",
                      options.max_distance);
  }
  const bool sampled = options.max_distance > 0.0;
  if ((!sampled && (!options.samples.empty() || !options.sample_map.empty() ||
                    !options.removed_map.empty() || !options.approximate.empty())) ||
      options.sample_triangles.size() != options.samples.size() ||
      (!options.sample_sources.empty() &&
       options.sample_sources.size() != options.samples.size()) ||
      (!options.approximate.empty() && options.approximate.size() != mesh.triangles.size()) ||
      (!options.sample_map.empty() && options.sample_map.size() != options.samples.size()) ||
      (!options.removed_map.empty() && options.removed_map.size() != mesh.vertices.size()) ||
      options.samples.size() > UINT32_MAX - mesh.vertices.size() - 1) {
    return make_error(StatusCode::kInvalidArgument,
                      "decimate_qem: `samples`, `sample_map`, `removed_map` and `approximate` need "
                      "max_distance; `sample_triangles` and `sample_map` one entry per sample (",
                      options.samples.size(), "), `removed_map` one per vertex (",
                      mesh.vertices.size(), ")");
  }
  for (size_t i = 0; i < options.samples.size(); ++i) {
    if (options.sample_triangles[i] >= mesh.triangles.size() ||
        (!options.sample_sources.empty() && options.sample_sources[i] != kNone &&
         options.sample_sources[i] >= mesh.triangles.size())) {
      return make_error(StatusCode::kInvalidArgument, "decimate_qem: sample ", i,
                        " is assigned to (or lies on) a triangle beyond the mesh's ",
                        mesh.triangles.size(), " triangles")
          .at_index(i);
    }
    if (!is_finite(options.samples[i])) {
      return make_error(StatusCode::kNonFinite, "decimate_qem: sample ", i,
                        " has a coordinate that is NaN or infinite")
          .at_index(i);
    }
  }
  if (options.target_triangles == 0 && options.max_error == 0.0) {
    return make_error(StatusCode::kInvalidArgument,
                      "decimate_qem: give a target triangle count, an error limit or both");
  }
  const uint64_t nv64 = mesh.vertices.size(), nt64 = mesh.triangles.size();
  if (nv64 > UINT32_MAX - 1 || nt64 > (uint64_t{1} << 30)) {
    return make_error(StatusCode::kLimitExceeded, "decimate_qem: mesh too large: ", nt64,
                      " triangles, ", nv64, " vertices (at most 2^30 and 2^32 - 2)");
  }
  const uint32_t nv = static_cast<uint32_t>(nv64), nt = static_cast<uint32_t>(nt64);
  const Triangle* in_tris = mesh.triangles.data();
  const Vec3* in_verts = mesh.vertices.data();
  for (uint32_t t = 0; t < nt; ++t) {
    const uint32_t* v = in_tris[t].v;
    for (int k = 0; k < 3; ++k) {
      if (v[k] >= nv) {
        return make_error(StatusCode::kInvalidMesh, "decimate_qem: triangle ", t,
                          " refers to vertex ", v[k], " but the mesh has ", nv, " vertices")
            .at_index(t);
      }
    }
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) {
      return make_error(StatusCode::kInvalidMesh, "decimate_qem: triangle ", t,
                        " repeats a vertex (", v[0], ", ", v[1], ", ", v[2], ")")
          .at_index(t);
    }
  }
  for (uint32_t i = 0; i < nv; ++i) {
    if (!is_finite(in_verts[i])) {
      return make_error(StatusCode::kNonFinite, "decimate_qem: vertex ", i,
                        " has a coordinate that is NaN or infinite")
          .at_index(i);
    }
  }
  return Status::ok();
}

}  // namespace

uint64_t decimate_qem_bound(uint64_t vertex_count, uint64_t triangle_count, bool bounded_distance,
                            uint64_t given_samples) {
  uint64_t half = 0, first = 0, validation = 0, rest = 0, total = 0;
  if (!checked_mul(triangle_count, 3, &half)) return 0;
  uint64_t samples = 0;
  if (bounded_distance &&
      (!checked_add(given_samples, vertex_count, &samples) ||
       !add_alloc(&rest, triangle_count, 4) || !add_alloc(&rest, samples, 4) ||
       !add_alloc(&rest, vertex_count + 1, 4) || !add_alloc(&rest, half, 4) ||
       !add_alloc(&rest, kDecimateFanTriangles, sizeof(Decimator::FanTriangle)) ||
       !add_alloc(&rest, kDecimateMovedSamples, sizeof(uint64_t)))) {
    return 0;
  }
  if (!add_alloc(&first, triangle_count, sizeof(Face)) ||
      !add_alloc(&first, vertex_count, sizeof(VertexData)) || !add_alloc(&first, 3, 16) ||
      !add_alloc(&validation, vertex_count + 1, 4) || !add_alloc(&validation, half, 4) ||
      !add_alloc(&rest, half / 2 + 8, sizeof(uint64_t)) || !add_alloc(&rest, vertex_count, 4) ||
      !add_alloc(&rest, triangle_count, sizeof(Triangle)) ||
      !add_alloc(&rest, vertex_count, sizeof(Vec3))) {
    return 0;
  }
  if (!checked_add(first, validation > rest ? validation : rest, &total)) return 0;
  return total;
}

Status decimate_qem(const Context& ctx, const Mesh& mesh, const DecimateOptions& options, Mesh* out,
                    DecimateStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && out != nullptr);
  SPLINTCORE_ASSERT(out->vertices.arena() == ctx.arena && out->triangles.arena() == ctx.arena);
  SPLINTCORE_RETURN_IF_ERROR(check_decimate_input(mesh, options, *out));
  const uint32_t nv = static_cast<uint32_t>(mesh.vertices.size());
  const uint32_t nt = static_cast<uint32_t>(mesh.triangles.size());
  const Triangle* in_tris = mesh.triangles.data();
  DecimateStats local;
  local.input_vertices = nv;
  local.input_triangles = nt;
  if (nt == 0) {
    for (uint32_t& m : options.vertex_map) m = kNone;
    if (stats != nullptr) *stats = local;
    return Status::ok();
  }

  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // on an error the arena is as it was
  Decimator d;
  d.nv = nv;
  d.nt = nt;
  d.tri = arena.allocate_array<Face>(nt);
  d.vx = arena.allocate_array<VertexData>(nv);
  if (d.tri == nullptr || (d.vx == nullptr && nv > 0)) return arena.exhausted_status();
  for (uint32_t t = 0; t < nt; ++t) {
    d.tri[t] = Face{{in_tris[t].v[0], in_tris[t].v[1], in_tris[t].v[2]},
                    {kNone, kNone, kNone},
                    {kNone, kNone, kNone}};
  }
  d.keep = options.keep_positions;
  for (uint32_t i = 0; i < nv; ++i) {
    d.vx[i].flags = !options.locked.empty() && options.locked[i] != 0 ? kLocked : 0;
  }
  SPLINTCORE_RETURN_IF_ERROR(d.link_twins(arena, options.allow_boundary));

  d.heap.faces = d.tri;
  const uint32_t half = 3 * nt;
  uint64_t* heap_memory = arena.allocate_array<uint64_t>(half / 2 + 8);
  if (heap_memory != nullptr) {
    // Index 1 at the start of a cache line (speed only).
    size_t skip = 0;
    while ((reinterpret_cast<uintptr_t>(heap_memory + skip + 1) & 63u) != 0) ++skip;
    d.heap.items = heap_memory + skip;
  }
  if (d.heap.items == nullptr) return arena.exhausted_status();
  d.init_vertices(mesh.vertices.data());
  SPLINTCORE_RETURN_IF_ERROR(d.init_samples(arena, mesh, options));
  d.fill_heap();

  uint64_t live = nt;
  SPLINTCORE_RETURN_IF_ERROR(d.collapse_edges(ctx, options, &live, &local));
  // The compact output above the work, then moved down to where the top was.
  Mesh result(&arena);
  SPLINTCORE_RETURN_IF_ERROR(d.compact(arena, live, options, &result));
  move_mesh_down(arena, scope.start(), result, out);
  scope.commit();
  local.output_vertices = out->vertices.size();
  local.output_triangles = out->triangles.size();
  if (stats != nullptr) *stats = local;
  return Status::ok();
}

}  // namespace splintcore
