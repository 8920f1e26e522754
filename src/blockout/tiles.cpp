// The swept surface decimated tile by tile in the stream (tiles.h). Decimation: Garland and
// Heckbert's quadric error metric (remesh.h, decimate_qem) on each tile as an open patch with
// its border kept, half-edge collapses only; the tiles overlap as in M. Isenburg, P.
// Lindstrom, S. Gumhold and J. Snoeyink, "Large mesh simplification using processing
// sequences", IEEE Visualization 2003: what lies near a tile's top is carried into the next
// tile, and only the part below is final.
#include "blockout/tiles.h"

#include <cstring>

namespace splintcore {

namespace {

constexpr uint32_t kGone = ~uint32_t{0};

inline uint64_t round8(uint64_t n) { return (n + 7) & ~uint64_t{7}; }

// A part of the log as an array of T: the log is 8-byte aligned and every part starts at a
// multiple of 8 from it (round8), so the cast keeps T's alignment (through void*: the compiler
// cannot see that, and -Wcast-align is an error on 32-bit ARM).
template <typename T>
T* part(uint8_t* p) {
  return static_cast<T*>(static_cast<void*>(p));
}
template <typename T>
const T* part(const uint8_t* p) {
  return static_cast<const T*>(static_cast<const void*>(p));
}

// A chunk of the log: two 64-bit counts (vertices, triangles), the vertices (24 bytes each)
// and the triangles (12 bytes, then padding to 8).
uint64_t chunk_bytes(uint64_t nv, uint64_t nt) { return 16 + 24 * nv + round8(12 * nt); }

// The carry: four 32-bit counts (vertices, triangles, map entries, samples), positions (24
// bytes), w (8), output ids (4), beyond flags (1), triangles (12), map (4), the samples'
// positions (24) and triangles (4), each part padded to 8.
uint64_t carry_bytes(uint64_t nv, uint64_t nt, uint64_t nm, uint64_t ns) {
  return 16 + 24 * nv + 8 * nv + round8(4 * nv) + round8(nv) + round8(12 * nt) + round8(4 * nm) +
         24 * ns + round8(4 * ns);
}

bool beyond(const TileDecimator& d, const Vec3& p) {
  return p.x < d.lo.x || p.y < d.lo.y || p.z < d.lo.z || p.x > d.hi.x || p.y > d.hi.y ||
         p.z > d.hi.z;
}

void bind_current(TileDecimator& d) {
  Arena& arena = *d.ctx->arena;
  d.cur_pos.bind(&arena);
  d.cur_w.bind(&arena);
  d.cur_beyond.bind(&arena);
  d.cur_tris.bind(&arena);
}

void start(TileDecimator& d) {
  if (d.started) return;
  d.started = true;
  d.base = d.ctx->arena->mark();
  bind_current(d);
}

Status on_vertex(void* user, uint32_t id, const Vec3& p) {
  TileDecimator& d = *static_cast<TileDecimator*>(user);
  start(d);
  SPLINTCORE_ASSERT(id == d.cur_first + d.cur_pos.size());
  Vec3 w = d.world(d.frame, p);
  if (d.float32 && !round_to_float32(&w)) {
    return make_error(StatusCode::kLimitExceeded,
                      "sweep: a vertex of the swept volume is beyond float32 range")
        .at_index(id);
  }
  if (!d.cur_pos.push_back(w) || !d.cur_w.push_back(p.z) ||
      !d.cur_beyond.push_back(beyond(d, p) ? 1 : 0)) {
    return d.ctx->arena->exhausted_status();
  }
  return Status::ok();
}

Status on_triangle(void* user, const Triangle& t, const Vec3& a, const Vec3& b, const Vec3& c) {
  TileDecimator& d = *static_cast<TileDecimator*>(user);
  start(d);
  ++d.input_triangles;
  if (d.drop_caps && beyond(d, a) && beyond(d, b) && beyond(d, c)) {
    ++d.caps_dropped;
    return Status::ok();
  }
  if (!d.cur_tris.push_back(t)) return d.ctx->arena->exhausted_status();
  return Status::ok();
}

// The tile as an indexed patch: the carried vertices and triangles first, then the new
// vertices (extractor id - cur_first) and triangles. Per vertex: w, output id, locked.
struct Patch {
  Mesh mesh;
  double* w = nullptr;
  uint32_t* out = nullptr;
  uint8_t* locked = nullptr;
};

Status assemble(TileDecimator& d, Patch* p) {
  Arena& arena = *d.ctx->arena;
  const uint32_t nc = d.carried_vertices, n_new = static_cast<uint32_t>(d.cur_pos.size());
  const size_t nv = size_t{nc} + n_new, nt = size_t{d.carried_triangles} + d.cur_tris.size();
  p->mesh.bind(&arena);
  p->w = arena.allocate_array<double>(nv);
  p->out = arena.allocate_array<uint32_t>(nv);
  p->locked = arena.allocate_array<uint8_t>(nv);
  if (!p->mesh.vertices.resize(nv) || !p->mesh.triangles.resize(nt) ||
      (nv > 0 && (p->w == nullptr || p->out == nullptr || p->locked == nullptr))) {
    return arena.exhausted_status();
  }
  for (uint32_t i = 0; i < nc; ++i) {
    p->mesh.vertices[i] = d.c_pos[i];
    p->w[i] = d.c_w[i];
    p->out[i] = d.c_out[i];
    // On the seam with what is final (an output id), or a cap's: stays.
    p->locked[i] = d.c_out[i] != kGone || d.c_beyond[i] != 0 ? 1 : 0;
  }
  for (uint32_t j = 0; j < n_new; ++j) {
    p->mesh.vertices[nc + j] = d.cur_pos[j];
    p->w[nc + j] = d.cur_w[j];
    p->out[nc + j] = kGone;
    p->locked[nc + j] = d.cur_beyond[j];
  }
  for (uint32_t t = 0; t < d.carried_triangles; ++t) p->mesh.triangles[t] = d.c_tris[t];
  for (size_t t = 0; t < d.cur_tris.size(); ++t) {
    Triangle local;
    for (int k = 0; k < 3; ++k) {
      const uint32_t id = d.cur_tris[t].v[k];
      if (id >= d.cur_first) {
        local.v[k] = nc + (id - d.cur_first);
        continue;
      }
      // Only the tile just before shares vertices with this one (on the plane between them),
      // and it carried every triangle that touches that plane.
      SPLINTCORE_ASSERT(id >= d.prev_first && id - d.prev_first < d.prev_count);
      local.v[k] = d.prev_map[id - d.prev_first];
      SPLINTCORE_ASSERT(local.v[k] != kGone);
    }
    p->mesh.triangles[d.carried_triangles + t] = local;
  }
  return Status::ok();
}

// The log without the old carry, then `block` (the new chunk and carry), down to `base`; false
// when an arena of blocks could not give the room (in buffer mode it is no more than was there).
bool move_down(TileDecimator& d, const uint8_t* block, uint64_t block_bytes) {
  Arena& arena = *d.ctx->arena;
  const uint64_t keep = d.log_bytes - d.carry_bytes;
  const uint8_t* old_log = d.log;
  arena.rewind(d.base);
  uint8_t* log = static_cast<uint8_t*>(arena.allocate(static_cast<size_t>(keep + block_bytes), 8));
  if (log == nullptr) return false;
  if (keep > 0 && log != old_log) std::memmove(log, old_log, static_cast<size_t>(keep));
  std::memmove(log + keep, block, static_cast<size_t>(block_bytes));
  d.log = log;
  d.log_bytes = keep + block_bytes;
  return true;
}

// Points the carry's arrays into the log (its last carry_bytes).
void read_carry(TileDecimator& d) {
  const uint8_t* c = d.log + d.log_bytes - d.carry_bytes;
  uint32_t counts[4];
  std::memcpy(counts, c, sizeof(counts));
  const uint64_t nv = counts[0], nt = counts[1], nm = counts[2];
  d.carried_vertices = counts[0];
  d.carried_triangles = counts[1];
  d.prev_count = counts[2];
  d.carried_samples = counts[3];
  c += 16;
  d.c_pos = part<Vec3>(c);
  c += 24 * nv;
  d.c_w = part<double>(c);
  c += 8 * nv;
  d.c_out = part<uint32_t>(c);
  c += round8(4 * nv);
  d.c_beyond = c;
  c += round8(nv);
  d.c_tris = part<Triangle>(c);
  c += round8(12 * nt);
  d.prev_map = part<uint32_t>(c);
  c += round8(4 * nm);
  d.c_samples = part<Vec3>(c);
  c += 24 * uint64_t{d.carried_samples};
  d.c_sample_tri = part<uint32_t>(c);
}

// The pieces of a decimated tile the carry is written from.
struct CarryParts {
  const Patch* p;
  const Mesh* dec;
  const uint32_t* source;    // dec vertex -> patch vertex
  const uint32_t* carry_id;  // dec vertex -> carried vertex (~0u: not carried)
  const uint8_t* carried;    // per dec triangle
  const uint32_t* vmap;      // patch vertex -> dec vertex
  uint32_t next_nc, next_nt, n_new, nc;
  // max_distance: the dec triangle of each carried sample and each removed patch vertex (~0u:
  // stays), the carried index of each dec triangle, and how many samples the carry gets.
  const uint32_t* sample_map;
  const uint32_t* removed_map;
  const uint32_t* carried_index;
  uint32_t next_ns;
};

// Writes the carry (layout: carry_bytes) at c.
void write_carry(const TileDecimator& d, const CarryParts& cp, uint8_t* c) {
  const Patch& p = *cp.p;
  const Mesh& dec = *cp.dec;
  const uint32_t* source = cp.source;
  const uint32_t* carry_id = cp.carry_id;
  const uint32_t next_nc = cp.next_nc, next_nt = cp.next_nt, n_new = cp.n_new, nc = cp.nc;
  const size_t dv = dec.vertices.size(), dt = dec.triangles.size();
  const uint32_t counts[4] = {next_nc, next_nt, n_new, cp.next_ns};
  std::memcpy(c, counts, sizeof(counts));
  Vec3* pos = part<Vec3>(c + 16);
  double* w = part<double>(c + 16 + 24 * uint64_t{next_nc});
  uint32_t* out = part<uint32_t>(reinterpret_cast<uint8_t*>(w) + 8 * next_nc);
  uint8_t* bey = reinterpret_cast<uint8_t*>(out) + round8(4 * uint64_t{next_nc});
  Triangle* tris = part<Triangle>(bey + round8(next_nc));
  uint32_t* map = part<uint32_t>(reinterpret_cast<uint8_t*>(tris) + round8(12 * uint64_t{next_nt}));
  for (size_t i = 0; i < dv; ++i) {
    const uint32_t ci = carry_id[i];
    if (ci == kGone) continue;
    const uint32_t s = source[i];
    pos[ci] = p.mesh.vertices[s];
    w[ci] = p.w[s];
    out[ci] = p.out[s];
    bey[ci] = s >= nc ? d.cur_beyond[s - nc] : d.c_beyond[s];
  }
  uint32_t at = 0;
  for (size_t t = 0; t < dt; ++t) {
    if (cp.carried[t] == 0) continue;
    const uint32_t* v = dec.triangles[t].v;
    tris[at++] = Triangle{{carry_id[v[0]], carry_id[v[1]], carry_id[v[2]]}};
  }
  for (uint32_t j = 0; j < n_new; ++j) {
    const uint32_t m = cp.vmap[nc + j];
    map[j] = m == kGone ? kGone : carry_id[m];
  }
  if (cp.next_ns == 0) return;
  // The samples of the carried triangles: the old carry's, then the removed vertices, in order.
  Vec3* spos = part<Vec3>(reinterpret_cast<uint8_t*>(map) + round8(4 * uint64_t{n_new}));
  uint32_t* stri = part<uint32_t>(reinterpret_cast<uint8_t*>(spos) + 24 * uint64_t{cp.next_ns});
  uint32_t at_s = 0;
  for (uint32_t i = 0; i < d.given_count; ++i) {
    const uint32_t t = cp.sample_map[i];
    if (cp.carried[t] == 0) continue;
    spos[at_s] = d.given_pos[i];
    stri[at_s++] = cp.carried_index[t];
  }
  for (size_t i = 0; i < p.mesh.vertices.size(); ++i) {
    const uint32_t t = cp.removed_map[i];
    if (t == kGone || cp.carried[t] == 0) continue;
    spos[at_s] = p.mesh.vertices[i];
    stri[at_s++] = cp.carried_index[t];
  }
  SPLINTCORE_ASSERT(at_s == cp.next_ns);
}

// The tile's given samples (TileDecimator::given_*), in the arena: the carried ones (the
// carried triangles are the patch's first, assemble: the same indices), then per new triangle
// the midpoints of its sides that run from the smaller id, then its centroid.
Status gather_given(TileDecimator& d, const Patch& p) {
  Arena& arena = *d.ctx->arena;
  const size_t nt = p.mesh.triangles.size();
  uint64_t count = d.carried_samples;
  for (size_t t = d.carried_triangles; t < nt; ++t) {
    const uint32_t* v = p.mesh.triangles[t].v;
    count += 1u + (v[0] < v[1] ? 1u : 0u) + (v[1] < v[2] ? 1u : 0u) + (v[2] < v[0] ? 1u : 0u);
  }
  if (count > UINT32_MAX / 2) {
    return make_error(StatusCode::kLimitExceeded, "sweep: a tile has ", count, " samples");
  }
  Vec3* pos = arena.allocate_array<Vec3>(static_cast<size_t>(count));
  uint32_t* tri = arena.allocate_array<uint32_t>(static_cast<size_t>(count));
  uint32_t* source = arena.allocate_array<uint32_t>(static_cast<size_t>(count));
  if (count > 0 && (pos == nullptr || tri == nullptr || source == nullptr)) {
    return arena.exhausted_status();
  }
  uint32_t at = 0;
  for (uint32_t i = 0; i < d.carried_samples; ++i, ++at) {
    pos[at] = d.c_samples[i];
    tri[at] = d.c_sample_tri[i];
    source[at] = kGone;  // on a triangle of an earlier tile
  }
  const Vec3* x = p.mesh.vertices.data();
  for (size_t t = d.carried_triangles; t < nt; ++t) {
    const uint32_t* v = p.mesh.triangles[t].v;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = v[k], b = v[(k + 1) % 3];
      if (a >= b) continue;
      pos[at] = (x[a] + x[b]) * 0.5;
      source[at] = static_cast<uint32_t>(t);
      tri[at++] = static_cast<uint32_t>(t);
    }
    pos[at] = (x[v[0]] + x[v[1]] + x[v[2]]) * (1.0 / 3.0);
    source[at] = static_cast<uint32_t>(t);
    tri[at++] = static_cast<uint32_t>(t);
  }
  d.given_count = at;
  d.given_pos = pos;
  d.given_tri = tri;
  d.given_source = source;
  return Status::ok();
}

// Decimates the tile's patch into *dec, with the maps it gives: *vmap (patch vertex -> dec
// vertex) and, with max_distance, *sample_map (carried sample -> dec triangle) and
// *removed_map (patch vertex -> dec triangle, ~0u when it stays), all in the arena below dec.
Status decimate_tile(TileDecimator& d, const Patch& p, uint32_t** vmap, uint32_t** sample_map,
                     uint32_t** removed_map, Mesh* dec) {
  Arena& arena = *d.ctx->arena;
  const size_t nv = p.mesh.vertices.size();
  *vmap = arena.allocate_array<uint32_t>(nv);
  if (nv > 0 && *vmap == nullptr) return arena.exhausted_status();
  DecimateOptions o;
  o.max_error = d.max_error;
  o.allow_boundary = true;
  o.keep_positions = true;
  o.locked = Span<const uint8_t>(p.locked, nv);
  o.vertex_map = Span<uint32_t>(*vmap, nv);
  if (d.max_distance > 0) {
    SPLINTCORE_RETURN_IF_ERROR(gather_given(d, p));
    const uint32_t ns = d.given_count;
    *sample_map = arena.allocate_array<uint32_t>(ns);
    *removed_map = arena.allocate_array<uint32_t>(nv);
    if ((ns > 0 && *sample_map == nullptr) || (nv > 0 && *removed_map == nullptr)) {
      return arena.exhausted_status();
    }
    o.max_distance = d.max_distance;
    o.samples = Span<const Vec3>(d.given_pos, ns);
    o.sample_triangles = Span<const uint32_t>(d.given_tri, ns);
    o.sample_sources = Span<const uint32_t>(d.given_source, ns);
    // The carried triangles (the patch's first) are an earlier tile's result.
    const size_t nt = p.mesh.triangles.size();
    uint8_t* approximate = arena.allocate_array<uint8_t>(nt);
    if (nt > 0 && approximate == nullptr) return arena.exhausted_status();
    for (size_t t = 0; t < nt; ++t) approximate[t] = t < d.carried_triangles ? 1 : 0;
    o.approximate = Span<const uint8_t>(approximate, nt);
    o.sample_map = Span<uint32_t>(*sample_map, ns);
    o.removed_map = Span<uint32_t>(*removed_map, nv);
  }
  const Context quiet(d.ctx->arena, d.ctx->executor, nullptr);
  DecimateStats ds;
  SPLINTCORE_RETURN_IF_ERROR(decimate_qem(quiet, p.mesh, o, dec, &ds));
  if (ds.max_error > d.max_collapse_error) d.max_collapse_error = ds.max_error;
  return Status::ok();
}

// What a tile's decimated triangles become: emitted (and their vertices, counted in p.out
// without numbers) or carried, a triangle that reaches the top kCarryLayers cell layers above
// w_cut (none after the last tile); carried ones and their vertices numbered for the carry.
struct CarryCount {
  uint64_t emitted_v = 0, emitted_t = 0;
  uint32_t next_nc = 0, next_nt = 0;  // the carry's vertices and triangles
};

CarryCount mark_carried(Patch& p, const Mesh& dec, const uint32_t* source, bool last, double w_cut,
                        uint32_t* carry_id, uint8_t* carried, uint32_t* carried_index) {
  const bool sampled = carried_index != nullptr;
  CarryCount c;
  for (size_t t = 0; t < dec.triangles.size(); ++t) {
    const uint32_t* v = dec.triangles[t].v;
    bool top = false;
    for (int k = 0; k < 3; ++k) top = top || (!last && p.w[source[v[k]]] >= w_cut);
    carried[t] = top ? 1 : 0;
    if (sampled) carried_index[t] = top ? c.next_nt : kGone;
    if (top) {
      ++c.next_nt;
      for (int k = 0; k < 3; ++k) {
        if (carry_id[v[k]] == kGone) carry_id[v[k]] = c.next_nc++;
      }
    } else {
      ++c.emitted_t;
      for (int k = 0; k < 3; ++k) {
        uint32_t& o_id = p.out[source[v[k]]];
        if (o_id == kGone) {
          o_id = kGone - 1;  // counted; numbered below
          ++c.emitted_v;
        }
      }
    }
  }
  for (size_t i = 0; i < dec.vertices.size(); ++i) {
    if (p.out[source[i]] == kGone - 1) p.out[source[i]] = kGone;
  }
  return c;
}

// The tile's final part, in order, with its vertices by first use: streamed to d.out, or
// (logging: d.out null) written into `block` after its {vertices, triangles} header.
Status emit_final_part(TileDecimator& d, Patch& p, const Mesh& dec, const uint32_t* source,
                       const uint8_t* carried, uint64_t emitted_v, uint64_t emitted_t,
                       uint8_t* block) {
  const bool logging = d.out == nullptr;
  if (logging) {
    const uint64_t header[2] = {emitted_v, emitted_t};
    std::memcpy(block, header, sizeof(header));
  }
  uint8_t* vdst = logging ? block + 16 : nullptr;
  uint8_t* tdst = logging ? vdst + 24 * emitted_v : nullptr;
  uint32_t next_vertex = static_cast<uint32_t>(d.out_vertices);
  for (size_t t = 0; t < dec.triangles.size(); ++t) {
    if (carried[t] != 0) continue;
    Triangle tri;
    Vec3 q[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = source[dec.triangles[t].v[k]];
      q[k] = p.mesh.vertices[i];
      if (p.out[i] == kGone) {
        p.out[i] = next_vertex++;
        if (logging) {
          std::memcpy(vdst, &q[k], sizeof(Vec3));
          vdst += sizeof(Vec3);
        } else if (d.out->vertex != nullptr) {
          SPLINTCORE_RETURN_IF_ERROR(d.out->vertex(d.out->user, p.out[i], q[k]));
        }
      }
      tri.v[k] = p.out[i];
    }
    if (logging) {
      std::memcpy(tdst, &tri, sizeof(Triangle));
      tdst += sizeof(Triangle);
    } else if (d.out->triangle != nullptr) {
      SPLINTCORE_RETURN_IF_ERROR(d.out->triangle(d.out->user, tri, q[0], q[1], q[2]));
    }
  }
  d.out_vertices = next_vertex;
  d.out_triangles += emitted_t;
  return Status::ok();
}

// Decimates the tile; streams (or logs) the triangles below the carry band, in order, with
// their vertices by first use; writes the rest as the next carry.
Status flush(TileDecimator& d, int64_t cz) {
  Arena& arena = *d.ctx->arena;
  const uint32_t n_new = static_cast<uint32_t>(d.cur_pos.size());
  const uint32_t nc = d.carried_vertices;
  Patch p;
  SPLINTCORE_RETURN_IF_ERROR(assemble(d, &p));
  const size_t nv = p.mesh.vertices.size();
  if (p.mesh.triangles.size() > d.peak_tile_triangles) {
    d.peak_tile_triangles = p.mesh.triangles.size();
  }
  uint32_t* vmap = nullptr;
  uint32_t* sample_map = nullptr;
  uint32_t* removed_map = nullptr;
  Mesh dec(&arena);
  SPLINTCORE_RETURN_IF_ERROR(decimate_tile(d, p, &vmap, &sample_map, &removed_map, &dec));
  const bool sampled = d.max_distance > 0;
  ++d.tiles;
  const size_t dv = dec.vertices.size(), dt = dec.triangles.size();
  uint32_t* source = arena.allocate_array<uint32_t>(dv);    // dec vertex -> patch vertex
  uint32_t* carry_id = arena.allocate_array<uint32_t>(dv);  // dec vertex -> next carry
  uint8_t* carried = arena.allocate_array<uint8_t>(dt);
  uint32_t* carried_index = sampled ? arena.allocate_array<uint32_t>(dt) : nullptr;
  if ((dv > 0 && (source == nullptr || carry_id == nullptr)) ||
      (dt > 0 && (carried == nullptr || (sampled && carried_index == nullptr)))) {
    return arena.exhausted_status();
  }
  for (size_t i = 0; i < nv; ++i) {
    if (vmap[i] != kGone) source[vmap[i]] = static_cast<uint32_t>(i);
  }
  for (size_t i = 0; i < dv; ++i) carry_id[i] = kGone;
  // Carried: a triangle that reaches the top kCarryLayers cell layers (none after the last).
  const bool last = cz >= d.last_layer;
  const double w_cut = d.lo.z + d.spacing_w * static_cast<double>(cz + 1 - kCarryLayers);
  const CarryCount c = mark_carried(p, dec, source, last, w_cut, carry_id, carried, carried_index);
  const uint64_t emitted_v = c.emitted_v, emitted_t = c.emitted_t;
  const uint32_t next_nc = c.next_nc, next_nt = c.next_nt;
  if (d.out_vertices + emitted_v >= kGone - 1) {
    return make_error(StatusCode::kLimitExceeded,
                      "sweep: more than 2^32 - 2 vertices after decimation");
  }
  const bool logging = d.out == nullptr;
  const uint64_t chunk = logging ? chunk_bytes(emitted_v, emitted_t) : 0;
  uint32_t next_ns = 0;  // the samples the carried triangles take along
  if (sampled && !last) {
    for (uint32_t i = 0; i < d.given_count; ++i) next_ns += carried[sample_map[i]];
    for (size_t i = 0; i < nv; ++i) {
      if (removed_map[i] != kGone) next_ns += carried[removed_map[i]];
    }
  }
  const uint64_t carry = last ? 0 : carry_bytes(next_nc, next_nt, n_new, next_ns);
  uint8_t* block = static_cast<uint8_t*>(arena.allocate(static_cast<size_t>(chunk + carry), 8));
  if (chunk + carry > 0 && block == nullptr) return arena.exhausted_status();
  SPLINTCORE_RETURN_IF_ERROR(
      emit_final_part(d, p, dec, source, carried, emitted_v, emitted_t, block));
  // The carry: the other triangles and their vertices, and the map of this tile's new ones.
  if (!last) {
    const CarryParts parts{&p,      &dec,  source, carry_id,   carried,     vmap,          next_nc,
                           next_nt, n_new, nc,     sample_map, removed_map, carried_index, next_ns};
    write_carry(d, parts, block + chunk);
  }
  if (!move_down(d, block, chunk + carry)) return arena.exhausted_status();
  d.carry_bytes = carry;
  d.prev_first = d.cur_first;
  d.cur_first += n_new;
  if (carry > 0) {
    read_carry(d);
  } else {
    d.carried_vertices = d.carried_triangles = d.prev_count = d.carried_samples = 0;
  }
  bind_current(d);
  return Status::ok();
}

// After the last tile (mesh variant): the chunks as one mesh above the log.
Status split_log(TileDecimator& d) {
  Arena& arena = *d.ctx->arena;
  d.mesh.bind(&arena);
  Triangle* tris = arena.allocate_array<Triangle>(static_cast<size_t>(d.out_triangles));
  Vec3* verts = arena.allocate_array<Vec3>(static_cast<size_t>(d.out_vertices));
  if ((d.out_triangles > 0 && tris == nullptr) || (d.out_vertices > 0 && verts == nullptr)) {
    return arena.exhausted_status();
  }
  uint64_t at = 0, tv = 0, tt = 0;
  while (at < d.log_bytes) {
    uint64_t header[2];
    std::memcpy(header, d.log + at, sizeof(header));
    const uint8_t* p = d.log + at + 16;
    if (header[0] > 0) std::memcpy(verts + tv, p, static_cast<size_t>(24 * header[0]));
    p += 24 * header[0];
    if (header[1] > 0) std::memcpy(tris + tt, p, static_cast<size_t>(12 * header[1]));
    tv += header[0];
    tt += header[1];
    at += chunk_bytes(header[0], header[1]);
  }
  SPLINTCORE_ASSERT(tv == d.out_vertices && tt == d.out_triangles);
  d.mesh.triangles.adopt(tris, static_cast<size_t>(tt), static_cast<size_t>(tt));
  d.mesh.vertices.adopt(verts, static_cast<size_t>(tv), static_cast<size_t>(tv));
  return Status::ok();
}

Status on_layer_done(void* user, int64_t cz) {
  TileDecimator& d = *static_cast<TileDecimator*>(user);
  start(d);
  const bool last = cz >= d.last_layer;
  const uint64_t held = uint64_t{d.carried_triangles} + d.cur_tris.size();
  if (held >= kTileTriangles + d.carried_triangles / 2 || (last && held > 0)) {
    SPLINTCORE_RETURN_IF_ERROR(flush(d, cz));
  }
  if (last && d.out == nullptr) SPLINTCORE_RETURN_IF_ERROR(split_log(d));
  return Status::ok();
}

}  // namespace

MarchingCubesVisitor tile_visitor(TileDecimator* d) {
  MarchingCubesVisitor v;
  v.vertex = on_vertex;
  v.triangle = on_triangle;
  v.layer_done = on_layer_done;
  v.user = d;
  return v;
}

}  // namespace splintcore
