// The commands that build a splint step by step: base, boolean, and the synthetic jaws they are
// tried on (phantom).
#include <sys/stat.h>

#include <functional>
#include <string>
#include <vector>

#include "../common/phantom.h"
#include "command.h"
#include "files.h"
#include "splintcore/boolean.h"
#include "splintcore/design.h"

namespace splintcore {
namespace tool {

namespace {

// ---- base -------------------------------------------------------------------------------------

struct BaseArgs {
  CommonArgs common;
  const char* output = nullptr;
  bool ascii = false;
  uint64_t max_input_bytes = cli::kMaxCaseBytes;
};

// `base`'s options, in the order its --help lists them.
std::vector<OptionSpec> base_options(BaseArgs* a) {
  return {
      output_option("BASE.stl", &a->output, "the base to write: STL (BASE.ply: binary PLY)"),
      flag("--ascii", &a->ascii, "write ASCII STL (default binary)"),
      size("--max-input-bytes", "SIZE", &a->max_input_bytes,
           "refuse a larger case file (default 16M)",
           "--max-input-bytes needs a size such as 16M, 2G or 1048576"),
  };
}

struct BaseResult {
  BaseReport report;
  double t_parse = 0, t_build = 0, t_end = 0;
};

void print_base_report(const Run& run, const BaseArgs& a, const CaseFile& c, const Mesh& base,
                       const BaseResult& r) {
  const BaseReport& report = r.report;
  const double t0 = run.start;
  if (a.common.json) {
    JsonObject j;
    j.add("command", "base");
    j.add("case", a.common.positional[0]);
    j.add("case_id", c.case_id);
    j.add("output", a.output);
    j.add_status(Status::ok());
    j.add("upper_picks", static_cast<uint64_t>(c.upper.size()));
    j.add("lower_picks", static_cast<uint64_t>(c.lower.size()));
    j.add("sections", report.sections);
    j.add("points_per_section", report.points_per_section);
    j.add("vertices", static_cast<uint64_t>(base.vertices.size()));
    j.add("triangles", static_cast<uint64_t>(base.triangles.size()));
    j.add("volume_mm3", report.volume);
    j.add("self_intersection_candidates", report.self_intersection_candidates);
    j.add("parse_s", r.t_parse - t0);
    j.add("build_s", r.t_build - r.t_parse);
    j.add("time_s", r.t_end - t0);
    j.add("peak_arena_bytes", run.peak_arena());
    print_json(j);
    return;
  }
  std::printf("case: %s (%s), %zu upper and %zu lower picks\n", a.common.positional[0], c.case_id,
              c.upper.size(), c.lower.size());
  std::printf("base: %u sections x %u points: %zu vertices, %zu triangles, %.3f mm^3\n",
              report.sections, report.points_per_section, base.vertices.size(),
              base.triangles.size(), report.volume);
  std::printf(
      "checked: closed, edge-manifold, outward, no self-intersection (%llu candidate "
      "pairs tested)\n",
      static_cast<unsigned long long>(report.self_intersection_candidates));
  std::printf("output: %s (%s)\n", a.output, mesh_output_format(a.output, a.ascii));
  std::printf("time: build %.4f s, total %.4f s, peak arena: %llu bytes\n", r.t_build - r.t_parse,
              r.t_end - t0, static_cast<unsigned long long>(run.peak_arena()));
}

// ---- boolean ----------------------------------------------------------------------------------

struct BooleanArgs {
  CommonArgs common;
  int op = -1;  // kBooleanOps
  const char* output = nullptr;
  std::vector<Vec3> translate_b;
  bool ascii = false;
  bool self_check = true;
  uint64_t max_pairs = 0;  // BooleanOptions::max_candidate_pairs (0: its default)
};

constexpr BooleanOp kBooleanOps[] = {BooleanOp::kDifference, BooleanOp::kUnion,
                                     BooleanOp::kIntersection};

// `boolean`'s options, in the order its --help lists them.
std::vector<OptionSpec> boolean_options(BooleanArgs* a) {
  const char* one = "give one of --difference, --union, --intersection";
  return {
      one_of("--difference", &a->op, 0, "A minus B", one),
      one_of("--union", &a->op, 1, "A or B", one),
      one_of("--intersection", &a->op, 2, "A and B", one),
      output_option("OUT.stl", &a->output, "the result to write: STL (OUT.ply: binary PLY)"),
      point_list("--translate-b", "X,Y,Z", &a->translate_b,
                 "move B, mm: once for every B file, or once per B file",
                 "--translate-b needs X,Y,Z (three finite numbers, mm)"),
      flag("--ascii", &a->ascii, "write ASCII STL (default binary)"),
      clear_flag("--no-self-check", &a->self_check, "skip the self-intersection check"),
      count("--max-pairs", "N", &a->max_pairs, 1, UINT64_MAX,
            "the work bound: candidate triangle pairs in all (default 64 per triangle + 2^22)",
            "--max-pairs needs a whole number of pairs, at least 1"),
  };
}

// The move of B file f (1..): its --translate-b (one for every file, or one per file).
Vec3 b_move(const BooleanArgs& a, size_t f) {
  const std::vector<Vec3>& moves = a.translate_b;
  return moves.empty() ? Vec3{} : moves[moves.size() == 1 ? 0 : f - 1];
}

// B: the shells of every file after A, in order, in one mesh, each file moved by its
// --translate-b. The files are read into the arena one after the other, each cropped as it is
// read to `region` (boolean_region: where B matters to the Boolean; empty: everything) in the
// file's own frame (before its move), with a micrometre to spare for the move's rounding: the
// triangles beyond it are never welded or held (issue 29: most of the real dentition's 887k
// triangles are nowhere near the splint). Then B is made where they lie: the triangles
// (renumbered) go to a scratch copy above them, the vertices move down into one array, the
// triangles follow them. Peak: the files' meshes and B's triangles once more (appending file
// after file to two growing arrays moved them up again and again: four times B on the real
// dentition's 31 files). *file_triangles: the files' triangles, cropped or not.
Status read_b(Run& run, const BooleanArgs& a, const Aabb& region, Mesh* b,
              uint64_t* file_triangles) {
  Arena& arena = run.arena;
  const std::vector<const char*>& files = a.common.positional;
  const Arena::Marker start = arena.mark();
  std::vector<Mesh> parts(files.size() - 1, Mesh(&arena));
  std::vector<MeshFormat> formats(files.size() - 1);
  *file_triangles = 0;
  for (size_t f = 1; f < files.size(); ++f) {
    const Vec3 d = b_move(a, f);
    Aabb keep;
    if (!region.empty()) {
      const Vec3 spare{1e-3, 1e-3, 1e-3};
      keep = Aabb{region.lo - d - spare, region.hi - d + spare};
    }
    MeshFileInfo info;
    SPLINTCORE_RETURN_IF_ERROR(
        read_mesh_file(run.ctx, files[f], kNoInputLimit, false, &parts[f - 1], &info, keep));
    *file_triangles += info.triangles;
    formats[f - 1] = info.format;
  }
  uint64_t total_v = 0, total_t = 0;
  for (size_t f = 1; f < files.size(); ++f) {
    Mesh& part = parts[f - 1];
    total_v += part.vertices.size();
    total_t += part.triangles.size();
    if (total_v >= (uint64_t{1} << 31) || total_t >= (uint64_t{1} << 31)) {
      return Status::error(StatusCode::kLimitExceeded, "B is too large").in_file(files[f]);
    }
    const Vec3 d = b_move(a, f);
    // A moved jaw is rounded to float32, as its own STL would hold it: the Boolean keeps B's
    // vertices bit for bit, so they must be what the output file can store. A binary STL that
    // stays where it is holds them already (its floats, with no -0: the exact weld's +0.0).
    const bool unmoved = d.x == 0.0 && d.y == 0.0 && d.z == 0.0;
    if (unmoved && formats[f - 1] == MeshFormat::kStlBinary) continue;
    for (Vec3& v : part.vertices) {
      v = v + d;
      if (!round_to_float32(&v)) {
        return Status::error(StatusCode::kLimitExceeded,
                             "a translated vertex is beyond float32 range")
            .in_file(files[f]);
      }
    }
  }
  if (parts.size() == 1) {
    *b = parts[0];
    return Status::ok();
  }
  const size_t nv = static_cast<size_t>(total_v), nt = static_cast<size_t>(total_t);
  // (The gap: B's two arrays may take more alignment padding than the files' did.)
  uint8_t* gap = arena.allocate_array<uint8_t>(2 * Arena::kDefaultAlignment);
  Triangle* scratch = arena.allocate_array<Triangle>(nt > 0 ? nt : 1);
  if (gap == nullptr || scratch == nullptr) return arena.exhausted_status();
  size_t k = 0;
  uint32_t off = 0;
  for (const Mesh& p : parts) {
    for (const Triangle& t : p.triangles) {
      scratch[k++] = Triangle{{t.v[0] + off, t.v[1] + off, t.v[2] + off}};
    }
    off += static_cast<uint32_t>(p.vertices.size());
  }
  // Every file's arrays lie above the previous files' (both of them), so each file's vertices
  // move down (or stay) and never onto a later file's; B's two arrays end below the scratch.
  arena.rewind(start);
  Vec3* verts = arena.allocate_array<Vec3>(nv);
  Triangle* tris = arena.allocate_array<Triangle>(nt);
  SPLINTCORE_ASSERT((verts != nullptr || nv == 0) && (tris != nullptr || nt == 0));
  SPLINTCORE_ASSERT(nt == 0 || tris + nt <= scratch);
  size_t at = 0;
  for (const Mesh& p : parts) {
    if (!p.vertices.empty()) {
      std::memmove(static_cast<void*>(verts + at), p.vertices.data(),
                   p.vertices.size() * sizeof(Vec3));
    }
    at += p.vertices.size();
  }
  if (nt > 0) std::memcpy(static_cast<void*>(tris), scratch, nt * sizeof(Triangle));
  b->vertices.adopt(verts, nv, nv);
  b->triangles.adopt(tris, nt, nt);
  return Status::ok();
}

struct BooleanResult {
  uint64_t a_triangles = 0, b_triangles = 0;  // in the files
  uint64_t b_kept = 0;                        // B's as cropped (read_b)
  BooleanStats st;
  MeshReport report;
  double t_read = 0, t_op = 0, t_write = 0, t_check = 0, t_end = 0;  // (the write, then the check)
};

void print_boolean_json(const Run& run, const BooleanArgs& a, const BooleanResult& r) {
  const BooleanStats& st = r.st;
  const double t0 = run.start;
  JsonObject j;
  j.add("command", "boolean");
  j.add("operation", boolean_op_name(kBooleanOps[a.op]));
  j.add("a", a.common.positional[0]);
  j.add("output", a.output);
  j.add_status(Status::ok());
  j.add("a_triangles", r.a_triangles);
  j.add("b_triangles", r.b_triangles);
  j.add("b_triangles_kept", r.b_kept);
  j.add("near_b_triangles", st.near_b_triangles);
  j.add("candidate_pairs", st.candidate_pairs);
  j.add("intersecting_pairs", st.intersecting_pairs);
  j.add("degenerate_pairs", st.degenerate_pairs);
  j.add("intersection_points", st.intersection_points);
  j.add("cut_triangles_a", st.cut_triangles_a);
  j.add("cut_triangles_b", st.cut_triangles_b);
  j.add("winding_queries", st.winding_queries);
  j.add("attempts", static_cast<uint64_t>(st.attempts));
  j.add("nudge_mm", st.nudge);
  j.add("b_shells", static_cast<uint64_t>(st.shells));
  j.add("shell_groups", static_cast<uint64_t>(st.shell_groups));
  j.add("passes", static_cast<uint64_t>(st.passes));
  j.add("self_intersection_checked", a.self_check);
  add_mesh_report(&j, r.report);
  j.add("valid_solid", r.report.is_valid_solid());
  j.add("read_s", r.t_read - t0);
  j.add("boolean_s", r.t_op - r.t_read);
  j.add("self_check_s", r.t_check - r.t_write);
  j.add("write_s", (r.t_write - r.t_op) + (r.t_end - r.t_check));  // with the sync's wait
  j.add("time_s", r.t_end - t0);
  j.add("peak_arena_bytes", run.peak_arena());
  print_json(j);
}

void print_boolean_text(const Run& run, const BooleanArgs& a, const BooleanResult& r) {
  const BooleanStats& st = r.st;
  const double t0 = run.start;
  std::printf(
      "A: %s, %llu triangles; B: %zu file(s), %llu triangles (%llu kept as read, %llu near A)\n",
      a.common.positional[0], static_cast<unsigned long long>(r.a_triangles),
      a.common.positional.size() - 1, static_cast<unsigned long long>(r.b_triangles),
      static_cast<unsigned long long>(r.b_kept),
      static_cast<unsigned long long>(st.near_b_triangles));
  std::printf(
      "%s: %llu candidate pairs, %llu crossing, %llu touching exactly, %llu "
      "intersection points, %llu + %llu triangles cut, %u attempt(s)\n",
      boolean_op_name(kBooleanOps[a.op]), static_cast<unsigned long long>(st.candidate_pairs),
      static_cast<unsigned long long>(st.intersecting_pairs),
      static_cast<unsigned long long>(st.degenerate_pairs),
      static_cast<unsigned long long>(st.intersection_points),
      static_cast<unsigned long long>(st.cut_triangles_a),
      static_cast<unsigned long long>(st.cut_triangles_b), st.attempts);
  if (st.attempts > (st.passes > 0 ? st.passes : 1)) {  // attempts are summed over the passes
    std::printf(
        "A was nudged by (%.3g, %.3g, %.3g) mm out of a degenerate or float32-fragile "
        "configuration\n",
        st.nudge.x, st.nudge.y, st.nudge.z);
  }
  print_mesh_report(r.report);
  std::printf("self-intersection: %s\n", a.self_check ? "none (exact check)" : "not checked");
  std::printf("output: %s (%s)\n", a.output, mesh_output_format(a.output, a.ascii));
  std::printf(
      "time: read %.4f s, boolean %.4f s, check %.4f s, write %.4f s, total %.4f s; peak "
      "arena %llu bytes\n",
      r.t_read - t0, r.t_op - r.t_read, r.t_check - r.t_write,
      (r.t_write - r.t_op) + (r.t_end - r.t_check), r.t_end - t0,
      static_cast<unsigned long long>(run.peak_arena()));
}

// The Boolean's result, checked for self-intersections as float32 unless --no-self-check.
Status check_self_intersection(const Context& ctx, const Mesh& out) {
  SelfIntersectionReport si;
  SPLINTCORE_RETURN_IF_ERROR(find_self_intersections(ctx, out, 1, &si));
  if (si.self_intersecting()) {
    return make_error(StatusCode::kUnsupported,
                      "the result self-intersects as float32: "
                      "triangles ",
                      si.first_a, " and ", si.first_b, "; nothing written");
  }
  return Status::ok();
}

// ---- phantom ----------------------------------------------------------------------------------

struct PhantomArgs {
  CommonArgs common;
  uint64_t triangles = 0;
  const char* output = nullptr;
  bool scan = false;
  uint64_t seed = 1;
};

// `phantom`'s options, in the order its --help lists them.
std::vector<OptionSpec> phantom_options(PhantomArgs* a) {
  return {
      count("--triangles", "N", &a->triangles, 0, UINT64_MAX, "triangles per jaw, 2000..16000000",
            "--triangles needs a count"),
      output_option("DIR", &a->output, "the folder to write into"),
      flag("--scan", &a->scan, "open, scan-like jaws (STL and PLY with colours) instead"),
      count("--seed", "N", &a->seed, 0, UINT64_MAX, "where --scan places its defects (default 1)",
            "--seed needs a number"),
  };
}

// Writes DIR/NAME.stl for one jaw; `row` gets its JSON object, or `line` what prints its
// summary line (once the run's files are placed).
Status write_phantom_jaw(const PhantomArgs& a, int index, std::string* row,
                         std::function<void()>* line, cli::OutputSet* outputs) {
  const char* names[2] = {"maxilla", "mandible"};
  phantom::JawMesh jaw;
  phantom::PhantomOptions po;
  po.target_triangles = a.triangles;
  const phantom::Jaw which = index == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible;
  SPLINTCORE_RETURN_IF_ERROR(phantom::make_jaw(which, po, &jaw));
  std::vector<uint8_t> bytes;
  SPLINTCORE_RETURN_IF_ERROR(phantom::stl_bytes(jaw, &bytes));
  const std::string path = std::string(a.output) + "/" + names[index] + ".stl";
  SPLINTCORE_RETURN_IF_ERROR(write_bytes_atomically(path, bytes.data(), bytes.size(), outputs));
  const std::string hex = hex_sha256(bytes.data(), bytes.size());
  if (a.common.json) {
    JsonObject r;
    r.add("jaw", names[index]);
    r.add("file", path.c_str());
    r.add("triangles", static_cast<uint64_t>(jaw.triangles.size()));
    r.add("vertices", static_cast<uint64_t>(jaw.vertices.size()));
    r.add("sha256", hex);
    *row = r.str();
  } else {
    const char* name = names[index];
    const size_t triangles = jaw.triangles.size(), vertices = jaw.vertices.size();
    *line = [=] {
      std::printf("%s: %s, %zu triangles, %zu vertices, sha256 %s\n", name, path.c_str(), triangles,
                  vertices, hex.c_str());
    };
  }
  return Status::ok();
}

// Writes DIR/NAME_scan.stl and .ply for one scan-like jaw; `row` and `line` as above.
Status write_scan_jaw(const PhantomArgs& a, int index, std::string* row,
                      std::function<void()>* line, cli::OutputSet* outputs) {
  const char* names[2] = {"maxilla", "mandible"};
  phantom::ScanJaw jaw;
  phantom::ScanOptions so;
  so.seed = a.seed;
  const phantom::Jaw which = index == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible;
  SPLINTCORE_RETURN_IF_ERROR(phantom::make_scan_jaw(which, so, &jaw));
  const Mesh mesh = mesh_view(Span<const Vec3>(jaw.vertices.data(), jaw.vertices.size()),
                              Span<const Triangle>(jaw.triangles.data(), jaw.triangles.size()));
  std::string stl, ply;
  std::vector<uint8_t> memory(size_t{128} << 10);
  Arena arena(memory.data(), memory.size());  // write_stl's record buffer (64,000 bytes)
  SPLINTCORE_RETURN_IF_ERROR(
      write_stl(Context(&arena), mesh, cli::string_sink(&stl), StlWriteOptions{}));
  SPLINTCORE_RETURN_IF_ERROR(
      write_ply(mesh, Span<const uint8_t>(jaw.rgb.data(), jaw.rgb.size()), cli::string_sink(&ply)));
  const std::string base = std::string(a.output) + "/" + names[index] + "_scan";
  SPLINTCORE_RETURN_IF_ERROR(write_bytes_atomically(base + ".stl", stl, outputs));
  SPLINTCORE_RETURN_IF_ERROR(write_bytes_atomically(base + ".ply", ply, outputs));
  if (a.common.json) {
    JsonObject r;
    r.add("jaw", names[index]);
    r.add("stl", base + ".stl");
    r.add("ply", base + ".ply");
    r.add("triangles", static_cast<uint64_t>(jaw.triangles.size()));
    r.add("stl_sha256", hex_sha256(stl.data(), stl.size()));
    r.add("ply_sha256", hex_sha256(ply.data(), ply.size()));
    r.add("holes", jaw.holes);
    r.add("max_hole_edges", jaw.max_hole_edges);
    r.add("islands", jaw.islands);
    r.add("nonmanifold_edges", jaw.nonmanifold_edges);
    r.add("duplicate_triangles", jaw.duplicates);
    r.add("flipped_triangles", jaw.flipped_triangles);
    *row = r.str();
  } else {
    const char* name = names[index];
    const size_t triangles = jaw.triangles.size();
    *line = [name, base, triangles, holes = jaw.holes, edges = jaw.max_hole_edges,
             islands = jaw.islands, nonmanifold = jaw.nonmanifold_edges,
             duplicates = jaw.duplicates, flipped = jaw.flipped_triangles] {
      std::printf(
          "%s: %s.stl and .ply, %zu triangles; planted: %u holes (at most %u edges), %u islands, "
          "%u non-manifold edges, %u duplicate triangles, %u triangles wound the other way\n",
          name, base.c_str(), triangles, holes, edges, islands, nonmanifold, duplicates, flipped);
    };
  }
  return Status::ok();
}

// phantom --scan: both scan-like jaws.
int run_scan_phantom(const Command& command, const PhantomArgs& a) {
  const double t0 = monotonic_seconds();
  std::string rows;
  std::function<void()> lines[2];  // printed once the files are placed
  cli::OutputSet outputs;          // the four files placed together
  for (int j = 0; j < 2; ++j) {
    std::string row;
    const Status s = write_scan_jaw(a, j, &row, &lines[j], &outputs);
    if (!s.is_ok()) return rejected(a.common, command.name, s, nullptr);
    if (a.common.json) rows += (j > 0 ? "," : "") + row;
  }
  const Status placed = outputs.commit();
  if (!placed.is_ok()) return rejected(a.common, command.name, placed, nullptr);
  if (!a.common.json) {
    for (const std::function<void()>& print : lines) print();
    return kExitOk;
  }
  JsonObject j;
  j.add("command", "phantom");
  j.add_status(Status::ok());
  j.add("seed", a.seed);
  j.add_raw("scans", "[" + rows + "]");
  j.add("time_s", monotonic_seconds() - t0);
  print_json(j);
  return kExitOk;
}

}  // namespace

int run_base(const Command& command, int argc, char** argv) {
  BaseArgs a;
  CommandLine line(command, &a.common, base_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.size() != 1) return line.usage_error("base takes one case file");
  if (a.output == nullptr) return line.usage_error("base needs -o BASE.stl");
  const char* case_path = a.common.positional[0];
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();
  if (const Status out = check_mesh_output(a.output, a.ascii); !out.is_ok()) return run.reject(out);

  std::vector<uint8_t> text;
  Status s = read_whole_input(case_path, a.max_input_bytes, &text);
  if (!s.is_ok()) return run.reject(s);
  CaseFile c;
  s = parse_case(run.ctx, reinterpret_cast<const char*>(text.data()), text.size(), case_path, &c);
  if (!s.is_ok()) return run.reject(s);
  BaseResult r;
  r.t_parse = monotonic_seconds();
  Mesh base(&run.arena);
  s = build_case_base(run.ctx, c, &base, &r.report);
  if (!s.is_ok()) return run.reject(s.in_file(case_path));
  r.t_build = monotonic_seconds();
  s = write_mesh_atomically(run.ctx, base, a.output, a.ascii);
  if (!s.is_ok()) return run.reject(s);
  r.t_end = monotonic_seconds();
  print_base_report(run, a, c, base, r);
  return kExitOk;
}

int run_boolean(const Command& command, int argc, char** argv) {
  BooleanArgs a;
  CommandLine line(command, &a.common, boolean_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  const size_t files = a.common.positional.size();
  if (a.op < 0) return line.usage_error("boolean needs --difference, --union or --intersection");
  if (files < 2) return line.usage_error("boolean takes A.stl and at least one B.stl");
  if (a.output == nullptr) return line.usage_error("boolean needs -o OUT.stl");
  if (a.translate_b.size() > 1 && a.translate_b.size() != files - 1) {
    return line.usage_error("--translate-b: give it once, or once per B file");
  }
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();
  if (const Status out = check_mesh_output(a.output, a.ascii); !out.is_ok()) return run.reject(out);

  BooleanOptions bo;
  bo.max_candidate_pairs = a.max_pairs;
  bo.op = kBooleanOps[a.op];
  bo.check_self_intersection = false;  // timed separately below
  BooleanResult r;
  bo.result_report = &r.report;  // the result check's own edge pass makes the report
  const Arena::Marker a_start = run.arena.mark();
  Mesh ma(&run.arena), mb(&run.arena);
  Status s = read_mesh_file(run.ctx, a.common.positional[0], kNoInputLimit, false, &ma, nullptr);
  if (!s.is_ok()) return run.reject(s);
  const Arena::Marker b_start = run.arena.mark();
  // Where B matters; the union's is everywhere (infinite bounds): B is then read whole.
  Aabb region = boolean_region(ma, bo);
  if (!is_finite(region.lo) || !is_finite(region.hi)) region = Aabb{};
  s = read_b(run, a, region, &mb, &r.b_triangles);
  if (!s.is_ok()) return run.reject(s);
  r.t_read = monotonic_seconds();
  Mesh out;
  s = mesh_boolean(run.ctx, ma, mb, bo, &out, &r.st);
  if (!s.is_ok() && !region.empty() && s.code() != StatusCode::kArenaExhausted &&
      s.code() != StatusCode::kCancelled) {
    // B was read cropped to where it matters: the same solid as B whole (boolean_region), its
    // triangles in another order. A refusal is said as B whole says it, naming the files' own
    // vertices and loops (e.g. where an open B's border meets A): B read again whole.
    run.arena.rewind(b_start);
    mb = Mesh(&run.arena);
    out = Mesh();
    r.st = BooleanStats{};
    s = read_b(run, a, Aabb{}, &mb, &r.b_triangles);
    if (s.is_ok()) s = mesh_boolean(run.ctx, ma, mb, bo, &out, &r.st);
  }
  if (!s.is_ok()) return run.reject(s);
  r.a_triangles = ma.triangles.size();
  r.b_kept = mb.triangles.size();
  // A and B are done with: the result down over them, so that the checks' memory comes on
  // top of the result alone (the checks make the run's high water: the real dentition's
  // 4.6 MB of B is 4.6 MB less memory touched).
  Mesh low;
  move_mesh_down(run.arena, a_start, out, &low);
  out = low;
  r.t_op = monotonic_seconds();
  if (!r.st.result_report_made) s = check_mesh(run.ctx, out, &r.report);
  if (!s.is_ok()) return run.reject(s);
  // The file written and its fsync started before the self-intersection check, which runs
  // while the disk syncs; it is renamed into place only when the check passes (and removed
  // when it does not). A failed check is said before a failed write, as when the check came
  // first.
  AtomicFile file;
  const Status written = write_mesh_uncommitted(run.ctx, out, a.output, a.ascii, &file);
  if (written.is_ok()) s = file.sync_in_background();
  const Status synced = s;
  r.t_write = monotonic_seconds();
  s = a.self_check ? check_self_intersection(run.ctx, out) : Status::ok();
  r.t_check = monotonic_seconds();
  if (!s.is_ok()) {
    file.abort();
    return run.reject(s);
  }
  if (!written.is_ok()) return run.reject(written);
  if (!synced.is_ok()) return run.reject(synced);
  s = file.commit();
  if (!s.is_ok()) return run.reject(s);
  r.t_end = monotonic_seconds();
  if (a.common.json) {
    print_boolean_json(run, a, r);
  } else {
    print_boolean_text(run, a, r);
  }
  return kExitOk;
}

int run_phantom(const Command& command, int argc, char** argv) {
  PhantomArgs a;
  CommandLine line(command, &a.common, phantom_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (!a.common.positional.empty()) return line.usage_error("phantom takes no input file");
  if (a.output == nullptr) return line.usage_error("phantom needs -o DIR");
  ::mkdir(a.output, 0777);  // as design's OUTDIR: an existing folder is fine
  if (a.scan) {
    if (a.triangles != 0) return line.usage_error("phantom --scan takes no --triangles");
    return run_scan_phantom(command, a);
  }
  if (a.triangles < phantom::kMinTriangles || a.triangles > phantom::kMaxTriangles) {
    return line.usage_error("--triangles must be 2000..16000000");
  }
  const double t0 = monotonic_seconds();
  std::string rows;
  std::function<void()> lines[2];  // printed once the files are placed
  cli::OutputSet outputs;          // the jaws and the case placed together
  for (int j = 0; j < 2; ++j) {
    std::string row;
    const Status s = write_phantom_jaw(a, j, &row, &lines[j], &outputs);
    if (!s.is_ok()) return rejected(a.common, command.name, s, nullptr);
    if (a.common.json) rows += (j > 0 ? "," : "") + row;
  }
  // The case that goes with them (the paper-scale picks): design it with
  // `splintcore design DIR/case.json -o OUT`.
  const std::string text = phantom::case_json(("phantom-" + std::to_string(a.triangles)).c_str());
  const std::string path = std::string(a.output) + "/case.json";
  Status s = write_bytes_atomically(path, text, &outputs);
  if (s.is_ok()) s = outputs.commit();
  if (!s.is_ok()) return rejected(a.common, command.name, s, nullptr);
  if (!a.common.json) {
    for (const std::function<void()>& print : lines) print();
    std::printf("case: %s\n", path.c_str());
    return kExitOk;
  }
  JsonObject j;
  j.add("command", "phantom");
  j.add_status(Status::ok());
  j.add_raw("jaws", "[" + rows + "]");
  j.add("time_s", monotonic_seconds() - t0);
  print_json(j);
  return kExitOk;
}

}  // namespace tool
}  // namespace splintcore
