// Wall thickness of a printed part by inward rays: the single-ray form of the shape diameter
// (Shapira, Shamir, Cohen-Or, "Consistent mesh partitioning and skeletonisation using the
// shape diameter function", The Visual Computer 2008), as print-preparation tools measure
// minimum wall thickness. From each triangle's centroid a ray goes along the inward normal;
// the distance to the first surface it meets is the local thickness there.
#include "splintcore/design.h"
#include "splintcore/distance.h"

namespace splintcore {

namespace {

// Thickness values are >= 0: their IEEE bits order as the values do.
uint64_t order_key(double t) {
  uint64_t bits = 0;
  std::memcpy(&bits, &t, sizeof bits);
  return bits;
}

}  // namespace

// The index, then the thin triangles (every one at worst) and the radix sort's scratch.
uint64_t check_wall_thickness_bound(uint64_t vertex_count, uint64_t triangle_count) {
  return distance_index_bound(vertex_count, triangle_count, DistanceIndexOptions{}) +
         2 * arena_array_bound<KeyIndex>(triangle_count);
}

Status check_wall_thickness(const Context& ctx, const Mesh& mesh, double min_thickness,
                            ThicknessReport* report) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && report != nullptr);
  *report = ThicknessReport{};
  report->min_required = min_thickness;
  if (!(min_thickness > 0) || !(min_thickness <= 1e3)) {
    return make_error(StatusCode::kInvalidArgument,
                      "thickness: the minimum must be in (0, 1000] "
                      "mm (",
                      min_thickness, ")");
  }
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // the index and the list of thin triangles are temporaries
  DistanceIndex index;
  SPLINTCORE_RETURN_IF_ERROR(build_distance_index(ctx, mesh, DistanceIndexOptions{}, &index));
  ArenaArray<KeyIndex> thin(&arena);
  // The ray starts this far inside, past its own triangle; it is added back to the distance.
  constexpr double kStart = 1e-6;
  const size_t nt = mesh.triangles.size();
  for (size_t i = 0; i < nt; ++i) {
    if ((i & 0xFFFF) == 0) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "thickness", i, nt));
    }
    const Triangle& t = mesh.triangles[i];
    const Vec3 a = mesh.vertices[t.v[0]], b = mesh.vertices[t.v[1]], c = mesh.vertices[t.v[2]];
    const Vec3 n = cross(b - a, c - a);
    const double len = length(n);
    if (!(len > 0)) continue;  // no direction (a valid solid has none)
    ++report->triangles_checked;
    const Vec3 inward = n * (-1.0 / len);
    const Vec3 centroid = (a + b + c) * (1.0 / 3.0);
    RayHit hit;
    if (!ray_intersect(index, centroid + inward * kStart, inward, min_thickness, &hit)) continue;
    const double thickness = hit.t + kStart;
    if (!(thickness < min_thickness)) continue;
    ++report->thin_triangles;
    report->thin_area_mm2 += 0.5 * len;
    if (!thin.push_back(KeyIndex{order_key(thickness), static_cast<uint32_t>(i), 0})) {
      return arena.exhausted_status();
    }
  }
  if (thin.empty()) {
    report->thinnest = min_thickness;
    return Status::ok();
  }
  SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena, thin.span()));  // thinnest first, then by id
  std::memcpy(&report->thinnest, &thin[0].key, sizeof report->thinnest);
  // The spots: the thinnest places, at least kSpotSpacing apart.
  const double spacing2 = ThicknessReport::kSpotSpacing * ThicknessReport::kSpotSpacing;
  for (const KeyIndex& k : thin) {
    if (report->spot_count == ThicknessReport::kMaxSpots) break;
    const Triangle& t = mesh.triangles[k.index];
    const Vec3 p =
        (mesh.vertices[t.v[0]] + mesh.vertices[t.v[1]] + mesh.vertices[t.v[2]]) * (1.0 / 3.0);
    bool near = false;
    for (uint32_t s = 0; s < report->spot_count && !near; ++s) {
      near = length_squared(report->spots[s].position - p) < spacing2;
    }
    if (near) continue;
    ThicknessSpot& spot = report->spots[report->spot_count++];
    spot.position = p;
    std::memcpy(&spot.thickness, &k.key, sizeof spot.thickness);
    spot.triangle = k.index;
  }
  return Status::ok();
}

}  // namespace splintcore
