// `prepare` (issue 30): scan preparation (prepare_scan, mesh.h) from a file to an STL, the
// steps printed with their counts.
#include <string>
#include <vector>

#include "command.h"
#include "files.h"
#include "options.h"

namespace splintcore {
namespace tool {

namespace {

struct PrepareArgs {
  CommonArgs common;
  const char* output = nullptr;
  bool ascii = false;
  double min_island = PrepareOptions{}.min_island_area;
  uint64_t min_island_triangles = 0;
  uint64_t max_hole_edges = PrepareOptions{}.max_hole_edges;
  Vec3 occlusal{0, 0, 0};
};

// `prepare`'s options, in the order its --help lists them.
std::vector<OptionSpec> prepare_options(PrepareArgs* a) {
  return {
      output_option("OUT.stl", &a->output, "the prepared mesh: STL (OUT.ply: binary PLY)"),
      flag("--ascii", &a->ascii, "write ASCII STL (default binary)"),
      non_negative("--min-island", "MM2", &a->min_island,
                   "remove components under this area, mm^2 (default 10; the largest stays)",
                   "--min-island needs an area >= 0 (mm^2)"),
      count("--min-island-triangles", "N", &a->min_island_triangles, 0, UINT32_MAX,
            "count triangles instead: remove components of fewer than N",
            "--min-island-triangles needs a count"),
      count("--max-hole-edges", "N", &a->max_hole_edges, 0, UINT32_MAX,
            "fill holes of at most N boundary edges (default 32; 0: none)",
            "--max-hole-edges needs a count"),
      direction("--occlusal", "X,Y,Z", &a->occlusal,
                "turn the mesh so its net normal points this way (the crowns' side)",
                "--occlusal needs a non-zero direction X,Y,Z"),
  };
}

struct Step {
  const char* name;
  uint64_t count;
  const char* what;
};

// The steps in the order prepare_scan runs them.
std::vector<Step> steps_of(const PrepareReport& r) {
  return {
      {"duplicate_triangles", r.duplicate_triangles, "duplicate triangles removed"},
      {"degenerate_triangles", r.degenerate_triangles, "degenerate triangles removed"},
      {"nonmanifold_edges", r.nonmanifold_edges, "edges with 3+ triangles resolved"},
      {"nonmanifold_triangles", r.nonmanifold_triangles, "  triangles removed there"},
      {"nonmanifold_vertices", r.nonmanifold_vertices, "non-manifold vertices split"},
      {"split_vertices_added", r.split_vertices_added, "  vertices added"},
      {"islands", r.islands, "islands removed"},
      {"island_triangles", r.island_triangles, "  their triangles"},
      {"components", r.components, "  components kept"},
      {"flipped_triangles", r.flipped_triangles, "triangles turned (orientation)"},
      {"flipped_components", r.flipped_components, "  components turned whole"},
      {"orientation_conflicts", r.orientation_conflicts, "  edges left disagreeing"},
      {"holes_filled", r.holes_filled, "holes filled"},
      {"hole_triangles", r.hole_triangles, "  triangles added"},
      {"holes_left", r.holes_left, "  boundary loops left open (the border)"},
      {"unreferenced_vertices", r.unreferenced_vertices, "unused vertices removed"},
  };
}

void print_prepare(const Run& run, const PrepareArgs& a, const char* input, const PrepareReport& r,
                   const MeshReport& after) {
  const double seconds = monotonic_seconds() - run.start;
  if (a.common.json) {
    JsonObject j;
    j.add("command", "prepare");
    j.add("input", input);
    j.add("output", a.output);
    j.add_status(Status::ok());
    j.add("input_vertices", r.input_vertices);
    j.add("input_triangles", r.input_triangles);
    JsonObject steps;
    for (const Step& s : steps_of(r)) steps.add(s.name, s.count);
    j.add_raw("steps", steps.str());
    JsonObject result;
    add_mesh_report(&result, after);
    j.add_raw("result", result.str());
    j.add("time_s", seconds);
    j.add("peak_arena_bytes", run.peak_arena());
    print_json(j);
    return;
  }
  std::printf("input: %s (%llu vertices, %llu triangles)\n", input,
              static_cast<unsigned long long>(r.input_vertices),
              static_cast<unsigned long long>(r.input_triangles));
  int number = 0;
  for (const Step& s : steps_of(r)) {
    if (s.what[0] == ' ') {
      std::printf("     %-40s %llu\n", s.what + 2, static_cast<unsigned long long>(s.count));
    } else {
      std::printf("  %d. %-40s %llu\n", ++number, s.what, static_cast<unsigned long long>(s.count));
    }
  }
  print_mesh_report(after);
  std::printf("output: %s (%s)\n", a.output, mesh_output_format(a.output, a.ascii));
  run.print_time(seconds);
}

}  // namespace

int run_prepare(const Command& command, int argc, char** argv) {
  PrepareArgs a;
  CommandLine line(command, &a.common, prepare_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.size() != 1) return line.usage_error("prepare takes one input file");
  if (a.output == nullptr) return line.usage_error("prepare needs -o OUT.stl");
  const char* input = a.common.positional[0];
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();
  if (const Status out = check_mesh_output(a.output, a.ascii); !out.is_ok()) return run.reject(out);

  Mesh mesh(&run.arena);
  Status s = read_mesh_file(run.ctx, input, kNoInputLimit, false, &mesh, nullptr);
  if (!s.is_ok()) return run.reject(s);
  PrepareOptions po;
  po.min_island_area = a.min_island;
  po.min_island_triangles = static_cast<uint32_t>(a.min_island_triangles);
  po.max_hole_edges = static_cast<uint32_t>(a.max_hole_edges);
  po.occlusal = a.occlusal;
  Mesh out;
  PrepareReport r;
  s = prepare_scan(run.ctx, mesh, po, &out, &r);
  if (!s.is_ok()) return run.reject(s.in_file(input));
  MeshReport after;
  s = check_mesh(run.ctx, out, &after);
  if (s.is_ok()) s = write_mesh_atomically(run.ctx, out, a.output, a.ascii);
  if (!s.is_ok()) return run.reject(s);
  print_prepare(run, a, input, r, after);
  return kExitOk;
}

}  // namespace tool
}  // namespace splintcore
