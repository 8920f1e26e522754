// Mesh measures and transforms. Sums run in triangle order, relative to the bounding-box
// centre (which keeps the volume sum well conditioned far from the origin), so the results
// are the same on every platform.
#include "splintcore/mesh.h"

#include <cmath>

#include "core/union_find.h"

namespace splintcore {

Aabb mesh_bounds(const Mesh& mesh) {
  Aabb box;
  for (const Vec3& v : mesh.vertices) box.add(v);
  return box;
}

double mesh_area(const Mesh& mesh) {
  double sum = 0.0;
  const Vec3* v = mesh.vertices.data();
  for (const Triangle& t : mesh.triangles) {
    sum += 0.5 * length(cross(v[t.v[1]] - v[t.v[0]], v[t.v[2]] - v[t.v[0]]));
  }
  return sum;
}

double mesh_volume(const Mesh& mesh) {
  const Vec3 c = mesh_bounds(mesh).center();
  const Vec3* v = mesh.vertices.data();
  double sum = 0.0;
  for (const Triangle& t : mesh.triangles) {
    sum += dot(v[t.v[0]] - c, cross(v[t.v[1]] - c, v[t.v[2]] - c));
  }
  return sum / 6.0;
}

void transform_mesh(const RigidTransform& x, Mesh* mesh) {
  for (Vec3& v : mesh->vertices) v = x.apply_point(v);
}

Status scale_mesh(double factor, Mesh* mesh) {
  if (!(factor > 0.0) || !std::isfinite(factor)) {
    return make_error(StatusCode::kInvalidArgument,
                      "scale factor must be a finite number above 0 (got ", factor, ")");
  }
  // Every vertex checked before any is changed.
  const size_t n = mesh->vertices.size();
  for (size_t i = 0; i < n; ++i) {
    const Vec3& v = mesh->vertices[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) {
      return make_error(StatusCode::kNonFinite, "vertex ", i, " is not finite (NaN or infinity)")
          .at_index(i);
    }
    Vec3 p = v * factor;
    if (!round_to_float32(&p)) {
      return make_error(StatusCode::kLimitExceeded, "vertex ", i, " scaled by ", factor,
                        " is beyond float32 range")
          .at_index(i);
    }
  }
  for (Vec3& v : mesh->vertices) {
    v = v * factor;
    (void)round_to_float32(&v);  // in range: checked above
  }
  return Status::ok();
}

uint64_t remove_small_shells_bound(uint64_t vertex_count) {
  return arena_array_bound<uint32_t>(vertex_count) + arena_array_bound<double>(vertex_count) +
         arena_array_bound<uint32_t>(vertex_count);
}

Status remove_small_shells(const Context& ctx, double min_volume, Mesh* mesh,
                           SmallShells* removed) {
  *removed = SmallShells{};
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  const uint64_t nv64 = mesh->vertices.size();
  const size_t nt = mesh->triangles.size();
  if (nv64 >= UINT32_MAX) {
    return make_error(StatusCode::kLimitExceeded, "too many vertices for 32-bit ids: ", nv64);
  }
  const uint32_t nv = static_cast<uint32_t>(nv64);
  Triangle* tris = mesh->triangles.data();
  for (size_t t = 0; t < nt; ++t) {
    for (uint32_t k : tris[t].v) {
      if (k >= nv) {
        return make_error(StatusCode::kInvalidMesh, "triangle ", t, " refers to vertex ", k,
                          " but the mesh has ", nv, " vertices")
            .at_index(t);
      }
    }
  }
  // Shells: the vertices' components; per root, six times its volume and its triangles.
  UnionFind shells;
  if (!shells.init(arena, nv)) return arena.exhausted_status();
  double* six_volume = arena.allocate_array<double>(nv);
  uint32_t* count = arena.allocate_array<uint32_t>(nv);  // then per vertex its new id, or kGone
  if ((six_volume == nullptr || count == nullptr) && nv > 0) return arena.exhausted_status();
  for (size_t t = 0; t < nt; ++t) {
    shells.unite(tris[t].v[0], tris[t].v[1]);
    shells.unite(tris[t].v[1], tris[t].v[2]);
  }
  for (uint32_t i = 0; i < nv; ++i) six_volume[i] = 0, count[i] = 0;
  const Vec3 c = mesh_bounds(*mesh).center();
  const Vec3* v = mesh->vertices.data();
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* k = tris[t].v;
    const uint32_t root = shells.find(k[0]);
    six_volume[root] += dot(v[k[0]] - c, cross(v[k[1]] - c, v[k[2]] - c));
    ++count[root];
  }
  uint32_t largest = nv;  // the shell of the largest volume (the first such root)
  for (uint32_t i = 0; i < nv; ++i) {
    if (count[i] > 0 && (largest == nv || six_volume[i] > six_volume[largest])) largest = i;
  }
  if (largest == nv) return Status::ok();  // no triangles
  removed->largest_kept_mm3 = six_volume[largest] / 6.0;
  constexpr uint32_t kGone = ~uint32_t{0};
  for (uint32_t i = 0; i < nv; ++i) {
    const bool small = count[i] > 0 && i != largest && std::fabs(six_volume[i]) < 6.0 * min_volume;
    if (small) {
      ++removed->removed;
      removed->triangles += count[i];
      removed->volume_mm3 += std::fabs(six_volume[i]) / 6.0;
    }
    count[i] = small ? kGone : 0;  // per root now: taken out or not
  }
  if (removed->removed == 0) return Status::ok();
  // New vertex ids in order, the kept vertices moved down to them; then the kept triangles.
  uint32_t next = 0;
  Vec3* verts = mesh->vertices.data();
  for (uint32_t i = 0; i < nv; ++i) {
    const uint32_t root = shells.find(i);
    if (count[root] == kGone && root != i) {
      count[i] = kGone;
      continue;
    }
    if (count[i] == kGone) continue;  // a root taken out (its mark stays for its members)
    verts[next] = verts[i];
    count[i] = next++;
  }
  size_t kept = 0;
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* k = tris[t].v;
    if (count[k[0]] == kGone) continue;
    tris[kept++] = Triangle{{count[k[0]], count[k[1]], count[k[2]]}};
  }
  mesh->vertices.shrink_size(next);
  mesh->triangles.shrink_size(kept);
  return Status::ok();
}

void move_mesh_down(Arena& arena, const Arena::Marker& start, const Mesh& mesh, Mesh* out,
                    bool vertices_first) {
  const size_t t_count = mesh.triangles.size();
  const size_t v_count = mesh.vertices.size();
  const Triangle* src_t = mesh.triangles.data();
  const Vec3* src_v = mesh.vertices.data();
  Vec3* verts = nullptr;
  Triangle* tris = nullptr;
  {
    // The array allocated first moves first (ArenaMover).
    ArenaMover mover(arena, start);
    if (vertices_first) verts = mover.move(src_v, v_count);
    tris = mover.move(src_t, t_count);
    if (!vertices_first) verts = mover.move(src_v, v_count);
  }
  out->bind(&arena);
  out->triangles.adopt(tris, t_count, t_count);
  out->vertices.adopt(verts, v_count, v_count);
}

}  // namespace splintcore
