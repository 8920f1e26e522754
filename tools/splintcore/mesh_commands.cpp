// The commands that read meshes and report on them: check, convert, distance, compare, render,
// autorotate.
#include <charconv>
#include <cstring>
#include <string>
#include <vector>

#include "../common/compare.h"
#include "../common/preview.h"
#include "command.h"
#include "files.h"
#include "splintcore/distance.h"
#include "splintcore/outline.h"
#include "splintcore/printer.h"
#include "splintcore/render.h"

namespace splintcore {
namespace tool {

namespace {

// ---- check ------------------------------------------------------------------------------------

struct CheckArgs {
  CommonArgs common;
  const char* printer = "eden260";
  bool place = true;
};

// `check`'s options, in the order its --help lists them.
std::vector<OptionSpec> check_options(CheckArgs* a) {
  return {
      text("--printer", "NAME", &a->printer, "the printer to check for (default eden260)",
           "--printer needs a name"),
      clear_flag("--no-place", &a->place, "check the mesh where it is, not centred on the tray"),
  };
}

void print_check_json(const Run& run, const char* input, const MeshFileInfo& info,
                      const PrinterProfile& profile, const PrintCheck& pc, const Status& verdict,
                      double seconds) {
  JsonObject j;
  j.add("command", "check");
  j.add("input", input);
  j.add_status(verdict);
  j.add("format", encoding_name(info.format));
  j.add("input_bytes", info.bytes);
  j.add("input_triangles", info.triangles);
  add_mesh_report(&j, pc.mesh);
  j.add("printer", profile.name);
  j.add("extent_mm", pc.extent);
  j.add("fits", pc.fits);
  j.add("fits_rotated", pc.fits_rotated);
  j.add("placement_translation_mm", pc.placement.t);
  j.add("layers", pc.layers);
  j.add("units_suspect", pc.units_suspect);
  j.add("printable", pc.printable);
  j.add("time_s", seconds);
  j.add("peak_arena_bytes", run.peak_arena());
  print_json(j);
}

void print_check_text(const Run& run, const char* input, const MeshFileInfo& info,
                      const PrinterProfile& profile, const PrintCheck& pc, double seconds) {
  std::printf("input: %s (%s, %llu triangles, %llu bytes)\n", input, mesh_format_name(info.format),
              static_cast<unsigned long long>(info.triangles),
              static_cast<unsigned long long>(info.bytes));
  print_mesh_report(pc.mesh);
  std::printf("printer: %s: extent %.3f x %.3f x %.3f mm, %s, %llu layers\n", profile.name,
              pc.extent.x, pc.extent.y, pc.extent.z,
              pc.fits ? "fits" : (pc.fits_rotated ? "fits turned 90 degrees" : "does NOT fit"),
              static_cast<unsigned long long>(pc.layers));
  if (pc.units_suspect) std::printf("warning: the size suggests wrong units (not mm?)\n");
  std::printf("printable: %s\n", pc.printable ? "yes" : "no");
  run.print_time(seconds);
}

// ---- convert ----------------------------------------------------------------------------------

struct ConvertArgs {
  CommonArgs common;
  const char* output = nullptr;
  bool ascii = false;
  double scale = 1.0;
};

// `convert`'s options, in the order its --help lists them.
std::vector<OptionSpec> convert_options(ConvertArgs* a) {
  return {
      output_option("OUT.stl", &a->output, "the mesh to write: STL (OUT.ply: binary PLY)"),
      flag("--ascii", &a->ascii, "write ASCII STL (default binary)"),
      positive("--scale", "F", &a->scale, "multiply every coordinate by F (default 1)",
               "--scale needs a number > 0, e.g. 25.4 for a mesh in inches"),
  };
}

// ---- distance ---------------------------------------------------------------------------------

struct DistanceArgs {
  CommonArgs common;
  std::vector<Vec3> queries;
  int sign = 0;  // kSignMethods
};

// `distance`'s options, in the order its --help lists them.
std::vector<OptionSpec> distance_options(DistanceArgs* a) {
  return {
      point_list("--query", "X,Y,Z", &a->queries, "a query point, mm (give it once per point)",
                 "--query needs X,Y,Z (three finite numbers, mm)"),
      choice("--sign", "auto|pseudonormal|winding", &a->sign,
             "how the sign is decided (default auto)",
             "--sign takes auto, pseudonormal or winding"),
  };
}

constexpr SignMethod kSignMethods[] = {SignMethod::kAuto, SignMethod::kPseudonormal,
                                       SignMethod::kWindingNumber};

// One query: printed as a line, or returned as a JSON object.
std::string answer_query(const DistanceIndex& index, const Vec3& q, SignMethod sign, bool json) {
  SignedDistance sd;
  signed_distance(index, q, sign, &sd);
  const double w = sd.method == SignMethod::kWindingNumber ? sd.winding : winding_number(index, q);
  const char* method = sd.method == SignMethod::kPseudonormal ? "pseudonormal" : "winding";
  if (!json) {
    std::printf(
        "query %.6g,%.6g,%.6g: closest %.9g,%.9g,%.9g on triangle %u (%s %u), "
        "distance %.9g, signed %.9g (%s), winding number %.6f\n",
        q.x, q.y, q.z, sd.closest.point.x, sd.closest.point.y, sd.closest.point.z,
        sd.closest.triangle, feature_name(sd.closest.feature), sd.closest.feature_index,
        sd.closest.distance, sd.distance, method, w);
    return "";
  }
  JsonObject r;
  r.add("query", q);
  r.add("closest_point", sd.closest.point);
  r.add("triangle", static_cast<uint64_t>(sd.closest.triangle));
  r.add("feature", feature_name(sd.closest.feature));
  r.add("feature_index", static_cast<uint64_t>(sd.closest.feature_index));
  r.add("distance", sd.closest.distance);
  r.add("signed_distance", sd.distance);
  r.add("inside", sd.distance < 0);
  r.add("winding_number", w);
  r.add("sign_method", method);
  return r.str();
}

// ---- compare ----------------------------------------------------------------------------------

struct CompareArgs {
  CommonArgs common;
  const char* ply = nullptr;
  const char* png = nullptr;
  double range = -1;  // <= 0: the A-to-B maximum
};

// `compare`'s options, in the order its --help lists them.
std::vector<OptionSpec> compare_options(CompareArgs* a) {
  return {
      text("--ply", "OUT.ply", &a->ply, "write A coloured by its distance to B (binary PLY)",
           "--ply needs a file name"),
      text("--png", "OUT.png", &a->png, "write a 1024x1024 PNG of A coloured the same way",
           "--png needs a file name"),
      positive("--range", "MAX", &a->range,
               "the colour ramp's top, mm (default: the A-to-B maximum)",
               "--range needs a number of mm > 0"),
  };
}

struct CompareResult {
  MeshFileInfo info_a, info_b;
  cli::Comparison c;
  cli::PreviewInfo png;
  double seconds = 0;
};

void print_compare_json(const Run& run, const CompareArgs& a, const Mesh& ma, const Mesh& mb,
                        const CompareResult& r) {
  const cli::Comparison& c = r.c;
  JsonObject j;
  j.add("command", "compare");
  j.add("a", a.common.positional[0]);
  j.add("b", a.common.positional[1]);
  j.add_status(Status::ok());
  j.add("a_format", mesh_format_name(r.info_a.format));
  j.add("b_format", mesh_format_name(r.info_b.format));
  j.add("a_vertices", static_cast<uint64_t>(ma.vertices.size()));
  j.add("a_triangles", static_cast<uint64_t>(ma.triangles.size()));
  j.add("b_vertices", static_cast<uint64_t>(mb.vertices.size()));
  j.add("b_triangles", static_cast<uint64_t>(mb.triangles.size()));
  j.add("a_to_b_mean_mm", c.a_to_b.mean);
  j.add("a_to_b_max_mm", c.a_to_b.max);
  j.add("a_to_b_rms_mm", c.a_to_b.rms);
  j.add("b_to_a_mean_mm", c.b_to_a.mean);
  j.add("b_to_a_max_mm", c.b_to_a.max);
  j.add("b_to_a_rms_mm", c.b_to_a.rms);
  j.add("hausdorff_mm", c.hausdorff);
  if (a.ply != nullptr) {
    j.add("ply", a.ply);
    j.add("range_mm", a.range);
  }
  if (a.png != nullptr) {
    j.add("png", a.png);
    j.add("png_sha256", r.png.sha256);
    j.add("png_range_mm", a.range > 0 ? a.range : 1.0);
  }
  j.add("time_s", r.seconds);
  j.add("peak_arena_bytes", run.peak_arena());
  print_json(j);
}

void print_compare_text(const Run& run, const CompareArgs& a, const Mesh& ma, const Mesh& mb,
                        const CompareResult& r) {
  const cli::Comparison& c = r.c;
  std::printf("A: %s (%s, %zu vertices, %zu triangles)\n", a.common.positional[0],
              mesh_format_name(r.info_a.format), ma.vertices.size(), ma.triangles.size());
  std::printf("B: %s (%s, %zu vertices, %zu triangles)\n", a.common.positional[1],
              mesh_format_name(r.info_b.format), mb.vertices.size(), mb.triangles.size());
  std::printf("A to B: mean %.6f mm, max %.6f mm, RMS %.6f mm\n", c.a_to_b.mean, c.a_to_b.max,
              c.a_to_b.rms);
  std::printf("B to A: mean %.6f mm, max %.6f mm, RMS %.6f mm\n", c.b_to_a.mean, c.b_to_a.max,
              c.b_to_a.rms);
  std::printf("Hausdorff (symmetric max): %.6f mm\n", c.hausdorff);
  if (a.ply != nullptr) std::printf("ply: %s (colour range [0, %.6f] mm)\n", a.ply, a.range);
  if (a.png != nullptr) {
    std::printf("png: %s (colour range [0, %.6f] mm, blue to red)\n", a.png,
                a.range > 0 ? a.range : 1.0);
  }
  run.print_time(r.seconds);
}

// ---- render -----------------------------------------------------------------------------------

struct RenderArgs {
  CommonArgs common;
  const char* output = nullptr;
  RenderOptions render;
  int shading = 0;  // flat|gouraud
};

// "WxH" -> the image's two sides, each 1..kRenderMaxSide.
bool parse_image_size(const char* text, RenderOptions* ro) {
  const char* x = std::strchr(text, 'x');
  if (x == nullptr) return false;
  const char* end = text + std::strlen(text);
  uint64_t a = 0, b = 0;
  auto ra = std::from_chars(text, x, a);
  auto rb = std::from_chars(x + 1, end, b);
  if (ra.ec != std::errc() || ra.ptr != x || rb.ec != std::errc() || rb.ptr != end) return false;
  if (a == 0 || b == 0 || a > kRenderMaxSide || b > kRenderMaxSide) return false;
  ro->width = static_cast<uint32_t>(a);
  ro->height = static_cast<uint32_t>(b);
  return true;
}

// "front,top,..." -> the views, in order (1..kRenderMaxViews of them).
bool parse_views(const char* v, RenderOptions* ro) {
  ro->view_count = 0;
  bool ok = *v != '\0';
  while (ok && *v != '\0') {
    const char* comma = std::strchr(v, ',');
    const size_t n = comma != nullptr ? static_cast<size_t>(comma - v) : std::strlen(v);
    ok = ro->view_count < kRenderMaxViews && parse_render_view(v, n, &ro->views[ro->view_count]);
    ++ro->view_count;
    v += n;
    if (*v == ',') {
      ++v;
      ok = ok && *v != '\0';
    }
  }
  return ok;
}

// `render`'s options, in the order its --help lists them.
std::vector<OptionSpec> render_options(RenderArgs* a) {
  return {
      output_option("PREVIEW.png", &a->output, "the PNG to write"),
      custom<RenderOptions, parse_image_size>("--size", "WxH", &a->render,
                                              "the whole image, pixels (default 1024x1024)",
                                              "--size needs WxH, each side 1..8192 pixels"),
      custom<RenderOptions, parse_views>(
          "--views", "LIST", &a->render,
          "comma-separated front, top, right, iso (default all four)",
          "--views needs a list of front, top, right, iso (at most 8)"),
      choice("--shading", "flat|gouraud", &a->shading, "lighting (default flat)",
             "--shading takes flat or gouraud"),
  };
}

struct RenderResult {
  uint64_t triangles = 0;
  double t_read = 0, t_end = 0;
  cli::PreviewInfo info;
};

void print_render_report(const Run& run, const RenderArgs& a, size_t meshes,
                         const RenderResult& r) {
  const RenderOptions& ro = a.render;
  std::string views;
  for (uint32_t v = 0; v < ro.view_count; ++v) {
    views += std::string(v > 0 ? "," : "") + render_view_name(ro.views[v]);
  }
  const cli::PreviewInfo& info = r.info;
  if (a.common.json) {
    JsonObject j;
    j.add("command", "render");
    j.add_status(Status::ok());
    j.add("output", a.output);
    j.add("png_sha256", info.sha256);
    j.add("png_bytes", info.png_bytes);
    j.add("width", static_cast<uint64_t>(info.width));
    j.add("height", static_cast<uint64_t>(info.height));
    j.add("views", views);
    j.add("shading", ro.shading == RenderShading::kGouraud ? "gouraud" : "flat");
    j.add("meshes", static_cast<uint64_t>(meshes));
    j.add("triangles", r.triangles);
    j.add("pixels_per_mm", info.pixels_per_mm);
    j.add("read_s", r.t_read - run.start);
    j.add("render_s", info.render_seconds);
    j.add("encode_s", info.encode_seconds);
    j.add("time_s", r.t_end - run.start);
    j.add("peak_arena_bytes", run.peak_arena());
    print_json(j);
    return;
  }
  std::printf("render: %zu mesh(es), %llu triangles, views %s, %u x %u pixels, %.4g px/mm\n",
              meshes, static_cast<unsigned long long>(r.triangles), views.c_str(), info.width,
              info.height, info.pixels_per_mm);
  std::printf("wrote %s (%llu bytes, sha256 %s)\n", a.output,
              static_cast<unsigned long long>(info.png_bytes), info.sha256.c_str());
  std::printf(
      "time: read %.3f s, render %.3f s, encode %.3f s, total %.3f s; peak arena %llu "
      "bytes\n",
      r.t_read - run.start, info.render_seconds, info.encode_seconds, r.t_end - run.start,
      static_cast<unsigned long long>(run.peak_arena()));
}

// ---- autorotate -------------------------------------------------------------------------------

struct Hinge {
  Vec3 p[2];
};

// "X1,Y1,Z1,X2,Y2,Z2": two points (split at the third comma).
bool parse_hinge(const char* text, Hinge* out) {
  const std::string all(text);
  size_t at = std::string::npos;
  for (int k = 0, from = 0; k < 3; ++k) {
    at = all.find(',', static_cast<size_t>(from));
    if (at == std::string::npos) return false;
    from = static_cast<int>(at) + 1;
  }
  return parse_point(all.substr(0, at).c_str(), &out->p[0]) &&
         parse_point(all.substr(at + 1).c_str(), &out->p[1]);
}

struct AutorotateArgs {
  CommonArgs common;
  Hinge hinge;
  bool has_hinge = false;
  double opening = 0;
  bool has_opening = false;
  const char* output = nullptr;
  bool ascii = false;
};

std::vector<OptionSpec> autorotate_options(AutorotateArgs* a) {
  return {
      custom<Hinge, parse_hinge>("--hinge", "X1,Y1,Z1,X2,Y2,Z2", &a->hinge,
                                 "the condylar points (mm): the hinge axis through them",
                                 "--hinge needs six numbers X1,Y1,Z1,X2,Y2,Z2")
          .marks(&a->has_hinge),
      non_negative("--opening", "MM", &a->opening,
                   "the smallest distance between the jaws to turn to (mm, 0 to 10)",
                   "--opening needs a number of mm from 0 to 10")
          .marks(&a->has_opening),
      output_option("ROTATED.stl", &a->output, "write the mandible turned by the angle found"),
      flag("--ascii", &a->ascii, "write ASCII STL (default binary)"),
  };
}

std::string matrix_json(const RigidTransform& m) {
  std::string out = "[";
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out += cli::json_number(m.r[i][j]) + ",";
    out += cli::json_number(m.t[i]) + ",";
  }
  return out + "0,0,0,1]";
}

void print_autorotate(const Run& run, const AutorotateArgs& a, const AutorotateReport& r,
                      double seconds) {
  const double degrees = r.angle_rad * (180.0 / 3.14159265358979323846);
  if (a.common.json) {
    JsonObject j;
    j.add("command", "autorotate");
    j.add("maxilla", a.common.positional[0]);
    j.add("mandible", a.common.positional[1]);
    if (a.output != nullptr) j.add("output", a.output);
    j.add_status(Status::ok());
    j.add("hinge_mm", a.hinge.p[0]);
    j.add("hinge2_mm", a.hinge.p[1]);
    j.add("opening_asked_mm", a.opening);
    j.add("angle_rad", r.angle_rad);
    j.add("angle_deg", degrees);
    j.add_raw("transform", matrix_json(r.transform));
    j.add("opening_mm", r.opening);
    j.add("closing_sign", r.closing_sign);
    j.add("gap_as_given_mm", r.gap_as_given);
    j.add("met_as_given", r.met_as_given);
    j.add("start_angle_rad", r.start_angle_rad);
    j.add("bracket_rad", r.bracket_rad);
    j.add("lever_mm", r.lever_mm);
    j.add("steps", r.steps);
    j.add("contact_maxilla_mm", r.contact_maxilla);
    j.add("contact_mandible_mm", r.contact_mandible);
    j.add("triangle_maxilla", r.triangle_maxilla);
    j.add("triangle_mandible", r.triangle_mandible);
    j.add("time_s", seconds);
    j.add("peak_arena_bytes", run.peak_arena());
    print_json(j);
    return;
  }
  std::printf("angle: %.12f rad (%.9f degrees), closing sense %s about hinge 1 -> 2\n", r.angle_rad,
              degrees, r.closing_sign > 0 ? "positive" : "negative");
  std::printf("as given: %s, %.9f mm apart; closed from %.9f rad in %u distance evaluations\n",
              r.met_as_given ? "meeting" : "apart", r.gap_as_given, r.start_angle_rad, r.steps);
  std::printf("opening measured: %.9f mm (asked %.9f mm)\n", r.opening, a.opening);
  std::printf(
      "contact: maxilla [%.6f, %.6f, %.6f] (triangle %u), mandible [%.6f, %.6f, %.6f] "
      "(triangle %u)\n",
      r.contact_maxilla.x, r.contact_maxilla.y, r.contact_maxilla.z, r.triangle_maxilla,
      r.contact_mandible.x, r.contact_mandible.y, r.contact_mandible.z, r.triangle_mandible);
  std::printf("transform (row-major 4x4, applied to the mandible):\n");
  for (int i = 0; i < 3; ++i) {
    std::printf("  %.17g %.17g %.17g %.17g\n", r.transform.r[i][0], r.transform.r[i][1],
                r.transform.r[i][2], r.transform.t[i]);
  }
  std::printf("  0 0 0 1\n");
  if (a.output != nullptr) std::printf("output: %s\n", a.output);
  run.print_time(seconds);
}

}  // namespace

int run_check(const Command& command, int argc, char** argv) {
  CheckArgs a;
  CommandLine line(command, &a.common, check_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.size() != 1) return line.usage_error("check takes one input file");
  const char* input = a.common.positional[0];
  const PrinterProfile* profile = find_printer_profile(a.printer);
  if (profile == nullptr) {
    return line.usage_error(std::string("unknown printer '") + a.printer + "' (known: eden260)");
  }
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();

  Mesh mesh(&run.arena);
  MeshFileInfo info;
  Status s = read_mesh_file(run.ctx, input, kNoInputLimit, false, &mesh, &info);
  if (!s.is_ok()) return run.reject(s);
  PrintCheckOptions pco;
  pco.place_on_tray = a.place;
  PrintCheck pc;
  s = check_printable(run.ctx, mesh, *profile, pco, &pc);
  if (!s.is_ok()) return run.reject(s.in_file(input));
  Status verdict = require_printable(pc, *profile);
  if (!verdict.is_ok()) verdict.in_file(input);
  const double seconds = monotonic_seconds() - run.start;

  if (a.common.json) {
    print_check_json(run, input, info, *profile, pc, verdict, seconds);
  } else {
    print_check_text(run, input, info, *profile, pc, seconds);
  }
  if (!verdict.is_ok()) {
    cli::print_error(verdict);
    return kExitRejected;
  }
  return kExitOk;
}

int run_convert(const Command& command, int argc, char** argv) {
  ConvertArgs a;
  CommandLine line(command, &a.common, convert_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.size() != 1) return line.usage_error("convert takes one input file");
  if (a.output == nullptr) return line.usage_error("convert needs -o OUT.stl");
  const char* input = a.common.positional[0];
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();
  if (const Status out = check_mesh_output(a.output, a.ascii); !out.is_ok()) return run.reject(out);

  Mesh mesh(&run.arena);
  MeshFileInfo info;
  Status s = read_mesh_file(run.ctx, input, kNoInputLimit, false, &mesh, &info);
  if (!s.is_ok()) return run.reject(s);
  if (a.scale != 1.0) {
    s = scale_mesh(a.scale, &mesh);
    if (!s.is_ok()) return run.reject(s.in_file(input));
  }
  MeshReport report;
  s = check_mesh(run.ctx, mesh, &report);
  if (!s.is_ok()) return run.reject(s.in_file(input));
  s = write_mesh_atomically(run.ctx, mesh, a.output, a.ascii);
  if (!s.is_ok()) return run.reject(s);
  const double seconds = monotonic_seconds() - run.start;

  if (a.common.json) {
    JsonObject j;
    j.add("command", "convert");
    j.add("input", input);
    j.add("output", a.output);
    j.add_status(Status::ok());
    j.add("input_format", encoding_name(info.format));
    j.add("output_format", a.ascii ? "ascii" : "binary");
    j.add("scale", a.scale);
    j.add("input_triangles", info.triangles);
    add_mesh_report(&j, report);
    j.add("valid_solid", report.is_valid_solid());
    j.add("time_s", seconds);
    j.add("peak_arena_bytes", run.peak_arena());
    print_json(j);
  } else {
    std::printf("input: %s (%s, %llu triangles)\n", input, mesh_format_name(info.format),
                static_cast<unsigned long long>(info.triangles));
    if (a.scale != 1.0) std::printf("scaled by %.17g about the origin\n", a.scale);
    print_mesh_report(report);
    std::printf("output: %s (%s)\n", a.output, mesh_output_format(a.output, a.ascii));
    run.print_time(seconds);
  }
  return kExitOk;
}

int run_distance(const Command& command, int argc, char** argv) {
  DistanceArgs a;
  CommandLine line(command, &a.common, distance_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.size() != 1) return line.usage_error("distance takes one mesh file");
  if (a.queries.empty()) return line.usage_error("distance needs at least one --query X,Y,Z");
  const char* input = a.common.positional[0];
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();

  Mesh mesh(&run.arena);
  Status s = read_mesh_file(run.ctx, input, kNoInputLimit, false, &mesh, nullptr);
  if (!s.is_ok()) return run.reject(s);
  if (mesh.triangles.size() == 0) {
    return run.reject(Status::error(StatusCode::kInvalidMesh, "mesh is empty").in_file(input));
  }
  const size_t before = run.arena.used();
  DistanceIndex index;
  s = build_distance_index(run.ctx, mesh, DistanceIndexOptions{}, &index);
  if (!s.is_ok()) return run.reject(s.in_file(input));
  const double t_build = monotonic_seconds();
  const size_t index_bytes = run.arena.used() - before;

  std::string rows = "[";
  for (size_t i = 0; i < a.queries.size(); ++i) {
    const std::string row = answer_query(index, a.queries[i], kSignMethods[a.sign], a.common.json);
    if (a.common.json) rows += (i > 0 ? "," : "") + row;
  }
  rows += "]";
  const double t_end = monotonic_seconds();
  if (a.common.json) {
    JsonObject j;
    j.add("command", "distance");
    j.add("input", input);
    j.add_status(Status::ok());
    j.add("triangles", static_cast<uint64_t>(mesh.triangles.size()));
    j.add("closed_manifold", index.closed_manifold);
    j.add("index_nodes", static_cast<uint64_t>(index.nodes.size()));
    j.add("index_bytes", static_cast<uint64_t>(index_bytes));
    j.add_raw("queries", rows);
    j.add("build_s", t_build - run.start);
    j.add("time_s", t_end - run.start);
    j.add("peak_arena_bytes", run.peak_arena());
    print_json(j);
  } else {
    std::printf(
        "index: %zu triangles, %zu nodes, %zu bytes, %s; built in %.4f s; peak arena "
        "%llu bytes\n",
        mesh.triangles.size(), index.nodes.size(), index_bytes,
        index.closed_manifold ? "closed manifold" : "open or non-manifold", t_build - run.start,
        static_cast<unsigned long long>(run.peak_arena()));
  }
  return kExitOk;
}

int run_compare(const Command& command, int argc, char** argv) {
  CompareArgs a;
  CommandLine line(command, &a.common, compare_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.size() != 2) return line.usage_error("compare takes two mesh files");
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();

  CompareResult r;
  std::vector<Mesh> both;
  std::vector<MeshFileInfo> infos;
  Status s = read_mesh_files(run.ctx, a.common.positional, kNoInputLimit, false, &both, &infos);
  if (!s.is_ok()) return run.reject(s);
  const Mesh& ma = both[0];
  const Mesh& mb = both[1];
  r.info_a = infos[0];
  r.info_b = infos[1];
  std::vector<double> da, db;
  s = cli::compare_meshes(run.ctx, ma, mb, &da, &db, &r.c);
  if (!s.is_ok()) return run.reject(s);
  if (a.range <= 0) a.range = r.c.a_to_b.max;
  if (a.ply != nullptr) {
    s = write_bytes_atomically(a.ply, cli::distance_ply(ma, da, a.range));
    if (!s.is_ok()) return run.reject(s);
  }
  if (a.png != nullptr) {  // identical meshes (range 0): all blue on a 1 mm ramp
    s = cli::write_distance_png(run.ctx, ma, da, a.range > 0 ? a.range : 1.0, a.png, 1024, 1024,
                                &r.png);
    if (!s.is_ok()) return run.reject(s);
  }
  r.seconds = monotonic_seconds() - run.start;
  if (a.common.json) {
    print_compare_json(run, a, ma, mb, r);
  } else {
    print_compare_text(run, a, ma, mb, r);
  }
  return kExitOk;
}

int run_render(const Command& command, int argc, char** argv) {
  RenderArgs a;
  CommandLine line(command, &a.common, render_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.empty()) return line.usage_error("render takes at least one mesh file");
  if (a.output == nullptr) return line.usage_error("render needs -o PREVIEW.png");
  a.render.shading = a.shading == 1 ? RenderShading::kGouraud : RenderShading::kFlat;
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();

  // The first mesh is the splint (opaque blue), the others jaws (translucent grey).
  std::vector<Mesh> meshes;
  std::vector<RenderMesh> items;
  RenderResult r;
  {
    const Status s =
        read_mesh_files(run.ctx, a.common.positional, kNoInputLimit, false, &meshes, nullptr);
    if (!s.is_ok()) return run.reject(s);
  }
  for (const Mesh& m : meshes) r.triangles += m.triangles.size();
  r.t_read = monotonic_seconds();
  for (size_t i = 0; i < meshes.size(); ++i) {
    RenderMesh m;
    m.mesh = &meshes[i];
    const uint8_t* rgb = i == 0 ? cli::kSplintRgb : cli::kJawRgb;
    for (int k = 0; k < 3; ++k) m.rgb[k] = rgb[k];
    m.alpha = i == 0 ? 255 : cli::kJawAlpha;
    items.push_back(m);
  }
  Status s = cli::write_png_file(run.ctx, items, a.render, a.output, &r.info);
  if (!s.is_ok()) return run.reject(s);
  r.t_end = monotonic_seconds();
  print_render_report(run, a, meshes.size(), r);
  return kExitOk;
}

}  // namespace tool
}  // namespace splintcore

namespace splintcore {
namespace tool {

int run_autorotate(const Command& command, int argc, char** argv) {
  AutorotateArgs a;
  CommandLine line(command, &a.common, autorotate_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.size() != 2) {
    return line.usage_error("autorotate takes two mesh files: MAXILLA MANDIBLE");
  }
  if (!a.has_hinge) return line.usage_error("autorotate needs --hinge X1,Y1,Z1,X2,Y2,Z2");
  if (!a.has_opening) return line.usage_error("autorotate needs --opening MM");
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();
  if (a.output != nullptr) {
    if (const Status out = check_mesh_output(a.output, a.ascii); !out.is_ok()) {
      return run.reject(out);
    }
  }
  std::vector<Mesh> jaws;
  {
    const Status s =
        read_mesh_files(run.ctx, a.common.positional, kNoInputLimit, false, &jaws, nullptr);
    if (!s.is_ok()) return run.reject(s);
  }
  AutorotateOptions o;
  o.hinge[0] = a.hinge.p[0];
  o.hinge[1] = a.hinge.p[1];
  o.opening_mm = a.opening;
  AutorotateReport r;
  Status s = autorotate_mandible(run.ctx, jaws[0], jaws[1], o, &r);
  if (!s.is_ok()) return run.reject(s);
  if (a.output != nullptr) {
    for (Vec3& v : jaws[1].vertices) v = r.transform.apply_point(v);
    s = write_mesh_atomically(run.ctx, jaws[1], a.output, a.ascii);
    if (!s.is_ok()) return run.reject(s);
  }
  print_autorotate(run, a, r, monotonic_seconds() - run.start);
  return kExitOk;
}

}  // namespace tool
}  // namespace splintcore
