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

}  // namespace splintcore
