// Closed test shapes as triangle soup (tools and tests only: these use libm and std::vector,
// which the core never does; their outputs are inputs, never golden bytes).
#ifndef SPLINTCORE_TOOLS_SHAPES_H
#define SPLINTCORE_TOOLS_SHAPES_H

#include <cmath>
#include <cstdint>
#include <vector>

#include "splintcore/mesh.h"

namespace splintcore {
namespace shapes {

inline SoupTriangle soup_triangle(const float* a, const float* b, const float* c) {
  SoupTriangle t;
  for (int i = 0; i < 3; ++i) {
    t.p[0][i] = a[i];
    t.p[1][i] = b[i];
    t.p[2][i] = c[i];
  }
  return t;
}

// Torus around z with radii R (ring) and r (tube), u x v quads, 2uv outward triangles.
inline std::vector<SoupTriangle> torus(uint32_t u, uint32_t v, double R, double r) {
  std::vector<float> pts(static_cast<size_t>(u) * v * 3);
  const double kTwoPi = 6.283185307179586;
  for (uint32_t i = 0; i < u; ++i) {
    for (uint32_t j = 0; j < v; ++j) {
      double a = kTwoPi * i / u, b = kTwoPi * j / v;
      float* p = &pts[(static_cast<size_t>(i) * v + j) * 3];
      p[0] = static_cast<float>((R + r * std::cos(b)) * std::cos(a));
      p[1] = static_cast<float>((R + r * std::cos(b)) * std::sin(a));
      p[2] = static_cast<float>(r * std::sin(b));
    }
  }
  auto at = [&](uint32_t i, uint32_t j) {
    return &pts[(static_cast<size_t>(i % u) * v + (j % v)) * 3];
  };
  std::vector<SoupTriangle> out;
  out.reserve(static_cast<size_t>(u) * v * 2);
  for (uint32_t i = 0; i < u; ++i) {
    for (uint32_t j = 0; j < v; ++j) {
      const float* p00 = at(i, j);
      const float* p10 = at(i + 1, j);
      const float* p01 = at(i, j + 1);
      const float* p11 = at(i + 1, j + 1);
      out.push_back(soup_triangle(p00, p10, p11));
      out.push_back(soup_triangle(p00, p11, p01));
    }
  }
  return out;
}

// Axis-aligned box [lo, hi], 12 outward triangles.
inline std::vector<SoupTriangle> box(const float lo[3], const float hi[3]) {
  float c[8][3];
  for (int k = 0; k < 8; ++k) {
    c[k][0] = (k & 1) ? hi[0] : lo[0];
    c[k][1] = (k & 2) ? hi[1] : lo[1];
    c[k][2] = (k & 4) ? hi[2] : lo[2];
  }
  static const int kFaces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                    {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                    {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  std::vector<SoupTriangle> out;
  for (const auto& f : kFaces) out.push_back(soup_triangle(c[f[0]], c[f[1]], c[f[2]]));
  return out;
}

}  // namespace shapes
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_SHAPES_H
