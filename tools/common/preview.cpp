// PNG previews (tools/common/preview.h): colours, an in-memory sink, atomic file output.
#include "preview.h"

#include <cstring>

#include "splintcore/platform.h"

namespace splintcore {
namespace cli {

std::string sha256_hex(const std::vector<uint8_t>& bytes) {
  Sha256 sha;
  sha.update(bytes.data(), bytes.size());
  uint8_t digest[32];
  sha.finish(digest);
  char hex[65];
  Sha256::to_hex(digest, hex);
  return hex;
}

namespace {

bool vector_write(void* user, const uint8_t* data, size_t bytes) {
  auto* out = static_cast<std::vector<uint8_t>*>(user);
  out->insert(out->end(), data, data + bytes);
  return true;
}

// Adds a closed, thin square bar from a to b (half-width w) to `m`'s vertex and triangle lists.
void add_bar(const Vec3& a, const Vec3& b, double w, std::vector<Vec3>* v,
             std::vector<Triangle>* t) {
  const Vec3 d = b - a;
  const double len = length(d);
  if (!(len > 1e-9)) return;
  const Vec3 u = d * (1.0 / len);
  const Vec3 ref = u.z * u.z < 0.5 ? Vec3(0, 0, 1) : Vec3(1, 0, 0);
  Vec3 e1 = cross(u, ref);
  e1 = e1 * (w / length(e1));
  const Vec3 e2 = cross(u, e1);  // |e2| = w
  const uint32_t base = static_cast<uint32_t>(v->size());
  const Vec3 ring[4] = {e1 + e2, e2 - e1, Vec3(0, 0, 0) - e1 - e2, e1 - e2};
  for (const Vec3& r : ring) v->push_back(a + r);
  for (const Vec3& r : ring) v->push_back(b + r);
  for (uint32_t k = 0; k < 4; ++k) {
    const uint32_t n = (k + 1) % 4;
    t->push_back(Triangle{{base + k, base + n, base + 4 + n}});
    t->push_back(Triangle{{base + k, base + 4 + n, base + 4 + k}});
  }
  t->push_back(Triangle{{base, base + 2, base + 1}});
  t->push_back(Triangle{{base, base + 3, base + 2}});
  t->push_back(Triangle{{base + 4, base + 5, base + 6}});
  t->push_back(Triangle{{base + 4, base + 6, base + 7}});
}

// Adds an octahedron of radius r at c.
void add_octahedron(const Vec3& c, double r, std::vector<Vec3>* v, std::vector<Triangle>* t) {
  const uint32_t b = static_cast<uint32_t>(v->size());
  const Vec3 tips[6] = {Vec3(r, 0, 0),  Vec3(0, r, 0), Vec3(-r, 0, 0),
                        Vec3(0, -r, 0), Vec3(0, 0, r), Vec3(0, 0, -r)};
  for (const Vec3& p : tips) v->push_back(c + p);
  for (uint32_t k = 0; k < 4; ++k) {
    const uint32_t n = (k + 1) % 4;
    t->push_back(Triangle{{b + k, b + n, b + 4}});
    t->push_back(Triangle{{b + n, b + k, b + 5}});
  }
}

constexpr double kMarkRadius = 0.6;  // mm: the picks' octahedra
constexpr double kBarWidth = 0.15;   // mm: half the bars' width

// The marks as one mesh in `arena`.
Status marks_mesh(Arena& arena, const PreviewMarks& marks, Mesh* out) {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  std::vector<Vec3>* v = &vertices;
  std::vector<Triangle>* t = &triangles;
  for (const Span<const Pick>* side : {&marks.upper, &marks.lower}) {
    for (const Pick& p : *side) {
      const Vec3 at = marks.move.apply_point(p.position);
      const Vec3 d = marks.move.apply_vector(p.direction);
      add_octahedron(at, kMarkRadius, v, t);
      add_bar(at - d * p.inner_length, at + d * p.outside_length, kBarWidth, v, t);
    }
  }
  for (size_t i = 1; i < marks.arch.size(); ++i) {
    add_bar(marks.move.apply_point(marks.arch[i - 1]), marks.move.apply_point(marks.arch[i]),
            kBarWidth, v, t);
  }
  *out = Mesh(&arena);
  if (!out->vertices.resize(vertices.size()) || !out->triangles.resize(triangles.size())) {
    return arena.exhausted_status();
  }
  for (size_t i = 0; i < vertices.size(); ++i) out->vertices[i] = vertices[i];
  for (size_t i = 0; i < triangles.size(); ++i) out->triangles[i] = triangles[i];
  return Status::ok();
}

// Draws the scene, then (with marks) the marks alone in the same framing, copied over it.
// `scene[0]` is the splint; the rest are translucent jaws.
Status render_with_marks(const Context& ctx, const std::vector<RenderMesh>& scene,
                         const Mesh* marks, const RenderOptions& options, RenderImage* image) {
  std::vector<RenderMesh> first = scene;
  Mesh frame_only;  // the marks' vertices without triangles: the same framing in both passes
  if (marks != nullptr) {
    frame_only.vertices = marks->vertices;
    RenderMesh f;
    f.mesh = &frame_only;
    first.push_back(f);
  }
  SPLINTCORE_RETURN_IF_ERROR(
      render_meshes(ctx, Span<const RenderMesh>(first.data(), first.size()), options, image));
  if (marks == nullptr) return Status::ok();
  std::vector<RenderMesh> second;
  RenderMesh m;
  m.mesh = marks;
  for (int k = 0; k < 3; ++k) m.rgb[k] = kMarkRgb[k];
  second.push_back(m);
  // The marks alone, framed as the first pass framed the scene (nothing hides them).
  RenderOptions o = options;
  o.framing = &image->framing;
  for (int k = 0; k < 3; ++k) o.background[k] = 0;
  ArenaScope scope(*ctx.arena);
  RenderImage marked;
  SPLINTCORE_RETURN_IF_ERROR(
      render_meshes(ctx, Span<const RenderMesh>(second.data(), second.size()), o, &marked));
  // The marks' pixels are the red ones (green and blue 0, on black): tile lines are grey.
  const size_t pixels = static_cast<size_t>(image->width) * image->height;
  for (size_t i = 0; i < pixels; ++i) {
    const uint8_t* q = marked.rgb + 3 * i;
    if (q[0] != 0 && q[1] == 0 && q[2] == 0) std::memcpy(image->rgb + 3 * i, q, 3);
  }
  return Status::ok();
}

// write_png_file with marks drawn over the scene (render_with_marks; marks may be null), the
// file kept in `outputs` when not null (write_preview).
Status write_marked_png_file(const Context& ctx, const std::vector<RenderMesh>& meshes,
                             const Mesh* marks, const RenderOptions& options,
                             const std::string& path, PreviewInfo* info,
                             OutputSet* outputs = nullptr) {
  std::vector<uint8_t> png;
  const double t0 = monotonic_seconds();
  double render_seconds = 0;
  RenderImage image;
  {
    ArenaScope scope(*ctx.arena);  // the image and the encoder's temporaries
    SPLINTCORE_RETURN_IF_ERROR(render_with_marks(ctx, meshes, marks, options, &image));
    render_seconds = monotonic_seconds() - t0;
    ByteSink sink;
    sink.write = &vector_write;
    sink.user = &png;
    sink.name = path.c_str();
    SPLINTCORE_RETURN_IF_ERROR(write_png(ctx, image, sink));
  }
  const double t2 = monotonic_seconds();
  SPLINTCORE_RETURN_IF_ERROR(write_bytes_atomically(path, png.data(), png.size(), outputs));
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

// One jaw's part near the splint (write_preview): its triangles (where `move`, if any, puts
// them) not wholly beyond one side of `near`, and the vertices they use, in their order. mark()
// then fill() (each jaw in a task of its own), with `code` and `index` (a byte and a uint32 a
// vertex) and then `out`'s arrays (sized by mark's counts) taken from the arena before each.
struct JawNear {
  const Mesh* jaw = nullptr;
  const RigidTransform* move = nullptr;
  uint8_t* code = nullptr;
  uint32_t* index = nullptr;
  uint32_t vertices = 0;
  size_t triangles = 0;
  Mesh out;

  bool kept(const Triangle& t) const {
    const size_t n = jaw->vertices.size();
    return t.v[0] < n && t.v[1] < n && t.v[2] < n &&
           (code[t.v[0]] & code[t.v[1]] & code[t.v[2]]) == 0;
  }
  void mark(const Aabb& near) {
    const size_t n = jaw->vertices.size();
    for (size_t v = 0; v < n; ++v) {
      const Vec3& p = jaw->vertices[v];
      code[v] = near.outcode(move != nullptr ? move->apply_point(p) : p);
      index[v] = UINT32_MAX;
    }
    for (const Triangle& t : jaw->triangles) {
      if (!kept(t)) continue;
      ++triangles;
      for (uint32_t v : t.v) index[v] = 0;
    }
    for (size_t v = 0; v < n; ++v) {
      if (index[v] == 0) index[v] = vertices++;
    }
  }
  void fill() {
    for (size_t v = 0; v < jaw->vertices.size(); ++v) {
      if (index[v] != UINT32_MAX) out.vertices[index[v]] = jaw->vertices[v];
    }
    size_t k = 0;
    for (const Triangle& t : jaw->triangles) {
      if (kept(t)) out.triangles[k++] = Triangle{{index[t.v[0]], index[t.v[1]], index[t.v[2]]}};
    }
  }
};

}  // namespace

Status write_png_file(const Context& ctx, const std::vector<RenderMesh>& meshes,
                      const RenderOptions& options, const std::string& path, PreviewInfo* info) {
  return write_marked_png_file(ctx, meshes, nullptr, options, path, info);
}

Status write_preview(const Context& ctx, const Mesh& splint, const std::vector<const Mesh*>& jaws,
                     const std::vector<RigidTransform>& moves, const std::string& path,
                     uint32_t width, uint32_t height, PreviewInfo* info, const PreviewMarks* marks,
                     OutputSet* outputs) {
  if (!moves.empty() && moves.size() != jaws.size()) {
    return make_error(StatusCode::kInvalidArgument, "preview: ", moves.size(), " transforms for ",
                      jaws.size(), " jaws");
  }
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // the marks' mesh
  std::vector<RenderMesh> meshes;
  RenderMesh s;
  s.mesh = &splint;
  for (int k = 0; k < 3; ++k) s.rgb[k] = kSplintRgb[k];
  meshes.push_back(s);
  // The jaws near the splint: its box widened by kPreviewJawMarginMm.
  Aabb near = mesh_bounds(splint);
  const Vec3 margin{kPreviewJawMarginMm, kPreviewJawMarginMm, kPreviewJawMarginMm};
  near.lo = near.lo - margin;
  near.hi = near.hi + margin;
  std::vector<JawNear> cropped(jaws.size());
  for (size_t i = 0; i < jaws.size(); ++i) {
    JawNear& c = cropped[i];
    c.jaw = jaws[i];
    c.move = moves.empty() ? nullptr : &moves[i];
    const size_t n = c.jaw->vertices.size();
    c.code = arena.allocate_array<uint8_t>(n);
    c.index = arena.allocate_array<uint32_t>(n);
    if ((c.code == nullptr || c.index == nullptr) && n > 0) return arena.exhausted_status();
  }
  const uint32_t count = static_cast<uint32_t>(jaws.size());
  auto mark = [&](uint32_t i) { cropped[i].mark(near); };
  parallel_for_each(ctx.executor, count, mark);
  for (JawNear& c : cropped) {
    c.out.bind(&arena);
    if (!c.out.vertices.resize(c.vertices) || !c.out.triangles.resize(c.triangles)) {
      return arena.exhausted_status();
    }
  }
  auto fill = [&](uint32_t i) { cropped[i].fill(); };
  parallel_for_each(ctx.executor, count, fill);
  for (size_t i = 0; i < jaws.size(); ++i) {
    RenderMesh j;
    j.mesh = &cropped[i].out;
    j.transform = moves.empty() ? nullptr : &moves[i];  // drawn moved, not copied
    for (int k = 0; k < 3; ++k) j.rgb[k] = kJawRgb[k];
    j.alpha = kJawAlpha;
    meshes.push_back(j);
  }
  RenderOptions options;
  options.width = width;
  options.height = height;
  Mesh mark_mesh;
  if (marks != nullptr) SPLINTCORE_RETURN_IF_ERROR(marks_mesh(arena, *marks, &mark_mesh));
  return write_marked_png_file(ctx, meshes, marks != nullptr ? &mark_mesh : nullptr, options, path,
                               info, outputs);
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
