// The real case for benchmarks and tests: the 31 CBCT teeth of ../shared/realdata (never copied
// into this repository: its licence is non-commercial), the bite opened by translating the
// mandible's teeth, and a wafer fitted to this patient's arch from the teeth themselves:
// one upper and one lower pick per tooth pair (second molar to second molar, 14 each), at the
// crown's centre in the occlusal plane, at the height that makes the crown tip bite `depth` mm
// into the wafer. Tools and tests only (std::vector, files).
#ifndef SPLINTCORE_TOOLS_REALCASE_H
#define SPLINTCORE_TOOLS_REALCASE_H

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "cli.h"
#include "splintcore/core.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "splintcore/spline.h"

namespace splintcore {
namespace realcase {

struct Tooth {
  int number = 0;  // Universal Numbering: 1-16 upper, 17-32 lower
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
};

struct RealCase {
  std::vector<Tooth> teeth;  // 1..15 then 17..32, the mandible's already opened
  std::vector<Pick> upper, lower;
};

inline bool read_tooth(const std::string& path, Tooth* t, std::string* error) {
  std::vector<uint8_t> bytes;
  if (!cli::read_whole_file(path, &bytes)) {
    *error = "cannot read " + path;
    return false;
  }
  std::vector<unsigned char> memory(bytes.size() * 4 + (size_t{8} << 20));
  Arena arena(memory.data(), memory.size());
  MemorySource ms;
  ms.data = bytes.data();
  ms.size = bytes.size();
  Mesh mesh;
  Status s = read_stl_mesh(Context(&arena), memory_source(&ms, path.c_str()), StlReadOptions{},
                           &mesh, nullptr);
  if (!s.is_ok()) {
    *error = path + ": " + s.message();
    return false;
  }
  t->vertices.assign(mesh.vertices.begin(), mesh.vertices.end());
  t->triangles.assign(mesh.triangles.begin(), mesh.triangles.end());
  return true;
}

// dir: .../open-full-jaw-patient26. opening: mm the mandible moves down (-z). depth: mm the
// crown tips bite into the wafer. reach: inner and outside line lengths (mm).
inline bool load(const std::string& dir, double opening, double depth, double reach, RealCase* out,
                 std::string* error) {
  out->teeth.clear();
  for (int number = 1; number <= 32; ++number) {
    if (number == 16) continue;  // absent in the source
    Tooth t;
    t.number = number;
    const std::string path = dir + (number <= 16 ? "/maxilla/tooth_" : "/mandible/tooth_") +
                             std::to_string(number) + ".stl";
    if (!read_tooth(path, &t, error)) return false;
    if (number > 16) {
      for (Vec3& v : t.vertices) v.z -= opening;  // exact for these magnitudes? rounded: fine
    }
    out->teeth.push_back(std::move(t));
  }
  // Crown centre and tip per tooth: the tip is the lowest (upper teeth) or highest (lower)
  // vertex; the centre is the mean of the vertices within 3 mm of the tip height.
  auto crown = [&](int number, Vec3* centre, double* tip) {
    for (const Tooth& t : out->teeth) {
      if (t.number != number) continue;
      const bool upper = number <= 16;
      double best = upper ? 1e300 : -1e300;
      for (const Vec3& v : t.vertices)
        best = upper ? (v.z < best ? v.z : best) : (v.z > best ? v.z : best);
      Vec3 sum{};
      double count = 0;
      for (const Vec3& v : t.vertices) {
        const double d = upper ? v.z - best : best - v.z;
        if (d <= 3.0) {
          sum = sum + v;
          count += 1;
        }
      }
      *centre = sum * (1.0 / count);
      *tip = best;
      return;
    }
  };
  out->upper.clear();
  out->lower.clear();
  for (int k = 0; k < 14; ++k) {
    const int up = 2 + k, low = 31 - k;  // second molar to second molar, paired across
    Vec3 cu, cl;
    double tu = 0, tl = 0;
    crown(up, &cu, &tu);
    crown(low, &cl, &tl);
    Pick pu, pl;
    pu.position = Vec3{cu.x, cu.y, tu + depth};
    pl.position = Vec3{cl.x, cl.y, tl - depth};
    pu.inner_length = pl.inner_length = reach;
    pu.outside_length = pl.outside_length = reach;
    out->upper.push_back(pu);
    out->lower.push_back(pl);
  }
  return true;
}

// All teeth as one mesh (B of the Boolean) in `arena`.
inline Status teeth_mesh(Arena& arena, const RealCase& c, Mesh* out) {
  out->bind(&arena);
  size_t nv = 0, nt = 0;
  for (const Tooth& t : c.teeth) {
    nv += t.vertices.size();
    nt += t.triangles.size();
  }
  if (!out->vertices.reserve(nv) || !out->triangles.reserve(nt)) return arena.exhausted_status();
  for (const Tooth& t : c.teeth) {
    const uint32_t off = static_cast<uint32_t>(out->vertices.size());
    for (const Vec3& v : t.vertices) (void)out->vertices.push_back(v);
    for (const Triangle& tr : t.triangles) {
      (void)out->triangles.push_back(Triangle{{tr.v[0] + off, tr.v[1] + off, tr.v[2] + off}});
    }
  }
  return Status::ok();
}

// The wafer: spacing chosen for about 2,600 triangles, as in the paper.
inline Status wafer_mesh(Arena& arena, const RealCase& c, double spacing, Mesh* out,
                         BaseReport* report) {
  const Context ctx(&arena);
  ArenaArray<Line> upper(&arena), lower(&arena);
  const Vec3 up{0, 0, 1};
  SPLINTCORE_RETURN_IF_ERROR(
      make_lines(ctx, Span<const Pick>(c.upper.data(), c.upper.size()), up, "upper", &upper));
  SPLINTCORE_RETURN_IF_ERROR(
      make_lines(ctx, Span<const Pick>(c.lower.data(), c.lower.size()), up, "lower", &lower));
  BaseParams params;
  params.spacing_mm = spacing;
  out->bind(&arena);
  return build_splint_base(ctx, upper.span(), lower.span(), params, out, report);
}

// The real case as a case folder for `splintcore design`: maxilla.stl (teeth 1-16) and
// mandible.stl (17-32, already opened), each one binary STL of its teeth's shells, and
// case.json with the picks (17 significant digits) and the wafer's spacing. False (with
// *error) when a file cannot be written.
inline bool write_case_folder(const RealCase& c, const std::string& dir, double spacing,
                              std::string* error) {
  for (int jaw = 0; jaw < 2; ++jaw) {
    std::vector<uint8_t> bytes(84, 0);
    uint32_t count = 0;
    for (const Tooth& t : c.teeth) {
      if ((t.number <= 16) != (jaw == 0)) continue;
      for (const Triangle& tr : t.triangles) {
        float f[12] = {};
        for (int k = 0; k < 3; ++k) {
          const Vec3& v = t.vertices[tr.v[k]];
          f[3 + 3 * k] = static_cast<float>(v.x);
          f[4 + 3 * k] = static_cast<float>(v.y);
          f[5 + 3 * k] = static_cast<float>(v.z);
        }
        const size_t at = bytes.size();
        bytes.resize(at + 50, 0);
        std::memcpy(bytes.data() + at, f, sizeof f);
        ++count;
      }
    }
    std::memcpy(bytes.data() + 80, &count, 4);
    const std::string path = dir + (jaw == 0 ? "/maxilla.stl" : "/mandible.stl");
    FILE* out = std::fopen(path.c_str(), "wb");
    if (out == nullptr || std::fwrite(bytes.data(), 1, bytes.size(), out) != bytes.size() ||
        std::fclose(out) != 0) {
      *error = "cannot write " + path;
      return false;
    }
  }
  auto picks = [](const std::vector<Pick>& list) {
    std::string text;
    for (size_t i = 0; i < list.size(); ++i) {
      char row[320];
      std::snprintf(row, sizeof row,
                    "%s\n      {\"position\": [%.17g, %.17g, %.17g], \"inner_length_mm\": %.17g, "
                    "\"outside_length_mm\": %.17g}",
                    i > 0 ? "," : "", list[i].position.x, list[i].position.y, list[i].position.z,
                    list[i].inner_length, list[i].outside_length);
      text += row;
    }
    return text;
  };
  char head[256];
  std::snprintf(head, sizeof head,
                "  \"base\": {\n    \"occlusal_normal\": [0, 0, 1],\n"
                "    \"spacing_mm\": %.17g,\n    \"upper\": [",
                spacing);
  std::string json =
      "{\n  \"splintcore_case\": 1,\n  \"case_id\": \"realdata-patient26\",\n"
      "  \"units\": \"mm\",\n  \"jaws\": [\n"
      "    {\"role\": \"maxilla\", \"mesh\": \"maxilla.stl\"},\n"
      "    {\"role\": \"mandible\", \"mesh\": \"mandible.stl\"}\n  ],\n";
  json += head;
  json += picks(c.upper) + "\n    ],\n    \"lower\": [" + picks(c.lower) + "\n    ]\n  },\n";
  json +=
      "  \"insertion_direction\": [0, 0, 1],\n  \"printer\": \"eden260\",\n"
      "  \"memory_cap\": \"1G\",\n"
      "  \"output\": {\"splint\": \"splint.stl\", \"report\": \"report.json\"}\n}\n";
  const std::string path = dir + "/case.json";
  FILE* out = std::fopen(path.c_str(), "wb");
  if (out == nullptr || std::fwrite(json.data(), 1, json.size(), out) != json.size() ||
      std::fclose(out) != 0) {
    *error = "cannot write " + path;
    return false;
  }
  return true;
}

}  // namespace realcase
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_REALCASE_H
