// Preview rasteriser (include/splintcore/render.h).
//
// Sources: J. Pineda, "A parallel algorithm for polygon rasterization", SIGGRAPH 1988 (edge
// functions, evaluated here exactly in 64-bit integers on a 1/256-pixel grid); the top-left
// fill rule of Direct3D 10 as explained by F. Giesen, "Triangle rasterization in practice"
// (2013), which draws a pixel on an edge shared by two triangles exactly once; E. Catmull, "A
// subdivision algorithm for computer display of curved surfaces" (1974) for the z-buffer; H.
// Gouraud, "Continuous shading of curved surfaces", IEEE Trans. Computers C-20(6), 1971 for
// interpolated intensities; Lambert's cosine law with a fixed light for the intensity.
//
// Everything that reaches the pixels uses + - * / sqrt and floor only, in a fixed order, so
// the bytes are the same on every compiler and CPU. Views are tiles of the image: drawing them
// in parallel writes disjoint pixels, and within a tile meshes and triangles are drawn in
// order, a depth tie keeping the earlier one.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "splintcore/render.h"

namespace splintcore {
namespace {

constexpr int64_t kSubpixel = 256;  // fixed-point grid: 1/256 pixel
constexpr double kAmbient = 0.3;
constexpr double kDiffuse = 0.7;
constexpr double kMargin = 0.9;  // the scene fills 90% of a tile's shorter fit
constexpr float kFarDepth = 3.0e38f;

struct Basis {
  Vec3 right, up, toward;
};

Basis view_basis(RenderView view) {
  const double s2 = 1.0 / std::sqrt(2.0), s3 = 1.0 / std::sqrt(3.0), s6 = 1.0 / std::sqrt(6.0);
  switch (view) {
    case RenderView::kFront: return {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}};
    case RenderView::kTop: return {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    case RenderView::kRight: return {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}};
    case RenderView::kIso:
    default: return {{-s2, s2, 0}, {-s6, -s6, 2 * s6}, {s3, s3, s3}};
  }
}

// The light, fixed relative to the eye: from the upper left, in front.
Vec3 view_light(const Basis& b) {
  const Vec3 l = b.right * -0.35 + b.up * 0.45 + b.toward * 0.82;
  return l * (1.0 / length(l));
}

uint8_t shade(uint8_t channel, double intensity) {
  double v = static_cast<double>(channel) * intensity + 0.5;
  if (!(v > 0)) v = 0;
  if (v > 255) v = 255;
  return static_cast<uint8_t>(v);
}

// Framing keeps every vertex inside its tile; these bounds only keep absurd coordinates (a
// scene wider than 1e300 mm) from overflowing the integer and float conversions.
constexpr double kFarPixel = 1 << 20;
double clamp(double v, double bound) { return v < -bound ? -bound : (v > bound ? bound : v); }

// floor(v) for |v| < 2^62, inline (the libm call was a tenth of the drawing time).
int64_t floor_to_int(double v) {
  int64_t t = static_cast<int64_t>(v);  // towards zero
  if (static_cast<double>(t) > v) --t;
  return t;
}

// floor(a / kSubpixel): an arithmetic shift right (kSubpixel is 2^8). C++17 leaves the shift of
// a negative value to the implementation; g++ and clang++ shift arithmetically, and the
// static_assert below checks it for the compiler at hand (C++20 requires it).
static_assert(kSubpixel == 256, "floor_subpixel shifts by 8");
constexpr int64_t floor_subpixel(int64_t a) { return a >> 8; }
static_assert(floor_subpixel(-1) == -1 && floor_subpixel(-256) == -1 &&
                  floor_subpixel(-257) == -2 && floor_subpixel(255) == 0 &&
                  floor_subpixel(256) == 1,
              "floor_subpixel");

struct View {
  Basis basis;
  Vec3 light;
  double centre_u = 0, centre_v = 0;       // the scene's projected box centre (mm)
  double pixel_x = 0, pixel_y = 0;         // the tile's centre (pixels, image coordinates)
  int64_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // tile pixels [x0, x1) x [y0, y1)
};

struct Layer {
  uint8_t* rgb = nullptr;
  float* depth = nullptr;
  uint8_t* alpha = nullptr;  // the translucent layer: each pixel's weight
};

struct Frame {
  const RenderOptions* options = nullptr;
  uint32_t width = 0;
  double scale = 1;  // pixels per mm
  View views[kRenderMaxViews];
  Layer opaque, overlay;
};

// A vertex as one view sees it (each vertex is projected once per view, not per triangle).
struct Projected {
  int32_t x, y;     // fixed point, inside the tile (|x|, |y| < 2^22)
  float depth;      // smaller is nearer
  float intensity;  // Gouraud: the vertex's lighting
};

// Vertex i of a mesh where it is drawn (moved by the item's transform, if any).
inline Vec3 placed(const RenderMesh& item, const Vec3& p) {
  return item.transform != nullptr ? item.transform->apply_point(p) : p;
}

Projected project(const Frame& f, const View& v, const Vec3& p) {
  const double u = dot(p, v.basis.right) - v.centre_u;
  const double w = dot(p, v.basis.up) - v.centre_v;
  const double sx = v.pixel_x + u * f.scale;
  const double sy = v.pixel_y - w * f.scale;
  Projected out;
  const double grid = static_cast<double>(kSubpixel);
  out.x = static_cast<int32_t>(floor_to_int(clamp(sx, kFarPixel) * grid + 0.5));
  out.y = static_cast<int32_t>(floor_to_int(clamp(sy, kFarPixel) * grid + 0.5));
  out.depth = static_cast<float>(clamp(-dot(p, v.basis.toward), 1.0e37));
  out.intensity = 0;
  return out;
}

// A triangle's corners on the screen, counter-clockwise (positive area): fixed-point positions
// and the mesh vertices they are.
struct Corners {
  int64_t x[3], y[3];
  uint32_t vertex[3];
};

// An edge a->b owns the pixels exactly on it when it goes down, or left when horizontal: of two
// triangles sharing the edge (traversed in opposite directions) exactly one owns it.
inline int64_t edge_bias(const Corners& c, int a, int b) {
  const int64_t dy = c.y[b] - c.y[a], dx = c.x[b] - c.x[a];
  return (dy > 0 || (dy == 0 && dx < 0)) ? 0 : -1;
}

struct MeshJob {
  Frame* frame = nullptr;
  const RenderMesh* item = nullptr;
  const float* normals = nullptr;  // Gouraud: 3 per vertex (unnormalised), else nullptr
  Projected* projected = nullptr;  // a batch of views x vertex count
};

struct PixelBox {
  int64_t x0, x1, y0, y1;  // inclusive
};

// The pixel centres p * 256 + 128 (one axis) between the smallest and the largest of the
// fixed-point a, b, c and in the tile's [lo, hi]: [*first, *last], false when there are none.
inline bool centre_range(int64_t a, int64_t b, int64_t c, int64_t lo, int64_t hi, int64_t* first,
                         int64_t* last) {
  const int64_t least = std::min(std::min(a, b), c), most = std::max(std::max(a, b), c);
  *first = std::max<int64_t>(-floor_subpixel(kSubpixel / 2 - least), lo);
  *last = std::min<int64_t>(floor_subpixel(most - kSubpixel / 2), hi);
  return *first <= *last;
}

double lambert(const Vec3& normal, double normal_length, const Vec3& light) {
  double c = dot(normal, light) / normal_length;
  if (c < 0) c = -c;  // both sides lit: open scans are seen from inside too
  if (c > 1) c = 1;
  return kAmbient + kDiffuse * c;
}

// Flat shading of one triangle (its corners `vertex` in the mesh's order, moved where drawn),
// computed when its first pixel is written (most triangles of a fine mesh write none: hidden,
// or no pixel centre inside).
struct FlatLight {
  const RenderMesh* item;
  uint32_t vertex[3];
  const Vec3* light;
  bool ready;
  double intensity;
  uint8_t shaded[3];
  void prepare() {
    const Vec3* vertices = item->mesh->vertices.data();
    const Vec3 p[3] = {placed(*item, vertices[vertex[0]]), placed(*item, vertices[vertex[1]]),
                       placed(*item, vertices[vertex[2]])};
    const Vec3 normal = cross(p[1] - p[0], p[2] - p[0]);
    const double len = length(normal);
    intensity = len > 0 ? lambert(normal, len, *light) : kAmbient;
    for (int k = 0; k < 3; ++k) shaded[k] = shade(item->rgb[k], intensity);
    ready = true;
  }
};

// What a covered pixel of a triangle needs besides its edge values (w0, w1, w2: opposite the
// corners 0, 1, 2, summing to the area), set up (prepare) at the triangle's first covered pixel:
// most triangles of a fine mesh cover none, so nothing is initialised before.
struct Fill {
  const MeshJob* job;
  const Layer* layer;
  double inv_area;
  double depth[3], intensity[3], scalar[3];
  FlatLight flat;

  void prepare(const MeshJob& mesh_job, const Layer& target, const Projected* projected,
               const Triangle& tri, const Corners& corners, int64_t area, const View& view) {
    job = &mesh_job;
    layer = &target;
    inv_area = 1.0 / static_cast<double>(area);
    const RenderMesh& item = *job->item;
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = corners.vertex[k];
      depth[k] = static_cast<double>(projected[i].depth);
      intensity[k] = static_cast<double>(projected[i].intensity);
      scalar[k] = item.scalars != nullptr ? item.scalars[i] : 0;
      flat.vertex[k] = tri.v[k];
    }
    flat.item = &item;
    flat.light = &view.light;
    flat.ready = false;
  }

  // The pixel `index` with edge values w0, w1, w2: depth-tested, written when nearer.
  void pixel(size_t index, int64_t w0, int64_t w1, int64_t w2) {
    const RenderMesh& item = *job->item;
    const double l0 = static_cast<double>(w0), l1 = static_cast<double>(w1),
                 l2 = static_cast<double>(w2);
    const double z = (l0 * depth[0] + l1 * depth[1] + l2 * depth[2]) * inv_area;
    const float zf = static_cast<float>(z);
    if (!(zf < layer->depth[index])) return;
    layer->depth[index] = zf;
    if (layer->alpha != nullptr) layer->alpha[index] = item.alpha;
    uint8_t* out = layer->rgb + index * 3;
    const bool gouraud = job->normals != nullptr;
    const bool scalars = item.scalars != nullptr;
    if (!gouraud && !flat.ready) flat.prepare();
    if (!gouraud && !scalars) {
      out[0] = flat.shaded[0];
      out[1] = flat.shaded[1];
      out[2] = flat.shaded[2];
      return;
    }
    const double shading =
        gouraud ? (l0 * intensity[0] + l1 * intensity[1] + l2 * intensity[2]) * inv_area
                : flat.intensity;
    uint8_t base[3] = {item.rgb[0], item.rgb[1], item.rgb[2]};
    if (scalars) {
      const double s = (l0 * scalar[0] + l1 * scalar[1] + l2 * scalar[2]) * inv_area;
      render_ramp_colour(s, item.scalar_max, base);
    }
    out[0] = shade(base[0], shading);
    out[1] = shade(base[1], shading);
    out[2] = shade(base[2], shading);
  }
};

// The edge function of the corners p -> q at the fixed-point point (x, y): positive left of it
// (inside the counter-clockwise triangle), twice the area of (p, q, (x, y)).
inline int64_t edge_at(const Corners& c, int p, int q, int64_t x, int64_t y) {
  return (c.x[q] - c.x[p]) * (y - c.y[p]) - (c.y[q] - c.y[p]) * (x - c.x[p]);
}

// The corners of the triangle `tri` (fixed-point x, y in its order, signed area `area` != 0)
// counter-clockwise: corners 1 and 2 swapped when the area is negative.
inline void make_corners(const Triangle& tri, const int64_t x[3], const int64_t y[3], int64_t area,
                         Corners* c) {
  const int second = area > 0 ? 1 : 2, third = 3 - second;
  c->x[0] = x[0];
  c->y[0] = y[0];
  c->vertex[0] = tri.v[0];
  c->x[1] = x[second];
  c->y[1] = y[second];
  c->vertex[1] = tri.v[second];
  c->x[2] = x[third];
  c->y[2] = y[third];
  c->vertex[2] = tri.v[third];
}

// The one pixel centre (px, py) of the box of the triangle `tri` (fixed-point corners x, y in
// its order, signed area `area` != 0) is inside it or on its boundary: its edge values there in
// the triangle's order, e12 (of the edge from corner 1 to 2), e20 and e01, are all >= 0 when
// the area is positive, all <= 0 when negative. The fill rule on an edge, the depth test, then
// the pixel: the decisions and values draw_triangle makes for that pixel (most triangles of a
// fine mesh that draw anything have a box of one pixel centre).
__attribute__((noinline)) void draw_one_pixel(const MeshJob& job, const View& view,
                                              const Layer& layer, const Projected* projected,
                                              const Triangle& tri, const int64_t x[3],
                                              const int64_t y[3], int64_t area, int64_t e12,
                                              int64_t e20, int64_t e01, int64_t px, int64_t py) {
  Corners c;
  make_corners(tri, x, y, area, &c);
  // Opposite the counter-clockwise corners: an edge reversed negates its value.
  const int64_t w0 = area > 0 ? e12 : -e12, w1 = area > 0 ? e20 : -e01, w2 = area > 0 ? e01 : -e20;
  // On an edge: drawn only by the triangle that owns it (the bias is 0 or -1).
  if ((w0 == 0 && edge_bias(c, 1, 2) < 0) || (w1 == 0 && edge_bias(c, 2, 0) < 0) ||
      (w2 == 0 && edge_bias(c, 0, 1) < 0)) {
    return;
  }
  const int64_t size = area > 0 ? area : -area;
  const size_t index = static_cast<size_t>(py) * job.frame->width + static_cast<size_t>(px);
  // The depth test before anything else is looked up (Fill::pixel repeats it, same values).
  const double z = (static_cast<double>(w0) * static_cast<double>(projected[c.vertex[0]].depth) +
                    static_cast<double>(w1) * static_cast<double>(projected[c.vertex[1]].depth) +
                    static_cast<double>(w2) * static_cast<double>(projected[c.vertex[2]].depth)) *
                   (1.0 / static_cast<double>(size));
  if (!(static_cast<float>(z) < layer.depth[index])) return;
  Fill fill;
  fill.prepare(job, layer, projected, tri, c, size, view);
  fill.pixel(index, w0, w1, w2);
}

// The columns [*first, *last] (offsets from the box's left column, at most `last_column`) where
// an edge's biased value, `w` at offset 0 and falling by `step` a column, is >= 0: narrowed, and
// false when none is left. Exact integer arithmetic (|w| < 2^60, |step| < 2^38); a division only
// where the edge crosses the row inside the box.
inline bool edge_span(int64_t w, int64_t step, int64_t last_column, int64_t* first, int64_t* last) {
  if (step > 0) {  // falling: from offset 0 up to floor(w / step)
    if (w < 0) return false;
    if (w - *last * step < 0) *last = w / step;
  } else if (step < 0) {  // rising: from ceil(-w / -step)
    if (w < 0) {
      const int64_t rise = -step;
      if (w + last_column * rise < 0) return false;
      const int64_t from = (-w + rise - 1) / rise;
      if (from > *first) *first = from;
    }
  } else if (w < 0) {
    return false;
  }
  return *first <= *last;
}

// Draws the triangle `tri` with corners `c` (counter-clockwise, of fixed-point area `area` > 0)
// over the pixels of `box` (centre_range: not empty). Edge functions in exact integers: in each row
// the columns where all three are >= 0 (edge_span: the pixels the stepped per-pixel test
// covers, a row of a convex shape being one run), then only those pixels, in order.
__attribute__((noinline)) void draw_triangle(const MeshJob& job, const View& view,
                                             const Layer& layer, const Projected* projected,
                                             const Triangle& tri, const Corners& c, int64_t area,
                                             const PixelBox& box) {
  const int64_t px0 = box.x0, py0 = box.y0, py1 = box.y1, last_column = box.x1 - box.x0;
  // w0 is opposite corner 0 (edge 1->2), and so on; positive inside.
  const int64_t bias0 = edge_bias(c, 1, 2), bias1 = edge_bias(c, 2, 0), bias2 = edge_bias(c, 0, 1);
  const int64_t sx = px0 * kSubpixel + kSubpixel / 2, sy = py0 * kSubpixel + kSubpixel / 2;
  // Biased: a pixel is covered when all three are >= 0.
  int64_t row0 = edge_at(c, 1, 2, sx, sy) + bias0, row1 = edge_at(c, 2, 0, sx, sy) + bias1,
          row2 = edge_at(c, 0, 1, sx, sy) + bias2;
  const int64_t step_x0 = (c.y[2] - c.y[1]) * kSubpixel, step_x1 = (c.y[0] - c.y[2]) * kSubpixel,
                step_x2 = (c.y[1] - c.y[0]) * kSubpixel;
  const int64_t step_y0 = (c.x[2] - c.x[1]) * kSubpixel, step_y1 = (c.x[0] - c.x[2]) * kSubpixel,
                step_y2 = (c.x[1] - c.x[0]) * kSubpixel;
  Fill fill;
  bool ready = false;
  const size_t width = job.frame->width;
  for (int64_t py = py0;;) {
    int64_t first = 0, last = last_column;
    if (edge_span(row0, step_x0, last_column, &first, &last) &&
        edge_span(row1, step_x1, last_column, &first, &last) &&
        edge_span(row2, step_x2, last_column, &first, &last)) {
      if (!ready) {
        fill.prepare(job, layer, projected, tri, c, area, view);
        ready = true;
      }
      // Unbiased values at the run's first pixel.
      int64_t w0 = row0 - first * step_x0 - bias0, w1 = row1 - first * step_x1 - bias1,
              w2 = row2 - first * step_x2 - bias2;
      const size_t row_start = static_cast<size_t>(py) * width + static_cast<size_t>(px0);
      for (int64_t i = first;; ++i) {
        fill.pixel(row_start + static_cast<size_t>(i), w0, w1, w2);
        if (i == last) break;
        w0 -= step_x0;
        w1 -= step_x1;
        w2 -= step_x2;
      }
    }
    if (++py > py1) break;
    row0 += step_y0;
    row1 += step_y1;
    row2 += step_y2;
  }
}

// Vertices a task of the vertex passes (checks and framing, projection) takes at most.
constexpr size_t kVertexChunk = 16384;

// Projects the vertices [begin, end) of the job's mesh into the views [first, first + count)
// (slots 0.. of job.projected): each vertex moved (placed) once for all of them.
void project_chunk(const MeshJob& job, uint32_t first, uint32_t count, size_t begin, size_t end) {
  const Frame& f = *job.frame;
  const RenderMesh& item = *job.item;
  const Vec3* vertices = item.mesh->vertices.data();
  const size_t vertex_count = item.mesh->vertices.size();
  for (size_t i = begin; i < end; ++i) {
    const Vec3 p = placed(item, vertices[i]);
    for (uint32_t slot = 0; slot < count; ++slot) {
      const View& view = f.views[first + slot];
      Projected& q = job.projected[static_cast<size_t>(slot) * vertex_count + i];
      q = project(f, view, p);
      if (job.normals != nullptr) {
        const float* n = job.normals + i * 3;
        const Vec3 normal(static_cast<double>(n[0]), static_cast<double>(n[1]),
                          static_cast<double>(n[2]));
        const double len = length(normal);
        q.intensity = static_cast<float>(len > 0 ? lambert(normal, len, view.light) : kAmbient);
      }
    }
  }
}

// Projects the job's mesh into the views [first, first + count), in chunks of vertices on the
// executor (each writes its own vertices' slots: the same values at every thread count).
void project_mesh(const Executor* executor, const MeshJob& job, uint32_t first, uint32_t count) {
  const size_t n = job.item->mesh->vertices.size();
  const uint32_t chunks = static_cast<uint32_t>((n + kVertexChunk - 1) / kVertexChunk);
  auto task = [&job, first, count, n](uint32_t c) {
    const size_t begin = static_cast<size_t>(c) * kVertexChunk;
    project_chunk(job, first, count, begin, std::min(n, begin + kVertexChunk));
  };
  parallel_for_each(executor, chunks, task);
}

// Draws the job's mesh into view `view_index`, its vertices projected in slot `slot`.
void draw_mesh_view(const MeshJob& job, uint32_t view_index, uint32_t slot) {
  const Frame& f = *job.frame;
  const View& view = f.views[view_index];
  const RenderMesh& item = *job.item;
  const Mesh& mesh = *item.mesh;
  const Layer& layer = item.alpha == 255 ? f.opaque : f.overlay;
  const size_t vertex_count = mesh.vertices.size();
  const Projected* projected = job.projected + static_cast<size_t>(slot) * vertex_count;
  const Triangle* triangles = mesh.triangles.data();
  const size_t triangle_count = mesh.triangles.size();
  // The tile in locals: the pixel writes (through uint8_t*) would otherwise reload them.
  const int64_t tile_x0 = view.x0, tile_x1 = view.x1 - 1, tile_y0 = view.y0, tile_y1 = view.y1 - 1;
  constexpr int64_t kHalf = kSubpixel / 2;
  for (size_t t = 0; t < triangle_count; ++t) {
    const Triangle& tri = triangles[t];
    const Projected& q0 = projected[tri.v[0]];
    const Projected& q1 = projected[tri.v[1]];
    const Projected& q2 = projected[tri.v[2]];
    // No pixel centre in its box: nothing to light or draw (most triangles of a fine mesh).
    // The columns first: half the triangles of a fine mesh have none.
    PixelBox box;
    if (!centre_range(q0.x, q1.x, q2.x, tile_x0, tile_x1, &box.x0, &box.x1) ||
        !centre_range(q0.y, q1.y, q2.y, tile_y0, tile_y1, &box.y0, &box.y1)) {
      continue;
    }
    const int64_t x[3] = {q0.x, q1.x, q2.x}, y[3] = {q0.y, q1.y, q2.y};
    // Zero area in the fixed grid (also edge-on faces): nothing to draw.
    const int64_t area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
    if (area == 0) continue;
    if (box.x0 == box.x1 && box.y0 == box.y1) {
      // One pixel centre: the edge values there, from the corners relative to it (the same
      // integers as edge_at's).
      const int64_t cx = box.x0 * kSubpixel + kHalf, cy = box.y0 * kSubpixel + kHalf;
      const int64_t r0x = x[0] - cx, r0y = y[0] - cy, r1x = x[1] - cx, r1y = y[1] - cy,
                    r2x = x[2] - cx, r2y = y[2] - cy;
      const int64_t e12 = r1x * r2y - r1y * r2x, e20 = r2x * r0y - r2y * r0x,
                    e01 = r0x * r1y - r0y * r1x;
      const bool inside = area > 0 ? (e12 | e20 | e01) >= 0 : ((-e12) | (-e20) | (-e01)) >= 0;
      if (inside) {
        draw_one_pixel(job, view, layer, projected, tri, x, y, area, e12, e20, e01, box.x0, box.y0);
      }
      continue;
    }
    Corners c;
    make_corners(tri, x, y, area, &c);
    draw_triangle(job, view, layer, projected, tri, c, area > 0 ? area : -area, box);
  }
}

Status validate_options(const RenderOptions& o) {
  if (o.width == 0 || o.height == 0 || o.width > kRenderMaxSide || o.height > kRenderMaxSide) {
    return make_error(StatusCode::kInvalidArgument, "render size ", o.width, " x ", o.height,
                      " is out of range (each side 1..", kRenderMaxSide, " pixels)");
  }
  if (o.view_count == 0 || o.view_count > kRenderMaxViews) {
    return make_error(StatusCode::kInvalidArgument, "render needs 1..", kRenderMaxViews,
                      " views, got ", o.view_count);
  }
  for (uint32_t i = 0; i < o.view_count; ++i) {
    if (static_cast<uint8_t>(o.views[i]) > static_cast<uint8_t>(RenderView::kIso)) {
      return make_error(StatusCode::kInvalidArgument, "render view ", i, " is not a known view");
    }
  }
  if (o.framing != nullptr) {
    const RenderFraming& fr = *o.framing;
    bool finite = is_finite(fr.pixels_per_mm) && fr.pixels_per_mm > 0;
    for (uint32_t i = 0; i < o.view_count; ++i) {
      finite = finite && is_finite(fr.centre_u[i]) && is_finite(fr.centre_v[i]);
    }
    if (!finite) {
      return Status::error(StatusCode::kInvalidArgument,
                           "render framing: the scale must be finite and > 0 and every view's "
                           "centre finite");
    }
  }
  return Status::ok();
}

// Each view's box of the projected vertices: the least and most u (right) and v (up).
struct ViewBoxes {
  bool any = false;  // a vertex was added (to every view)
  double lo_u[kRenderMaxViews] = {}, hi_u[kRenderMaxViews] = {};
  double lo_v[kRenderMaxViews] = {}, hi_v[kRenderMaxViews] = {};
};

// [*least, *most] widened to [lo, hi] by strict comparisons: of equal values (-0 and +0) the
// one there first stays, so boxes of consecutive runs of points merged in order are the box of
// all the points added one by one, bit for bit. (No NaN reaches here: the vertices are finite
// and a dot product of finite values with a unit axis is finite or infinite, never NaN.)
inline void widen(double lo, double hi, double* least, double* most) {
  if (lo < *least) *least = lo;
  if (*most < hi) *most = hi;
}

// Adds [lo_u, hi_u] x [lo_v, hi_v] (a point: lo = hi) to view vi's box of `b`.
inline void add_view_box(ViewBoxes* b, uint32_t vi, double lo_u, double hi_u, double lo_v,
                         double hi_v) {
  if (!b->any) {
    b->lo_u[vi] = lo_u;
    b->hi_u[vi] = hi_u;
    b->lo_v[vi] = lo_v;
    b->hi_v[vi] = hi_v;
    return;
  }
  widen(lo_u, hi_u, &b->lo_u[vi], &b->hi_u[vi]);
  widen(lo_v, hi_v, &b->lo_v[vi], &b->hi_v[vi]);
}

// The point p (moved where drawn) projected into the views of `bases`, added to their boxes.
inline void add_point(ViewBoxes* b, const Basis* bases, uint32_t view_count, const Vec3& p) {
  for (uint32_t vi = 0; vi < view_count; ++vi) {
    const double u = dot(p, bases[vi].right), v = dot(p, bases[vi].up);
    add_view_box(b, vi, u, u, v, v);
  }
  b->any = true;
}

// The boxes `c` (of later points) merged into `b`.
void merge_boxes(ViewBoxes* b, const ViewBoxes& c, uint32_t view_count) {
  if (!c.any) return;
  for (uint32_t vi = 0; vi < view_count; ++vi) {
    add_view_box(b, vi, c.lo_u[vi], c.hi_u[vi], c.lo_v[vi], c.hi_v[vi]);
  }
  b->any = true;
}

// Chunks of one round of a checking pass, their results on the stack.
constexpr uint32_t kChunksPerRound = 16;

// [0, n) in chunks of kVertexChunk on the executor, kChunksPerRound at a time: scan(begin, end,
// &chunk) fills a Chunk (its first_bad: the first bad index of the range, or SIZE_MAX); the
// chunks are then taken in order, merge(chunk) for each up to the first with a bad index,
// which is returned (SIZE_MAX: none). The same result at every thread count.
template <class Chunk, class Scan, class Merge>
size_t scan_chunks(const Executor* executor, size_t n, Scan& scan, Merge& merge) {
  constexpr size_t kRound = kVertexChunk * kChunksPerRound;
  for (size_t start = 0; start < n; start += kRound) {
    const size_t round = std::min(n - start, kRound);
    const uint32_t count = static_cast<uint32_t>((round + kVertexChunk - 1) / kVertexChunk);
    Chunk chunks[kChunksPerRound];
    auto task = [&](uint32_t c) {
      const size_t begin = start + static_cast<size_t>(c) * kVertexChunk;
      scan(begin, std::min(n, begin + kVertexChunk), &chunks[c]);
    };
    parallel_for_each(executor, count, task);
    for (uint32_t c = 0; c < count; ++c) {
      if (chunks[c].first_bad != SIZE_MAX) return chunks[c].first_bad;
      merge(chunks[c]);
    }
  }
  return SIZE_MAX;
}

struct VertexChunk {
  size_t first_bad = SIZE_MAX;  // the first vertex not finite, or not finite when moved
  ViewBoxes boxes;              // with framing: the boxes of its vertices where drawn
};

struct TriangleChunk {
  size_t first_bad = SIZE_MAX;  // the first triangle naming a missing vertex
};

// The vertices of `item` checked finite (also where drawn) and, when `bases` is not null,
// added to `boxes` (in order), in chunks on the executor. Errors: kNonFinite.
Status check_vertices(const Executor* executor, size_t m, const RenderMesh& item,
                      const Basis* bases, uint32_t view_count, ViewBoxes* boxes) {
  const Vec3* vertices = item.mesh->vertices.data();
  auto scan = [&](size_t begin, size_t end, VertexChunk* chunk) {
    for (size_t v = begin; v < end; ++v) {
      const Vec3 p = placed(item, vertices[v]);
      if (!is_finite(vertices[v]) || !is_finite(p)) {
        chunk->first_bad = v;
        return;
      }
      if (bases != nullptr) add_point(&chunk->boxes, bases, view_count, p);
    }
  };
  auto merge = [&](const VertexChunk& chunk) { merge_boxes(boxes, chunk.boxes, view_count); };
  const size_t v = scan_chunks<VertexChunk>(executor, item.mesh->vertices.size(), scan, merge);
  if (v == SIZE_MAX) return Status::ok();
  return make_error(StatusCode::kNonFinite, "render mesh ", m, ": vertex ", v, " is not finite")
      .at_index(v);
}

// The triangles of `mesh` name its vertices, checked in chunks on the executor. Errors:
// kInvalidMesh.
Status check_triangles(const Executor* executor, size_t m, const Mesh& mesh) {
  const Triangle* triangles = mesh.triangles.data();
  const size_t vertex_count = mesh.vertices.size();
  auto named = [&](size_t t, int k) { return triangles[t].v[k] < vertex_count; };
  auto scan = [&](size_t begin, size_t end, TriangleChunk* chunk) {
    for (size_t t = begin; t < end; ++t) {
      if (!named(t, 0) || !named(t, 1) || !named(t, 2)) {
        chunk->first_bad = t;
        return;
      }
    }
  };
  auto merge = [](const TriangleChunk&) {};
  const size_t t = scan_chunks<TriangleChunk>(executor, mesh.triangles.size(), scan, merge);
  if (t == SIZE_MAX) return Status::ok();
  const int k = !named(t, 0) ? 0 : (!named(t, 1) ? 1 : 2);
  return make_error(StatusCode::kInvalidMesh, "render mesh ", m, ": triangle ", t, " names vertex ",
                    triangles[t].v[k], " of ", vertex_count)
      .at_index(t);
}

Status check_scalars(size_t m, const RenderMesh& item) {
  if (item.scalars == nullptr) return Status::ok();
  if (!is_finite(item.scalar_max) || !(item.scalar_max > 0)) {
    return make_error(StatusCode::kInvalidArgument, "render mesh ", m,
                      ": the scalar range must be a finite number > 0, got ", item.scalar_max);
  }
  for (size_t v = 0; v < item.mesh->vertices.size(); ++v) {
    if (!is_finite(item.scalars[v])) {
      return make_error(StatusCode::kNonFinite, "render mesh ", m, ": the scalar of vertex ", v,
                        " is not finite")
          .at_index(v);
    }
  }
  return Status::ok();
}

// The options and the meshes checked (in order: each mesh's vertices, triangles, scalars) and,
// unless options.framing is given, each view's box of all meshes' vertices where drawn, in
// mesh and vertex order (*boxes; chunks of vertices on the executor, merged in order: the same
// values as one pass).
Status validate(const Executor* executor, Span<const RenderMesh> meshes, const RenderOptions& o,
                ViewBoxes* boxes) {
  SPLINTCORE_RETURN_IF_ERROR(validate_options(o));
  Basis bases[kRenderMaxViews];
  for (uint32_t vi = 0; vi < o.view_count; ++vi) bases[vi] = view_basis(o.views[vi]);
  const Basis* framed = o.framing == nullptr ? bases : nullptr;
  for (size_t m = 0; m < meshes.size(); ++m) {
    const RenderMesh& item = meshes[m];
    if (item.mesh == nullptr) {
      return make_error(StatusCode::kInvalidArgument, "render mesh ", m, " is null");
    }
    SPLINTCORE_RETURN_IF_ERROR(check_vertices(executor, m, item, framed, o.view_count, boxes));
    SPLINTCORE_RETURN_IF_ERROR(check_triangles(executor, m, *item.mesh));
    SPLINTCORE_RETURN_IF_ERROR(check_scalars(m, item));
  }
  return Status::ok();
}

uint64_t round16(uint64_t n) { return n > UINT64_MAX - 15 ? UINT64_MAX : (n + 15) / 16 * 16; }

}  // namespace

const char* render_view_name(RenderView view) {
  switch (view) {
    case RenderView::kFront: return "front";
    case RenderView::kTop: return "top";
    case RenderView::kRight: return "right";
    case RenderView::kIso: return "iso";
  }
  return "unknown";
}

bool parse_render_view(const char* text, size_t length, RenderView* out) {
  const RenderView all[] = {RenderView::kFront, RenderView::kTop, RenderView::kRight,
                            RenderView::kIso};
  for (RenderView v : all) {
    const char* name = render_view_name(v);
    if (std::strlen(name) == length && std::memcmp(name, text, length) == 0) {
      *out = v;
      return true;
    }
  }
  return false;
}

void render_ramp_colour(double value, double max, uint8_t rgb[3]) {
  double t = max > 0 ? value / max : 0;
  if (!(t > 0)) t = 0;  // also NaN
  if (t > 1) t = 1;
  auto channel = [](double x) { return static_cast<uint8_t>(std::floor(255.0 * x + 0.5)); };
  if (t < 0.5) {
    const double u = 2 * t;
    rgb[0] = 0;
    rgb[1] = channel(u);
    rgb[2] = channel(1 - u);
  } else {
    const double u = 2 * t - 1;
    rgb[0] = channel(u);
    rgb[1] = channel(1 - u);
    rgb[2] = 0;
  }
}

uint64_t render_bound(uint32_t width, uint32_t height, uint64_t largest_mesh_vertices,
                      uint32_t views_at_once) {
  uint64_t pixels = 0, total = 0, part = 0;
  if (!checked_mul(width, height, &pixels)) return UINT64_MAX;
  // Image 3, depth 4, translucent depth 4, colour 3 and weight 1: 15 bytes a pixel, five
  // arrays padded to 16.
  if (!checked_mul(pixels, 15, &total) || !checked_add(total, 5 * 16, &total)) {
    return UINT64_MAX;
  }
  // Gouraud: 3 floats a vertex of the mesh being drawn.
  if (!checked_mul(largest_mesh_vertices, 12, &part) || !checked_add(total, part + 16, &total)) {
    return UINT64_MAX;
  }
  // Its projections in the views drawn at once: 16 bytes each.
  if (!checked_mul(largest_mesh_vertices, 16, &part) || !checked_mul(part, views_at_once, &part) ||
      !checked_add(total, part + 16, &total)) {
    return UINT64_MAX;
  }
  return round16(total);
}

namespace {

// Tiles in columns x rows, a legend strip at the right when asked.
struct Layout {
  uint32_t columns = 1, rows = 1, legend_width = 0, tile_w = 0, tile_h = 0;  // set by lay_out()
};

Status lay_out(const RenderOptions& options, Layout* l) {
  const uint32_t width = options.width, height = options.height;
  const uint32_t view_count = options.view_count;
  if (view_count == 0) {  // validate() refused it already; stated here for the divisions below
    return Status::error(StatusCode::kInvalidArgument, "render: no views");
  }
  l->columns = options.columns != 0 ? options.columns : (view_count == 1 ? 1 : 2);
  if (l->columns > view_count) l->columns = view_count;
  l->rows = (view_count + l->columns - 1) / l->columns;
  if (options.legend) {
    l->legend_width = width / 48 > 8 ? width / 48 : 8;
    if (l->legend_width >= width) l->legend_width = 0;
  }
  l->tile_w = (width - l->legend_width) / l->columns;
  l->tile_h = height / l->rows;
  if (l->tile_w == 0 || l->tile_h == 0) {
    return make_error(StatusCode::kInvalidArgument, "render size ", width, " x ", height,
                      " is too small for ", view_count, " views in ", l->columns, " column(s)");
  }
  return Status::ok();
}

// Framing: each view's tile and, from each view's box of all vertices (`boxes`, validate()),
// its centre; one scale for all views. With options.framing the given centres and scale.
void frame_views(const RenderOptions& options, const Layout& l, const ViewBoxes& boxes,
                 Frame* frame) {
  const uint32_t view_count = options.view_count;
  for (uint32_t vi = 0; vi < view_count; ++vi) {
    View& view = frame->views[vi];
    view.basis = view_basis(options.views[vi]);
    view.light = view_light(view.basis);
    const uint32_t col = vi % l.columns, row = vi / l.columns;
    view.x0 = static_cast<int64_t>(col) * l.tile_w;
    view.y0 = static_cast<int64_t>(row) * l.tile_h;
    view.x1 = view.x0 + l.tile_w;
    view.y1 = view.y0 + l.tile_h;
    view.pixel_x = static_cast<double>(view.x0) + 0.5 * l.tile_w;
    view.pixel_y = static_cast<double>(view.y0) + 0.5 * l.tile_h;
  }
  if (options.framing != nullptr) {
    for (uint32_t vi = 0; vi < view_count; ++vi) {
      frame->views[vi].centre_u = options.framing->centre_u[vi];
      frame->views[vi].centre_v = options.framing->centre_v[vi];
    }
    frame->scale = options.framing->pixels_per_mm;
    return;
  }
  const double *lo_u = boxes.lo_u, *hi_u = boxes.hi_u, *lo_v = boxes.lo_v, *hi_v = boxes.hi_v;
  double scale = 0;
  for (uint32_t vi = 0; vi < view_count; ++vi) {
    View& view = frame->views[vi];
    view.centre_u = 0.5 * lo_u[vi] + 0.5 * hi_u[vi];
    view.centre_v = 0.5 * lo_v[vi] + 0.5 * hi_v[vi];
    const double du = hi_u[vi] - lo_u[vi], dv = hi_v[vi] - lo_v[vi];
    const double fits[2] = {du > 0 ? kMargin * l.tile_w / du : 0,
                            dv > 0 ? kMargin * l.tile_h / dv : 0};
    for (double s : fits) {
      if (s > 0 && (scale == 0 || s < scale)) scale = s;
    }
  }
  frame->scale = scale > 0 ? scale : 1;
}

// Gouraud: area-weighted vertex normals of the mesh of `item` where it is drawn (its corners
// moved by placed(); 3 floats a vertex), from the arena.
Status vertex_normals(Arena& arena, const RenderMesh& item, const float** out) {
  const Mesh& mesh = *item.mesh;
  const Vec3* vertices = mesh.vertices.data();
  const size_t n = mesh.vertices.size();
  *out = nullptr;
  if (n == 0) return Status::ok();
  float* nv = arena.allocate_array<float>(n * 3);
  if (nv == nullptr) return arena.exhausted_status();
  std::memset(nv, 0, n * 3 * sizeof(float));
  for (const Triangle& t : mesh.triangles) {
    const Vec3 p0 = placed(item, vertices[t.v[0]]);
    const Vec3 c = cross(placed(item, vertices[t.v[1]]) - p0, placed(item, vertices[t.v[2]]) - p0);
    for (int k = 0; k < 3; ++k) {
      float* q = nv + static_cast<size_t>(t.v[k]) * 3;
      q[0] += static_cast<float>(c.x);
      q[1] += static_cast<float>(c.y);
      q[2] += static_cast<float>(c.z);
    }
  }
  *out = nv;
  return Status::ok();
}

// Pixels a task of the per-pixel passes (clearing, blending) takes at most.
constexpr size_t kPixelBand = 65536;

// fill(begin, end) over [0, pixels) in bands of kPixelBand pixels on the executor (each band
// writes its own pixels only: the same bytes at every thread count).
template <class F>
void for_pixel_bands(const Executor* executor, size_t pixels, F& fill) {
  const uint32_t bands = static_cast<uint32_t>((pixels + kPixelBand - 1) / kPixelBand);
  auto task = [&fill, pixels](uint32_t b) {
    const size_t begin = static_cast<size_t>(b) * kPixelBand;
    fill(begin, std::min(pixels, begin + kPixelBand));
  };
  parallel_for_each(executor, bands, task);
}

// The image cleared to the background and the depth buffers to far, in bands on the executor.
void clear_layers(const Executor* executor, const Frame& frame, size_t pixels,
                  const uint8_t background[3]) {
  auto clear = [&frame, background](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) std::memcpy(frame.opaque.rgb + i * 3, background, 3);
    for (size_t i = begin; i < end; ++i) frame.opaque.depth[i] = kFarDepth;
    if (frame.overlay.depth == nullptr) return;
    for (size_t i = begin; i < end; ++i) frame.overlay.depth[i] = kFarDepth;
  };
  for_pixel_bands(executor, pixels, clear);
}

// Translucent surfaces in front of the opaque ones, blended over them, in bands on the executor.
void blend_overlay(const Executor* executor, const Frame& frame, size_t pixels, uint8_t* rgb) {
  auto blend = [&frame, rgb](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      if (!(frame.overlay.depth[i] < frame.opaque.depth[i])) continue;
      const uint32_t alpha = frame.overlay.alpha[i];
      for (size_t k = 0; k < 3; ++k) {
        const uint32_t front = frame.overlay.rgb[i * 3 + k], back = rgb[i * 3 + k];
        rgb[i * 3 + k] = static_cast<uint8_t>((front * alpha + back * (255 - alpha) + 127) / 255);
      }
    }
  };
  for_pixel_bands(executor, pixels, blend);
}

// Tile separators (light grey) and the legend.
void draw_decorations(const Layout& l, uint32_t width, uint32_t height, uint8_t* rgb) {
  const uint8_t kLine[3] = {210, 210, 210};
  for (uint32_t col = 1; col < l.columns; ++col) {
    const size_t x = static_cast<size_t>(col) * l.tile_w;
    for (size_t y = 0; y < static_cast<size_t>(l.rows) * l.tile_h; ++y) {
      std::memcpy(rgb + (y * width + x) * 3, kLine, 3);
    }
  }
  for (uint32_t row = 1; row < l.rows; ++row) {
    const size_t y = static_cast<size_t>(row) * l.tile_h;
    for (size_t x = 0; x < static_cast<size_t>(l.columns) * l.tile_w; ++x) {
      std::memcpy(rgb + (y * width + x) * 3, kLine, 3);
    }
  }
  if (l.legend_width == 0) return;
  const uint32_t bx0 = width - l.legend_width + 2, bx1 = width - 2;
  const uint32_t by0 = height / 20, by1 = height - height / 20;  // [by0, by1)
  const uint8_t kFrame[3] = {60, 60, 60};
  for (uint32_t y = by0; y < by1; ++y) {
    const double t = by1 - by0 > 1 ? static_cast<double>(by1 - 1 - y) / (by1 - by0 - 1) : 0;
    uint8_t colour[3];
    render_ramp_colour(t, 1.0, colour);
    for (uint32_t x = bx0; x < bx1; ++x) {
      const bool edge = x == bx0 || x + 1 == bx1 || y == by0 || y + 1 == by1;
      std::memcpy(rgb + (static_cast<size_t>(y) * width + x) * 3, edge ? kFrame : colour, 3);
    }
  }
}

// The depth buffer and, with a translucent mesh, the overlay layer, from the arena.
Status allocate_layers(Arena& arena, Span<const RenderMesh> meshes, size_t pixels, Frame* frame) {
  bool any_overlay = false;
  for (const RenderMesh& item : meshes) any_overlay = any_overlay || item.alpha != 255;
  frame->opaque.depth = arena.allocate_array<float>(pixels);
  if (frame->opaque.depth == nullptr) return arena.exhausted_status();
  if (!any_overlay) return Status::ok();
  frame->overlay.depth = arena.allocate_array<float>(pixels);
  if (frame->overlay.depth == nullptr) return arena.exhausted_status();
  frame->overlay.rgb = arena.allocate_array<uint8_t>(pixels * 3);
  if (frame->overlay.rgb == nullptr) return arena.exhausted_status();
  frame->overlay.alpha = arena.allocate_array<uint8_t>(pixels);
  if (frame->overlay.alpha == nullptr) return arena.exhausted_status();
  return Status::ok();
}

// Draws one mesh into every view: its normals (Gouraud), then the views in batches of as many
// as the executor runs at once, each batch projected (chunks of vertices, each moved once for
// the batch) then drawn (a view a task: disjoint tiles, so the bytes are the same).
Status draw_mesh(const Context& ctx, Frame* frame, const RenderMesh& item) {
  if (item.mesh->triangles.empty()) return Status::ok();  // framed (validate), nothing to draw
  Arena& arena = *ctx.arena;
  ArenaScope mesh_scope(arena);  // the normals and projections of this mesh
  MeshJob job;
  job.frame = frame;
  job.item = &item;
  if (frame->options->shading == RenderShading::kGouraud) {
    SPLINTCORE_RETURN_IF_ERROR(vertex_normals(arena, item, &job.normals));
  }
  const size_t vertex_count = item.mesh->vertices.size();
  const uint32_t view_count = frame->options->view_count;
  const uint32_t concurrency = ctx.executor != nullptr ? ctx.executor->concurrency : 1;
  const uint32_t batch =
      concurrency < 1 ? 1 : (concurrency < view_count ? concurrency : view_count);
  uint64_t projections = 0;
  if (!checked_mul(vertex_count, batch, &projections) || projections > SIZE_MAX) {
    return make_error(StatusCode::kArenaExhausted, "render: ", vertex_count, " vertices in ", batch,
                      " views do not fit in memory");
  }
  job.projected = arena.allocate_array<Projected>(static_cast<size_t>(projections));
  if (job.projected == nullptr) return arena.exhausted_status();
  for (uint32_t first = 0; first < view_count; first += batch) {
    const uint32_t count = view_count - first < batch ? view_count - first : batch;
    project_mesh(ctx.executor, job, first, count);
    auto task = [&job, first](uint32_t slot) { draw_mesh_view(job, first + slot, slot); };
    parallel_for_each(ctx.executor, count, task);
  }
  return Status::ok();
}

void fill_result(const Frame& frame, const Layout& layout, uint8_t* rgb, RenderImage* out) {
  out->width = frame.options->width;
  out->height = frame.options->height;
  out->rgb = rgb;
  out->pixels_per_mm = frame.scale;
  out->framing.pixels_per_mm = frame.scale;
  for (uint32_t vi = 0; vi < frame.options->view_count; ++vi) {
    out->framing.centre_u[vi] = frame.views[vi].centre_u;
    out->framing.centre_v[vi] = frame.views[vi].centre_v;
  }
  out->tile_width = layout.tile_w;
  out->tile_height = layout.tile_h;
  out->columns = layout.columns;
}

}  // namespace

Status render_meshes(const Context& ctx, Span<const RenderMesh> meshes,
                     const RenderOptions& options, RenderImage* out) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && out != nullptr);
  *out = RenderImage{};
  ViewBoxes boxes;
  SPLINTCORE_RETURN_IF_ERROR(validate(ctx.executor, meshes, options, &boxes));
  Arena& arena = *ctx.arena;
  const uint32_t width = options.width, height = options.height;
  const size_t pixels = static_cast<size_t>(width) * height;  // <= 2^26: no overflow
  Layout layout;
  SPLINTCORE_RETURN_IF_ERROR(lay_out(options, &layout));

  // The output image, kept; everything after the scope's mark is temporary.
  uint8_t* rgb = arena.allocate_array<uint8_t>(pixels * 3);
  if (rgb == nullptr) return arena.exhausted_status();
  ArenaScope scope(arena);
  Frame frame;
  frame.options = &options;
  frame.width = width;
  frame.opaque.rgb = rgb;
  SPLINTCORE_RETURN_IF_ERROR(allocate_layers(arena, meshes, pixels, &frame));
  clear_layers(ctx.executor, frame, pixels, options.background);
  frame_views(options, layout, boxes, &frame);

  // Meshes in order; the views of one mesh in parallel (disjoint tiles).
  for (size_t m = 0; m < meshes.size(); ++m) {
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "render", m, meshes.size()));
    SPLINTCORE_RETURN_IF_ERROR(draw_mesh(ctx, &frame, meshes[m]));
  }
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "render", meshes.size(), meshes.size()));
  if (frame.overlay.depth != nullptr) blend_overlay(ctx.executor, frame, pixels, rgb);
  draw_decorations(layout, width, height, rgb);
  fill_result(frame, layout, rgb, out);
  return Status::ok();
}

}  // namespace splintcore
