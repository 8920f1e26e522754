// Scan-like phantom jaws (phantom.h, "scan-like jaws"): an open height-field band along the
// arch with planted defects, for scan preparation and open-jaw tests.
#include <cmath>
#include <utility>

#include "phantom.h"

namespace splintcore {
namespace phantom {

namespace {

// A coordinate as a scan's float32 file holds it.
inline double f32(double x) { return static_cast<double>(static_cast<float>(x)); }

constexpr double kT0 = -0.25, kT1 = 3.141592653589793 + 0.25;  // arch parameter range
constexpr double kWidth = 16.0;                                // band across the arch, mm
constexpr double kCrownHeight = 7.0, kGumHeight = 2.0;

struct Rng {
  uint64_t state;
  uint64_t next() { return hash_mix(state += 0x9E3779B97F4A7C15ull); }
  uint32_t below(uint32_t n) { return static_cast<uint32_t>(next() % n); }
  double unit() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
};

// Height above the gum base at (arch parameter t, offset u across the band), and whether the
// point is on a crown.
double height(double t, double u, bool* crown) {
  const double w = 2.0 * u / kWidth;
  double h = kGumHeight * (1.0 - w * w);
  const double dt = (kT1 - kT0) / kTeethPerJaw;
  const int k = static_cast<int>((t - kT0) / dt);
  double bump = 0;
  if (k >= 0 && k < static_cast<int>(kTeethPerJaw)) {
    const double s = (t - (kT0 + (k + 0.5) * dt)) / (0.45 * dt), v = u / 4.5;
    const double r2 = s * s + v * v;
    if (r2 < 1.0) bump = kCrownHeight * (1.0 - r2 * r2);
  }
  *crown = bump > 0.5;
  return h + bump;
}

struct Builder {
  ScanJaw* out;
  Rng rng;
  bool upper;
  double a, b, z0;

  Vec3 point(double t, double u, double dz, bool* crown) {
    double st = 0, ct = 0;
    sin_cos(t, &st, &ct);
    const double nx = b * ct, ny = a * st, nl = std::sqrt(nx * nx + ny * ny);
    const double h = height(t, u, crown) + dz;
    const double x = a * ct + u * nx / nl, y = b * st + u * ny / nl;
    const double z = upper ? z0 - h : z0 + h;
    return Vec3{f32(x), f32(y), f32(z)};
  }
  uint32_t add(const Vec3& p, bool crown) {
    out->vertices.push_back(p);
    const uint8_t ivory[3] = {236, 230, 214}, pink[3] = {206, 122, 128};
    const uint8_t* c = crown ? ivory : pink;
    out->rgb.insert(out->rgb.end(), c, c + 3);
    return static_cast<uint32_t>(out->vertices.size() - 1);
  }
};

// Cell (i, j) is kept unless the ragged border or a hole took it.
struct Cells {
  uint32_t columns, rows;
  std::vector<uint8_t> removed;  // per cell
  bool kept(uint32_t i, uint32_t j) const { return removed[size_t{i} * rows + j] == 0; }
};

void plant_holes(Rng* rng, Cells* cells, ScanJaw* out) {
  const uint32_t sizes[3][2] = {{1, 1}, {2, 1}, {2, 2}};
  for (uint32_t h = 0; h < 3; ++h) {
    const uint32_t i = cells->columns * (2 + 5 * h) / 20 + rng->below(5);
    const uint32_t j = cells->rows / 2 - 3 + rng->below(6);
    for (uint32_t di = 0; di < sizes[h][0]; ++di) {
      for (uint32_t dj = 0; dj < sizes[h][1]; ++dj) {
        cells->removed[size_t{i + di} * cells->rows + j + dj] = 1;
      }
    }
    ++out->holes;
    const uint32_t edges = 2 * (sizes[h][0] + sizes[h][1]);
    out->max_hole_edges = edges > out->max_hole_edges ? edges : out->max_hole_edges;
  }
}

void plant_islands(Builder* bld, uint32_t count) {
  for (uint32_t k = 0; k < count; ++k) {
    const double t = kT0 + (kT1 - kT0) * (0.15 + 0.3 * k + 0.05 * bld->rng.unit());
    bool crown = false;
    uint32_t base = 0;
    for (uint32_t j = 0; j < 3; ++j) {
      for (uint32_t i = 0; i < 3; ++i) {
        const double u = kWidth / 2 + 3.0 + 0.4 * j;
        const uint32_t id = bld->add(bld->point(t + 0.004 * i, u, 1.0, &crown), false);
        if (i == 0 && j == 0) base = id;
      }
    }
    for (uint32_t j = 0; j < 2; ++j) {
      for (uint32_t i = 0; i < 2; ++i) {
        const uint32_t v00 = base + 3 * j + i, v10 = v00 + 1, v01 = v00 + 3, v11 = v01 + 1;
        bld->out->triangles.push_back(Triangle{{v00, v10, v11}});
        bld->out->triangles.push_back(Triangle{{v00, v11, v01}});
      }
    }
    ++bld->out->islands;
  }
}

// The band's grid (vertex (i, j) at base + i * (rows + 1) + j) and its kept cells.
void band(Builder* bld, const Cells& cells, uint32_t* base) {
  const uint32_t C = cells.columns, R = cells.rows;
  *base = static_cast<uint32_t>(bld->out->vertices.size());
  for (uint32_t i = 0; i <= C; ++i) {
    const double t = kT0 + (kT1 - kT0) * i / C;
    for (uint32_t j = 0; j <= R; ++j) {
      const double u = -kWidth / 2 + kWidth * j / R;
      const double noise = (bld->rng.unit() - 0.5) * 0.05;
      bool crown = false;
      const Vec3 p = bld->point(t, u, noise, &crown);
      bld->add(p, crown);
    }
  }
  for (uint32_t i = 0; i < C; ++i) {
    for (uint32_t j = 0; j < R; ++j) {
      if (!cells.kept(i, j)) continue;
      const uint32_t v00 = *base + i * (R + 1) + j, v10 = v00 + R + 1, v01 = v00 + 1, v11 = v10 + 1;
      bld->out->triangles.push_back(Triangle{{v00, v10, v11}});
      bld->out->triangles.push_back(Triangle{{v00, v11, v01}});
    }
  }
}

}  // namespace

Status make_scan_jaw(Jaw jaw, const ScanOptions& options, ScanJaw* out) {
  const uint32_t C = options.columns, R = options.rows;
  if (C < 100 || R < 32 || C > 4000 || R > 4000) {
    return make_error(StatusCode::kInvalidArgument, "scan phantom: ", C, " columns and ", R,
                      " rows (100..4000 and 32..4000)");
  }
  *out = ScanJaw{};
  const bool upper = jaw == Jaw::kMaxilla;
  Builder bld{out,
              Rng{options.seed * 2 + (upper ? 1 : 0)},
              upper,
              upper ? 25.0 : 24.0,
              upper ? 42.0 : 40.5,
              upper ? 9.5 : -9.5};
  Cells cells{C, R, std::vector<uint8_t>(size_t{C} * R, 0)};
  for (uint32_t i = 0; i < C; ++i) {  // the ragged border: a staircase at either side
    const uint32_t lo = bld.rng.below(3), hi = bld.rng.below(3);
    for (uint32_t j = 0; j < lo; ++j) cells.removed[size_t{i} * R + j] = 1;
    for (uint32_t j = 0; j < hi; ++j) cells.removed[size_t{i} * R + R - 1 - j] = 1;
  }
  plant_holes(&bld.rng, &cells, out);
  uint32_t base = 0;
  band(&bld, cells, &base);
  // Air side up for the mandible, down for the maxilla: the grid's winding turned if need be.
  Vec3 net{};
  for (const Triangle& t : out->triangles) {
    const Vec3 &p0 = out->vertices[t.v[0]], &p1 = out->vertices[t.v[1]],
               &p2 = out->vertices[t.v[2]];
    net = net + cross(p1 - p0, p2 - p0);
  }
  if ((net.z < 0) != upper) {
    for (Triangle& t : out->triangles) std::swap(t.v[1], t.v[2]);
  }
  const size_t band_triangles = out->triangles.size();
  // A 2x2-cell patch wound the other way, at 85% along the arch, mid-band.
  const uint32_t fi = C * 17 / 20 + bld.rng.below(4), fj = R / 2 - 1;
  for (Triangle& t : out->triangles) {
    const uint32_t i = (t.v[0] - base) / (R + 1), j = (t.v[0] - base) % (R + 1);
    if (i >= fi && i < fi + 2 && j >= fj && j < fj + 2) {
      std::swap(t.v[1], t.v[2]);
      ++out->flipped_triangles;
    }
  }
  // Flaps on two cells' diagonals (30% and 60% along), duplicates of two triangles (10%, 50%).
  for (uint32_t k = 0; k < 2; ++k) {
    const uint32_t i = C * (6 + 6 * k) / 20 + bld.rng.below(4), j = R / 2 + 6 + bld.rng.below(2);
    const uint32_t v00 = base + i * (R + 1) + j, v11 = v00 + R + 2;
    const Vec3 mid = (out->vertices[v00] + out->vertices[v11]) * 0.5;
    const Vec3 tip{f32(mid.x), f32(mid.y), f32(mid.z + (upper ? -1.5 : 1.5))};
    const uint32_t f = bld.add(tip, false);
    out->triangles.push_back(Triangle{{v00, v11, f}});
    ++out->nonmanifold_edges;
  }
  for (uint32_t k = 0; k < 2; ++k) {
    const uint32_t i = C * (2 + 8 * k) / 20 + bld.rng.below(4), j = R / 2 + 10;
    const uint32_t v00 = base + i * (R + 1) + j;
    for (size_t t = 0; t < band_triangles; ++t) {
      if (out->triangles[t].v[0] == v00) {
        out->triangles.push_back(out->triangles[t]);
        ++out->duplicates;
        break;
      }
    }
  }
  plant_islands(&bld, 3);
  return Status::ok();
}

}  // namespace phantom
}  // namespace splintcore
