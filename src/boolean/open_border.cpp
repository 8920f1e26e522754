// An open B (a scan) refused up front when its border meets A (issue 30). The Boolean takes an
// open B when B's border lies outside A (boolean.h): then the part of B inside A is bounded by
// the intersection curve alone and the result is closed. When the border crosses A's surface
// or lies inside A, the classification finds pieces of B with no consistent side and used to
// answer "inconsistent inside/outside classification (overlapping shells in B, ...)", which
// never said that B was open. This check says it first, and where.
//
// Only B's edges whose boxes meet A's region can matter, and every triangle using such an edge
// meets the region too, so the boundary edges there are found among the near triangles alone
// (per-vertex outcodes against the region): their sides as (smaller id, larger id) keys,
// radix-sorted, a key seen once being a boundary edge; a closed B is passed by a fingerprint
// (the XOR of the keys' hashes, zero when every edge is used twice) without the sort. Each such
// edge is then tested against A exactly (segment_intersects_mesh, orient3d based) and, when it does
// not meet A's surface, by the winding number of A at one end (the whole edge is then on one side
// of A's closed surface).
#include "boolean/boolean_internal.h"
#include "splintcore/distance.h"

namespace splintcore {

namespace {

// The sides of B's triangles [begin, end) whose edges meet the region, as (smaller id << 32 |
// larger id), into keys (kList); their count, and the XOR of their hashes.
template <bool kList>
size_t near_edges(const Mesh& b, size_t begin, size_t end, const uint8_t* code, uint64_t* keys,
                  uint64_t* fingerprint) {
  size_t n = 0;
  for (size_t t = begin; t < end; ++t) {
    const Triangle& tri = b.triangles[t];
    if ((code[tri.v[0]] & code[tri.v[1]] & code[tri.v[2]]) != 0) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t p = tri.v[k], q = tri.v[(k + 1) % 3];
      if (p == q || (code[p] & code[q]) != 0) continue;
      const uint32_t lo = p < q ? p : q;  // (a select, not a branch: p < q is a coin toss)
      const uint64_t key = uint64_t{lo} << 32 | (p ^ q ^ lo);
      if (kList) keys[n] = key;
      *fingerprint ^= hash_mix(key);
      ++n;
    }
  }
  return n;
}

// B's vertices' outcodes, and its triangles' near edges, in ranges run on the executor (the
// real dentition's 192k triangles: 27M instructions on one thread). count() takes each range's
// count and fingerprint; their XOR is one pass's fingerprint. list() then writes each range's
// keys after the earlier ranges' (the order of one pass).
class NearEdges {
 public:
  NearEdges(const Executor* executor, const Mesh& b, uint8_t* code)
      : executor_(executor), b_(b), code_(code) {}

  void outcodes(const Aabb& region) {
    const Vec3* v = b_.vertices.data();
    const size_t nv = b_.vertices.size();
    uint8_t* code = code_;  // (a local: a byte stored through a member could alias the member)
    auto task = [v, nv, code, &region](uint32_t i) {
      for (size_t k = part(nv, i); k < part(nv, i + 1); ++k) code[k] = region.outcode(v[k]);
    };
    parallel_for_each(executor_, kRanges, task);
  }
  // The near edges' count; their fingerprint in *fingerprint.
  size_t count(uint64_t* fingerprint) {
    run(nullptr);
    size_t n = 0;
    *fingerprint = 0;
    for (uint32_t i = 0; i < kRanges; ++i) {
      start_[i] = n;
      n += count_[i];
      *fingerprint ^= fingerprint_[i];
    }
    return n;
  }
  void list(uint64_t* keys) { run(keys); }

 private:
  static constexpr uint32_t kRanges = 8;
  static size_t part(size_t n, uint32_t i) { return task_start(n, i, kRanges); }
  void run(uint64_t* keys) {
    const size_t nt = b_.triangles.size();
    auto task = [&](uint32_t i) {
      uint64_t f = 0;
      count_[i] =
          keys != nullptr
              ? near_edges<true>(b_, part(nt, i), part(nt, i + 1), code_, keys + start_[i], &f)
              : near_edges<false>(b_, part(nt, i), part(nt, i + 1), code_, nullptr, &f);
      fingerprint_[i] = f;
    };
    parallel_for_each(executor_, kRanges, task);
  }

  const Executor* executor_;
  const Mesh& b_;
  uint8_t* code_;
  size_t count_[kRanges] = {}, start_[kRanges] = {};
  uint64_t fingerprint_[kRanges] = {};
};

// The vertex of B where its border meets A first (in key order), or kNoTriangle when none does.
uint32_t first_border_vertex_in_a(const DistanceIndex& index, const Mesh& b, const uint64_t* keys,
                                  size_t n) {
  for (size_t i = 0; i < n; ++i) {
    if ((i > 0 && keys[i] == keys[i - 1]) || (i + 1 < n && keys[i] == keys[i + 1])) continue;
    const uint32_t lo = static_cast<uint32_t>(keys[i] >> 32), hi = static_cast<uint32_t>(keys[i]);
    const Vec3 &p = b.vertices[lo], &q = b.vertices[hi];
    uint32_t hit = 0;
    if (segment_intersects_mesh(index, p, q, &hit)) return lo;
    if (winding_number(index, p) >= 0.5) return lo;
  }
  return kNoTriangle;
}

}  // namespace

Status refuse_open_border_in_a(const Context& ctx, const Mesh& a, const Mesh& b, const Aabb& region,
                               bool b_valid) {
  Arena& arena = *ctx.arena;
  const uint32_t nv = static_cast<uint32_t>(b.vertices.size());
  const Vec3* vb = b.vertices.data();
  if (!b_valid) {
    for (const Triangle& tri : b.triangles) {
      if (tri.v[0] >= nv || tri.v[1] >= nv || tri.v[2] >= nv) return Status::ok();  // named later
    }
    for (uint32_t v = 0; v < nv; ++v) {
      if (!is_finite(vb[v])) return Status::ok();  // the run names it (kNonFinite)
    }
  }
  ArenaScope scope(arena);
  uint8_t* code = arena.allocate_array<uint8_t>(nv);
  if (code == nullptr && nv > 0) return arena.exhausted_status();
  NearEdges edges(ctx.executor, b, code);
  edges.outcodes(region);
  // A closed B (the usual case) uses every edge twice, so the XOR of its edges' hashes is 0:
  // only a non-zero fingerprint pays for the sort that finds the edges used once. (An open B
  // whose fingerprint is 0 by chance, about 2^-64, gets the run's own message, as before.)
  uint64_t fingerprint = 0;
  const size_t n = edges.count(&fingerprint);
  if (fingerprint == 0) return Status::ok();
  uint64_t* keys = arena.allocate_array<uint64_t>(n);
  uint64_t* scratch = arena.allocate_array<uint64_t>(n);
  if (keys == nullptr || scratch == nullptr) return arena.exhausted_status();
  edges.list(keys);
  radix_sort_bits(Span<uint64_t>(keys, n), Span<uint64_t>(scratch, n), 0, 64);
  bool open_near = false;
  for (size_t i = 0; i < n && !open_near; ++i) {
    open_near = (i == 0 || keys[i] != keys[i - 1]) && (i + 1 == n || keys[i] != keys[i + 1]);
  }
  if (!open_near) return Status::ok();
  // A that is not a solid is the run's error to name ("A must be a solid"): its winding
  // number would mean nothing here.
  if (!check_closed_oriented(ctx, a, nullptr).is_ok()) {
    arena.forget_failure();
    return Status::ok();
  }
  DistanceIndex index;
  const Status built = build_distance_index(ctx, a, DistanceIndexOptions{}, &index);
  if (built.code() == StatusCode::kArenaExhausted || built.code() == StatusCode::kCancelled) {
    return built;
  }
  if (!built.is_ok()) return Status::ok();  // A not finite: the run names it
  const uint32_t v = first_border_vertex_in_a(index, b, keys, n);
  if (v == kNoTriangle) return Status::ok();
  // The whole border, for the message (its loops); what the check cannot afford is left out.
  arena.rewind(scope.start());
  MeshReport r;
  const bool counted = check_mesh(ctx, b, &r).is_ok();
  if (!counted) arena.forget_failure();
  // To the micrometre: a Status holds 256 bytes, and callers append where (design: the jaw).
  auto um = [](double x) {
    return static_cast<double>(static_cast<int64_t>(x * 1000 + (x < 0 ? -0.5 : 0.5))) / 1000;
  };
  const Vec3& p = b.vertices[v];
  Status e = make_error(StatusCode::kInvalidMesh, "B is open");
  if (counted) {
    e = make_error(StatusCode::kInvalidMesh, "B is open: ", r.boundary_edges, " boundary edges in ",
                   r.boundary_loops, r.boundary_loops == 1 ? " loop" : " loops");
  }
  return make_error(StatusCode::kInvalidMesh, e.message(), "; its border meets A at vertex ", v,
                    " (", um(p.x), ", ", um(p.y), ", ", um(p.z),
                    "): fill it (splintcore prepare --max-hole-edges N) or use a larger scan")
      .at_index(v);
}

}  // namespace splintcore
