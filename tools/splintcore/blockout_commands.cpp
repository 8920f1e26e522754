// Interference elimination (issue 6): the jaws' swept volume (sweep) and the splint minus it
// (blockout).
#include <string>
#include <vector>

#include "command.h"
#include "files.h"
#include "splintcore/blockout.h"

namespace splintcore {
namespace tool {

namespace {

// What sweep and blockout both take.
struct SweepArgs {
  CommonArgs common;
  const char* output = nullptr;
  Vec3 direction{0, 0, 1};
  bool has_direction = false;
  double voxel = 0;
  double extent = 0;
  double inset = -1;  // < 0: the command's default
  double closing = 0;
  bool ascii = false;
  bool self_check = true;  // blockout only
  bool exact = false;      // blockout only: the exact swept boundary, no voxels
};

// `sweep`'s options, or (`blockout` true) `blockout`'s, in the order their --help lists them.
std::vector<OptionSpec> sweep_options(SweepArgs* a, bool blockout) {
  std::vector<OptionSpec> specs = {
      direction("--direction", "X,Y,Z", &a->direction, "the insertion direction",
                "--direction needs X,Y,Z (three finite numbers, not all 0)")
          .marks(&a->has_direction),
      non_negative("--voxel", "H", &a->voxel, "the voxel size, mm (> 0)",
                   "--voxel needs a number of mm >= 0"),
      output_option(blockout ? "OUT.stl" : "SWEPT.stl", &a->output,
                    blockout ? "the STL to write (OUT.ply: binary PLY)" : "the STL to write"),
  };
  if (!blockout) {
    specs.push_back(non_negative("--extent", "E", &a->extent,
                                 "keep E mm past the jaws' far end (default 0)",
                                 "--extent needs a number of mm >= 0"));
  }
  specs.push_back(non_negative("--close", "R", &a->closing,
                               "close gaps narrower than 2R mm (R >= 2H; default 0: none)",
                               "--close needs a number of mm >= 0"));
  specs.push_back(non_negative("--inset", "D", &a->inset,
                               blockout ? "the swept surface D mm inside (default H / 2)"
                                        : "the surface D mm inside (0 <= D < 2H; default 0)",
                               "--inset needs a number of mm >= 0"));
  specs.push_back(flag("--ascii", &a->ascii, "write ASCII STL (default binary)"));
  if (blockout) {
    specs.push_back(
        clear_flag("--no-self-check", &a->self_check, "skip the self-intersection check"));
    specs.push_back(flag("--exact", &a->exact, "the exact swept boundary, no voxels"));
  }
  return specs;
}

// The usage errors sweep and blockout share, after their inputs are checked.
std::string sweep_usage_problem(const SweepArgs& a, const char* name, const char* output) {
  if (a.output == nullptr) return std::string(name) + " needs -o " + output;
  if (!a.has_direction) return std::string(name) + " needs --direction X,Y,Z";
  if (a.exact) {
    if (a.voxel > 0 || a.inset >= 0 || a.closing > 0) {
      return std::string(name) + " --exact has no voxels: no --voxel, --inset or --close";
    }
    return "";
  }
  if (!(a.voxel > 0)) return std::string(name) + " needs --voxel H (mm, > 0)";
  return "";
}

void add_sweep_stats(JsonObject* j, const SweepStats& st) {
  j->add("grid",
         std::to_string(st.nx) + " x " + std::to_string(st.ny) + " x " + std::to_string(st.nz));
  j->add("voxels", st.voxels);
  j->add("preroll_layers", static_cast<uint64_t>(st.preroll_layers));
  j->add("front_triangles", st.front_triangles);
  j->add("segment_tests", st.segment_tests);
  j->add("distance_evaluations", st.distance_evaluations);
  j->add("inside_columns", st.inside_columns);
  j->add("corrected_samples", st.corrected_samples);
  j->add("closing_samples", st.closing_samples);
  j->add("closed_samples", st.closed_samples);
  j->add("layers_per_tile", static_cast<uint64_t>(st.extraction.layers_per_tile));
  j->add("tiles", static_cast<uint64_t>(st.extraction.fill_calls));
  j->add("extractor_working_set_bytes", st.extraction.working_set_bytes);
}

struct SweepToStl {
  StlWriter* writer = nullptr;
  static Status triangle(void* user, const Triangle&, const Vec3& a, const Vec3& b, const Vec3& c) {
    return static_cast<SweepToStl*>(user)->writer->add(a, b, c);
  }
};

// The swept volume meshed straight into the STL file (never held whole), atomically.
Status sweep_to_file(const Context& ctx, const std::vector<Mesh>& jaws, const SweepOptions& so,
                     const SweepArgs& a, StlWriter* writer, SweepStats* st) {
  AtomicFile file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(a.output));
  StlWriteOptions wo;
  wo.format = a.ascii ? StlFormat::kAscii : StlFormat::kBinary;
  SPLINTCORE_RETURN_IF_ERROR(
      file.with_write_cause(writer->begin(ctx, file.sink(), wo, kUnknownSize)));
  SweepToStl to_stl{writer};
  MarchingCubesVisitor visitor;
  visitor.triangle = SweepToStl::triangle;
  visitor.user = &to_stl;
  SPLINTCORE_RETURN_IF_ERROR(file.with_write_cause(
      sweep_volume(ctx, Span<const Mesh>(jaws.data(), jaws.size()), so, visitor, st)));
  SPLINTCORE_RETURN_IF_ERROR(file.with_write_cause(writer->finish()));
  return file.commit();  // on any error ~AtomicFile removes the temporary file
}

void print_sweep_report(const Run& run, const SweepArgs& a, const std::vector<Mesh>& jaws,
                        const SweepStats& st, const StlWriter& writer, double inset, double t_read,
                        double t_end) {
  uint64_t jaw_triangles = 0;
  for (const Mesh& m : jaws) jaw_triangles += m.triangles.size();
  if (a.common.json) {
    JsonObject j;
    j.add("command", "sweep");
    j.add("output", a.output);
    j.add_status(Status::ok());
    j.add("jaw_files", static_cast<uint64_t>(jaws.size()));
    j.add("jaw_triangles", jaw_triangles);
    j.add("direction", st.axis_w);
    j.add("voxel_mm", a.voxel);
    j.add("extent_mm", a.extent);
    j.add("inset_mm", inset);
    j.add("closing_radius_mm", a.closing);
    add_sweep_stats(&j, st);
    j.add("triangles", writer.triangles_written());
    j.add("bytes", writer.bytes_written());
    j.add("read_s", t_read - run.start);
    j.add("sweep_s", t_end - t_read);
    j.add("time_s", t_end - run.start);
    j.add("peak_arena_bytes", run.peak_arena());
    print_json(j);
    return;
  }
  std::printf("jaws: %zu file(s), %llu triangles; direction (%.6g, %.6g, %.6g)\n", jaws.size(),
              static_cast<unsigned long long>(jaw_triangles), st.axis_w.x, st.axis_w.y,
              st.axis_w.z);
  std::printf("grid: %u x %u x %u = %llu voxels of %.4g mm, %u tile(s) of %u layer(s)\n", st.nx,
              st.ny, st.nz, static_cast<unsigned long long>(st.voxels), a.voxel,
              st.extraction.fill_calls, st.extraction.layers_per_tile);
  std::printf("swept volume: %llu triangles -> %s (%s STL)\n",
              static_cast<unsigned long long>(writer.triangles_written()), a.output,
              a.ascii ? "ascii" : "binary");
  std::printf("time: read %.4f s, sweep %.4f s; peak arena %llu bytes\n", t_read - run.start,
              t_end - t_read, static_cast<unsigned long long>(run.peak_arena()));
}

// The jaw files as one mesh, in file order (vertex ids offset by the files before).
Status join_meshes(const Context& ctx, const std::vector<Mesh>& meshes, Mesh* out) {
  out->bind(ctx.arena);
  uint64_t nv = 0, nt = 0;
  for (const Mesh& m : meshes) {
    nv += m.vertices.size();
    nt += m.triangles.size();
  }
  if (nv > 0xffffffffu) {
    return make_error(StatusCode::kLimitExceeded, "blockout --exact: the jaw files have ", nv,
                      " vertices together (at most 2^32 - 1)");
  }
  if (!out->vertices.reserve(static_cast<size_t>(nv)) ||
      !out->triangles.reserve(static_cast<size_t>(nt))) {
    return ctx.arena->exhausted_status();
  }
  for (const Mesh& m : meshes) {
    const uint32_t base = static_cast<uint32_t>(out->vertices.size());
    for (const Vec3& v : m.vertices) (void)out->vertices.push_back(v);
    for (const Triangle& t : m.triangles) {
      (void)out->triangles.push_back(Triangle{{t.v[0] + base, t.v[1] + base, t.v[2] + base}});
    }
  }
  return Status::ok();
}

struct BlockoutResult {
  BlockoutStats st;
  MeshReport report;
  double inset = 0, removed = 0;
  size_t splint_triangles = 0, jaw_files = 0;
  double t_read = 0, t_op = 0, t_end = 0;
};

void print_blockout_json(const Run& run, const SweepArgs& a, const BlockoutResult& r) {
  const BlockoutStats& st = r.st;
  JsonObject j;
  j.add("command", "blockout");
  j.add("splint", a.common.positional[0]);
  j.add("output", a.output);
  j.add_status(Status::ok());
  if (a.exact) {
    const ExactSweepStats& e = st.exact;
    j.add("method", "exact");
    j.add("direction", e.direction);
    j.add("front_triangles", e.front_triangles);
    j.add("kept_front_triangles", e.kept_triangles);
    j.add("walls", e.walls);
    j.add("fold_vertices", e.fold_vertices);
    j.add("back_triangles_taken_in", e.absorbed_triangles);
    j.add("fold_pockets_clear_of_splint", e.pockets_clear);
    j.add("shells_checked", e.shells);
    j.add("swept_triangles", st.swept_triangles);
  } else {
    j.add("method", "voxel");
    j.add("direction", st.sweep.axis_w);
    j.add("voxel_mm", a.voxel);
    j.add("inset_mm", r.inset);
    j.add("closing_radius_mm", a.closing);
    add_sweep_stats(&j, st.sweep);
    j.add("swept_triangles", st.swept_triangles);
    j.add("cap_triangles_dropped", st.sweep.cap_triangles_dropped);
  }
  j.add("intersecting_pairs", st.boolean.intersecting_pairs);
  j.add("removed_volume_mm3", r.removed);
  add_mesh_report(&j, r.report);
  j.add("valid_solid", r.report.is_valid_solid());
  j.add("read_s", r.t_read - run.start);
  j.add("blockout_s", r.t_op - r.t_read);
  j.add("time_s", r.t_end - run.start);
  j.add("peak_arena_bytes", run.peak_arena());
  print_json(j);
}

void print_blockout_text(const Run& run, const SweepArgs& a, const BlockoutResult& r) {
  const BlockoutStats& st = r.st;
  std::printf("splint: %s, %zu triangles; jaws: %zu file(s)\n", a.common.positional[0],
              r.splint_triangles, r.jaw_files);
  if (a.exact) {
    std::printf(
        "swept volume (exact): %llu of %llu front triangles kept, %llu walls, %llu fold "
        "vertices, %llu triangles\n",
        static_cast<unsigned long long>(st.exact.kept_triangles),
        static_cast<unsigned long long>(st.exact.front_triangles),
        static_cast<unsigned long long>(st.exact.walls),
        static_cast<unsigned long long>(st.exact.fold_vertices),
        static_cast<unsigned long long>(st.swept_triangles));
    std::printf("removed: %.4f mm^3 of interference\n", r.removed);
  } else {
    std::printf(
        "swept volume: grid %u x %u x %u of %.4g mm (+%u layers before the splint), "
        "%llu triangles in the splint's bounds\n",
        st.sweep.nx, st.sweep.ny, st.sweep.nz, a.voxel, st.sweep.preroll_layers,
        static_cast<unsigned long long>(st.swept_triangles));
    std::printf("removed: %.4f mm^3 of interference (inset %.4g mm)\n", r.removed, r.inset);
  }
  print_mesh_report(r.report);
  std::printf("output: %s (%s)\n", a.output, mesh_output_format(a.output, a.ascii));
  std::printf("time: read %.4f s, blockout %.4f s, total %.4f s; peak arena %llu bytes\n",
              r.t_read - run.start, r.t_op - r.t_read, r.t_end - run.start,
              static_cast<unsigned long long>(run.peak_arena()));
}

}  // namespace

int run_sweep(const Command& command, int argc, char** argv) {
  SweepArgs a;
  CommandLine line(command, &a.common, sweep_options(&a, false));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.empty()) return line.usage_error("sweep takes at least one JAW.stl");
  const std::string problem = sweep_usage_problem(a, "sweep", "SWEPT.stl");
  if (!problem.empty()) return line.usage_error(problem);
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();
  if (const Status out = check_mesh_output(a.output, a.ascii, true); !out.is_ok())
    return run.reject(out);

  std::vector<Mesh> jaws;
  Status s = read_mesh_files(run.ctx, a.common.positional, kNoInputLimit, false, &jaws, nullptr);
  if (!s.is_ok()) return run.reject(s);
  const double t_read = monotonic_seconds();
  SweepOptions so;
  so.direction = a.direction;
  so.voxel = a.voxel;
  so.extent = a.extent;
  so.inset = a.inset < 0 ? 0 : a.inset;
  so.closing_radius = a.closing;
  StlWriter writer;
  SweepStats st;
  s = sweep_to_file(run.ctx, jaws, so, a, &writer, &st);
  if (!s.is_ok()) return run.reject(s);
  print_sweep_report(run, a, jaws, st, writer, so.inset, t_read, monotonic_seconds());
  return kExitOk;
}

int run_blockout(const Command& command, int argc, char** argv) {
  SweepArgs a;
  CommandLine line(command, &a.common, sweep_options(&a, true));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  const std::vector<const char*>& files = a.common.positional;
  if (files.size() < 2) {
    return line.usage_error("blockout takes SPLINT.stl and at least one JAW.stl");
  }
  const std::string problem = sweep_usage_problem(a, "blockout", "OUT.stl");
  if (!problem.empty()) return line.usage_error(problem);
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();
  if (const Status out = check_mesh_output(a.output, a.ascii); !out.is_ok()) return run.reject(out);

  Mesh splint(&run.arena);
  std::vector<Mesh> jaws;
  Status s = read_mesh_file(run.ctx, files[0], kNoInputLimit, false, &splint, nullptr);
  if (s.is_ok()) {
    s = read_mesh_files(run.ctx, std::vector<const char*>(files.begin() + 1, files.end()),
                        kNoInputLimit, false, &jaws, nullptr);
  }
  if (!s.is_ok()) return run.reject(s);
  BlockoutResult r;
  r.t_read = monotonic_seconds();
  BlockoutOptions bo;
  bo.sweep.direction = a.direction;
  bo.boolean.check_self_intersection = a.self_check;
  bo.exact = a.exact;
  if (!a.exact) {
    bo.sweep.voxel = a.voxel;
    bo.sweep.inset = a.inset < 0 ? 0.5 * a.voxel : a.inset;
    bo.sweep.closing_radius = a.closing;
  }
  // The exact sweep takes one jaw: the files joined (each file's closed shells stay shells).
  Mesh joined;
  if (a.exact) s = join_meshes(run.ctx, jaws, &joined);
  if (!s.is_ok()) return run.reject(s);
  Mesh out;
  s = a.exact
          ? blockout(run.ctx, splint, Span<const Mesh>(&joined, 1), bo, &out, &r.st)
          : blockout(run.ctx, splint, Span<const Mesh>(jaws.data(), jaws.size()), bo, &out, &r.st);
  if (!s.is_ok()) return run.reject(s);
  r.t_op = monotonic_seconds();
  s = check_mesh(run.ctx, out, &r.report);
  if (s.is_ok()) s = write_mesh_atomically(run.ctx, out, a.output, a.ascii);
  if (!s.is_ok()) return run.reject(s);
  r.t_end = monotonic_seconds();
  r.inset = bo.sweep.inset;
  r.removed = mesh_volume(splint) - r.report.volume;
  r.splint_triangles = splint.triangles.size();
  r.jaw_files = jaws.size();
  if (a.common.json) {
    print_blockout_json(run, a, r);
  } else {
    print_blockout_text(run, a, r);
  }
  return kExitOk;
}

}  // namespace tool
}  // namespace splintcore
