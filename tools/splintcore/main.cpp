// splintcore: the command-line program. One subcommand per stage of the method; each takes
// --help, --json, --memory-cap SIZE and --threads N, exits 0 on success, 1 when the input is
// rejected (or a check fails, or the memory cap is too small), 2 on a usage error.
#include <sys/stat.h>
#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "../common/cli.h"
#include "../common/compare.h"
#include "../common/ct_files.h"
#include "../common/ct_phantom.h"
#include "../common/ct_write.h"
#include "../common/phantom.h"
#include "../common/preview.h"
#include "splintcore/blockout.h"
#include "splintcore/boolean.h"
#include "splintcore/core.h"
#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "splintcore/platform.h"
#include "splintcore/printer.h"
#include "splintcore/remesh.h"
#include "splintcore/segment.h"

namespace splintcore {
namespace {

using cli::JsonObject;
using cli::kExitOk;
using cli::kExitRejected;
using cli::kExitUsage;

constexpr uint64_t kDefaultMemoryCap = uint64_t{1} << 30;

// The general text of `splintcore --help`; the list of commands comes from kCommands.
const char kUsageHead[] = "usage: splintcore <command> [options]\n\ncommands:\n";
const char kUsageTail[] =
    "\n"
    "options of every command:\n"
    "  --help            this text for the command\n"
    "  --json            one JSON object on stdout with every figure\n"
    "  --memory-cap SIZE arena cap, e.g. 64M or 2G (default 1G)\n"
    "  --threads N       worker threads (default 1; results are identical for any N)\n"
    "\n"
    "mesh inputs may be STL (binary or ASCII), PLY (ASCII or binary) or OBJ, told apart by\n"
    "their content (then the file extension); PLY and OBJ polygons are fan-triangulated.\n"
    "\n"
    "exit status: 0 success, 1 input rejected or check failed, 2 usage error\n";

const char kCheckUsage[] =
    "usage: splintcore check IN.stl [--printer NAME] [--no-place] [--json]\n"
    "                       [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "Reads a binary or ASCII STL, welds identical vertices and reports: closed, edge-manifold,\n"
    "consistently and outward oriented, degenerate and duplicate triangles, shells, genus,\n"
    "area, volume, extent, and whether it fits the printer's build volume (centred on the\n"
    "tray unless --no-place). Exit 0 only when the mesh is printable.\n"
    "Printers: eden260 (Stratasys Eden260-class PolyJet, 255 x 252 x 200 mm, 16 um layers).\n";

const char kConvertUsage[] =
    "usage: splintcore convert IN.stl -o OUT.stl [--ascii] [--json]\n"
    "                         [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "Reads a binary or ASCII STL, welds identical vertices, checks it, and writes it through\n"
    "the streaming writer (binary unless --ascii). The output is written atomically: on any\n"
    "error no output file is left behind. The bytes depend only on the input's triangles.\n";

const char kBaseUsage[] =
    "usage: splintcore base CASE.json -o BASE.stl [--ascii] [--json]\n"
    "                      [--memory-cap SIZE] [--threads N] [--max-input-bytes SIZE]\n"
    "\n"
    "Builds the initial splint base of the case (Chen et al. 2016): each pick becomes a line\n"
    "(inner and outside point), centripetal Catmull-Rom splines run through the line ends,\n"
    "and ruled surfaces between sections sampled at matched arc length form one closed solid.\n"
    "The base is checked (closed, manifold, outward, no self-intersection, as float32) before\n"
    "it is written, atomically. The case format is in docs/case-format.md.\n"
    "--max-input-bytes SIZE refuses a larger case file (default 16M).\n";

const char kDistanceUsage[] =
    "usage: splintcore distance MESH.stl --query X,Y,Z [--query X,Y,Z ...]\n"
    "                          [--sign auto|pseudonormal|winding] [--json]\n"
    "                          [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "Builds the distance index (a BVH) over the mesh and prints, per query point (mm): the\n"
    "closest point, its triangle and feature (face, edge or vertex), the unsigned and signed\n"
    "distance (negative inside) and the generalised winding number. --sign auto uses\n"
    "pseudonormals on a closed manifold mesh and the winding number otherwise.\n";

const char kBooleanUsage[] =
    "usage: splintcore boolean --difference|--union|--intersection A.stl B.stl [B2.stl ...]\n"
    "                         -o OUT.stl [--translate-b X,Y,Z] [--ascii] [--no-self-check]\n"
    "                         [--json] [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "A is a closed solid (the splint base); B is the union of the other files' shells (the\n"
    "jaws: one closed shell per tooth is fine; shells that overlap are united, one pass per\n"
    "group of shells that do not overlap, as --json's shell_groups and passes say),\n"
    "translated by --translate-b (mm; given once it moves every B file, given once per B file\n"
    "it moves each in order: e.g. 0,0,0 then 0,0,-2 opens the bite; moved vertices are rounded\n"
    "to float32, as a moved jaw's STL would hold them). Both are split along\n"
    "their intersection with exact predicates, re-triangulated, classified and assembled; the\n"
    "jaw's own triangles form the imprint, its vertices copied bit for bit. The result is\n"
    "checked as float32 (closed, manifold, outward, no vertex merged or triangle flattened by\n"
    "rounding, and, unless --no-self-check, no self-intersection) before it is written,\n"
    "atomically. Exact degenerate contacts (a vertex on the other surface, edges crossing\n"
    "exactly, coplanar faces) are resolved exactly; where the exact result is not a manifold\n"
    "solid (e.g. parts touching along an edge), A is nudged by at most about 1 um and the\n"
    "summary says so.\n";

const char kPhantomUsage[] =
    "usage: splintcore phantom --triangles N -o DIR [--json]\n"
    "\n"
    "Writes DIR/maxilla.stl and DIR/mandible.stl: synthetic dental-arch jaws (a gum ridge and\n"
    "14 big-end-up crowns with cusps each, one closed genus-0 shell per jaw, float32-exact), N\n"
    "triangles per jaw (2000..16000000, within 1%), in occlusion, in the frame of\n"
    "fixtures/cases/paper_scale.json: with that case's mandible transform (2 mm down) its base\n"
    "cuts 1.3-1.5 mm into every crown. Also DIR/case.json, that case for these jaws (design\n"
    "it with `splintcore design DIR/case.json -o OUT`). The bytes depend only on N.\n";

const char kDesignUsage[] =
    "usage: splintcore design CASE.json -o OUTDIR [--json] [--memory-cap SIZE] [--threads N]\n"
    "                        [--max-input-bytes SIZE]\n"
    "\n"
    "Runs the method on a case file (docs/case-format.md): reads the jaws it names (paths\n"
    "relative to the case file), moves each by its transform (rounded to float32, as a moved\n"
    "jaw's STL holds it), builds the base from the picks, subtracts the jaws (exact Boolean),\n"
    "checks the result for the case's printer, and writes OUTDIR/splint.stl (or the case's\n"
    "output.splint) and OUTDIR/report.json (or output.report), each atomically. The report holds\n"
    "what an auditor needs to reproduce the run: library version, SHA-256 of the case and of\n"
    "every input, every parameter as used, each stage's time, the peak arena, each check, and\n"
    "the splint's SHA-256. Progress goes to stderr when it is a terminal. With a \"blockout\"\n"
    "object in the case, each jaw's interference (undercut) is removed after the Boolean\n"
    "(see `splintcore blockout --help`), reported per jaw. A jaw may instead come from the\n"
    "case's CT volume (\"ct\" and a seed per jaw: see `splintcore reconstruct --help`).\n"
    "--max-input-bytes SIZE refuses a larger case or jaw file (defaults: 16M for the case,\n"
    "2G for a jaw mesh).\n"
    "Exit status: 0 splint written, 1 rejected (the message names the stage), 2 usage.\n";

const char kSweepUsage[] =
    "usage: splintcore sweep JAW.stl [JAW2.stl ...] --direction X,Y,Z --voxel H -o SWEPT.stl\n"
    "                       [--extent E] [--close R] [--inset D] [--ascii] [--json]\n"
    "                       [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "The blocked-out (temporary) model of interference elimination (Chen et al. 2016): every\n"
    "point the jaws pass through as they move along the direction (the splint's insertion\n"
    "direction), kept E mm past the jaws' far end (default 0) and closed there. Sampled on a\n"
    "grid of H mm voxels whose third axis is the direction, swept layer by layer with a 2-D\n"
    "state (exact distance outside, extrapolated inside: no inward bias), optionally closed\n"
    "morphologically with a ball of radius R mm (fills gaps narrower than 2R; R >= 2H), and\n"
    "meshed by the tiled extractor straight into the STL file (never held whole), atomically.\n"
    "--inset D extracts the surface D mm inside (0 <= D < 2H). The bytes are the same for any\n"
    "memory cap that suffices and any thread count.\n";

const char kBlockoutUsage[] =
    "usage: splintcore blockout SPLINT.stl JAW.stl [JAW2.stl ...] --direction X,Y,Z --voxel H\n"
    "                          -o OUT.stl [--close R] [--inset D] [--ascii] [--no-self-check]\n"
    "                          [--json] [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "Interference elimination: the splint minus the jaws' swept volume along the direction\n"
    "(as `sweep`, cut to the splint's bounds), subtracted by the exact Boolean and checked\n"
    "(closed, manifold, outward, float32, no self-intersection unless --no-self-check) before\n"
    "it is written, atomically. The direction is the one the splint is seated along for these\n"
    "jaws (for a wafer: the maxilla's is the mandible's reversed; run once per jaw). The swept\n"
    "surface is taken --inset D mm inside (default H / 2): the splint already holds the jaw's\n"
    "imprint, which the swept volume reproduces to within the voxel error, and the inset keeps\n"
    "the two apart; at most D of undercut is left.\n";

struct Options {
  bool help = false;
  bool json = false;
  uint64_t memory_cap = kDefaultMemoryCap;
  bool memory_cap_given = false;  // --memory-cap on the command line (it overrides a case's)
  uint64_t max_input_bytes = 0;   // 0: cli::kMaxCaseBytes for cases, cli::kMaxMeshBytes for meshes
  unsigned threads = 1;
  std::vector<const char*> positional;
  const char* output = nullptr;
  const char* printer = "eden260";
  bool ascii = false;
  bool place = true;
  std::vector<Vec3> queries;
  SignMethod sign = SignMethod::kAuto;
  int boolean_op = -1;
  uint64_t triangles = 0;
  bool self_check = true;
  std::vector<Vec3> translate_b;
  Vec3 direction{0, 0, 1};
  bool has_direction = false;
  double voxel = 0;
  double extent = 0;
  double inset = -1;  // < 0: the command's default
  double closing = 0;
};

// "X,Y,Z" -> a point; false when malformed or not finite.
bool parse_point(const char* text, Vec3* out) {
  const char* p = text;
  for (int a = 0; a < 3; ++a) {
    const char* end = p;
    while (*end != '\0' && *end != ',') ++end;
    double value = 0;
    auto r = std::from_chars(p, end, value);
    if (r.ec != std::errc() || r.ptr != end || !is_finite(value)) return false;
    (*out)[a] = value;
    if (a < 2) {
      if (*end != ',') return false;
      p = end + 1;
    } else if (*end != '\0') {
      return false;
    }
  }
  return true;
}

int usage_error(const char* message, const char* usage) {
  std::fprintf(stderr, "splintcore: %s\n\n%s", message, usage);
  return kExitUsage;
}

// Parses argv after the command name. Returns -1 to go on, or an exit code.
int parse_options(int argc, char** argv, const char* usage, bool takes_output, Options* o) {
  for (int i = 0; i < argc; ++i) {
    const char* a = argv[i];
    auto value = [&](const char* name) -> const char* {
      if (i + 1 >= argc) return nullptr;
      (void)name;
      return argv[++i];
    };
    if (std::strcmp(a, "--help") == 0 || std::strcmp(a, "-h") == 0) {
      o->help = true;
    } else if (std::strcmp(a, "--json") == 0) {
      o->json = true;
    } else if (std::strcmp(a, "--memory-cap") == 0) {
      const char* v = value(a);
      if (v == nullptr || !cli::parse_size(v, &o->memory_cap) || o->memory_cap == 0) {
        return usage_error("--memory-cap needs a size such as 64M, 2G or 1048576", usage);
      }
      if (o->memory_cap > (uint64_t{1} << 40)) {
        return usage_error("--memory-cap is over 1T", usage);
      }
      o->memory_cap_given = true;
    } else if (std::strcmp(a, "--max-input-bytes") == 0) {
      const char* v = value(a);
      if (v == nullptr || !cli::parse_size(v, &o->max_input_bytes) || o->max_input_bytes == 0) {
        return usage_error("--max-input-bytes needs a size such as 16M, 2G or 1048576", usage);
      }
    } else if (std::strcmp(a, "--threads") == 0) {
      const char* v = value(a);
      uint64_t n = 0;
      if (v == nullptr || !cli::parse_unsigned(v, &n) || n == 0 || n > 64) {
        return usage_error("--threads needs a number from 1 to 64", usage);
      }
      o->threads = static_cast<unsigned>(n);
    } else if (takes_output && (std::strcmp(a, "-o") == 0 || std::strcmp(a, "--output") == 0)) {
      o->output = value(a);
      if (o->output == nullptr) return usage_error("-o needs a file name", usage);
    } else if (std::strcmp(a, "--printer") == 0) {
      o->printer = value(a);
      if (o->printer == nullptr) return usage_error("--printer needs a name", usage);
    } else if (std::strcmp(a, "--ascii") == 0 && takes_output) {
      o->ascii = true;
    } else if (std::strcmp(a, "--no-place") == 0) {
      o->place = false;
    } else if (std::strcmp(a, "--query") == 0) {
      const char* v = value(a);
      Vec3 q;
      if (v == nullptr || !parse_point(v, &q)) {
        return usage_error("--query needs X,Y,Z (three finite numbers, mm)", usage);
      }
      o->queries.push_back(q);
    } else if (std::strcmp(a, "--sign") == 0) {
      const char* v = value(a);
      if (v != nullptr && std::strcmp(v, "auto") == 0) {
        o->sign = SignMethod::kAuto;
      } else if (v != nullptr && std::strcmp(v, "pseudonormal") == 0) {
        o->sign = SignMethod::kPseudonormal;
      } else if (v != nullptr && std::strcmp(v, "winding") == 0) {
        o->sign = SignMethod::kWindingNumber;
      } else {
        return usage_error("--sign takes auto, pseudonormal or winding", usage);
      }
    } else if (std::strcmp(a, "--difference") == 0 || std::strcmp(a, "--union") == 0 ||
               std::strcmp(a, "--intersection") == 0) {
      const int op = a[2] == 'd' ? 0 : (a[2] == 'u' ? 1 : 2);
      if (o->boolean_op >= 0 && o->boolean_op != op) {
        return usage_error("give one of --difference, --union, --intersection", usage);
      }
      o->boolean_op = op;
    } else if (std::strcmp(a, "--triangles") == 0) {
      const char* v = value(a);
      if (v == nullptr || !cli::parse_unsigned(v, &o->triangles)) {
        return usage_error("--triangles needs a count", usage);
      }
    } else if (std::strcmp(a, "--no-self-check") == 0) {
      o->self_check = false;
    } else if (std::strcmp(a, "--translate-b") == 0) {
      const char* v = value(a);
      Vec3 d;
      if (v == nullptr || !parse_point(v, &d)) {
        return usage_error("--translate-b needs X,Y,Z (three finite numbers, mm)", usage);
      }
      o->translate_b.push_back(d);
    } else if (std::strcmp(a, "--direction") == 0) {
      const char* v = value(a);
      if (v == nullptr || !parse_point(v, &o->direction) || length(o->direction) == 0) {
        return usage_error("--direction needs X,Y,Z (three finite numbers, not all 0)", usage);
      }
      o->has_direction = true;
    } else if (std::strcmp(a, "--voxel") == 0 || std::strcmp(a, "--extent") == 0 ||
               std::strcmp(a, "--inset") == 0 || std::strcmp(a, "--close") == 0) {
      const char* v = value(a);
      double x = 0;
      const char* end = v == nullptr ? nullptr : v + std::strlen(v);
      if (v == nullptr || std::from_chars(v, end, x).ptr != end || !is_finite(x) || x < 0) {
        std::string m = std::string(a) + " needs a number of mm >= 0";
        return usage_error(m.c_str(), usage);
      }
      double* field = a[2] == 'v'   ? &o->voxel
                      : a[2] == 'e' ? &o->extent
                      : a[2] == 'i' ? &o->inset
                                    : &o->closing;
      *field = x;
    } else if (a[0] == '-' && a[1] != '\0') {
      std::string m = std::string("unknown option '") + a + "'";
      return usage_error(m.c_str(), usage);
    } else {
      o->positional.push_back(a);
    }
  }
  if (o->help) {
    std::fputs(usage, stdout);
    return kExitOk;
  }
  return -1;
}

// The arena for a run: one block of the cap, committed by the OS only as it is touched.
// 16-byte aligned (Arena::kDefaultAlignment): malloc gives only 8 on 32-bit ARM, which would
// shift the arena's padding and its reported figures.
struct RunMemory {
  void* buffer = nullptr;
  explicit RunMemory(uint64_t cap) {
    const uint64_t rounded = (cap + 15) / 16 * 16;
    buffer = std::aligned_alloc(16, static_cast<size_t>(rounded));
  }
  ~RunMemory() { std::free(buffer); }
};

// What every subcommand runs with: the arena, the thread pool, the context, the start time.
struct Run {
  RunMemory memory;
  Arena arena;
  ThreadExecutor threads;
  Context ctx;
  double start;
  explicit Run(const Options& o)
      : memory(o.memory_cap),
        arena(memory.buffer, memory.buffer != nullptr ? static_cast<size_t>(o.memory_cap) : 0),
        threads(o.threads),
        ctx(&arena, &threads.executor(), nullptr),
        start(monotonic_seconds()) {}
  bool has_memory() const { return memory.buffer != nullptr; }
};

// Reads a mesh file (STL binary or ASCII, PLY, OBJ: by content, then extension) into a mesh
// welded exactly (read_mesh with weld: PLY and OBJ meshes hold the same vertices as their STL
// would). `info` gets ascii/binary, the triangle count, the bytes read and, in `header`, the
// format (mesh_format_name).
Status read_mesh_file(const Context& ctx, const char* path, Mesh* mesh, StlInfo* info) {
  FileSource file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(path));
  MeshReadOptions options;
  options.weld = true;
  MeshReadInfo read;
  SPLINTCORE_RETURN_IF_ERROR(read_mesh(ctx, file.source(), options, mesh, &read));
  if (info != nullptr) {
    *info = StlInfo{};
    const bool text = read.format == MeshFormat::kStlAscii ||
                      read.format == MeshFormat::kPlyAscii || read.format == MeshFormat::kObj;
    info->format = text ? StlFormat::kAscii : StlFormat::kBinary;
    info->triangles = read.triangles;
    info->bytes = read.bytes;
    std::snprintf(info->header, sizeof(info->header), "%s", mesh_format_name(read.format));
  }
  return Status::ok();
}

// Writes a mesh through the streaming writer into a temporary file renamed over `path` only
// when everything succeeded.
Status write_atomically(const Context& ctx, const Mesh& mesh, const char* path, bool ascii) {
  AtomicFile out;
  SPLINTCORE_RETURN_IF_ERROR(out.open(path));
  StlWriteOptions wo;
  wo.format = ascii ? StlFormat::kAscii : StlFormat::kBinary;
  SPLINTCORE_RETURN_IF_ERROR(write_stl(ctx, mesh, out.sink(), wo));  // ~AtomicFile cleans up
  return out.commit();
}

void add_mesh_report(JsonObject* j, const MeshReport& r) {
  j->add("vertices", r.vertex_count);
  j->add("triangles", r.triangle_count);
  j->add("edges", r.edge_count);
  j->add("boundary_edges", r.boundary_edges);
  j->add("nonmanifold_edges", r.nonmanifold_edges);
  j->add("orientation_conflicts", r.orientation_conflicts);
  j->add("degenerate_triangles", r.degenerate_triangles);
  j->add("duplicate_triangles", r.duplicate_triangles);
  j->add("unreferenced_vertices", r.unreferenced_vertices);
  j->add("shells", r.shells);
  j->add("euler_characteristic", r.euler_characteristic);
  j->add("genus", r.genus);
  j->add("closed", r.closed());
  j->add("edge_manifold", r.edge_manifold());
  j->add("oriented", r.oriented());
  j->add("outward", r.outward());
  j->add("area_mm2", r.area);
  j->add("volume_mm3", r.volume);
  j->add("bounds_min_mm", r.bounds.lo);
  j->add("bounds_max_mm", r.bounds.hi);
}

void print_mesh_report(const MeshReport& r) {
  std::printf("mesh: %llu vertices, %llu triangles, %llu edges, %llu shell(s), genus %lld\n",
              static_cast<unsigned long long>(r.vertex_count),
              static_cast<unsigned long long>(r.triangle_count),
              static_cast<unsigned long long>(r.edge_count),
              static_cast<unsigned long long>(r.shells), static_cast<long long>(r.genus));
  std::printf("closed: %s (%llu boundary edges)\n", r.closed() ? "yes" : "no",
              static_cast<unsigned long long>(r.boundary_edges));
  std::printf("edge-manifold: %s (%llu edges with 3+ triangles)\n",
              r.edge_manifold() ? "yes" : "no",
              static_cast<unsigned long long>(r.nonmanifold_edges));
  std::printf("consistently oriented: %s (%llu conflicting edges)\n", r.oriented() ? "yes" : "no",
              static_cast<unsigned long long>(r.orientation_conflicts));
  std::printf("outward: %s\n", r.outward() ? "yes" : "no");
  std::printf("degenerate triangles: %llu, duplicate triangles: %llu\n",
              static_cast<unsigned long long>(r.degenerate_triangles),
              static_cast<unsigned long long>(r.duplicate_triangles));
  std::printf("area: %.6f mm^2, volume: %.6f mm^3\n", r.area, r.volume);
  std::printf("bounds: [%.6f, %.6f, %.6f] - [%.6f, %.6f, %.6f] mm\n", r.bounds.lo.x, r.bounds.lo.y,
              r.bounds.lo.z, r.bounds.hi.x, r.bounds.hi.y, r.bounds.hi.z);
}

const char* format_name(StlFormat f) {
  return f == StlFormat::kAscii ? "ascii" : (f == StlFormat::kBinary ? "binary" : "auto");
}

// Reports a failed run (JSON on stdout when asked, the message on stderr) and returns 1.
int rejected(const Options& o, const char* command, const Status& s, Arena* arena) {
  cli::print_error(s);
  if (o.json) {
    JsonObject j;
    j.add("command", command);
    j.add_status(s);
    if (arena != nullptr) j.add("peak_arena_bytes", static_cast<uint64_t>(arena->high_water()));
    std::printf("%s\n", j.str().c_str());
  }
  return kExitRejected;
}

int no_memory(const Options& o, const char* command) {
  return rejected(o, command,
                  make_error(StatusCode::kArenaExhausted, "cannot reserve the memory cap of ",
                             o.memory_cap, " bytes"),
                  nullptr);
}

int run_check(int argc, char** argv) {
  Options o;
  int early = parse_options(argc, argv, kCheckUsage, false, &o);
  if (early >= 0) return early;
  if (o.positional.size() != 1) return usage_error("check takes one input file", kCheckUsage);
  const PrinterProfile* profile = find_printer_profile(o.printer);
  if (profile == nullptr) {
    std::string m = std::string("unknown printer '") + o.printer + "' (known: eden260)";
    return usage_error(m.c_str(), kCheckUsage);
  }
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "check");
  Arena& arena = run.arena;
  const Context& ctx = run.ctx;
  const double t0 = run.start;

  Mesh mesh(&arena);
  StlInfo info;
  Status s = read_mesh_file(ctx, o.positional[0], &mesh, &info);
  if (!s.is_ok()) return rejected(o, "check", s, &arena);
  PrintCheckOptions pco;
  pco.place_on_tray = o.place;
  PrintCheck pc;
  s = check_printable(ctx, mesh, *profile, pco, &pc);
  if (!s.is_ok()) return rejected(o, "check", s.in_file(o.positional[0]), &arena);
  Status verdict = require_printable(pc, *profile);
  if (!verdict.is_ok()) verdict.in_file(o.positional[0]);
  const double seconds = monotonic_seconds() - t0;

  if (o.json) {
    JsonObject j;
    j.add("command", "check");
    j.add("input", o.positional[0]);
    j.add_status(verdict);
    j.add("format", format_name(info.format));
    j.add("input_bytes", info.bytes);
    j.add("input_triangles", info.triangles);
    add_mesh_report(&j, pc.mesh);
    j.add("printer", profile->name);
    j.add("extent_mm", pc.extent);
    j.add("fits", pc.fits);
    j.add("fits_rotated", pc.fits_rotated);
    j.add("placement_translation_mm", pc.placement.t);
    j.add("layers", pc.layers);
    j.add("units_suspect", pc.units_suspect);
    j.add("printable", pc.printable);
    j.add("time_s", seconds);
    j.add("peak_arena_bytes", static_cast<uint64_t>(arena.high_water()));
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("input: %s (%s, %llu triangles, %llu bytes)\n", o.positional[0], info.header,
                static_cast<unsigned long long>(info.triangles),
                static_cast<unsigned long long>(info.bytes));
    print_mesh_report(pc.mesh);
    std::printf("printer: %s: extent %.3f x %.3f x %.3f mm, %s, %llu layers\n", profile->name,
                pc.extent.x, pc.extent.y, pc.extent.z,
                pc.fits ? "fits" : (pc.fits_rotated ? "fits turned 90 degrees" : "does NOT fit"),
                static_cast<unsigned long long>(pc.layers));
    if (pc.units_suspect) std::printf("warning: the size suggests wrong units (not mm?)\n");
    std::printf("printable: %s\n", pc.printable ? "yes" : "no");
    std::printf("time: %.3f s, peak arena: %llu bytes\n", seconds,
                static_cast<unsigned long long>(arena.high_water()));
  }
  if (!verdict.is_ok()) {
    cli::print_error(verdict);
    return kExitRejected;
  }
  return kExitOk;
}

int run_convert(int argc, char** argv) {
  Options o;
  int early = parse_options(argc, argv, kConvertUsage, true, &o);
  if (early >= 0) return early;
  if (o.positional.size() != 1) return usage_error("convert takes one input file", kConvertUsage);
  if (o.output == nullptr) return usage_error("convert needs -o OUT.stl", kConvertUsage);
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "convert");
  Arena& arena = run.arena;
  const Context& ctx = run.ctx;
  const double t0 = run.start;

  Mesh mesh(&arena);
  StlInfo info;
  Status s = read_mesh_file(ctx, o.positional[0], &mesh, &info);
  if (!s.is_ok()) return rejected(o, "convert", s, &arena);
  MeshReport report;
  s = check_mesh(ctx, mesh, &report);
  if (!s.is_ok()) return rejected(o, "convert", s.in_file(o.positional[0]), &arena);

  s = write_atomically(ctx, mesh, o.output, o.ascii);
  if (!s.is_ok()) return rejected(o, "convert", s, &arena);
  const double seconds = monotonic_seconds() - t0;

  if (o.json) {
    JsonObject j;
    j.add("command", "convert");
    j.add("input", o.positional[0]);
    j.add("output", o.output);
    j.add_status(Status::ok());
    j.add("input_format", format_name(info.format));
    j.add("output_format", o.ascii ? "ascii" : "binary");
    j.add("input_triangles", info.triangles);
    add_mesh_report(&j, report);
    j.add("valid_solid", report.is_valid_solid());
    j.add("time_s", seconds);
    j.add("peak_arena_bytes", static_cast<uint64_t>(arena.high_water()));
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("input: %s (%s, %llu triangles)\n", o.positional[0], info.header,
                static_cast<unsigned long long>(info.triangles));
    print_mesh_report(report);
    std::printf("output: %s (%s STL)\n", o.output, o.ascii ? "ascii" : "binary");
    std::printf("time: %.3f s, peak arena: %llu bytes\n", seconds,
                static_cast<unsigned long long>(arena.high_water()));
  }
  return kExitOk;
}

int run_base(int argc, char** argv) {
  Options o;
  int early = parse_options(argc, argv, kBaseUsage, true, &o);
  if (early >= 0) return early;
  if (o.positional.size() != 1) return usage_error("base takes one case file", kBaseUsage);
  if (o.output == nullptr) return usage_error("base needs -o BASE.stl", kBaseUsage);
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "base");
  Arena& arena = run.arena;
  const Context& ctx = run.ctx;
  const double t0 = run.start;

  Span<uint8_t> text;
  Status s = read_file(arena, o.positional[0],
                       o.max_input_bytes != 0 ? o.max_input_bytes : cli::kMaxCaseBytes, &text);
  if (!s.is_ok()) return rejected(o, "base", s, &arena);
  CaseFile c;
  s = parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), o.positional[0], &c);
  if (!s.is_ok()) return rejected(o, "base", s, &arena);
  const double t_parse = monotonic_seconds();
  Mesh base(&arena);
  BaseReport report;
  s = build_case_base(ctx, c, &base, &report);
  if (!s.is_ok()) return rejected(o, "base", s.in_file(o.positional[0]), &arena);
  const double t_build = monotonic_seconds();

  s = write_atomically(ctx, base, o.output, o.ascii);
  if (!s.is_ok()) return rejected(o, "base", s, &arena);
  const double t_end = monotonic_seconds();

  if (o.json) {
    JsonObject j;
    j.add("command", "base");
    j.add("case", o.positional[0]);
    j.add("case_id", c.case_id);
    j.add("output", o.output);
    j.add_status(Status::ok());
    j.add("upper_picks", static_cast<uint64_t>(c.upper.size()));
    j.add("lower_picks", static_cast<uint64_t>(c.lower.size()));
    j.add("sections", report.sections);
    j.add("points_per_section", report.points_per_section);
    j.add("vertices", static_cast<uint64_t>(base.vertices.size()));
    j.add("triangles", static_cast<uint64_t>(base.triangles.size()));
    j.add("volume_mm3", report.volume);
    j.add("self_intersection_candidates", report.self_intersection_candidates);
    j.add("parse_s", t_parse - t0);
    j.add("build_s", t_build - t_parse);
    j.add("time_s", t_end - t0);
    j.add("peak_arena_bytes", static_cast<uint64_t>(arena.high_water()));
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("case: %s (%s), %zu upper and %zu lower picks\n", o.positional[0], c.case_id,
                c.upper.size(), c.lower.size());
    std::printf("base: %u sections x %u points: %zu vertices, %zu triangles, %.3f mm^3\n",
                report.sections, report.points_per_section, base.vertices.size(),
                base.triangles.size(), report.volume);
    std::printf(
        "checked: closed, edge-manifold, outward, no self-intersection (%llu candidate "
        "pairs tested)\n",
        static_cast<unsigned long long>(report.self_intersection_candidates));
    std::printf("output: %s (%s STL)\n", o.output, o.ascii ? "ascii" : "binary");
    std::printf("time: build %.4f s, total %.4f s, peak arena: %llu bytes\n", t_build - t_parse,
                t_end - t0, static_cast<unsigned long long>(arena.high_water()));
  }
  return kExitOk;
}

int run_distance(int argc, char** argv) {
  Options o;
  int early = parse_options(argc, argv, kDistanceUsage, false, &o);
  if (early >= 0) return early;
  if (o.positional.size() != 1) return usage_error("distance takes one mesh file", kDistanceUsage);
  if (o.queries.empty())
    return usage_error("distance needs at least one --query X,Y,Z", kDistanceUsage);
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "distance");
  Arena& arena = run.arena;
  const Context& ctx = run.ctx;
  const double t0 = run.start;

  Mesh mesh(&arena);
  StlInfo info;
  Status s = read_mesh_file(ctx, o.positional[0], &mesh, &info);
  if (!s.is_ok()) return rejected(o, "distance", s, &arena);
  if (mesh.triangles.size() == 0) {
    return rejected(
        o, "distance",
        Status::error(StatusCode::kInvalidMesh, "mesh is empty").in_file(o.positional[0]), &arena);
  }
  const size_t before = arena.used();
  DistanceIndex index;
  s = build_distance_index(ctx, mesh, DistanceIndexOptions{}, &index);
  if (!s.is_ok()) return rejected(o, "distance", s.in_file(o.positional[0]), &arena);
  const double t_build = monotonic_seconds();
  const size_t index_bytes = arena.used() - before;

  std::string rows = "[";
  for (size_t i = 0; i < o.queries.size(); ++i) {
    const Vec3& q = o.queries[i];
    SignedDistance sd;
    signed_distance(index, q, o.sign, &sd);
    const double w =
        sd.method == SignMethod::kWindingNumber ? sd.winding : winding_number(index, q);
    const char* method = sd.method == SignMethod::kPseudonormal ? "pseudonormal" : "winding";
    if (o.json) {
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
      rows += (i > 0 ? "," : "") + r.str();
    } else {
      std::printf(
          "query %.6g,%.6g,%.6g: closest %.9g,%.9g,%.9g on triangle %u (%s %u), "
          "distance %.9g, signed %.9g (%s), winding number %.6f\n",
          q.x, q.y, q.z, sd.closest.point.x, sd.closest.point.y, sd.closest.point.z,
          sd.closest.triangle, feature_name(sd.closest.feature), sd.closest.feature_index,
          sd.closest.distance, sd.distance, method, w);
    }
  }
  rows += "]";
  const double t_end = monotonic_seconds();
  if (o.json) {
    JsonObject j;
    j.add("command", "distance");
    j.add("input", o.positional[0]);
    j.add_status(Status::ok());
    j.add("triangles", static_cast<uint64_t>(mesh.triangles.size()));
    j.add("closed_manifold", index.closed_manifold);
    j.add("index_nodes", static_cast<uint64_t>(index.nodes.size()));
    j.add("index_bytes", static_cast<uint64_t>(index_bytes));
    j.add_raw("queries", rows);
    j.add("build_s", t_build - t0);
    j.add("time_s", t_end - t0);
    j.add("peak_arena_bytes", static_cast<uint64_t>(arena.high_water()));
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf(
        "index: %zu triangles, %zu nodes, %zu bytes, %s; built in %.4f s; peak arena "
        "%llu bytes\n",
        mesh.triangles.size(), index.nodes.size(), index_bytes,
        index.closed_manifold ? "closed manifold" : "open or non-manifold", t_build - t0,
        static_cast<unsigned long long>(arena.high_water()));
  }
  return kExitOk;
}

int run_boolean(int argc, char** argv) {
  Options o;
  int early = parse_options(argc, argv, kBooleanUsage, true, &o);
  if (early >= 0) return early;
  if (o.boolean_op < 0) {
    return usage_error("boolean needs --difference, --union or --intersection", kBooleanUsage);
  }
  if (o.positional.size() < 2)
    return usage_error("boolean takes A.stl and at least one B.stl", kBooleanUsage);
  if (o.output == nullptr) return usage_error("boolean needs -o OUT.stl", kBooleanUsage);
  if (o.translate_b.size() > 1 && o.translate_b.size() != o.positional.size() - 1) {
    return usage_error("--translate-b: give it once, or once per B file", kBooleanUsage);
  }
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "boolean");
  Arena& arena = run.arena;
  const Context& ctx = run.ctx;
  const double t0 = run.start;

  Mesh a(&arena);
  StlInfo info;
  Status s = read_mesh_file(ctx, o.positional[0], &a, &info);
  if (!s.is_ok()) return rejected(o, "boolean", s, &arena);
  // B: the shells of every other file, in order, in one mesh.
  Mesh b(&arena);
  for (size_t f = 1; f < o.positional.size(); ++f) {
    const Arena::Marker mark = arena.mark();
    Mesh part(&arena);
    s = read_mesh_file(ctx, o.positional[f], &part, &info);
    if (!s.is_ok()) return rejected(o, "boolean", s, &arena);
    if (b.vertices.size() + part.vertices.size() >= (size_t{1} << 31)) {
      return rejected(
          o, "boolean",
          Status::error(StatusCode::kLimitExceeded, "B is too large").in_file(o.positional[f]),
          &arena);
    }
    const Vec3 d =
        o.translate_b.empty() ? Vec3{} : o.translate_b[o.translate_b.size() == 1 ? 0 : f - 1];
    // A moved jaw is rounded to float32, as its own STL would hold it: the Boolean keeps B's
    // vertices bit for bit, so they must be what the output file can store.
    for (Vec3& v : part.vertices) {
      v = v + d;
      if (!round_to_float32(&v)) {
        return rejected(
            o, "boolean",
            Status::error(StatusCode::kLimitExceeded, "a translated vertex is beyond float32 range")
                .in_file(o.positional[f]),
            &arena);
      }
    }
    if (f == 1) {
      b = part;  // the first file's arrays stay where they are
      continue;
    }
    // Later files: copy after B's arrays (which then grow in place or move up).
    const uint32_t off = static_cast<uint32_t>(b.vertices.size());
    std::vector<Vec3> vs(part.vertices.begin(), part.vertices.end());
    std::vector<Triangle> ts(part.triangles.begin(), part.triangles.end());
    arena.rewind(mark);
    for (const Vec3& v : vs) {
      if (!b.vertices.push_back(v)) return rejected(o, "boolean", arena.exhausted_status(), &arena);
    }
    for (const Triangle& t : ts) {
      if (!b.triangles.push_back(Triangle{{t.v[0] + off, t.v[1] + off, t.v[2] + off}})) {
        return rejected(o, "boolean", arena.exhausted_status(), &arena);
      }
    }
  }
  const double t_read = monotonic_seconds();

  BooleanOptions bo;
  bo.op = o.boolean_op == 0 ? BooleanOp::kDifference
                            : (o.boolean_op == 1 ? BooleanOp::kUnion : BooleanOp::kIntersection);
  bo.check_self_intersection = false;  // timed separately below
  Mesh out;
  BooleanStats st;
  s = mesh_boolean(ctx, a, b, bo, &out, &st);
  if (!s.is_ok()) return rejected(o, "boolean", s, &arena);
  const double t_op = monotonic_seconds();
  SelfIntersectionReport si;
  if (o.self_check) {
    s = find_self_intersections(ctx, out, 1, &si);
    if (!s.is_ok()) return rejected(o, "boolean", s, &arena);
    if (si.self_intersecting()) {
      return rejected(o, "boolean",
                      make_error(StatusCode::kUnsupported,
                                 "the result self-intersects as float32: "
                                 "triangles ",
                                 si.first_a, " and ", si.first_b, "; nothing written"),
                      &arena);
    }
  }
  const double t_check = monotonic_seconds();
  MeshReport report;
  s = check_mesh(ctx, out, &report);
  if (!s.is_ok()) return rejected(o, "boolean", s, &arena);
  s = write_atomically(ctx, out, o.output, o.ascii);
  if (!s.is_ok()) return rejected(o, "boolean", s, &arena);
  const double t_end = monotonic_seconds();

  uint64_t b_triangles = b.triangles.size();
  if (o.json) {
    JsonObject j;
    j.add("command", "boolean");
    j.add("operation", boolean_op_name(bo.op));
    j.add("a", o.positional[0]);
    j.add("output", o.output);
    j.add_status(Status::ok());
    j.add("a_triangles", static_cast<uint64_t>(a.triangles.size()));
    j.add("b_triangles", b_triangles);
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
    j.add("self_intersection_checked", o.self_check);
    add_mesh_report(&j, report);
    j.add("valid_solid", report.is_valid_solid());
    j.add("read_s", t_read - t0);
    j.add("boolean_s", t_op - t_read);
    j.add("self_check_s", t_check - t_op);
    j.add("time_s", t_end - t0);
    j.add("peak_arena_bytes", static_cast<uint64_t>(arena.high_water()));
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("A: %s, %zu triangles; B: %zu file(s), %llu triangles (%llu near A)\n",
                o.positional[0], a.triangles.size(), o.positional.size() - 1,
                static_cast<unsigned long long>(b_triangles),
                static_cast<unsigned long long>(st.near_b_triangles));
    std::printf(
        "%s: %llu candidate pairs, %llu crossing, %llu touching exactly, %llu "
        "intersection points, %llu + %llu triangles cut, %u attempt(s)\n",
        boolean_op_name(bo.op), static_cast<unsigned long long>(st.candidate_pairs),
        static_cast<unsigned long long>(st.intersecting_pairs),
        static_cast<unsigned long long>(st.degenerate_pairs),
        static_cast<unsigned long long>(st.intersection_points),
        static_cast<unsigned long long>(st.cut_triangles_a),
        static_cast<unsigned long long>(st.cut_triangles_b), st.attempts);
    if (st.attempts > 1) {
      std::printf(
          "A was nudged by (%.3g, %.3g, %.3g) mm out of a degenerate or float32-fragile "
          "configuration\n",
          st.nudge.x, st.nudge.y, st.nudge.z);
    }
    print_mesh_report(report);
    std::printf("self-intersection: %s\n", o.self_check ? "none (exact check)" : "not checked");
    std::printf("output: %s (%s STL)\n", o.output, o.ascii ? "ascii" : "binary");
    std::printf(
        "time: read %.4f s, boolean %.4f s, check %.4f s, total %.4f s; peak arena %llu "
        "bytes\n",
        t_read - t0, t_op - t_read, t_check - t_op, t_end - t0,
        static_cast<unsigned long long>(arena.high_water()));
  }
  return kExitOk;
}

Status write_bytes_atomically(const std::string& path, const std::string& bytes);

int run_phantom(int argc, char** argv) {
  Options o;
  int early = parse_options(argc, argv, kPhantomUsage, true, &o);
  if (early >= 0) return early;
  if (!o.positional.empty()) return usage_error("phantom takes no input file", kPhantomUsage);
  if (o.output == nullptr) return usage_error("phantom needs -o DIR", kPhantomUsage);
  if (o.triangles < phantom::kMinTriangles || o.triangles > phantom::kMaxTriangles) {
    return usage_error("--triangles must be 2000..16000000", kPhantomUsage);
  }
  const double t0 = monotonic_seconds();
  std::string rows;
  const char* names[2] = {"maxilla", "mandible"};
  for (int j = 0; j < 2; ++j) {
    phantom::JawMesh jaw;
    phantom::PhantomOptions po;
    po.target_triangles = o.triangles;
    Status s =
        phantom::make_jaw(j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, po, &jaw);
    std::vector<uint8_t> bytes;
    if (s.is_ok()) s = phantom::stl_bytes(jaw, &bytes);
    const std::string path = std::string(o.output) + "/" + names[j] + ".stl";
    AtomicFile file;
    if (s.is_ok()) s = file.open(path.c_str());
    if (s.is_ok()) {
      ByteSink sink = file.sink();
      if (!sink.write(sink.user, bytes.data(), bytes.size())) {
        s = Status::error(StatusCode::kIoError, "cannot write").in_file(path.c_str());
      }
    }
    if (s.is_ok()) s = file.commit();
    if (!s.is_ok()) return rejected(o, "phantom", s, nullptr);
    Sha256 sha;
    sha.update(bytes.data(), bytes.size());
    uint8_t digest[32];
    sha.finish(digest);
    char hex[65];
    Sha256::to_hex(digest, hex);
    if (o.json) {
      JsonObject r;
      r.add("jaw", names[j]);
      r.add("file", path.c_str());
      r.add("triangles", static_cast<uint64_t>(jaw.triangles.size()));
      r.add("vertices", static_cast<uint64_t>(jaw.vertices.size()));
      r.add("sha256", hex);
      rows += (j > 0 ? "," : "") + r.str();
    } else {
      std::printf("%s: %s, %zu triangles, %zu vertices, sha256 %s\n", names[j], path.c_str(),
                  jaw.triangles.size(), jaw.vertices.size(), hex);
    }
  }
  // The case that goes with them (the paper-scale picks): design it with
  // `splintcore design DIR/case.json -o OUT`.
  {
    const std::string text = phantom::case_json(("phantom-" + std::to_string(o.triangles)).c_str());
    const std::string path = std::string(o.output) + "/case.json";
    Status s = write_bytes_atomically(path, text);
    if (!s.is_ok()) return rejected(o, "phantom", s, nullptr);
    if (!o.json) std::printf("case: %s\n", path.c_str());
  }
  if (o.json) {
    JsonObject j;
    j.add("command", "phantom");
    j.add_status(Status::ok());
    j.add_raw("jaws", "[" + rows + "]");
    j.add("time_s", monotonic_seconds() - t0);
    std::printf("%s\n", j.str().c_str());
  }
  return kExitOk;
}

// Stage times and peak arena per stage from the progress callback (tools only: the clock).
struct DesignClock {
  Arena* arena = nullptr;
  bool print = false;
  std::vector<std::string> names;
  std::vector<double> seconds;
  std::vector<uint64_t> peaks;
  std::string current;
  double since = 0;
  static bool report(void* user, const char* stage, uint64_t, uint64_t) {
    DesignClock* c = static_cast<DesignClock*>(user);
    if (std::strncmp(stage, "design: ", 8) != 0 || c->current == stage) return true;
    const double now = monotonic_seconds();
    if (!c->current.empty()) {
      c->names.push_back(c->current.substr(8));
      c->seconds.push_back(now - c->since);
      c->peaks.push_back(c->arena->high_water());
      if (c->print) std::fprintf(stderr, " %.3f s\n", now - c->since);
    }
    c->current = stage;
    c->since = now;
    if (c->print && c->current != "design: done") std::fprintf(stderr, "%s...", stage + 8);
    return true;
  }
};

std::string hex_sha256(const void* data, size_t size) {
  Sha256 sha;
  sha.update(data, size);
  uint8_t digest[32];
  sha.finish(digest);
  char hex[65];
  Sha256::to_hex(digest, hex);
  return hex;
}

Status write_bytes_atomically(const std::string& path, const std::string& bytes) {
  AtomicFile file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(path.c_str()));
  ByteSink sink = file.sink();
  if (!sink.write(sink.user, reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size())) {
    return Status::error(StatusCode::kIoError, "cannot write").in_file(path.c_str());
  }
  return file.commit();
}

int run_design(int argc, char** argv) {
  Options o;
  int early = parse_options(argc, argv, kDesignUsage, true, &o);
  if (early >= 0) return early;
  if (o.positional.size() != 1) return usage_error("design takes one case file", kDesignUsage);
  if (o.output == nullptr) return usage_error("design needs -o OUTDIR", kDesignUsage);
  const std::string case_path = o.positional[0];
  std::vector<uint8_t> case_bytes;
  Status s = cli::read_whole_file(
      case_path, o.max_input_bytes != 0 ? o.max_input_bytes : cli::kMaxCaseBytes, &case_bytes);
  if (!s.is_ok()) return rejected(o, "design", s, nullptr);
  // The memory cap: --memory-cap, else the case's "memory_cap", else the default. The case is
  // parsed once in a scratch arena to learn it (the real parse below keeps its strings in the
  // run's arena, whose size must be known first).
  const char* cap_source = o.memory_cap_given ? "command line" : "default";
  if (!o.memory_cap_given) {
    std::vector<unsigned char> scratch(case_bytes.size() * 8 + (size_t{1} << 20));
    Arena scratch_arena(scratch.data(), scratch.size());
    CaseFile pre;
    if (parse_case(Context(&scratch_arena), reinterpret_cast<const char*>(case_bytes.data()),
                   case_bytes.size(), case_path.c_str(), &pre)
            .is_ok() &&
        pre.memory_cap != 0) {
      o.memory_cap = pre.memory_cap;
      cap_source = "case";
    }
  }
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "design");
  ::mkdir(o.output, 0777);  // an existing folder is fine; a failure shows when writing
  Arena& arena = run.arena;
  const double t0 = run.start;
  CaseFile c;
  s = parse_case(run.ctx, reinterpret_cast<const char*>(case_bytes.data()), case_bytes.size(),
                 case_path.c_str(), &c);
  if (!s.is_ok()) return rejected(o, "design", s, &arena);
  const size_t slash = case_path.find_last_of('/');
  const std::string folder = slash == std::string::npos ? "" : case_path.substr(0, slash + 1);

  DesignClock clock;
  clock.arena = &arena;
  clock.print = isatty(2) != 0 && !o.json;
  Progress progress;
  progress.report = &DesignClock::report;
  progress.user = &clock;
  const Context ctx(&arena, &run.threads.executor(), &progress);

  // The jaws, as read (their bytes hashed for the report).
  std::vector<std::string> jaw_paths, jaw_hashes;
  std::vector<Mesh> jaws;
  bool any_ct = false;
  for (const CaseJaw& j : c.jaws) {
    if (j.has_seed) {  // reconstructed from the case's CT below
      any_ct = true;
      jaw_paths.emplace_back();
      jaw_hashes.emplace_back();
      jaws.emplace_back(&arena);
      continue;
    }
    const std::string path = j.mesh[0] == '/' ? std::string(j.mesh) : folder + j.mesh;
    std::vector<uint8_t> bytes;
    s = cli::read_whole_file(path, o.max_input_bytes != 0 ? o.max_input_bytes : cli::kMaxMeshBytes,
                             &bytes);
    if (!s.is_ok()) return rejected(o, "design", s, &arena);
    MemorySource ms{bytes.data(), bytes.size(), 0, 0};
    Mesh m;
    MeshReadOptions read_options;  // STL, PLY or OBJ (by content), welded as STL is
    read_options.weld = true;
    s = read_mesh(ctx, memory_source(&ms, path.c_str()), read_options, &m, nullptr);
    if (!s.is_ok()) return rejected(o, "design", s, &arena);
    jaw_paths.push_back(path);
    jaw_hashes.push_back(hex_sha256(bytes.data(), bytes.size()));
    jaws.push_back(m);
  }
  // Jaws from CT: the volume read once, every seed grown in competition, each region meshed.
  CaseCtReport ct_report;
  CtInfo ct_info;
  std::string ct_path, ct_hash;
  if (any_ct) {
    ct_path = c.ct_volume[0] == '/' ? std::string(c.ct_volume) : folder + c.ct_volume;
    CtVolume volume;
    s = cli::read_ct_path(ctx, ct_path, CtReadOptions{}, &volume, &ct_info);
    if (!s.is_ok()) return rejected(o, "design", s, &arena);
    ct_hash = hex_sha256(volume.hu, static_cast<size_t>(volume.voxel_count() * 2));
    s = reconstruct_case_jaws(ctx, c, volume, Span<Mesh>(jaws.data(), jaws.size()), &ct_report);
    if (!s.is_ok()) return rejected(o, "design", s, &arena);
    for (size_t i = 0; i < c.jaws.size(); ++i) {
      if (!c.jaws[i].has_seed) continue;
      jaw_paths[i] = ct_path;
      jaw_hashes[i] = ct_hash;
    }
  }
  const double t_read = monotonic_seconds();
  Mesh splint;
  DesignReport report;
  s = design_splint(ctx, c, Span<const Mesh>(jaws.data(), jaws.size()), &splint, &report);
  if (clock.print && !s.is_ok()) std::fprintf(stderr, " failed\n");
  if (!s.is_ok()) return rejected(o, "design", s.in_file(case_path.c_str()), &arena);
  const double t_design = monotonic_seconds();

  // The splint's bytes: hashed, then written atomically.
  std::vector<uint8_t> stl(84 + 50 * splint.triangles.size());
  MemorySink sink{stl.data(), stl.size(), 0, 0};
  s = write_stl(ctx, splint, memory_sink(&sink), StlWriteOptions{});
  if (!s.is_ok()) return rejected(o, "design", s, &arena);
  stl.resize(static_cast<size_t>(sink.size));
  const std::string out_dir = o.output;
  const std::string splint_path =
      out_dir + "/" + (c.output_splint != nullptr ? c.output_splint : "splint.stl");
  const std::string report_path =
      out_dir + "/" + (c.output_report != nullptr ? c.output_report : "report.json");
  const std::string splint_hash = hex_sha256(stl.data(), stl.size());
  s = write_bytes_atomically(splint_path, std::string(stl.begin(), stl.end()));
  if (!s.is_ok()) return rejected(o, "design", s, &arena);
  // OUTDIR/preview.png: the splint on the jaws as the plan (and a tray placement) moved them.
  // Not fatal: the splint is written; a preview that fails (e.g. a tight --memory-cap) is a
  // warning and the report says why.
  cli::PreviewInfo preview;
  Status preview_status;
  char preview_error[512] = "";
  {
    std::vector<const Mesh*> preview_jaws;
    std::vector<RigidTransform> preview_moves;
    for (size_t i = 0; i < jaws.size(); ++i) {
      preview_jaws.push_back(&jaws[i]);
      // On the tray the whole case moved by tray_translation before the design: the jaws
      // follow it, so the preview shows the fit where the splint is.
      preview_moves.push_back(
          report.placed_on_tray
              ? compose(RigidTransform::translation(report.tray_translation), c.jaws[i].transform)
              : c.jaws[i].transform);
    }
    preview_status = cli::write_preview(ctx, splint, preview_jaws, preview_moves,
                                        out_dir + "/preview.png", 1024, 1024, &preview);
    if (!preview_status.is_ok()) {
      preview_status.format(preview_error, sizeof(preview_error));
      std::fprintf(stderr, "splintcore: warning: no preview: %s\n", preview_error);
    } else if (!o.json) {
      std::printf("preview: %s\n", preview.path.c_str());
    }
  }
  const double t_end = monotonic_seconds();

  // report.json: the library's report (the C API writes the same bytes), this run's part last.
  std::vector<const char*> path_list, hash_list;
  for (size_t i = 0; i < jaw_paths.size(); ++i) {
    path_list.push_back(jaw_paths[i].c_str());
    hash_list.push_back(jaw_hashes[i].c_str());
  }
  DesignReportFiles files;
  files.case_path = case_path.c_str();
  files.jaw_paths = Span<const char* const>(path_list.data(), path_list.size());
  files.jaw_sha256 = Span<const char* const>(hash_list.data(), hash_list.size());
  if (any_ct) {
    files.ct_path = ct_path.c_str();
    files.ct_size[0] = ct_info.nx;
    files.ct_size[1] = ct_info.ny;
    files.ct_size[2] = ct_info.nz;
    files.ct = &ct_report;
  }
  files.splint_path = splint_path.c_str();
  files.splint_sha256 = splint_hash.c_str();  // of the bytes just written
  if (preview_status.is_ok()) {
    files.preview_path = preview.path.c_str();
    files.preview_sha256 = preview.sha256.c_str();
  } else {
    files.preview_error = preview_error;
  }
  std::vector<DesignStageTime> stage_times;
  for (size_t i = 0; i < clock.names.size(); ++i) {
    stage_times.push_back(
        DesignStageTime{clock.names[i].c_str(), clock.seconds[i], clock.peaks[i]});
  }
  DesignRunInfo run_info;
  run_info.memory_cap_bytes = o.memory_cap;
  run_info.memory_cap_from = cap_source;
  run_info.threads = o.threads;
  run_info.stages = Span<const DesignStageTime>(stage_times.data(), stage_times.size());
  run_info.read_seconds = t_read - t0;
  run_info.design_seconds = t_design - t_read;
  run_info.preview_seconds =
      preview_status.is_ok() ? preview.render_seconds + preview.encode_seconds : 0;
  run_info.total_seconds = t_end - t0;
  run_info.peak_arena_bytes = arena.high_water();
  std::string report_text;
  s = write_design_report(ctx, c, Span<const Mesh>(jaws.data(), jaws.size()), splint, report, files,
                          &run_info, cli::string_sink(&report_text));
  if (!s.is_ok()) return rejected(o, "design", s, &arena);
  s = write_bytes_atomically(report_path, report_text + "\n");
  if (!s.is_ok()) return rejected(o, "design", s, &arena);

  if (o.json) {
    std::printf("%s\n", report_text.c_str());
  } else {
    std::printf("case %s (%s): %zu jaw(s), %llu triangles; base %u sections, %zu + %zu picks\n",
                case_path.c_str(), c.case_id, jaws.size(),
                static_cast<unsigned long long>(report.jaw_triangles), report.base.sections,
                c.upper.size(), c.lower.size());
    if (report.imprint_offset) {
      std::printf("imprint: a %.3g mm clearance around each jaw's swept volume\n",
                  c.blockout.offset);
    } else {
      std::printf("boolean: %llu crossing pairs, %llu intersection points, %u attempt(s)\n",
                  static_cast<unsigned long long>(report.boolean.intersecting_pairs),
                  static_cast<unsigned long long>(report.boolean.intersection_points),
                  report.boolean.attempts);
    }
    for (uint32_t i = 0; i < report.blockout_jaws; ++i) {
      std::printf(
          "blockout (%s): %.4f mm^3 of interference removed, %llu swept triangles, "
          "inset %.3g mm\n",
          c.jaws[i].role, report.blockout_removed_mm3[i],
          static_cast<unsigned long long>(report.blockout[i].swept_triangles),
          report.blockout[i].inset_used);
    }
    if (report.labelled) {
      std::printf("label: \"%s\" %s, %u glyphs, %.1f mm long\n", report.label.text,
                  c.label.mode == LabelMode::kEmboss ? "embossed" : "engraved", report.label.glyphs,
                  report.label.text_length_mm);
    }
    if (report.thickness_checked) {
      const ThicknessReport& t = report.thickness;
      if (t.thin_triangles == 0) {
        std::printf("thickness: no wall thinner than %.3g mm\n", t.min_required);
      } else {
        std::printf(
            "thickness: %llu triangles (%.3f mm^2) thinner than %.3g mm; thinnest "
            "%.3f mm at (%.2f, %.2f, %.2f); %u spot(s) in report.json\n",
            static_cast<unsigned long long>(t.thin_triangles), t.thin_area_mm2, t.min_required,
            t.thinnest, t.spots[0].position.x, t.spots[0].position.y, t.spots[0].position.z,
            t.spot_count);
      }
    }
    std::printf(
        "splint: %zu triangles, %.3f mm^3, closed, manifold, no self-intersection; "
        "printable on %s (%s%s)\n",
        splint.triangles.size(), report.print.mesh.volume, report.printer,
        report.print.fits ? "fits the tray" : "fits turned 90 degrees",
        report.placed_on_tray ? ", placed on the tray" : "");
    std::printf("wrote %s (sha256 %s) and %s\n", splint_path.c_str(), splint_hash.c_str(),
                report_path.c_str());
    std::printf("time: read %.3f s, design %.3f s, total %.3f s; peak arena %llu bytes\n",
                t_read - t0, t_design - t_read, t_end - t0,
                static_cast<unsigned long long>(arena.high_water()));
  }
  return kExitOk;
}

// ---- CT: the skull phantom and reconstruction (issue 7) -------------------------------------

const char kCtPhantomUsage[] =
    "usage: splintcore ct-phantom -o PATH --format dicom|nrrd|mha [--size NX,NY,NZ]\n"
    "                             [--spacing SX,SY,SZ] [--noise HU] [--no-streak] [--seed N]\n"
    "                             [--json]\n"
    "\n"
    "Writes a synthetic skull-like CT with known analytic surfaces (tools/common/ct_phantom.h):\n"
    "14 round-cone teeth per jaw on two parabolic arches in occlusion (the molar crowns overlap\n"
    "0.3 mm, the premolars touch), maxillary and mandibular bone, soft tissue, air, Gaussian-like\n"
    "noise (--noise, standard deviation, default 20 HU) and a metal-artefact streak (unless\n"
    "--no-streak). --format dicom writes a folder of slices at PATH; nrrd writes PATH (.nrrd\n"
    "or .nhdr), mha writes PATH (.mha or .mhd). Defaults: --size 160,160,100, --spacing\n"
    "0.5,0.5,0.5 (mm), --seed 1. Prints the seed points to give `splintcore reconstruct`.\n"
    "The bytes depend only on the options.\n";

const char kReconstructUsage[] =
    "usage: splintcore reconstruct VOLUME -o OUTDIR --seed-maxilla X,Y,Z --seed-mandible X,Y,Z\n"
    "                              [--hu-min 300] [--hu-max 4000] [--connectivity 6|26]\n"
    "                              [--split-plane PX,PY,PZ,NX,NY,NZ] [--keep-double] [--json]\n"
    "                              [--smooth N] [--decimate T] [--memory-cap SIZE]\n"
    "\n"
    "Reads a CT volume (a .nrrd/.nhdr/.mha/.mhd file or a folder of DICOM slices), marks the\n"
    "voxels in the HU window [--hu-min, --hu-max], grows the maxilla and the mandible from their\n"
    "seed points (patient mm) in competition (each voxel to the seed it is fewer face steps from,\n"
    "ties to the maxilla; see include/splintcore/segment.h), and reconstructs each jaw with the\n"
    "tiled marching tetrahedra at HU = hu-min - 0.5, interpolated between voxels. --split-plane\n"
    "restricts the maxilla to the side its normal points to and the mandible to the other.\n"
    "Writes OUTDIR/maxilla.stl and OUTDIR/mandible.stl (binary, float32, each checked closed,\n"
    "manifold and outward, written atomically) and prints a summary: voxels per region,\n"
    "triangles, volume, warnings (a region touching the volume's border), stage times, peak\n"
    "arena. Memory: 2 bytes per voxel for the volume, 1 for the labels, 4 per window voxel\n"
    "while growing, about 80 per mesh vertex. --smooth N runs N Taubin lambda|mu iterations\n"
    "(volume-preserving; no vertex moves more than half the smallest voxel spacing) and\n"
    "--decimate T reduces each jaw to at most T triangles by quadric-error edge collapses\n"
    "(closed, manifold, genus kept), in that order, before the check and the write.\n";

// "A,B,C" of unsigned integers.
bool parse_u32_triple(const char* text, uint32_t out[3]) {
  const char* p = text;
  for (int a = 0; a < 3; ++a) {
    const char* end = p;
    while (*end != '\0' && *end != ',') ++end;
    uint32_t value = 0;
    auto r = std::from_chars(p, end, value);
    if (r.ec != std::errc() || r.ptr != end) return false;
    out[a] = value;
    if (a < 2) {
      if (*end != ',') return false;
      p = end + 1;
    } else if (*end != '\0') {
      return false;
    }
  }
  return true;
}

// The options only the CT commands take: removed from argv before parse_options sees it.
struct CtOptions {
  const char* format = nullptr;
  uint32_t size[3] = {160, 160, 100};
  Vec3 spacing{0.5, 0.5, 0.5};
  double noise = 20.0;
  bool streak = true;
  uint64_t seed = 1;
  int32_t hu_min = 300, hu_max = 4000;
  bool has_seed[2] = {false, false};
  Vec3 seeds[2];
  Connectivity connectivity = Connectivity::k6;
  bool has_plane = false;
  SplitPlane plane;
  bool keep_double = false;
  uint32_t smooth = 0;    // Taubin iterations (0: none)
  uint64_t decimate = 0;  // target triangles per jaw (0: none)
};

// Returns -1 to go on (with `rest` holding the other arguments), or an exit code.
int take_ct_options(int argc, char** argv, const char* usage, bool phantom, CtOptions* c,
                    std::vector<char*>* rest) {
  for (int i = 0; i < argc; ++i) {
    const char* a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    auto bad = [&](const char* message) { return usage_error(message, usage); };
    if (phantom && std::strcmp(a, "--format") == 0) {
      if (v == nullptr || (std::strcmp(v, "dicom") != 0 && std::strcmp(v, "nrrd") != 0 &&
                           std::strcmp(v, "mha") != 0)) {
        return bad("--format takes dicom, nrrd or mha");
      }
      c->format = v;
      ++i;
    } else if (phantom && std::strcmp(a, "--size") == 0) {
      if (v == nullptr || !parse_u32_triple(v, c->size)) return bad("--size needs NX,NY,NZ");
      ++i;
    } else if (phantom && std::strcmp(a, "--spacing") == 0) {
      if (v == nullptr || !parse_point(v, &c->spacing)) return bad("--spacing needs SX,SY,SZ (mm)");
      ++i;
    } else if (phantom && std::strcmp(a, "--noise") == 0) {
      auto r = v == nullptr ? std::from_chars_result{nullptr, std::errc::invalid_argument}
                            : std::from_chars(v, v + std::strlen(v), c->noise);
      if (v == nullptr || r.ec != std::errc() || *r.ptr != '\0') return bad("--noise needs HU");
      ++i;
    } else if (phantom && std::strcmp(a, "--no-streak") == 0) {
      c->streak = false;
    } else if (phantom && std::strcmp(a, "--seed") == 0) {
      if (v == nullptr || !cli::parse_unsigned(v, &c->seed)) return bad("--seed needs a number");
      ++i;
    } else if (!phantom && (std::strcmp(a, "--hu-min") == 0 || std::strcmp(a, "--hu-max") == 0)) {
      int32_t value = 0;
      auto r = v == nullptr ? std::from_chars_result{nullptr, std::errc::invalid_argument}
                            : std::from_chars(v, v + std::strlen(v), value);
      if (v == nullptr || r.ec != std::errc() || *r.ptr != '\0' || value < -32768 ||
          value > 32767) {
        return bad("--hu-min and --hu-max need an integer HU (-32768..32767)");
      }
      (std::strcmp(a, "--hu-min") == 0 ? c->hu_min : c->hu_max) = value;
      ++i;
    } else if (!phantom &&
               (std::strcmp(a, "--seed-maxilla") == 0 || std::strcmp(a, "--seed-mandible") == 0)) {
      const int jaw = std::strcmp(a, "--seed-maxilla") == 0 ? 0 : 1;
      if (v == nullptr || !parse_point(v, &c->seeds[jaw])) return bad("a seed needs X,Y,Z (mm)");
      c->has_seed[jaw] = true;
      ++i;
    } else if (!phantom && std::strcmp(a, "--connectivity") == 0) {
      if (v != nullptr && std::strcmp(v, "6") == 0) {
        c->connectivity = Connectivity::k6;
      } else if (v != nullptr && std::strcmp(v, "26") == 0) {
        c->connectivity = Connectivity::k26;
      } else {
        return bad("--connectivity takes 6 or 26");
      }
      ++i;
    } else if (!phantom && std::strcmp(a, "--split-plane") == 0) {
      // Two points' worth of numbers: PX,PY,PZ,NX,NY,NZ.
      std::string text = v != nullptr ? v : "";
      size_t cut = std::string::npos, commas = 0;
      for (size_t n = 0; n < text.size(); ++n) {
        if (text[n] == ',' && ++commas == 3) cut = n;
      }
      if (cut == std::string::npos || !parse_point(text.substr(0, cut).c_str(), &c->plane.point) ||
          !parse_point(text.substr(cut + 1).c_str(), &c->plane.normal)) {
        return bad("--split-plane needs PX,PY,PZ,NX,NY,NZ (a point and a normal, mm)");
      }
      c->plane.label_positive = 1;  // the normal points towards the maxilla
      c->plane.label_negative = 2;
      c->has_plane = true;
      ++i;
    } else if (!phantom && std::strcmp(a, "--keep-double") == 0) {
      c->keep_double = true;
    } else if (!phantom && std::strcmp(a, "--smooth") == 0) {
      uint64_t n = 0;
      if (v == nullptr || !cli::parse_unsigned(v, &n) || n > 1000) {
        return bad("--smooth needs a number of Taubin iterations (0..1000)");
      }
      c->smooth = static_cast<uint32_t>(n);
      ++i;
    } else if (!phantom && std::strcmp(a, "--decimate") == 0) {
      if (v == nullptr || !cli::parse_unsigned(v, &c->decimate) || c->decimate < 4) {
        return bad("--decimate needs a target triangle count per jaw (at least 4)");
      }
      ++i;
    } else {
      rest->push_back(argv[i]);
    }
  }
  return -1;
}

int run_ct_phantom(int argc, char** argv) {
  CtOptions c;
  std::vector<char*> rest;
  int early = take_ct_options(argc, argv, kCtPhantomUsage, true, &c, &rest);
  if (early >= 0) return early;
  Options o;
  early = parse_options(static_cast<int>(rest.size()), rest.data(), kCtPhantomUsage, true, &o);
  if (early >= 0) return early;
  if (!o.positional.empty()) return usage_error("ct-phantom takes no input", kCtPhantomUsage);
  if (o.output == nullptr) return usage_error("ct-phantom needs -o PATH", kCtPhantomUsage);
  if (c.format == nullptr) return usage_error("ct-phantom needs --format", kCtPhantomUsage);
  const double t0 = monotonic_seconds();
  cli::CtPhantomOptions po;
  po.nx = c.size[0];
  po.ny = c.size[1];
  po.nz = c.size[2];
  po.spacing = c.spacing;
  po.noise_hu = c.noise;
  po.streak = c.streak;
  po.seed = c.seed;
  cli::CtPhantom phantom;
  Status s = phantom.init(po);
  if (!s.is_ok()) return rejected(o, "ct-phantom", s, nullptr);
  std::vector<int16_t> hu;
  CtVolume volume;
  phantom.generate(&hu, &volume);
  const double t_generate = monotonic_seconds() - t0;
  cli::CtWriteOptions wo;
  if (std::strcmp(c.format, "dicom") == 0) {
    s = cli::write_dicom_series(volume, o.output, wo);
  } else if (std::strcmp(c.format, "nrrd") == 0) {
    s = cli::write_nrrd(volume, o.output, wo);
  } else {
    s = cli::write_metaimage(volume, o.output, wo);
  }
  if (!s.is_ok()) return rejected(o, "ct-phantom", s, nullptr);
  const std::string voxels_sha = hex_sha256(hu.data(), hu.size() * sizeof(int16_t));
  if (o.json) {
    JsonObject j;
    j.add("command", "ct-phantom");
    j.add_status(Status::ok());
    j.add("format", c.format);
    j.add("path", o.output);
    j.add_raw("size", "[" + std::to_string(volume.nx) + "," + std::to_string(volume.ny) + "," +
                          std::to_string(volume.nz) + "]");
    j.add("spacing", volume.spacing);
    j.add("origin", volume.origin);
    j.add("noise_hu", c.noise);
    j.add("streak", c.streak);
    j.add("seed", c.seed);
    j.add("seed_maxilla", phantom.seed_maxilla());
    j.add("seed_mandible", phantom.seed_mandible());
    j.add("voxels_sha256", voxels_sha);
    j.add("generate_s", t_generate);
    j.add("time_s", monotonic_seconds() - t0);
    std::printf("%s\n", j.str().c_str());
  } else {
    const Vec3 a = phantom.seed_maxilla(), b = phantom.seed_mandible();
    std::printf(
        "%s: %u x %u x %u voxels (%s), voxels sha256 %s\n"
        "seeds: --seed-maxilla %s,%s,%s --seed-mandible %s,%s,%s\n",
        o.output, volume.nx, volume.ny, volume.nz, c.format, voxels_sha.c_str(),
        cli::json_number(a.x).c_str(), cli::json_number(a.y).c_str(), cli::json_number(a.z).c_str(),
        cli::json_number(b.x).c_str(), cli::json_number(b.y).c_str(),
        cli::json_number(b.z).c_str());
  }
  return kExitOk;
}

int run_reconstruct(int argc, char** argv) {
  CtOptions c;
  std::vector<char*> rest;
  int early = take_ct_options(argc, argv, kReconstructUsage, false, &c, &rest);
  if (early >= 0) return early;
  Options o;
  early = parse_options(static_cast<int>(rest.size()), rest.data(), kReconstructUsage, true, &o);
  if (early >= 0) return early;
  if (o.positional.size() != 1) {
    return usage_error("reconstruct takes one volume (file or DICOM folder)", kReconstructUsage);
  }
  if (o.output == nullptr) return usage_error("reconstruct needs -o OUTDIR", kReconstructUsage);
  if (!c.has_seed[0] || !c.has_seed[1]) {
    return usage_error("reconstruct needs --seed-maxilla and --seed-mandible", kReconstructUsage);
  }
  if (c.hu_min > c.hu_max) return usage_error("--hu-min is above --hu-max", kReconstructUsage);
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "reconstruct");
  Arena& arena = run.arena;
  const Context& ctx = run.ctx;
  std::vector<std::pair<std::string, double>> stages;
  double since = monotonic_seconds();
  auto stage = [&](const char* name) {
    const double now = monotonic_seconds();
    stages.emplace_back(name, now - since);
    since = now;
  };

  CtVolume volume;
  CtInfo info;
  Status s = cli::read_ct_path(ctx, o.positional[0], CtReadOptions{}, &volume, &info);
  if (!s.is_ok()) return rejected(o, "reconstruct", s, &arena);
  stage("read");
  LabelVolume labels;
  ThresholdStats ts;
  s = threshold_window(ctx, volume, HuWindow{c.hu_min, c.hu_max}, &labels, &ts);
  if (!s.is_ok()) return rejected(o, "reconstruct", s, &arena);
  stage("threshold");
  RegionSeed seeds[2];
  for (int jaw = 0; jaw < 2; ++jaw) {
    seeds[jaw].label = static_cast<uint8_t>(jaw + 1);
    seeds[jaw].patient_mm = c.seeds[jaw];
  }
  RegionGrowOptions go;
  go.connectivity = c.connectivity;
  go.plane = c.has_plane ? &c.plane : nullptr;
  RegionStats rs;
  s = grow_regions(ctx, volume, Span<const RegionSeed>(seeds, 2), go, &labels, &rs);
  if (!s.is_ok()) return rejected(o, "reconstruct", s, &arena);
  stage("region growing");
  ::mkdir(o.output, 0777);  // an existing folder is fine; a failure shows when writing

  const char* names[2] = {"maxilla", "mandible"};
  std::string rows, warnings;
  for (int jaw = 0; jaw < 2; ++jaw) {
    ArenaScope scope(arena);  // one jaw's mesh at a time
    Mesh mesh(&arena);
    ReconstructOptions ro;
    ro.label = static_cast<uint8_t>(jaw + 1);
    ro.hu_lo = c.hu_min;
    ro.round_to_float32 = !c.keep_double;
    ReconstructStats st;
    s = reconstruct_region(ctx, volume, labels, ro, &mesh, &st);
    if (!s.is_ok()) return rejected(o, "reconstruct", s, &arena);
    stage(jaw == 0 ? "reconstruct maxilla" : "reconstruct mandible");
    // Smoothing (Taubin) then decimation (quadric error): both keep the mesh closed and
    // outward; the check below still says so of what is written.
    TaubinStats ts_smooth;
    DecimateStats ds;
    if (c.smooth > 0) {
      TaubinOptions to;
      to.iterations = c.smooth;
      const double h = std::fmin(volume.spacing.x, std::fmin(volume.spacing.y, volume.spacing.z));
      to.max_displacement = 0.5 * h;
      s = taubin_smooth(ctx, &mesh, to, &ts_smooth);
      if (!s.is_ok()) return rejected(o, "reconstruct", s, &arena);
      stage(jaw == 0 ? "smooth maxilla" : "smooth mandible");
    }
    if (c.decimate > 0 && mesh.triangles.size() > c.decimate) {
      Mesh fewer(&arena);
      DecimateOptions dopt;
      dopt.target_triangles = c.decimate;
      s = decimate_qem(ctx, mesh, dopt, &fewer, &ds);
      if (!s.is_ok()) return rejected(o, "reconstruct", s, &arena);
      mesh = fewer;
      stage(jaw == 0 ? "decimate maxilla" : "decimate mandible");
    }
    if ((c.smooth > 0 || c.decimate > 0) && !c.keep_double) {
      for (Vec3& p : mesh.vertices) {
        if (!round_to_float32(&p)) {
          return rejected(o, "reconstruct",
                          make_error(StatusCode::kLimitExceeded, "a vertex is beyond float32"),
                          &arena);
        }
      }
    }
    double mesh_vol = 0;
    s = check_closed_oriented(ctx, mesh, &mesh_vol);
    if (!s.is_ok()) return rejected(o, "reconstruct", s, &arena);
    const std::string path = std::string(o.output) + "/" + names[jaw] + ".stl";
    s = write_atomically(ctx, mesh, path.c_str(), false);
    if (!s.is_ok()) return rejected(o, "reconstruct", s.in_file(path.c_str()), &arena);
    stage(jaw == 0 ? "write maxilla" : "write mandible");
    const uint8_t l = ro.label;
    if (rs.touches_border[l]) {
      warnings += std::string(warnings.empty() ? "" : ",") + "\"" + names[jaw] +
                  " touches the volume's border: it may continue beyond the scan\"";
      std::fprintf(stderr, "splintcore: warning: the %s touches the volume's border\n", names[jaw]);
    }
    JsonObject r;
    r.add("jaw", names[jaw]);
    r.add("file", path);
    r.add("voxels", rs.voxels[l]);
    r.add("meets_other_region", rs.meets_other_region[l]);
    r.add("touches_border", rs.touches_border[l]);
    r.add_raw("box_voxels",
              "[" + std::to_string(st.box_lo[0]) + "," + std::to_string(st.box_lo[1]) + "," +
                  std::to_string(st.box_lo[2]) + "," + std::to_string(st.box_hi[0]) + "," +
                  std::to_string(st.box_hi[1]) + "," + std::to_string(st.box_hi[2]) + "]");
    r.add("vertices", static_cast<uint64_t>(mesh.vertices.size()));
    r.add("triangles", static_cast<uint64_t>(mesh.triangles.size()));
    r.add("volume_mm3", mesh_vol);
    r.add("layers_per_tile", st.marching.layers_per_tile);
    if (c.smooth > 0) {
      r.add("smooth_iterations", static_cast<uint64_t>(c.smooth));
      r.add("smooth_volume_change_mm3", ts_smooth.volume_after - ts_smooth.volume_before);
    }
    if (c.decimate > 0) {
      r.add("decimated_from_triangles", ds.input_triangles);
      r.add("decimate_max_error_mm", ds.max_error);
    }
    rows += (jaw > 0 ? "," : "") + r.str();
    if (!o.json) {
      std::printf("%s: %s, %llu voxels, %zu triangles, %.1f mm^3\n", names[jaw], path.c_str(),
                  static_cast<unsigned long long>(rs.voxels[l]), mesh.triangles.size(), mesh_vol);
    }
  }
  if (o.json) {
    JsonObject j;
    j.add("command", "reconstruct");
    j.add_status(Status::ok());
    j.add("input", o.positional[0]);
    j.add("format", ct_format_name(info.format));
    j.add_raw("size", "[" + std::to_string(volume.nx) + "," + std::to_string(volume.ny) + "," +
                          std::to_string(volume.nz) + "]");
    j.add("spacing", volume.spacing);
    j.add("hu_min", static_cast<int64_t>(c.hu_min));
    j.add("hu_max", static_cast<int64_t>(c.hu_max));
    j.add("connectivity", static_cast<uint64_t>(c.connectivity == Connectivity::k26 ? 26 : 6));
    j.add("split_plane", c.has_plane);
    j.add("window_voxels", ts.in_window);
    j.add("unclaimed_voxels", rs.unclaimed);
    j.add("growth_layers", static_cast<uint64_t>(rs.layers));
    j.add_raw("jaws", "[" + rows + "]");
    j.add_raw("warnings", "[" + warnings + "]");
    std::string times;
    for (const auto& st : stages) {
      times += (times.empty() ? "" : ",") + std::string("\"") + st.first +
               "\":" + cli::json_number(st.second);
    }
    j.add_raw("stage_s", "{" + times + "}");
    j.add("time_s", monotonic_seconds() - run.start);
    j.add("peak_arena_bytes", static_cast<uint64_t>(arena.high_water()));
    j.add("memory_cap_bytes", o.memory_cap);
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("window voxels %llu, unclaimed %llu; %.3f s, peak arena %llu bytes\n",
                static_cast<unsigned long long>(ts.in_window),
                static_cast<unsigned long long>(rs.unclaimed), monotonic_seconds() - run.start,
                static_cast<unsigned long long>(arena.high_water()));
  }
  return kExitOk;
}

// Reads each file into its own mesh (in the arena, in order).
Status read_mesh_files(const Context& ctx, const std::vector<const char*>& paths,
                       std::vector<Mesh>* out) {
  out->resize(paths.size());
  for (size_t i = 0; i < paths.size(); ++i) {
    (*out)[i].bind(ctx.arena);
    StlInfo info;
    SPLINTCORE_RETURN_IF_ERROR(read_mesh_file(ctx, paths[i], &(*out)[i], &info));
  }
  return Status::ok();
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

int run_sweep_command(int argc, char** argv) {
  Options o;
  int early = parse_options(argc, argv, kSweepUsage, true, &o);
  if (early >= 0) return early;
  if (o.positional.empty()) return usage_error("sweep takes at least one JAW.stl", kSweepUsage);
  if (o.output == nullptr) return usage_error("sweep needs -o SWEPT.stl", kSweepUsage);
  if (!o.has_direction) return usage_error("sweep needs --direction X,Y,Z", kSweepUsage);
  if (!(o.voxel > 0)) return usage_error("sweep needs --voxel H (mm, > 0)", kSweepUsage);
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "sweep");
  const Context& ctx = run.ctx;
  std::vector<Mesh> jaws;
  Status s = read_mesh_files(ctx, o.positional, &jaws);
  if (!s.is_ok()) return rejected(o, "sweep", s, &run.arena);
  const double t_read = monotonic_seconds();
  AtomicFile file;
  s = file.open(o.output);
  if (!s.is_ok()) return rejected(o, "sweep", s, &run.arena);
  StlWriter writer;
  StlWriteOptions wo;
  wo.format = o.ascii ? StlFormat::kAscii : StlFormat::kBinary;
  s = writer.begin(ctx, file.sink(), wo, kUnknownSize);
  if (!s.is_ok()) return rejected(o, "sweep", s, &run.arena);
  SweepToStl to_stl{&writer};
  MarchingCubesVisitor visitor;
  visitor.triangle = SweepToStl::triangle;
  visitor.user = &to_stl;
  SweepOptions so;
  so.direction = o.direction;
  so.voxel = o.voxel;
  so.extent = o.extent;
  so.inset = o.inset < 0 ? 0 : o.inset;
  so.closing_radius = o.closing;
  SweepStats st;
  s = sweep_volume(ctx, Span<const Mesh>(jaws.data(), jaws.size()), so, visitor, &st);
  if (s.is_ok()) s = writer.finish();
  if (s.is_ok()) s = file.commit();  // on any error ~AtomicFile removes the temporary file
  if (!s.is_ok()) return rejected(o, "sweep", s, &run.arena);
  const double t_end = monotonic_seconds();
  uint64_t jaw_triangles = 0;
  for (const Mesh& m : jaws) jaw_triangles += m.triangles.size();
  if (o.json) {
    JsonObject j;
    j.add("command", "sweep");
    j.add("output", o.output);
    j.add_status(Status::ok());
    j.add("jaw_files", static_cast<uint64_t>(jaws.size()));
    j.add("jaw_triangles", jaw_triangles);
    j.add("direction", st.axis_w);
    j.add("voxel_mm", o.voxel);
    j.add("extent_mm", o.extent);
    j.add("inset_mm", so.inset);
    j.add("closing_radius_mm", o.closing);
    add_sweep_stats(&j, st);
    j.add("triangles", writer.triangles_written());
    j.add("bytes", writer.bytes_written());
    j.add("read_s", t_read - run.start);
    j.add("sweep_s", t_end - t_read);
    j.add("time_s", t_end - run.start);
    j.add("peak_arena_bytes", static_cast<uint64_t>(run.arena.high_water()));
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("jaws: %zu file(s), %llu triangles; direction (%.6g, %.6g, %.6g)\n", jaws.size(),
                static_cast<unsigned long long>(jaw_triangles), st.axis_w.x, st.axis_w.y,
                st.axis_w.z);
    std::printf("grid: %u x %u x %u = %llu voxels of %.4g mm, %u tile(s) of %u layer(s)\n", st.nx,
                st.ny, st.nz, static_cast<unsigned long long>(st.voxels), o.voxel,
                st.extraction.fill_calls, st.extraction.layers_per_tile);
    std::printf("swept volume: %llu triangles -> %s (%s STL)\n",
                static_cast<unsigned long long>(writer.triangles_written()), o.output,
                o.ascii ? "ascii" : "binary");
    std::printf("time: read %.4f s, sweep %.4f s; peak arena %llu bytes\n", t_read - run.start,
                t_end - t_read, static_cast<unsigned long long>(run.arena.high_water()));
  }
  return kExitOk;
}

int run_blockout_command(int argc, char** argv) {
  Options o;
  int early = parse_options(argc, argv, kBlockoutUsage, true, &o);
  if (early >= 0) return early;
  if (o.positional.size() < 2) {
    return usage_error("blockout takes SPLINT.stl and at least one JAW.stl", kBlockoutUsage);
  }
  if (o.output == nullptr) return usage_error("blockout needs -o OUT.stl", kBlockoutUsage);
  if (!o.has_direction) return usage_error("blockout needs --direction X,Y,Z", kBlockoutUsage);
  if (!(o.voxel > 0)) return usage_error("blockout needs --voxel H (mm, > 0)", kBlockoutUsage);
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "blockout");
  const Context& ctx = run.ctx;
  Mesh splint(&run.arena);
  StlInfo info;
  Status s = read_mesh_file(ctx, o.positional[0], &splint, &info);
  if (!s.is_ok()) return rejected(o, "blockout", s, &run.arena);
  std::vector<Mesh> jaws;
  s = read_mesh_files(ctx, std::vector<const char*>(o.positional.begin() + 1, o.positional.end()),
                      &jaws);
  if (!s.is_ok()) return rejected(o, "blockout", s, &run.arena);
  const double t_read = monotonic_seconds();
  BlockoutOptions bo;
  bo.sweep.direction = o.direction;
  bo.sweep.voxel = o.voxel;
  bo.sweep.inset = o.inset < 0 ? 0.5 * o.voxel : o.inset;
  bo.sweep.closing_radius = o.closing;
  bo.boolean.check_self_intersection = o.self_check;
  Mesh out;
  BlockoutStats st;
  s = blockout(ctx, splint, Span<const Mesh>(jaws.data(), jaws.size()), bo, &out, &st);
  if (!s.is_ok()) return rejected(o, "blockout", s, &run.arena);
  const double t_op = monotonic_seconds();
  MeshReport report;
  s = check_mesh(ctx, out, &report);
  if (s.is_ok()) s = write_atomically(ctx, out, o.output, o.ascii);
  if (!s.is_ok()) return rejected(o, "blockout", s, &run.arena);
  const double t_end = monotonic_seconds();
  const double removed = mesh_volume(splint) - report.volume;
  if (o.json) {
    JsonObject j;
    j.add("command", "blockout");
    j.add("splint", o.positional[0]);
    j.add("output", o.output);
    j.add_status(Status::ok());
    j.add("direction", st.sweep.axis_w);
    j.add("voxel_mm", o.voxel);
    j.add("inset_mm", bo.sweep.inset);
    j.add("closing_radius_mm", o.closing);
    add_sweep_stats(&j, st.sweep);
    j.add("swept_triangles", st.swept_triangles);
    j.add("cap_triangles_dropped", st.sweep.cap_triangles_dropped);
    j.add("intersecting_pairs", st.boolean.intersecting_pairs);
    j.add("removed_volume_mm3", removed);
    add_mesh_report(&j, report);
    j.add("valid_solid", report.is_valid_solid());
    j.add("read_s", t_read - run.start);
    j.add("blockout_s", t_op - t_read);
    j.add("time_s", t_end - run.start);
    j.add("peak_arena_bytes", static_cast<uint64_t>(run.arena.high_water()));
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("splint: %s, %zu triangles; jaws: %zu file(s)\n", o.positional[0],
                splint.triangles.size(), jaws.size());
    std::printf(
        "swept volume: grid %u x %u x %u of %.4g mm (+%u layers before the splint), "
        "%llu triangles in the splint's bounds\n",
        st.sweep.nx, st.sweep.ny, st.sweep.nz, o.voxel, st.sweep.preroll_layers,
        static_cast<unsigned long long>(st.swept_triangles));
    std::printf("removed: %.4f mm^3 of interference (inset %.4g mm)\n", removed, bo.sweep.inset);
    print_mesh_report(report);
    std::printf("output: %s (%s STL)\n", o.output, o.ascii ? "ascii" : "binary");
    std::printf("time: read %.4f s, blockout %.4f s, total %.4f s; peak arena %llu bytes\n",
                t_read - run.start, t_op - t_read, t_end - run.start,
                static_cast<unsigned long long>(run.arena.high_water()));
  }
  return kExitOk;
}

const char kCompareUsage[] =
    "usage: splintcore compare A B [--ply OUT.ply] [--png OUT.png] [--range MAX] [--json]\n"
    "                         [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "Surface deviation between two meshes (STL, PLY or OBJ), the accuracy measure of Chen et\n"
    "al. 2016: for every vertex of A the distance (mm) to the surface of B (closest point over\n"
    "a BVH), and for every vertex of B the distance to A; mean, max and RMS of each direction\n"
    "and their symmetric maximum (the Hausdorff distance over the vertices). --ply writes A as\n"
    "binary PLY, atomically, with each vertex coloured on a blue-green-red ramp over [0, MAX]\n"
    "(default: the A-to-B maximum) and its distance as the 'quality' property. The figures and\n"
    "the PLY bytes are the same for any thread count. --png writes a 1024x1024 PNG of A in four\n"
    "views (front, top, right, iso) coloured per pixel on the same ramp (blue 0, green MAX/2,\n"
    "red MAX and beyond), with the ramp as a bar at the right edge (blue at the bottom).\n";

int run_compare(int argc, char** argv) {
  // Its own options first; the rest go through parse_options.
  const char* ply = nullptr;
  const char* png = nullptr;
  double range = -1;
  std::vector<char*> rest;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--ply") == 0) {
      if (i + 1 >= argc) return usage_error("--ply needs a file name", kCompareUsage);
      ply = argv[++i];
    } else if (std::strcmp(argv[i], "--png") == 0) {
      if (i + 1 >= argc) return usage_error("--png needs a file name", kCompareUsage);
      png = argv[++i];
    } else if (std::strcmp(argv[i], "--range") == 0) {
      const char* v = i + 1 < argc ? argv[++i] : nullptr;
      const char* end = v == nullptr ? nullptr : v + std::strlen(v);
      if (v == nullptr || std::from_chars(v, end, range).ptr != end || !is_finite(range) ||
          !(range > 0)) {
        return usage_error("--range needs a number of mm > 0", kCompareUsage);
      }
    } else {
      rest.push_back(argv[i]);
    }
  }
  Options o;
  int early = parse_options(static_cast<int>(rest.size()), rest.data(), kCompareUsage, false, &o);
  if (early >= 0) return early;
  if (o.positional.size() != 2) return usage_error("compare takes two mesh files", kCompareUsage);
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "compare");
  Arena& arena = run.arena;
  const Context& ctx = run.ctx;
  const double t0 = run.start;

  Mesh a(&arena), b(&arena);
  StlInfo info_a, info_b;
  Status s = read_mesh_file(ctx, o.positional[0], &a, &info_a);
  if (s.is_ok()) s = read_mesh_file(ctx, o.positional[1], &b, &info_b);
  if (!s.is_ok()) return rejected(o, "compare", s, &arena);
  std::vector<double> da, db;
  cli::Comparison c;
  s = cli::compare_meshes(ctx, a, b, &da, &db, &c);
  if (!s.is_ok()) return rejected(o, "compare", s, &arena);
  if (range <= 0) range = c.a_to_b.max;
  if (ply != nullptr) {
    s = write_bytes_atomically(ply, cli::distance_ply(a, da, range));
    if (!s.is_ok()) return rejected(o, "compare", s, &arena);
  }
  cli::PreviewInfo png_info;
  if (png != nullptr) {  // identical meshes (range 0): all blue on a 1 mm ramp
    s = cli::write_distance_png(ctx, a, da, range > 0 ? range : 1.0, png, 1024, 1024, &png_info);
    if (!s.is_ok()) return rejected(o, "compare", s, &arena);
  }
  const double seconds = monotonic_seconds() - t0;
  if (o.json) {
    JsonObject j;
    j.add("command", "compare");
    j.add("a", o.positional[0]);
    j.add("b", o.positional[1]);
    j.add_status(Status::ok());
    j.add("a_format", info_a.header);
    j.add("b_format", info_b.header);
    j.add("a_vertices", static_cast<uint64_t>(a.vertices.size()));
    j.add("a_triangles", static_cast<uint64_t>(a.triangles.size()));
    j.add("b_vertices", static_cast<uint64_t>(b.vertices.size()));
    j.add("b_triangles", static_cast<uint64_t>(b.triangles.size()));
    j.add("a_to_b_mean_mm", c.a_to_b.mean);
    j.add("a_to_b_max_mm", c.a_to_b.max);
    j.add("a_to_b_rms_mm", c.a_to_b.rms);
    j.add("b_to_a_mean_mm", c.b_to_a.mean);
    j.add("b_to_a_max_mm", c.b_to_a.max);
    j.add("b_to_a_rms_mm", c.b_to_a.rms);
    j.add("hausdorff_mm", c.hausdorff);
    if (ply != nullptr) {
      j.add("ply", ply);
      j.add("range_mm", range);
    }
    if (png != nullptr) {
      j.add("png", png);
      j.add("png_sha256", png_info.sha256);
      j.add("png_range_mm", range > 0 ? range : 1.0);
    }
    j.add("time_s", seconds);
    j.add("peak_arena_bytes", static_cast<uint64_t>(arena.high_water()));
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("A: %s (%s, %zu vertices, %zu triangles)\n", o.positional[0], info_a.header,
                a.vertices.size(), a.triangles.size());
    std::printf("B: %s (%s, %zu vertices, %zu triangles)\n", o.positional[1], info_b.header,
                b.vertices.size(), b.triangles.size());
    std::printf("A to B: mean %.6f mm, max %.6f mm, RMS %.6f mm\n", c.a_to_b.mean, c.a_to_b.max,
                c.a_to_b.rms);
    std::printf("B to A: mean %.6f mm, max %.6f mm, RMS %.6f mm\n", c.b_to_a.mean, c.b_to_a.max,
                c.b_to_a.rms);
    std::printf("Hausdorff (symmetric max): %.6f mm\n", c.hausdorff);
    if (ply != nullptr) std::printf("ply: %s (colour range [0, %.6f] mm)\n", ply, range);
    if (png != nullptr) {
      std::printf("png: %s (colour range [0, %.6f] mm, blue to red)\n", png,
                  range > 0 ? range : 1.0);
    }
    std::printf("time: %.3f s, peak arena: %llu bytes\n", seconds,
                static_cast<unsigned long long>(arena.high_water()));
  }
  return kExitOk;
}

// ---- render: PNG previews (issue 8) ----------------------------------------------------------
const char kRenderUsage[] =
    "usage: splintcore render MESH [MESH ...] -o PREVIEW.png [--size WxH] [--views LIST]\n"
    "                        [--shading flat|gouraud] [--json] [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "A PNG preview of meshes (STL, PLY or OBJ) drawn by splintcore's own rasteriser and PNG\n"
    "encoder: the first mesh as the splint (opaque blue), the others as jaws (translucent\n"
    "grey), in orthographic views tiled two per row: --views is a comma-separated list\n"
    "of front, top, right and iso (default all four, in that order). --size is the whole image\n"
    "(default 1024x1024, each side 1..8192). All views share one scale. --shading gouraud\n"
    "interpolates vertex lighting (default flat). The file is written atomically; its bytes\n"
    "depend only on the inputs and options (any --threads).\n";

// "WxH" -> two sides of 1..kRenderMaxSide.
bool parse_wxh(const char* text, uint32_t* w, uint32_t* h) {
  const char* x = std::strchr(text, 'x');
  if (x == nullptr) return false;
  const char* end = text + std::strlen(text);
  uint64_t a = 0, b = 0;
  auto ra = std::from_chars(text, x, a);
  auto rb = std::from_chars(x + 1, end, b);
  if (ra.ec != std::errc() || ra.ptr != x || rb.ec != std::errc() || rb.ptr != end) return false;
  if (a == 0 || b == 0 || a > kRenderMaxSide || b > kRenderMaxSide) return false;
  *w = static_cast<uint32_t>(a);
  *h = static_cast<uint32_t>(b);
  return true;
}

int run_render(int argc, char** argv) {
  RenderOptions ro;
  std::vector<char*> rest;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--size") == 0) {
      if (i + 1 >= argc || !parse_wxh(argv[i + 1], &ro.width, &ro.height)) {
        return usage_error("--size needs WxH, each side 1..8192 pixels", kRenderUsage);
      }
      ++i;
    } else if (std::strcmp(argv[i], "--views") == 0) {
      const char* v = i + 1 < argc ? argv[++i] : nullptr;
      ro.view_count = 0;
      bool ok = v != nullptr && *v != '\0';
      while (ok && *v != '\0') {
        const char* comma = std::strchr(v, ',');
        const size_t n = comma != nullptr ? static_cast<size_t>(comma - v) : std::strlen(v);
        ok = ro.view_count < kRenderMaxViews && parse_render_view(v, n, &ro.views[ro.view_count]);
        ++ro.view_count;
        v += n;
        if (*v == ',') {
          ++v;
          ok = ok && *v != '\0';
        }
      }
      if (!ok) {
        return usage_error("--views needs a list of front, top, right, iso (at most 8)",
                           kRenderUsage);
      }
    } else if (std::strcmp(argv[i], "--shading") == 0) {
      const char* v = i + 1 < argc ? argv[++i] : nullptr;
      if (v != nullptr && std::strcmp(v, "flat") == 0) {
        ro.shading = RenderShading::kFlat;
      } else if (v != nullptr && std::strcmp(v, "gouraud") == 0) {
        ro.shading = RenderShading::kGouraud;
      } else {
        return usage_error("--shading takes flat or gouraud", kRenderUsage);
      }
    } else {
      rest.push_back(argv[i]);
    }
  }
  Options o;
  int early = parse_options(static_cast<int>(rest.size()), rest.data(), kRenderUsage, true, &o);
  if (early >= 0) return early;
  if (o.positional.empty()) return usage_error("render takes at least one mesh file", kRenderUsage);
  if (o.output == nullptr) return usage_error("render needs -o PREVIEW.png", kRenderUsage);
  Run run(o);
  if (!run.has_memory()) return no_memory(o, "render");
  Arena& arena = run.arena;
  const Context& ctx = run.ctx;
  std::vector<Mesh> meshes(o.positional.size());
  uint64_t triangles = 0;
  for (size_t i = 0; i < meshes.size(); ++i) {
    meshes[i].bind(&arena);
    Status s = read_mesh_file(ctx, o.positional[i], &meshes[i], nullptr);
    if (!s.is_ok()) return rejected(o, "render", s, &arena);
    triangles += meshes[i].triangles.size();
  }
  const double t_read = monotonic_seconds();
  std::vector<RenderMesh> items;
  for (size_t i = 0; i < meshes.size(); ++i) {
    RenderMesh m;
    m.mesh = &meshes[i];
    const uint8_t* rgb = i == 0 ? cli::kSplintRgb : cli::kJawRgb;
    for (int k = 0; k < 3; ++k) m.rgb[k] = rgb[k];
    m.alpha = i == 0 ? 255 : cli::kJawAlpha;
    items.push_back(m);
  }
  cli::PreviewInfo info;
  Status s = cli::write_png_file(ctx, items, ro, o.output, &info);
  if (!s.is_ok()) return rejected(o, "render", s, &arena);
  const double t_end = monotonic_seconds();
  std::string views;
  for (uint32_t v = 0; v < ro.view_count; ++v) {
    views += std::string(v > 0 ? "," : "") + render_view_name(ro.views[v]);
  }
  if (o.json) {
    JsonObject j;
    j.add("command", "render");
    j.add_status(Status::ok());
    j.add("output", o.output);
    j.add("png_sha256", info.sha256);
    j.add("png_bytes", info.png_bytes);
    j.add("width", static_cast<uint64_t>(info.width));
    j.add("height", static_cast<uint64_t>(info.height));
    j.add("views", views);
    j.add("shading", ro.shading == RenderShading::kGouraud ? "gouraud" : "flat");
    j.add("meshes", static_cast<uint64_t>(meshes.size()));
    j.add("triangles", triangles);
    j.add("pixels_per_mm", info.pixels_per_mm);
    j.add("read_s", t_read - run.start);
    j.add("render_s", info.render_seconds);
    j.add("encode_s", info.encode_seconds);
    j.add("time_s", t_end - run.start);
    j.add("peak_arena_bytes", static_cast<uint64_t>(arena.high_water()));
    std::printf("%s\n", j.str().c_str());
  } else {
    std::printf("render: %zu mesh(es), %llu triangles, views %s, %u x %u pixels, %.4g px/mm\n",
                meshes.size(), static_cast<unsigned long long>(triangles), views.c_str(),
                info.width, info.height, info.pixels_per_mm);
    std::printf("wrote %s (%llu bytes, sha256 %s)\n", o.output,
                static_cast<unsigned long long>(info.png_bytes), info.sha256.c_str());
    std::printf(
        "time: read %.3f s, render %.3f s, encode %.3f s, total %.3f s; peak arena %llu "
        "bytes\n",
        t_read - run.start, info.render_seconds, info.encode_seconds, t_end - run.start,
        static_cast<unsigned long long>(arena.high_water()));
  }
  return kExitOk;
}

// The commands, in the order `splintcore --help` lists them: the one table the dispatch, the
// help text and the tests (tests/tools/cli_test.sh: README and --help agree with it) read.
struct Command {
  const char* name;
  int (*run)(int argc, char** argv);
  const char* usage;    // its --help text, starting "usage: splintcore NAME"
  const char* summary;  // one line for `splintcore --help`
};

const Command kCommands[] = {
    {"check", run_check, kCheckUsage, "check a mesh is a printable solid"},
    {"convert", run_convert, kConvertUsage, "read, weld, check and rewrite an STL"},
    {"base", run_base, kBaseUsage, "build the initial splint base from the picks"},
    {"distance", run_distance, kDistanceUsage, "closest point, signed distance, winding number"},
    {"boolean", run_boolean, kBooleanUsage, "splint base minus jaws (or --union, --intersection)"},
    {"phantom", run_phantom, kPhantomUsage, "synthetic maxilla.stl, mandible.stl and case.json"},
    {"design", run_design, kDesignUsage,
     "the splint from a case: splint.stl, report.json, preview.png"},
    {"sweep", run_sweep_command, kSweepUsage, "the jaws' swept volume (the blocked-out model)"},
    {"blockout", run_blockout_command, kBlockoutUsage,
     "interference elimination: splint minus the swept volume"},
    {"ct-phantom", run_ct_phantom, kCtPhantomUsage, "synthetic skull CT (dicom, nrrd or mha)"},
    {"reconstruct", run_reconstruct, kReconstructUsage, "CT in, maxilla.stl and mandible.stl out"},
    {"compare", run_compare, kCompareUsage, "surface deviation (mean/max/RMS, Hausdorff)"},
    {"render", run_render, kRenderUsage, "PNG preview: front, top, right and iso views"},
};

void print_usage(std::FILE* out) {
  std::fputs(kUsageHead, out);
  for (const Command& c : kCommands) std::fprintf(out, "  %-12s %s\n", c.name, c.summary);
  std::fputs(kUsageTail, out);
}

}  // namespace
}  // namespace splintcore

int main(int argc, char** argv) {
  using namespace splintcore;
  if (argc < 2) {
    print_usage(stderr);
    return cli::kExitUsage;
  }
  const char* command = argv[1];
  if (std::strcmp(command, "--help") == 0 || std::strcmp(command, "-h") == 0 ||
      std::strcmp(command, "help") == 0) {
    print_usage(stdout);
    return cli::kExitOk;
  }
  for (const Command& c : kCommands) {
    if (std::strcmp(command, c.name) == 0) return c.run(argc - 2, argv + 2);
  }
  std::fprintf(stderr, "splintcore: unknown command '%s'\n\n", command);
  print_usage(stderr);
  return cli::kExitUsage;
}
