// Mesh measures and transforms. Sums run in triangle order, relative to the bounding-box
// centre (which keeps the volume sum well conditioned far from the origin), so the results
// are the same on every platform.
#include "splintcore/mesh.h"

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

void move_mesh_down(Arena& arena, const Arena::Marker& start, const Mesh& mesh, Mesh* out,
                    bool vertices_first) {
  const size_t t_count = mesh.triangles.size();
  const size_t v_count = mesh.vertices.size();
  const Triangle* src_t = mesh.triangles.data();
  const Vec3* src_v = mesh.vertices.data();
  arena.rewind(start);
  Triangle* tris = nullptr;
  Vec3* verts = nullptr;
  // The array allocated first moves first: then no destination lies above bytes not yet copied.
  if (vertices_first) {
    verts = arena.allocate_array<Vec3>(v_count);
    if (v_count > 0) std::memmove(static_cast<void*>(verts), src_v, v_count * sizeof(Vec3));
  }
  tris = arena.allocate_array<Triangle>(t_count);
  if (t_count > 0) std::memmove(static_cast<void*>(tris), src_t, t_count * sizeof(Triangle));
  if (!vertices_first) {
    verts = arena.allocate_array<Vec3>(v_count);
    if (v_count > 0) std::memmove(static_cast<void*>(verts), src_v, v_count * sizeof(Vec3));
  }
  SPLINTCORE_ASSERT((tris != nullptr || t_count == 0) && (verts != nullptr || v_count == 0));
  out->bind(&arena);
  out->triangles.adopt(tris, t_count, t_count);
  out->vertices.adopt(verts, v_count, v_count);
}

}  // namespace splintcore
