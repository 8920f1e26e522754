// Building the distance index: a BVH over Morton-ordered leaves, split top-down at the highest
// differing Morton bit (Karras, "Maximizing parallelism in the construction of BVHs, octrees,
// and k-d trees", HPG 2012; here sequential with an explicit stack), four ways at a time: a
// node splits its range, then splits its larger part again, until it has four children (the
// 4-wide tree of Wald et al., "Getting rid of packets", IRT 2008, built directly rather than
// collapsed from a binary one), bounds and dipoles bottom-up, edge neighbours from per-vertex
// half-edge lists, and angle-weighted vertex
// pseudonormals (Baerentzen and Aanaes, "Signed distance computation using the angle weighted
// pseudonormal", IEEE TVCG 2005).
#include <cmath>
#include <cstring>

#include "splintcore/distance.h"

#include "distance/morton.h"
#include "geometry/float_bounds.h"

namespace splintcore {

namespace {

constexpr uint32_t kMaxDepth = 128;

// Triangles per leaf when the options leave it 0: 8. Against leaves of 4 (543k-triangle
// torus): half the nodes, 8.5% fewer instructions to build (386M, not 422M) and about 11% less
// time; the same work for large batches, which go triangle by triangle (regions.cpp: 10.23G
// instructions for 2 x 1,000,000 closest points either way); one tree search about 12% more
// instructions (44.6k, not 39.6k, a query within 2 mm of the surface).
inline uint32_t leaf_size_of(const DistanceIndexOptions& options) {
  return options.leaf_size != 0 ? options.leaf_size : 8;
}

// What an index with these options keeps besides the tree and the order (distance.h).
inline bool with_topology(const DistanceIndexOptions& o) {
  return !o.pairs_only && !o.winding_only;
}
inline bool with_dipoles(const DistanceIndexOptions& o) {
  return !o.pairs_only || o.oriented_boxes || o.winding_only;
}
inline bool with_triangle_boxes(const DistanceIndexOptions& o) {
  return o.pairs_only && !o.winding_only && !o.without_triangle_boxes;
}

// Morton codes of 16 bits an axis (detail::spread_bits, morton.h): 65536 cells per axis, finer
// than any triangle here.
using detail::spread_bits;

// In-place heap sort (Williams 1964): no memory, O(n log n) whatever the input, and with
// unique keys the order is fixed (no dependence on the standard library's sort).
template <class T, class Less>
void heap_sort(T* a, size_t n, Less less) {
  auto sift = [&](size_t root, size_t end) {
    for (;;) {
      size_t child = 2 * root + 1;
      if (child >= end) return;
      if (child + 1 < end && less(a[child], a[child + 1])) ++child;
      if (!less(a[root], a[child])) return;
      const T t = a[root];
      a[root] = a[child];
      a[child] = t;
      root = child;
    }
  };
  for (size_t i = n / 2; i-- > 0;) sift(i, n);
  for (size_t end = n; end > 1; --end) {
    const T t = a[0];
    a[0] = a[end - 1];
    a[end - 1] = t;
    sift(0, end - 1);
  }
}

// A float at most x (finite), cheaply: x lowered by 2^-20 of itself and 2^-140 before the
// conversion, whose rounding (at most 2^-24 relative or 2^-150 absolute) cannot undo that;
// below the float range, -infinity; above it, the largest float.
inline float float_below(double x) {
  constexpr double kMax = 3.4028234663852886e38;  // FLT_MAX
  const double y = x - (std::fabs(x) * 0x1p-20 + 0x1p-140);
  if (!(y >= -kMax)) return -HUGE_VALF;
  return static_cast<float>(y < kMax ? y : kMax);
}

inline int highest_bit(uint64_t x) { return 63 - __builtin_clzll(x); }

}  // namespace

const char* feature_name(Feature feature) {
  switch (feature) {
    case Feature::kFace: return "face";
    case Feature::kEdge: return "edge";
    case Feature::kVertex: return "vertex";
  }
  return "unknown";
}

uint64_t distance_index_bound(uint64_t vertex_count, uint64_t triangle_count,
                              const DistanceIndexOptions& options) {
  const uint64_t leaf = leaf_size_of(options);
  const uint64_t leaves = triangle_count == 0 ? 1 : (triangle_count + leaf - 1) / leaf;
  // Every node splits a range of at least two leaves (an empty or one-leaf mesh has a root).
  const uint64_t wide = leaves > 1 ? leaves - 1 : 1;
  const bool topology = with_topology(options);
  const bool dipoles = with_dipoles(options);
  const uint64_t per_node = sizeof(BvhNode) + (dipoles ? sizeof(BvhDipole) : 0) +
                            (options.oriented_boxes ? sizeof(BvhObb) : 0);
  const uint64_t kept = wide * per_node + triangle_count * (sizeof(uint32_t) * (topology ? 7 : 1)) +
                        (topology ? (vertex_count + 1) * sizeof(uint32_t) : 0) +
                        (with_triangle_boxes(options) ? triangle_count * 6 * sizeof(float) : 0);
  // Temporaries (the larger stage): Morton keys and scratch with the tree at its upper bound
  // before it moves down, or the per-vertex corner lists.
  const uint64_t tree = 2 * triangle_count * sizeof(uint64_t) + wide * per_node;
  const uint64_t lists = topology ? 3 * triangle_count * 2 * sizeof(uint32_t) : 0;
  const uint64_t temps = (tree > lists ? tree : lists) + kMaxDepth * 16;
  return kept + temps + 16 * 64;
}

namespace {

// The frame of a node whose area-weighted normal sum is `normal`: the unit normal and two
// unit vectors orthogonal to it (Duff et al., "Building an orthonormal basis, revisited",
// JCGT 2017: one division, no branch on the normal's direction), each rounded to float. False
// when the normal sum vanishes (a closed or empty part: no preferred direction).
bool normal_frame(const Vec3& normal, float axis[3][3]) {
  const double len2 = dot(normal, normal);
  if (!(len2 > 0)) return false;
  const Vec3 n = normal * (1.0 / std::sqrt(len2));
  const double s = n.z >= 0 ? 1.0 : -1.0;
  const double a = -1.0 / (s + n.z);
  const double b = n.x * n.y * a;
  const Vec3 u{1.0 + s * n.x * n.x * a, s * b, -s * n.x};
  const Vec3 w{b, s + n.y * n.y * a, -n.y};
  const Vec3* frame[3] = {&n, &u, &w};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) axis[i][j] = static_cast<float>((*frame[i])[j]);
  }
  return true;
}

inline Vec3 axis_of(const float a[3]) {
  return Vec3{static_cast<double>(a[0]), static_cast<double>(a[1]), static_cast<double>(a[2])};
}

inline double abs_max(double a, double b) {
  a = std::fabs(a);
  b = std::fabs(b);
  return a > b ? a : b;
}

// Child k's intervals in the frame `axis` (BvhObb), when child k is a leaf: its triangles'
// corners suffice (the region is convex). Each projection is three products and two sums,
// off by under 2^-50 |x|_inf; the margin 2^-46 (m + 1), m >= |x|_inf over the corners (from
// the leaf's box), covers it before rounding outward.
void leaf_intervals(const Mesh& mesh, const uint32_t* ids, uint32_t count, const float axis[3][3],
                    double m, float lo[3], float hi[3]) {
  const Vec3* v = mesh.vertices.data();
  const Vec3 a[3] = {axis_of(axis[0]), axis_of(axis[1]), axis_of(axis[2])};
  double l[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, h[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  // Neighbours in leaf order share corners: one already projected for the triangle before
  // is skipped (the same bits again would change nothing).
  uint32_t before[3] = {~0u, ~0u, ~0u};
  for (uint32_t j = 0; j < count; ++j) {
    const Triangle& tri = mesh.triangles[ids[j]];
    for (int c = 0; c < 3; ++c) {
      const uint32_t id = tri.v[c];
      if (id == before[0] || id == before[1] || id == before[2]) continue;
      const Vec3& x = v[id];
      for (int i = 0; i < 3; ++i) {
        const double p = dot(a[i], x);
        l[i] = p < l[i] ? p : l[i];
        h[i] = p > h[i] ? p : h[i];
      }
    }
    for (int c = 0; c < 3; ++c) before[c] = tri.v[c];
  }
  const double margin = (m + 1.0) * 0x1p-46;
  for (int i = 0; i < 3; ++i) {
    lo[i] = float_down(l[i] - margin);
    hi[i] = float_up(h[i] + margin);
  }
}

// Child k's intervals in the frame `axis`, when child k is inner node c (oriented boxes in
// `o`, in c's own frame b; `m` >= every |coordinate| in child k's axis-aligned box). For a
// parent axis a, a . x = sum_i alpha_i (b_i . x) + r . x exactly for any alpha_i, with
// r = a - sum_i alpha_i b_i; alpha_i = a . b_i makes r as small as the axes' rounding (about
// 1e-7), and |r . x| <= |r|_1 m. The rounding of r (under 2^-48 a component: |a|,
// |alpha_i b_i| <= 1) and of the sums (each |alpha_i (b_i . x)| <= 2 m + 1, so 2^-46 (8 m + 4)
// covers them) is added before rounding outward.
void inner_intervals(const BvhNode& c, const BvhObb& o, const float axis[3][3], double m,
                     float lo[3], float hi[3]) {
  const Vec3 b[3] = {axis_of(o.axis[0]), axis_of(o.axis[1]), axis_of(o.axis[2])};
  for (int i = 0; i < 3; ++i) {
    const Vec3 a = axis_of(axis[i]);
    double alpha[3];
    Vec3 r = a;
    for (int j = 0; j < 3; ++j) {
      alpha[j] = dot(a, b[j]);
      r = r - b[j] * alpha[j];
    }
    const double r1 = std::fabs(r.x) + std::fabs(r.y) + std::fabs(r.z) + 3 * 0x1p-48;
    const double margin = r1 * m * (1.0 + 0x1p-40) + (8.0 * m + 4.0) * 0x1p-46;
    double l = HUGE_VAL, h = -HUGE_VAL;
    for (int k = 0; k < 4; ++k) {
      if (c.child[k] == kNoChild) continue;
      double sum_lo = 0, sum_hi = 0;
      for (int j = 0; j < 3; ++j) {
        const double pl = alpha[j] * static_cast<double>(o.lo[j][k]);
        const double ph = alpha[j] * static_cast<double>(o.hi[j][k]);
        sum_lo += pl < ph ? pl : ph;
        sum_hi += pl < ph ? ph : pl;
      }
      l = sum_lo < l ? sum_lo : l;
      h = sum_hi > h ? sum_hi : h;
    }
    lo[i] = float_down(l - margin);
    hi[i] = float_up(h + margin);
  }
}

// A corner in the per-vertex lists of the edge-neighbour step: the next and previous vertex of
// each corner, beside vertex_uses (reading them from the triangles instead halves this memory
// but costs 10 ms at 543k triangles in random reads). A list longer than kScan (below) holds,
// instead, its next vertex and its use, sorted.
struct Corner {
  uint32_t next;
  uint32_t other;  // the previous vertex; in a long list, the use (3 * triangle + corner)
};

// A list of up to kScan corners (the usual vertex: six) is scanned once for each of its
// edges. A longer one is sorted by (next vertex, use) and searched, so that a vertex shared
// by d triangles costs O(d log d), not O(d^2) (hostile input: a fan of a million
// triangles, or a million copies of one triangle); its edges' reverse half-edges are
// counted in the other vertex's list, by search or scan.
constexpr uint32_t kScan = 32;

// First index in [lo, hi) of a sorted list whose next vertex is >= to (or > to when `after`).
inline uint32_t search_next(const Corner* lists, uint32_t lo, uint32_t hi, uint32_t to,
                            bool after) {
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    if (lists[mid].next < to || (after && lists[mid].next == to)) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return lo;
}

// The area-weighted sums of a node's dipole (BvhDipole), over its children.
struct DipoleSums {
  Vec3 wsum{};  // centroids times areas
  Vec3 nsum{};  // area-weighted normals
  double asum = 0;
};

// build_index_steps (below), stage by stage. What stays: order, neighbours and the per-vertex
// corner lists (for the vertex normals), allocated first; the 4-wide nodes and their dipoles,
// moved down over the temporaries once the tree is built.
struct IndexBuild {
  Arena& arena;
  const Mesh& mesh;
  const DistanceIndexOptions& options;
  const Vec3* v;
  const Triangle* tris;
  size_t nt, nv;
  uint32_t n = 0;  // nt, once it is known to fit
  uint32_t leaf_size;
  uint32_t leaves = 1;
  uint32_t wide_max = 1;  // the wide nodes' upper bound
  uint32_t* order = nullptr;
  float* tboxes = nullptr;  // pairs_only: 6 per triangle, in leaf order
  uint32_t* neighbors = nullptr;
  uint32_t* start = nullptr;
  uint32_t* vuses = nullptr;
  Aabb centroids;
  uint64_t* keys = nullptr;  // Morton code << id_bits | triangle, sorted (a temporary)
  BvhNode* nodes = nullptr;
  BvhDipole* dipoles = nullptr;
  BvhObb* obbs = nullptr;
  uint32_t node_count = 1;
  uint32_t depth = 0;
  bool closed_manifold = false;

  IndexBuild(Arena& a, const Mesh& m, const DistanceIndexOptions& o)
      : arena(a),
        mesh(m),
        options(o),
        v(m.vertices.data()),
        tris(m.triangles.data()),
        nt(m.triangles.size()),
        nv(m.vertices.size()),
        leaf_size(leaf_size_of(o)) {}

  Status check_input() const {
    if (leaf_size > 16) {
      return make_error(StatusCode::kInvalidArgument, "leaf size must be 1..16, got ", leaf_size);
    }
    // Corners are numbered 3 * triangle + corner in 32 bits (vertex_uses, neighbours).
    constexpr uint64_t kMaxTriangles = UINT32_MAX / 3;
    if (nt > kMaxTriangles) {
      return make_error(StatusCode::kLimitExceeded, "distance index: ", nt, " triangles, at most ",
                        kMaxTriangles, " (corners are numbered in 32 bits)");
    }
    for (size_t i = 0; i < nv; ++i) {
      if (!is_finite(v[i])) {
        return make_error(StatusCode::kInvalidMesh, "vertex ", i, " is not finite").at_index(i);
      }
    }
    return Status::ok();
  }

  // The arrays that stay (order, neighbours, the per-vertex lists), then one pass over the
  // triangles: their indices checked, their centroids bounded (for the Morton codes, step 1)
  // and each vertex's corners counted (for its list, step 4).
  Status scan_triangles() {
    order = arena.allocate_array<uint32_t>(nt);
    if (nt > 0 && order == nullptr) return arena.exhausted_status();
    if (with_triangle_boxes(options)) {
      tboxes = arena.allocate_array<float>(6 * nt);
      if (nt > 0 && tboxes == nullptr) return arena.exhausted_status();
    }
    if (with_topology(options)) {
      neighbors = arena.allocate_array<uint32_t>(3 * nt);
      start = arena.allocate_array<uint32_t>(nv + 1);
      vuses = arena.allocate_array<uint32_t>(3 * nt);
      if ((nt > 0 && (neighbors == nullptr || vuses == nullptr)) || start == nullptr) {
        return arena.exhausted_status();
      }
      for (size_t i = 0; i <= nv; ++i) start[i] = 0;
    }
    for (size_t t = 0; t < nt; ++t) {
      const Triangle& tri = tris[t];
      if (tri.v[0] >= nv || tri.v[1] >= nv || tri.v[2] >= nv) {
        return make_error(StatusCode::kInvalidMesh, "triangle ", t,
                          " refers to a vertex that does not exist")
            .at_index(t);
      }
      centroids.add((v[tri.v[0]] + v[tri.v[1]] + v[tri.v[2]]) * (1.0 / 3.0));
      if (start == nullptr) continue;
      for (int k = 0; k < 3; ++k) ++start[tri.v[k] + size_t{1}];
    }
    n = static_cast<uint32_t>(nt);
    leaves = n == 0 ? 1 : (n + leaf_size - 1) / leaf_size;
    // Every wide node splits a range of at least two leaves, so there are at most leaves - 1.
    wide_max = leaves > 1 ? leaves - 1 : 1;
    return Status::ok();
  }

  // 1. Morton order of the triangle centroids (keys live until the topology is built), and
  // the wide nodes and their dipoles at their upper bound, after the keys.
  Status morton_order() {
    // Key = Morton code in the high bits, triangle id in the low bits: one 64-bit word per
    // triangle to sort (half the traffic of a key-index pair). The code gets 3 * code_bits
    // bits, code_bits = min(16, (64 - id bits) / 3): 16 up to 65,536 triangles ... 14 up to 4
    // million.
    uint32_t id_bits = 1;
    while (id_bits < 32 && (uint64_t{1} << id_bits) < nt) ++id_bits;
    const uint32_t code_bits = (64 - id_bits) / 3 < 16 ? (64 - id_bits) / 3 : 16;
    keys = arena.allocate_array<uint64_t>(nt);
    uint64_t* scratch = arena.allocate_array<uint64_t>(nt);
    nodes = arena.allocate_array<BvhNode>(wide_max);
    const bool keep_dipoles = with_dipoles(options);
    if (keep_dipoles) dipoles = arena.allocate_array<BvhDipole>(wide_max);
    if (options.oriented_boxes) obbs = arena.allocate_array<BvhObb>(wide_max);
    if ((nt > 0 && (keys == nullptr || scratch == nullptr)) || nodes == nullptr ||
        (keep_dipoles && dipoles == nullptr) || (options.oriented_boxes && obbs == nullptr)) {
      return arena.exhausted_status();
    }
    const Vec3 lo = centroids.lo;
    const Vec3 ext = centroids.extent();
    const double cells = static_cast<double>((uint64_t{1} << code_bits) - 1);
    const double scale[3] = {ext.x > 0 ? cells / ext.x : 0.0, ext.y > 0 ? cells / ext.y : 0.0,
                             ext.z > 0 ? cells / ext.z : 0.0};
    for (uint32_t t = 0; t < n; ++t) {
      const Triangle& tri = tris[t];
      const Vec3 c = (v[tri.v[0]] + v[tri.v[1]] + v[tri.v[2]]) * (1.0 / 3.0);
      uint64_t q[3];
      for (int a = 0; a < 3; ++a) {
        double x = (c[a] - lo[a]) * scale[a];
        x = x < 0 ? 0 : (x > cells ? cells : x);
        q[a] = static_cast<uint64_t>(x);
      }
      const uint64_t code = (spread_bits(q[0]) << 2) | (spread_bits(q[1]) << 1) | spread_bits(q[2]);
      keys[t] = (code << id_bits) | t;
    }
    // The ids rise in input order, so a stable sort on the code bits alone gives the order
    // of the whole key.
    radix_sort_bits(Span<uint64_t>(keys, nt), Span<uint64_t>(scratch, nt), id_bits,
                    id_bits + 3 * code_bits);
    const uint64_t id_mask = (uint64_t{1} << id_bits) - 1;
    for (uint32_t i = 0; i < n; ++i) order[i] = static_cast<uint32_t>(keys[i] & id_mask);
    return Status::ok();
  }

  // A leaf's code is its first triangle's (the id bits only break ties among equal codes,
  // and splitting on them is as good as any other split there).
  uint64_t leaf_code(uint32_t l) const { return n == 0 ? 0 : keys[size_t{l} * leaf_size]; }

  // The last leaf of the first half of [first, last] (first < last).
  uint32_t split_point(uint32_t first, uint32_t last) const {
    const uint64_t a = leaf_code(first), b = leaf_code(last);
    if (a == b) return first + (last - first) / 2;
    const int bit = highest_bit(a ^ b);
    // The last leaf with that bit clear (first has it clear, last set): a binary search
    // that narrows by halves without a branch on the bit (which side it goes is a coin
    // toss). `base` has the bit clear, and the answer lies in [base, base + count).
    uint32_t base = first, count = last - first;
    while (count > 1) {
      const uint32_t half = count / 2;
      base = ((leaf_code(base + half) >> bit) & 1) == 0 ? base + half : base;
      count -= half;
    }
    return base;
  }

  // Splits the leaves [first[0], last[0]] into parts [first[k], last[k]]: at the highest
  // differing Morton bit, then the part with the most leaves (the first on a tie) again, until
  // there are four parts or only single leaves. Returns the number of parts.
  uint32_t split_four(uint32_t first[4], uint32_t last[4]) const {
    uint32_t parts = 1;
    while (parts < 4) {
      uint32_t widest = parts;
      for (uint32_t k = 0; k < parts; ++k) {
        if (last[k] > first[k] &&
            (widest == parts || last[k] - first[k] > last[widest] - first[widest])) {
          widest = k;
        }
      }
      if (widest == parts) break;
      const uint32_t split = split_point(first[widest], last[widest]);
      for (uint32_t k = parts; k > widest + 1; --k) {
        first[k] = first[k - 1];
        last[k] = last[k - 1];
      }
      first[widest + 1] = split + 1;
      last[widest + 1] = last[widest];
      last[widest] = split;
      ++parts;
    }
    return parts;
  }

  // 2. Topology, top-down over leaf ranges. Leaf l holds order[l * leaf_size ...]; its code is
  // its first triangle's. A wide node splits its range at the highest differing Morton bit,
  // then splits the part with the most leaves again (the first on a tie) until it has four
  // parts or only single leaves; a part of one leaf is a leaf child, a longer one a wide node.
  // Nodes are numbered as they are made, so children follow their parent and the reverse of
  // the numbering is bottom-up.
  Status build_topology() {
    struct Range {
      uint32_t node, first, last;  // leaves [first, last]
      uint32_t depth;              // of the node: the root is 1
    };
    const float inf = HUGE_VALF;
    Range stack[3 * kMaxDepth + 4];
    uint32_t top = 0;
    stack[top++] = Range{0, 0, leaves - 1, 1};
    while (top > 0) {
      const Range r = stack[--top];
      if (r.depth > depth) depth = r.depth;
      uint32_t first[4] = {r.first, 0, 0, 0}, last[4] = {r.last, 0, 0, 0};
      const uint32_t parts = split_four(first, last);
      BvhNode& w = nodes[r.node];
      for (uint32_t k = 0; k < 4; ++k) {
        for (int a = 0; a < 3; ++a) {
          w.lo[a][k] = inf;  // bounds come in step 3
          w.hi[a][k] = -inf;
        }
        w.child[k] = kNoChild;
        w.count[k] = 0;
        if (k >= parts) continue;
        if (first[k] == last[k]) {
          const uint32_t begin = first[k] * leaf_size;
          const uint32_t end = begin + leaf_size < n ? begin + leaf_size : n;
          if (end == begin) continue;  // the empty mesh's root: no child at all
          w.child[k] = begin;
          w.count[k] = static_cast<uint8_t>(end - begin);
          continue;
        }
        if (top + 1 > 3 * kMaxDepth + 4 || node_count >= wide_max) {
          return Status::error(StatusCode::kInternal, "distance index: hierarchy too deep");
        }
        w.child[k] = node_count;
        stack[top++] = Range{node_count++, first[k], last[k], r.depth + 1};
      }
    }
    return Status::ok();
  }

  // Child k of `node`, a leaf: its box and dipole sums from its triangles.
  void leaf_child_bounds(BvhNode& node, int k, DipoleSums* sums) const {
    Aabb box;
    for (uint32_t j = node.child[k]; j < node.child[k] + node.count[k]; ++j) {
      const Triangle& tri = tris[order[j]];
      const Vec3 &p0 = v[tri.v[0]], &p1 = v[tri.v[1]], &p2 = v[tri.v[2]];
      box.add(p0);
      box.add(p1);
      box.add(p2);
      if (tboxes != nullptr) {
        const Vec3 lo = min_vec(min_vec(p0, p1), p2), hi = max_vec(max_vec(p0, p1), p2);
        float* b = tboxes + 6 * size_t{j};
        for (int a = 0; a < 3; ++a) {
          b[a] = float_below(lo[a]);
          b[3 + a] = -float_below(-hi[a]);
        }
      }
      if (dipoles == nullptr) continue;  // boxes only (pairs_only)
      const Vec3 an = cross(p1 - p0, p2 - p0) * 0.5;
      const double ar = length(an);
      sums->nsum = sums->nsum + an;
      sums->wsum = sums->wsum + (p0 + p1 + p2) * (ar / 3.0);
      sums->asum += ar;
    }
    for (int a = 0; a < 3; ++a) {
      node.lo[a][k] = float_down(box.lo[a]);
      node.hi[a][k] = float_up(box.hi[a]);
    }
  }

  // Child k of `node`, an inner node: its box the union of that node's boxes, its dipole that
  // node's, in float.
  void inner_child_bounds(BvhNode& node, int k, DipoleSums* sums) const {
    const BvhNode& c = nodes[node.child[k]];
    float lo[3] = {HUGE_VALF, HUGE_VALF, HUGE_VALF}, hi[3] = {-HUGE_VALF, -HUGE_VALF, -HUGE_VALF};
    for (int j = 0; j < 4; ++j) {
      if (c.child[j] == kNoChild) continue;
      for (int a = 0; a < 3; ++a) {
        lo[a] = c.lo[a][j] < lo[a] ? c.lo[a][j] : lo[a];
        hi[a] = c.hi[a][j] > hi[a] ? c.hi[a][j] : hi[a];
      }
    }
    for (int a = 0; a < 3; ++a) {
      node.lo[a][k] = lo[a];
      node.hi[a][k] = hi[a];
    }
    if (dipoles == nullptr) return;  // boxes only (pairs_only)
    const BvhDipole& cd = dipoles[node.child[k]];
    const double ca = static_cast<double>(cd.area);
    sums->nsum =
        sums->nsum + Vec3{static_cast<double>(cd.normal[0]), static_cast<double>(cd.normal[1]),
                          static_cast<double>(cd.normal[2])};
    sums->wsum =
        sums->wsum + Vec3{static_cast<double>(cd.center[0]), static_cast<double>(cd.center[1]),
                          static_cast<double>(cd.center[2])} *
                         ca;
    sums->asum += ca;
  }

  // Node i's dipole from its children's sums; `all` is the union of its boxes.
  void set_dipole(uint32_t i, Aabb all, const DipoleSums& sums) {
    if (all.empty()) all.add(Vec3{});
    const Vec3 center = sums.asum > 0 ? sums.wsum * (1.0 / sums.asum) : all.center();
    // Radius: the box's half diagonal plus the centre's offset from the box centre bounds the
    // distance to every corner (triangle inequality), with one square root.
    const double reach = 0.5 * length(all.hi - all.lo) + length((all.lo + all.hi) * 0.5 - center);
    BvhDipole& dp = dipoles[i];
    for (int a = 0; a < 3; ++a) {
      dp.center[a] = static_cast<float>(center[a]);
      dp.normal[a] = static_cast<float>(sums.nsum[a]);
    }
    // The float centre moved by up to half an ulp per axis: widen the radius for that.
    const Vec3 fc{static_cast<double>(dp.center[0]), static_cast<double>(dp.center[1]),
                  static_cast<double>(dp.center[2])};
    dp.radius = float_up((reach + length(fc - center) * 2.0) * (1.0 + 1e-12));
    dp.area = static_cast<float>(sums.asum);
  }

  // Node i's oriented boxes in the frame of its normal sum (the leaves' corners are in cache
  // from its bounds), kept when their volumes sum to less than the axis-aligned ones.
  void set_oriented_boxes(uint32_t i, const Vec3& nsum) {
    const BvhNode& node = nodes[i];
    BvhObb& ob = obbs[i];
    bool oriented = normal_frame(nsum, ob.axis);
    if (oriented) {
      double obb_volume = 0, box_volume = 0;
      for (int k = 0; k < 4; ++k) {
        float lo[3] = {HUGE_VALF, HUGE_VALF, HUGE_VALF},
              hi[3] = {-HUGE_VALF, -HUGE_VALF, -HUGE_VALF};
        if (node.child[k] != kNoChild) {
          double m = 0;  // the largest |coordinate| in the child's box
          for (int a = 0; a < 3; ++a) {
            m = abs_max(
                m, abs_max(static_cast<double>(node.lo[a][k]), static_cast<double>(node.hi[a][k])));
          }
          if (node.count[k] > 0) {
            leaf_intervals(mesh, order + node.child[k], node.count[k], ob.axis, m, lo, hi);
          } else {
            inner_intervals(nodes[node.child[k]], obbs[node.child[k]], ob.axis, m, lo, hi);
          }
          double ov = 1, av = 1;
          for (int a = 0; a < 3; ++a) {
            ov *= static_cast<double>(hi[a]) - static_cast<double>(lo[a]);
            av *= static_cast<double>(node.hi[a][k]) - static_cast<double>(node.lo[a][k]);
          }
          obb_volume += ov;
          box_volume += av;
        }
        for (int a = 0; a < 3; ++a) {
          ob.lo[a][k] = lo[a];
          ob.hi[a][k] = hi[a];
        }
      }
      oriented = obb_volume < box_volume;
    }
    if (!oriented) {
      for (int a = 0; a < 3; ++a) {
        for (int j = 0; j < 3; ++j) ob.axis[a][j] = a == j ? 1.0f : 0.0f;
        for (int k = 0; k < 4; ++k) {
          ob.lo[a][k] = node.lo[a][k];
          ob.hi[a][k] = node.hi[a][k];
        }
      }
    }
  }

  // 3. Bounds and dipoles, bottom-up (children have larger indices than their parent). A
  // leaf child's box and dipole sums come from its triangles, an inner child's from its node
  // (its box is the union of that node's boxes, its dipole that node's, in float): the far
  // field is an approximation either way, and the radius is bounded from the node's own box.
  void bound_nodes() {
    for (uint32_t i = node_count; i-- > 0;) {
      BvhNode& node = nodes[i];
      Aabb all;
      DipoleSums sums;
      for (int k = 0; k < 4; ++k) {
        if (node.child[k] == kNoChild) continue;
        if (node.count[k] > 0) {
          leaf_child_bounds(node, k, &sums);
        } else {
          inner_child_bounds(node, k, &sums);
        }
        all.add(Vec3{static_cast<double>(node.lo[0][k]), static_cast<double>(node.lo[1][k]),
                     static_cast<double>(node.lo[2][k])});
        all.add(Vec3{static_cast<double>(node.hi[0][k]), static_cast<double>(node.hi[1][k]),
                     static_cast<double>(node.hi[2][k])});
      }
      if (dipoles != nullptr) set_dipole(i, all, sums);
      if (obbs != nullptr) set_oriented_boxes(i, sums.nsum);
    }
  }

  // The tree down over the Morton keys at `temps` (it was allocated after them, the nodes
  // first: ArenaMover).
  void move_tree_down(const Arena::Marker& temps) {
    ArenaMover mover(arena, temps);
    nodes = mover.move(nodes, node_count);
    dipoles = mover.move(dipoles, node_count);
    obbs = mover.move(obbs, node_count);
  }

  // Counting sort of the corners by vertex into vuses (kept, in triangle order) and `lists`,
  // with start[] as its own cursor: vertex a's corners were counted in start[a + 1]
  // (scan_triangles), then start[a + 1] becomes where a's list begins and moves on with each
  // corner placed, to end where a + 1's begins. Then the lists longer than kScan sorted by
  // (next vertex, use).
  void sort_corners(Corner* lists) {
    uint32_t sum = 0;
    for (size_t i = 0; i < nv; ++i) {
      const uint32_t count = start[i + 1];
      start[i + 1] = sum;
      sum += count;
    }
    for (uint32_t t = 0; t < n; ++t) {
      const uint32_t c0 = tris[t].v[0], c1 = tris[t].v[1], c2 = tris[t].v[2];
      uint32_t j = start[c0 + size_t{1}]++;
      vuses[j] = 3 * t;  // kept, in triangle order
      lists[j] = Corner{c1, c2};
      j = start[c1 + size_t{1}]++;
      vuses[j] = 3 * t + 1;
      lists[j] = Corner{c2, c0};
      j = start[c2 + size_t{1}]++;
      vuses[j] = 3 * t + 2;
      lists[j] = Corner{c0, c1};
    }
    const auto by_next = [](const Corner& x, const Corner& y) {
      return x.next != y.next ? x.next < y.next : x.other < y.other;
    };
    for (size_t i = 0; i < nv; ++i) {
      const uint32_t degree = start[i + 1] - start[i];
      if (degree <= kScan) continue;
      for (uint32_t j = start[i]; j < start[i + 1]; ++j) lists[j].other = vuses[j];
      heap_sort(lists + start[i], degree, by_next);
    }
  }

  // 4. Edge neighbours from per-vertex lists of corners (counting sort by vertex, in triangle
  // order). Half-edge a->b is a manifold edge when the mesh holds it once and b->a once; the
  // triangle of b->a is the neighbour. Both counts are in a's list alone: a corner at a with
  // next vertex b is a half-edge a->b, one with previous vertex b is the end of a half-edge
  // b->a (one corner per half-edge either way), so each edge is settled from the list of its
  // smaller vertex, read in cache, without a visit to the other vertex's list.
  Status link_neighbours() {
    ArenaScope lists_scope(arena);
    Corner* lists = arena.allocate_array<Corner>(3 * nt);
    if (nt > 0 && lists == nullptr) return arena.exhausted_status();
    sort_corners(lists);
    // Sets both sides of a manifold edge, given the uses (3 * triangle + corner) that start
    // its two half-edges. Each manifold edge is linked once (from its smaller vertex) and sets
    // two slots no other edge sets, so the mesh is a closed oriented manifold when the links
    // fill every slot.
    uint64_t links = 0;
    const auto link = [&](uint32_t own, uint32_t reverse) {
      neighbors[own] = reverse / 3;
      neighbors[reverse] = own / 3;
      ++links;
    };
    for (size_t i = 0; i < 3 * nt; ++i) neighbors[i] = kNoNeighbor;
    for (size_t vertex = 0; vertex < nv; ++vertex) {
      // Ids fit in 32 bits (Triangle); a vertex past them is in no triangle: an empty list.
      const uint32_t a = static_cast<uint32_t>(vertex);
      const uint32_t lo = start[vertex], hi = start[vertex + 1];
      if (hi - lo <= kScan) {
        link_short_list(lists, a, lo, hi, link);
      } else {
        link_long_list(lists, a, lo, hi, link);
      }
    }
    closed_manifold = n > 0 && 2 * links == 3 * uint64_t{n};
    return Status::ok();
  }

  // The edges vertex a settles (b > a) from its list lists[lo, hi) of at most kScan corners.
  template <class Link>
  void link_short_list(const Corner* lists, uint32_t a, uint32_t lo, uint32_t hi,
                       const Link& link) const {
    // The corners whose edge a settles, gathered without a branch first: which of them
    // qualify follows no pattern on real meshes.
    uint32_t up[kScan];
    uint32_t m = 0;
    for (uint32_t j = lo; j < hi; ++j) {
      up[m] = j;
      m += lists[j].next > a ? 1u : 0u;
    }
    for (uint32_t q = 0; q < m; ++q) {
      const uint32_t j = up[q];
      const uint32_t b = lists[j].next;
      uint32_t same = 0, reverse = 0, at = 0;
      for (uint32_t i = lo; i < hi; ++i) {
        same += lists[i].next == b ? 1u : 0u;
        const bool back = lists[i].other == b;
        reverse += back ? 1u : 0u;
        at = back ? i : at;
      }
      if (same != 1 || reverse != 1) continue;
      // Corner `at` of a follows b in its triangle: b's corner, the one before, starts b->a.
      const uint32_t use = vuses[at];
      link(vuses[j], use - use % 3 + (use % 3 == 0 ? 2 : use % 3 - 1));
    }
  }

  // The same from a sorted list lists[lo, hi) longer than kScan: each run of one next vertex
  // b > a, with the reverse half-edges counted in b's list.
  template <class Link>
  void link_long_list(const Corner* lists, uint32_t a, uint32_t lo, uint32_t hi,
                      const Link& link) const {
    for (uint32_t j = lo; j < hi; ++j) {
      const uint32_t b = lists[j].next;
      if (b <= a || (j > lo && lists[j - 1].next == b)) continue;  // first of its run only
      if (j + 1 < hi && lists[j + 1].next == b) continue;          // a->b more than once
      const uint32_t blo = start[b], bhi = start[b + 1];
      uint32_t reverse = 0, use = 0;
      if (bhi - blo <= kScan) {
        for (uint32_t i = blo; i < bhi; ++i) {
          if (lists[i].next != a) continue;
          ++reverse;
          use = vuses[i];
        }
      } else {
        const uint32_t begin = search_next(lists, blo, bhi, a, false);
        reverse = search_next(lists, begin, bhi, a, true) - begin;
        if (reverse > 0) use = lists[begin].other;
      }
      if (reverse == 1) link(lists[j].other, use);
    }
  }

  void publish(DistanceIndex* out) const {
    out->nodes = Span<const BvhNode>(nodes, node_count);
    out->dipoles = Span<const BvhDipole>(dipoles, dipoles != nullptr ? node_count : 0);
    out->obbs = Span<const BvhObb>(obbs, obbs != nullptr ? node_count : 0);
    out->order = Span<const uint32_t>(order, nt);
    out->triangle_boxes = Span<const float>(tboxes, tboxes != nullptr ? 6 * nt : 0);
    out->neighbors = Span<const uint32_t>(neighbors, neighbors != nullptr ? 3 * nt : 0);
    out->vertex_start = Span<const uint32_t>(start, start != nullptr ? nv + 1 : 0);
    out->vertex_uses = Span<const uint32_t>(vuses, vuses != nullptr ? 3 * nt : 0);
    out->closed_manifold = closed_manifold;
    out->depth = depth;
  }
};

// The body of build_distance_index (below), which undoes it on an error.
Status build_index_steps(const Context& ctx, const Mesh& mesh, const DistanceIndexOptions& options,
                         DistanceIndex* out) {
  out->mesh = &mesh;
  IndexBuild build(*ctx.arena, mesh, options);
  SPLINTCORE_RETURN_IF_ERROR(build.check_input());
  SPLINTCORE_RETURN_IF_ERROR(build.scan_triangles());
  const Arena::Marker tree_temps = ctx.arena->mark();
  SPLINTCORE_RETURN_IF_ERROR(build.morton_order());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "distance index", 1, 4));
  SPLINTCORE_RETURN_IF_ERROR(build.build_topology());
  build.bound_nodes();
  build.move_tree_down(tree_temps);
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "distance index", 2, 4));
  if (with_topology(options)) SPLINTCORE_RETURN_IF_ERROR(build.link_neighbours());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "distance index", 3, 4));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "distance index", 4, 4));
  build.publish(out);
  return Status::ok();
}

}  // namespace

Vec3 vertex_pseudonormal(const DistanceIndex& index, uint32_t vertex) {
  SPLINTCORE_ASSERT(vertex + size_t{1} < index.vertex_start.size());  // pairs_only: no lists
  const Mesh& mesh = *index.mesh;
  const Vec3* v = mesh.vertices.data();
  Vec3 sum{};
  for (uint32_t j = index.vertex_start[vertex]; j < index.vertex_start[vertex + 1]; ++j) {
    const uint32_t use = index.vertex_uses[j];
    const Triangle& tri = mesh.triangles[use / 3];
    const Vec3 normal = cross(v[tri.v[1]] - v[tri.v[0]], v[tri.v[2]] - v[tri.v[0]]);
    const double len = length(normal);
    if (!(len > 0)) continue;
    const Vec3 unit = normal * (1.0 / len);
    // The angles of a triangle sum to pi: two atan2 calls give the third. At every corner the
    // two edges' cross product has the length `len` (twice the area), so only the dot
    // products differ.
    const Vec3 &p0 = v[tri.v[0]], &p1 = v[tri.v[1]], &p2 = v[tri.v[2]];
    const uint32_t k = use % 3;
    double angle;
    if (k == 0) {
      angle = deterministic_atan2(len, dot(p1 - p0, p2 - p0));
    } else if (k == 1) {
      angle = deterministic_atan2(len, dot(p2 - p1, p0 - p1));
    } else {
      const double a0 = deterministic_atan2(len, dot(p1 - p0, p2 - p0));
      const double a1 = deterministic_atan2(len, dot(p2 - p1, p0 - p1));
      angle = 3.14159265358979323846 - a0 - a1;
      angle = angle < 0 ? 0 : angle;
    }
    sum = sum + unit * angle;
  }
  return sum;
}

uint64_t refit_distance_index_bound(const DistanceIndex& index) {
  return arena_array_bound<BvhNode>(index.nodes.size()) +
         arena_array_bound<float>(index.triangle_boxes.size());
}

Status refit_distance_index(const Context& ctx, const DistanceIndex& index, const Mesh& mesh,
                            DistanceIndex* out) {
  *out = DistanceIndex{};
  // Only what the pair queries read: dipoles and oriented boxes would need their own refits.
  SPLINTCORE_ASSERT(index.dipoles.empty() && index.obbs.empty());
  if (index.mesh == nullptr || mesh.triangles.size() != index.mesh->triangles.size()) {
    return make_error(StatusCode::kInvalidArgument, "distance index refit: the mesh has ",
                      mesh.triangles.size(), " triangles, the index's ",
                      index.mesh == nullptr ? 0 : index.mesh->triangles.size());
  }
  DistanceIndexOptions options;
  options.pairs_only = true;
  options.without_triangle_boxes = index.triangle_boxes.empty();
  IndexBuild build(*ctx.arena, mesh, options);
  SPLINTCORE_RETURN_IF_ERROR(build.check_input());
  for (size_t t = 0; t < build.nt; ++t) {
    const Triangle& tri = build.tris[t];
    if (tri.v[0] >= build.nv || tri.v[1] >= build.nv || tri.v[2] >= build.nv) {
      return make_error(StatusCode::kInvalidMesh, "triangle ", t,
                        " refers to a vertex that does not exist")
          .at_index(t);
    }
  }
  ArenaScope entry(*ctx.arena);
  build.n = static_cast<uint32_t>(build.nt);
  build.order = const_cast<uint32_t*>(index.order.data());  // read only (bound_nodes)
  build.node_count = static_cast<uint32_t>(index.nodes.size());
  build.nodes = ctx.arena->allocate_array<BvhNode>(build.node_count);
  if (build.nodes == nullptr) return ctx.arena->exhausted_status();
  std::memcpy(static_cast<void*>(build.nodes), index.nodes.data(),
              size_t{build.node_count} * sizeof(BvhNode));
  if (!index.triangle_boxes.empty()) {
    build.tboxes = ctx.arena->allocate_array<float>(6 * build.nt);
    if (build.nt > 0 && build.tboxes == nullptr) return ctx.arena->exhausted_status();
  }
  build.bound_nodes();
  out->mesh = &mesh;
  build.publish(out);
  out->depth = index.depth;
  entry.commit();
  return Status::ok();
}

Status build_distance_index(const Context& ctx, const Mesh& mesh,
                            const DistanceIndexOptions& options, DistanceIndex* out) {
  *out = DistanceIndex{};
  // On an error nothing stays: the arena goes back to its top at entry, *out is empty.
  ArenaScope entry(*ctx.arena);
  Status s = build_index_steps(ctx, mesh, options, out);
  if (s.is_ok()) {
    entry.commit();
  } else {
    *out = DistanceIndex{};
  }
  return s;
}

}  // namespace splintcore
