// `splintcore compare` (tools/common/compare.h): vertex-to-surface deviation both ways and the
// colour-coded PLY (format: Turk 1994 / Bourke, as read by src/io/ply_read.cpp).
#include "compare.h"

#include <cmath>
#include <cstring>

#include "cli.h"
#include "splintcore/distance.h"
#include "splintcore/render.h"

namespace splintcore {
namespace cli {
namespace {

Status one_way(const Context& ctx, const Mesh& from, const Mesh& to, const char* to_name,
               std::vector<double>* distances, Deviation* out) {
  if (to.triangles.size() == 0) {
    return make_error(StatusCode::kInvalidMesh, "mesh ", to_name, " has no triangles");
  }
  ArenaScope scope(*ctx.arena);
  DistanceIndex index;
  SPLINTCORE_RETURN_IF_ERROR(build_distance_index(ctx, to, DistanceIndexOptions{}, &index));
  std::vector<ClosestPoint> closest(from.vertices.size());
  SPLINTCORE_RETURN_IF_ERROR(batch_closest_points(
      ctx, index, from.vertices.span(), Span<ClosestPoint>(closest.data(), closest.size())));
  distances->resize(closest.size());
  double sum = 0, sum_squares = 0, max = 0;
  for (size_t i = 0; i < closest.size(); ++i) {
    const double d = closest[i].distance;
    (*distances)[i] = d;
    sum += d;
    sum_squares += d * d;
    if (d > max) max = d;
  }
  const double n = static_cast<double>(closest.size());
  out->vertices = closest.size();
  out->mean = closest.empty() ? 0 : sum / n;
  out->rms = closest.empty() ? 0 : std::sqrt(sum_squares / n);  // sqrt is correctly rounded
  out->max = max;
  return Status::ok();
}

void put_u32(std::string* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
void put_f32(std::string* out, float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  put_u32(out, bits);
}

}  // namespace

Status compare_meshes(const Context& ctx, const Mesh& a, const Mesh& b,
                      std::vector<double>* a_distances, std::vector<double>* b_distances,
                      Comparison* out) {
  *out = Comparison{};
  SPLINTCORE_RETURN_IF_ERROR(one_way(ctx, a, b, "B", a_distances, &out->a_to_b));
  SPLINTCORE_RETURN_IF_ERROR(one_way(ctx, b, a, "A", b_distances, &out->b_to_a));
  out->hausdorff = out->a_to_b.max > out->b_to_a.max ? out->a_to_b.max : out->b_to_a.max;
  return Status::ok();
}

void distance_colour(double distance, double range, uint8_t rgb[3]) {
  render_ramp_colour(distance, range, rgb);  // the preview's ramp (render.h): one definition
}

std::string distance_ply(const Mesh& mesh, const std::vector<double>& distances, double range) {
  std::string out =
      "ply\nformat binary_little_endian 1.0\n"
      "comment splintcore compare: colour = distance on a blue-green-red ramp over [0, ";
  out += json_number(range);  // shortest round-trip form, locale-free
  out += "] mm, quality = distance (mm)\n";
  out += "element vertex " + std::to_string(mesh.vertices.size()) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "property float quality\n";
  out += "element face " + std::to_string(mesh.triangles.size()) + "\n";
  out += "property list uchar uint vertex_indices\nend_header\n";
  out.reserve(out.size() + mesh.vertices.size() * 19 + mesh.triangles.size() * 13);
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3& v = mesh.vertices[i];
    const double d = i < distances.size() ? distances[i] : 0;
    for (int a = 0; a < 3; ++a) {
      const float f = static_cast<float>(v[a]);
      put_f32(&out, f == 0.0f ? 0.0f : f);  // -0 written as +0
    }
    uint8_t rgb[3];
    distance_colour(d, range, rgb);
    for (uint8_t c : rgb) out.push_back(static_cast<char>(c));
    put_f32(&out, static_cast<float>(d));
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    out.push_back(3);
    for (int k = 0; k < 3; ++k) put_u32(&out, mesh.triangles[t].v[k]);
  }
  return out;
}

}  // namespace cli
}  // namespace splintcore
