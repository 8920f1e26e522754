// PNG previews (tools/common/preview.h): colours, an in-memory sink, atomic file output.
#include "preview.h"

#include <cstring>

#include "splintcore/platform.h"

namespace splintcore {
namespace cli {
namespace {

bool vector_write(void* user, const uint8_t* data, size_t bytes) {
  auto* out = static_cast<std::vector<uint8_t>*>(user);
  out->insert(out->end(), data, data + bytes);
  return true;
}

std::string sha256_hex(const std::vector<uint8_t>& bytes) {
  Sha256 sha;
  sha.update(bytes.data(), bytes.size());
  uint8_t digest[32];
  sha.finish(digest);
  char hex[65];
  Sha256::to_hex(digest, hex);
  return hex;
}

}  // namespace

Status write_png_file(const Context& ctx, const std::vector<RenderMesh>& meshes,
                      const RenderOptions& options, const std::string& path, PreviewInfo* info) {
  std::vector<uint8_t> png;
  const double t0 = monotonic_seconds();
  double render_seconds = 0;
  RenderImage image;
  {
    ArenaScope scope(*ctx.arena);  // the image and the encoder's temporaries
    SPLINTCORE_RETURN_IF_ERROR(
        render_meshes(ctx, Span<const RenderMesh>(meshes.data(), meshes.size()), options, &image));
    render_seconds = monotonic_seconds() - t0;
    ByteSink sink;
    sink.write = &vector_write;
    sink.user = &png;
    sink.name = path.c_str();
    SPLINTCORE_RETURN_IF_ERROR(write_png(ctx, image, sink));
  }
  const double t2 = monotonic_seconds();
  AtomicFile file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(path.c_str()));
  ByteSink out = file.sink();
  if (!out.write(out.user, png.data(), png.size())) {
    return Status::error(StatusCode::kIoError, "cannot write the PNG").in_file(path.c_str());
  }
  SPLINTCORE_RETURN_IF_ERROR(file.commit());  // on error ~AtomicFile removes the temporary
  if (info != nullptr) {
    info->path = path;
    info->sha256 = sha256_hex(png);
    info->png_bytes = png.size();
    info->width = image.width;
    info->height = image.height;
    info->pixels_per_mm = image.pixels_per_mm;
    info->render_seconds = render_seconds;
    info->encode_seconds = t2 - t0 - render_seconds;
  }
  return Status::ok();
}

Status write_preview(const Context& ctx, const Mesh& splint, const std::vector<const Mesh*>& jaws,
                     const std::vector<RigidTransform>& moves, const std::string& path,
                     uint32_t width, uint32_t height, PreviewInfo* info) {
  if (!moves.empty() && moves.size() != jaws.size()) {
    return make_error(StatusCode::kInvalidArgument, "preview: ", moves.size(), " transforms for ",
                      jaws.size(), " jaws");
  }
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // the moved copies
  std::vector<Mesh> moved;
  for (size_t i = 0; i < jaws.size() && !moves.empty(); ++i) {
    const Mesh& jaw = *jaws[i];
    Mesh m(&arena);
    if (!m.vertices.resize(jaw.vertices.size()) || !m.triangles.resize(jaw.triangles.size())) {
      return arena.exhausted_status();
    }
    for (size_t v = 0; v < jaw.vertices.size(); ++v) {
      m.vertices[v] = moves[i].apply_point(jaw.vertices[v]);
    }
    if (jaw.triangles.size() > 0) {
      std::memcpy(m.triangles.data(), jaw.triangles.data(),
                  jaw.triangles.size() * sizeof(Triangle));
    }
    moved.push_back(m);
  }
  std::vector<RenderMesh> meshes;
  RenderMesh s;
  s.mesh = &splint;
  for (int k = 0; k < 3; ++k) s.rgb[k] = kSplintRgb[k];
  meshes.push_back(s);
  for (size_t i = 0; i < jaws.size(); ++i) {
    RenderMesh j;
    j.mesh = moves.empty() ? jaws[i] : &moved[i];
    for (int k = 0; k < 3; ++k) j.rgb[k] = kJawRgb[k];
    j.alpha = kJawAlpha;
    meshes.push_back(j);
  }
  RenderOptions options;
  options.width = width;
  options.height = height;
  return write_png_file(ctx, meshes, options, path, info);
}

Status write_distance_png(const Context& ctx, const Mesh& mesh,
                          const std::vector<double>& distances, double range,
                          const std::string& path, uint32_t width, uint32_t height,
                          PreviewInfo* info) {
  if (distances.size() != mesh.vertices.size()) {
    return make_error(StatusCode::kInvalidArgument, "distance PNG: ", distances.size(),
                      " distances for ", mesh.vertices.size(), " vertices");
  }
  RenderMesh m;
  m.mesh = &mesh;
  m.scalars = distances.data();
  m.scalar_max = range;
  RenderOptions options;
  options.width = width;
  options.height = height;
  options.shading = RenderShading::kGouraud;
  options.legend = true;
  return write_png_file(ctx, std::vector<RenderMesh>{m}, options, path, info);
}

}  // namespace cli
}  // namespace splintcore
