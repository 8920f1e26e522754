// Taubin lambda|mu smoothing.
//
// Source: G. Taubin, "A signal processing approach to fair surface design", SIGGRAPH 1995
// (section 4: the lambda|mu algorithm with the umbrella operator and uniform weights; mu < 0
// inflates after each shrinking step so that low frequencies, hence the volume, are kept).
//
// Adjacency: every triangle side becomes an undirected key (min id << 32 | max id); a stable
// radix sort groups them; distinct keys are the edges, a key used once is a boundary edge. The
// CSR lists are filled in key order, so each vertex's neighbours come in increasing id order and
// every sum runs in that order. Steps are Jacobi (read the previous positions, write a second
// buffer; the two alternate, so after each lambda|mu pair the result is back in the mesh), in
// fixed blocks of vertices that an executor may run in any order: each block writes only its
// own vertices and its own counter.
#include "splintcore/remesh.h"

namespace splintcore {

namespace {

constexpr uint32_t kBlockVertices = 4096;

// Adds `count` elements of `size` bytes plus the worst alignment padding to *total.
bool add_alloc(uint64_t* total, uint64_t count, uint64_t size) {
  uint64_t bytes = 0;
  return checked_mul(count, size, &bytes) && checked_add(bytes, 16, &bytes) &&
         checked_add(*total, bytes, total);
}

struct StepJob {
  const uint32_t* offsets;
  const uint32_t* neighbours;
  const uint8_t* fixed;  // boundary vertices that must not move (nullptr: none)
  const Vec3* original;  // positions before smoothing (nullptr: no clamp)
  const Vec3* from;
  Vec3* to;
  double factor;
  double max_displacement;
  uint32_t vertex_count;
  uint64_t* clamped;  // one counter per block
};

void step_block(void* context, uint32_t block) {
  const StepJob& job = *static_cast<const StepJob*>(context);
  const uint32_t begin = block * kBlockVertices;
  const uint32_t end =
      job.vertex_count - begin < kBlockVertices ? job.vertex_count : begin + kBlockVertices;
  const double limit2 = job.max_displacement * job.max_displacement;
  uint64_t clamped = 0;
  for (uint32_t i = begin; i < end; ++i) {
    const Vec3 x = job.from[i];
    const uint32_t first = job.offsets[i], last = job.offsets[i + 1];
    if (first == last || (job.fixed != nullptr && job.fixed[i] != 0)) {
      job.to[i] = x;
      continue;
    }
    Vec3 sum{};
    for (uint32_t k = first; k < last; ++k) sum = sum + (job.from[job.neighbours[k]] - x);
    const double n = static_cast<double>(last - first);
    const Vec3 laplacian{sum.x / n, sum.y / n, sum.z / n};
    Vec3 y = x + laplacian * job.factor;
    if (job.original != nullptr) {
      const Vec3 d = y - job.original[i];
      const double d2 = dot(d, d);
      if (d2 > limit2) {
        y = job.original[i] + d * (job.max_displacement / std::sqrt(d2));
        ++clamped;
      }
    }
    job.to[i] = y;
  }
  job.clamped[block] += clamped;
}

// The checks of taubin_smooth's arguments (no memory needed).
Status check_taubin_input(const Mesh& mesh, const TaubinOptions& options) {
  if (!is_finite(options.lambda) || !(options.lambda > 0.0) || !(options.lambda <= 1.0)) {
    return make_error(StatusCode::kInvalidArgument, "taubin_smooth: lambda must be in (0, 1], not ",
                      options.lambda);
  }
  if (!is_finite(options.mu) || !(options.mu >= -1.0) || !(options.mu <= 0.0)) {
    return make_error(StatusCode::kInvalidArgument, "taubin_smooth: mu must be in [-1, 0], not ",
                      options.mu);
  }
  if (!is_finite(options.max_displacement) || !(options.max_displacement >= 0.0)) {
    return make_error(StatusCode::kInvalidArgument,
                      "taubin_smooth: max_displacement must be a finite distance >= 0 mm, not ",
                      options.max_displacement);
  }
  const uint64_t nv64 = mesh.vertices.size(), nt64 = mesh.triangles.size();
  if (nv64 > UINT32_MAX - 1 || nt64 > (uint64_t{1} << 30)) {
    return make_error(StatusCode::kLimitExceeded, "taubin_smooth: mesh too large: ", nt64,
                      " triangles, ", nv64, " vertices (at most 2^30 and 2^32 - 2)");
  }
  const uint32_t nv = static_cast<uint32_t>(nv64), nt = static_cast<uint32_t>(nt64);
  const Triangle* tris = mesh.triangles.data();
  const Vec3* verts = mesh.vertices.data();
  for (uint32_t t = 0; t < nt; ++t) {
    for (uint32_t k : tris[t].v) {
      if (k >= nv) {
        return make_error(StatusCode::kInvalidMesh, "taubin_smooth: triangle ", t,
                          " refers to vertex ", k, " but the mesh has ", nv, " vertices")
            .at_index(t);
      }
    }
  }
  for (uint32_t i = 0; i < nv; ++i) {
    if (!is_finite(verts[i])) {
      return make_error(StatusCode::kNonFinite, "taubin_smooth: vertex ", i,
                        " has a coordinate that is NaN or infinite")
          .at_index(i);
    }
  }
  return Status::ok();
}

// The mesh's edges as CSR lists: the neighbours of vertex i are neighbours[offsets[i] ..
// offsets[i + 1]), in increasing id order; fixed[i] is 1 on the boundary.
struct Adjacency {
  uint8_t* fixed = nullptr;
  uint32_t* offsets = nullptr;
  uint32_t* neighbours = nullptr;
  uint32_t edges = 0;
};

// Undirected edge keys of the triangles' sides, sorted (the sort's scratch goes back right
// after it): *keys holds *key_count of them, room for 3 nt.
Status sorted_edge_keys(Arena& arena, const Triangle* tris, uint32_t nt, uint64_t** keys_out,
                        uint32_t* key_count) {
  const uint32_t uses = 3 * nt;
  uint64_t* keys = arena.allocate_array<uint64_t>(uses);
  if (keys == nullptr) return arena.exhausted_status();
  uint32_t count = 0;
  for (uint32_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t].v[k], b = tris[t].v[(k + 1) % 3];
      if (a == b) continue;  // a repeated id is no edge
      keys[count++] = a < b ? (uint64_t{a} << 32) | b : (uint64_t{b} << 32) | a;
    }
  }
  {
    ArenaScope scratch_scope(arena);
    uint64_t* scratch = arena.allocate_array<uint64_t>(uses);
    if (scratch == nullptr) return arena.exhausted_status();
    radix_sort(Span<uint64_t>(keys, count), Span<uint64_t>(scratch, count));
  }
  *keys_out = keys;
  *key_count = count;
  return Status::ok();
}

// The adjacency of a mesh of nv vertices: distinct keys are the edges, a key used once is a
// boundary edge. Filled in key order, so each list comes out in increasing neighbour id.
Status build_adjacency(Arena& arena, const Triangle* tris, uint32_t nt, uint32_t nv,
                       Adjacency* adj) {
  uint64_t* keys = nullptr;
  uint32_t key_count = 0;
  SPLINTCORE_RETURN_IF_ERROR(sorted_edge_keys(arena, tris, nt, &keys, &key_count));
  uint8_t* fixed = arena.allocate_array<uint8_t>(nv);
  uint32_t* offsets = arena.allocate_array<uint32_t>(size_t{nv} + 1);
  if (fixed == nullptr || offsets == nullptr) return arena.exhausted_status();
  std::memset(fixed, 0, nv);
  std::memset(offsets, 0, (size_t{nv} + 1) * sizeof(uint32_t));
  // Distinct edges in place; boundary vertices; degrees.
  uint32_t edges = 0;
  for (uint32_t i = 0; i < key_count;) {
    uint32_t j = i + 1;
    while (j < key_count && keys[j] == keys[i]) ++j;
    const uint32_t a = static_cast<uint32_t>(keys[i] >> 32), b = static_cast<uint32_t>(keys[i]);
    if (j - i == 1) fixed[a] = fixed[b] = 1;
    ++offsets[a + 1];
    ++offsets[b + 1];
    keys[edges++] = keys[i];
    i = j;
  }
  for (uint32_t i = 0; i < nv; ++i) offsets[i + 1] += offsets[i];
  uint32_t* neighbours = arena.allocate_array<uint32_t>(size_t{2} * edges);
  if (neighbours == nullptr) return arena.exhausted_status();
  for (uint32_t e = 0; e < edges; ++e) {
    const uint32_t a = static_cast<uint32_t>(keys[e] >> 32), b = static_cast<uint32_t>(keys[e]);
    neighbours[offsets[a]++] = b;
    neighbours[offsets[b]++] = a;
  }
  for (uint32_t i = nv; i > 0; --i) offsets[i] = offsets[i - 1];
  offsets[0] = 0;
  adj->fixed = fixed;
  adj->offsets = offsets;
  adj->neighbours = neighbours;
  adj->edges = edges;
  return Status::ok();
}

}  // namespace

uint64_t taubin_smooth_bound(uint64_t vertex_count, uint64_t triangle_count) {
  uint64_t keys = 0, sorting = 0, adjacency = 0, uses = 0, blocks = 0;
  if (!checked_mul(triangle_count, 3, &uses) || !add_alloc(&keys, uses, 8) ||
      !add_alloc(&sorting, uses, 8)) {
    return 0;
  }
  blocks = vertex_count / kBlockVertices + 1;
  if (!add_alloc(&adjacency, vertex_count, 1) ||             // boundary flags
      !add_alloc(&adjacency, vertex_count + 1, 4) ||         // offsets
      !add_alloc(&adjacency, uses, 8) ||                     // neighbours: 2 E <= 6 T
      !add_alloc(&adjacency, vertex_count, sizeof(Vec3)) ||  // Jacobi buffer
      !add_alloc(&adjacency, vertex_count, sizeof(Vec3)) ||  // positions before smoothing
      !add_alloc(&adjacency, blocks, 8)) {                   // clamp counters
    return 0;
  }
  uint64_t total = 0;
  return checked_add(keys, sorting > adjacency ? sorting : adjacency, &total) ? total : 0;
}

Status taubin_smooth(const Context& ctx, Mesh* mesh, const TaubinOptions& options,
                     TaubinStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && mesh != nullptr);
  SPLINTCORE_RETURN_IF_ERROR(check_taubin_input(*mesh, options));
  const uint32_t nv = static_cast<uint32_t>(mesh->vertices.size());
  const uint32_t nt = static_cast<uint32_t>(mesh->triangles.size());
  Vec3* verts = mesh->vertices.data();
  TaubinStats local;
  local.volume_before = mesh_volume(*mesh);
  local.volume_after = local.volume_before;
  if (stats != nullptr) *stats = local;
  if (nt == 0 || nv == 0) return Status::ok();

  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  Adjacency adj;
  SPLINTCORE_RETURN_IF_ERROR(build_adjacency(arena, mesh->triangles.data(), nt, nv, &adj));
  for (uint32_t i = 0; i < nv; ++i) local.boundary_vertices += adj.fixed[i];
  local.edges = adj.edges;

  Vec3* buffer = arena.allocate_array<Vec3>(nv);
  Vec3* original = nullptr;
  if (options.max_displacement > 0.0) original = arena.allocate_array<Vec3>(nv);
  const uint32_t blocks = (nv + kBlockVertices - 1) / kBlockVertices;
  uint64_t* clamped = arena.allocate_array<uint64_t>(blocks);
  if (buffer == nullptr || clamped == nullptr ||
      (options.max_displacement > 0.0 && original == nullptr)) {
    return arena.exhausted_status();
  }
  if (original != nullptr) std::memcpy(static_cast<void*>(original), verts, nv * sizeof(Vec3));
  std::memset(clamped, 0, blocks * sizeof(uint64_t));

  StepJob job{adj.offsets,
              adj.neighbours,
              options.fix_boundary ? adj.fixed : nullptr,
              original,
              verts,
              buffer,
              options.lambda,
              options.max_displacement,
              nv,
              clamped};
  for (uint32_t it = 0; it < options.iterations; ++it) {
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "taubin smooth", it, options.iterations));
    job.from = verts;
    job.to = buffer;
    job.factor = options.lambda;
    parallel_for(ctx.executor, blocks, step_block, &job);
    job.from = buffer;
    job.to = verts;
    job.factor = options.mu;
    parallel_for(ctx.executor, blocks, step_block, &job);
  }
  for (uint32_t b = 0; b < blocks; ++b) local.clamped += clamped[b];
  local.volume_after = mesh_volume(*mesh);
  if (stats != nullptr) *stats = local;
  return report_progress(ctx, "taubin smooth", options.iterations, options.iterations);
}

}  // namespace splintcore
