// splintcore: the command-line program. One subcommand per stage of the method; each takes
// --help, --json, --memory-cap SIZE and --threads N, exits 0 on success, 1 when the input is
// rejected (or a check fails, or the memory cap is too small), 2 on a usage error.
//
// This file is what the program offers: the command table (kCommands) with each command's
// usage text, and the dispatch. Each command's options are a table next to its code
// (mesh_commands.cpp, splint_commands.cpp, design_command.cpp, blockout_commands.cpp,
// ct_commands.cpp), read by the one option parser (options.h); its --help is its usage text
// followed by that table.
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "command.h"

namespace splintcore {
namespace tool {
namespace {

// The general text of `splintcore --help`: the list of commands comes from kCommands, the
// options of every command from common_options().
const char kUsageHead[] = "usage: splintcore <command> [options]\n\ncommands:\n";
const char kUsageTail[] =
    "\n"
    "mesh inputs may be STL (binary or ASCII), PLY (ASCII or binary) or OBJ, told apart by\n"
    "their content (then the file extension); PLY and OBJ polygons are fan-triangulated.\n"
    "\n"
    "exit status: 0 success, 1 input rejected or check failed, 2 usage error\n";

const char kCheckUsage[] =
    "usage: splintcore check IN.stl [--printer NAME] [--no-place] [--json]\n"
    "                       [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "Reads a mesh (STL, PLY or OBJ; STL welded) and reports: closed (else its boundary edges\n"
    "and loops), edge-manifold, consistently and outward oriented, degenerate and duplicate\n"
    "triangles, shells, genus, area, volume, extent, and whether it fits the printer's build\n"
    "volume (centred on the tray unless --no-place). An open mesh (a scan) has no volume, genus\n"
    "or outward side: they print as n/a (open), null in --json. Exit 0 only when the mesh is\n"
    "printable.\n"
    "Printers: eden260 (Stratasys Eden260-class PolyJet, 255 x 252 x 200 mm, 16 um layers).\n";

const char kConvertUsage[] =
    "usage: splintcore convert IN.stl -o OUT.stl [--ascii] [--scale F] [--json]\n"
    "                         [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "Reads a mesh (STL binary or ASCII, PLY or OBJ, by content; IN - is the standard input),\n"
    "welds identical vertices, optionally scales it about the origin (a mesh in other units\n"
    "to mm: --scale 25.4 from inches, 1000 from metres, 0.001 from micrometres; each\n"
    "coordinate rounded to float32), checks it, and writes it: OUT.ply as binary PLY, any\n"
    "other name as STL through the streaming writer (binary unless --ascii; .obj, .3mf and\n"
    "other mesh formats' names are refused). The output is written atomically: on any error\n"
    "no output file is left behind. The bytes depend only on the input's triangles and the\n"
    "scale.\n";

const char kBaseUsage[] =
    "usage: splintcore base CASE.json -o BASE.stl [--ascii] [--json]\n"
    "                      [--memory-cap SIZE] [--threads N] [--max-input-bytes SIZE]\n"
    "\n"
    "Builds the initial splint base of the case (Chen et al. 2016): each pick becomes a line\n"
    "(inner and outside point), centripetal Catmull-Rom splines run through the line ends,\n"
    "and ruled surfaces between sections sampled at matched arc length form one closed solid.\n"
    "The base is checked (closed, manifold, outward, no self-intersection, as float32) before\n"
    "it is written, atomically. The case format is in docs/case-format.md.\n";

const char kDistanceUsage[] =
    "usage: splintcore distance MESH.stl --query X,Y,Z [--query X,Y,Z ...]\n"
    "                          [--sign auto|pseudonormal|winding] [--json]\n"
    "                          [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "Builds the distance index (a BVH) over the mesh and prints, per query point (mm): the\n"
    "closest point, its triangle and feature (face, edge or vertex), the unsigned and signed\n"
    "distance (negative inside) and the generalised winding number. --sign auto uses\n"
    "pseudonormals on a closed manifold mesh and the winding number otherwise.\n";

const char kAutorotateUsage[] =
    "usage: splintcore autorotate MAXILLA MANDIBLE --hinge X1,Y1,Z1,X2,Y2,Z2 --opening MM\n"
    "                            [-o ROTATED.stl] [--ascii] [--json] [--memory-cap SIZE]\n"
    "\n"
    "Turns the mandible about the hinge axis (the line through the two condylar points, which\n"
    "stays fixed) to the angle at which, closing from open, the smallest distance between the\n"
    "jaws first equals MM (0 to 10): from the jaws as given when they are farther apart, else\n"
    "after opening them first. The closing sense is the one that moves the mandible's centroid\n"
    "towards the maxilla's. Exact to 1e-10 rad (conservative advancement over the distance\n"
    "index, no sampling in angle); at most 30 degrees either way, else rejected with the\n"
    "distances measured. Prints the angle (rad and degrees, right-handed about point 1 -> 2),\n"
    "the 4x4 applied to the mandible, the opening measured and the contact points; -o writes\n"
    "the turned mandible as STL, atomically.\n";

const char kRegisterUsage[] =
    "usage: splintcore register SCAN CT_JAW -o OUT.json [--landmarks \"X Y Z X Y Z; ...\"]\n"
    "                          [--overlap F] [--max-rms MM] [--moved MOVED.stl]\n"
    "                          [--toward X,Y,Z] [--json] [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "Scan-CT fusion: the rigid motion that places an intraoral scan (an open surface, crowns\n"
    "and gum) onto a jaw reconstructed from CT. The start is the best of nine after a coarse fit\n"
    "(the scan as given, turned 5 and 10 degrees either way about the CT's occlusal axis, or its\n"
    "principal axes onto the CT's), or the least-squares fit of 3+ landmark pairs (each a scan\n"
    "point then the same point on the CT, mm; pairs left over 2 mm RMS apart are rejected as a\n"
    "wrong pairing). Then a trimmed point-to-plane ICP: up to 3000 scan vertices (every k-th)\n"
    "paired with their closest points on the CT, the best --overlap of them (default 0.6: scans\n"
    "are mostly gum, which CT does not show) fitted, until the update is under 1e-7 mm and rad.\n"
    "A fit whose RMS is over --max-rms (default 0.3 mm) is rejected, and so is a scan that faces\n"
    "away: wound inside out against the CT's surface, or, with --toward (the direction from the\n"
    "CT jaw to the other jaw), with its occlusal side pointing away from it (upside down; the\n"
    "starts that end so are passed over). Writes OUT.json (the 4x4\n"
    "scan -> CT, row-major; RMS; the overlap: samples within 0.5 mm; iterations) and with\n"
    "--moved the moved scan (STL), atomically. The bytes are the same at any --threads.\n"
    "A scan that is mostly gum may need landmarks (docs/commands.md).\n";

const char kBooleanUsage[] =
    "usage: splintcore boolean --difference|--union|--intersection A.stl B.stl [B2.stl ...]\n"
    "                         -o OUT.stl [--translate-b X,Y,Z] [--ascii] [--no-self-check]\n"
    "                         [--max-pairs N] [--json] [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "A is a closed solid (the splint base); B is the union of the other files' shells (the\n"
    "jaws: one closed shell per tooth is fine; shells that overlap are united, one pass per\n"
    "group of shells that do not overlap, as --json's shell_groups and passes say),\n"
    "translated by --translate-b (mm; given once it moves every B file, given once per B file\n"
    "it moves each in order: e.g. 0,0,0 then 0,0,-2 opens the bite; moved vertices are rounded\n"
    "to float32, as a moved jaw's STL would hold them). For --difference and --intersection\n"
    "B is read cropped to where it can matter (A's box, with room for the nudges): the\n"
    "triangles beyond it are never welded or held (--json's b_triangles_kept counts the rest),\n"
    "the same solid as with B whole; a refusal is said as B whole says it. Both are split along\n"
    "their intersection with exact predicates, re-triangulated, classified and assembled; the\n"
    "jaw's own triangles form the imprint, its vertices copied bit for bit. The result is\n"
    "checked as float32 (closed, manifold, outward, no vertex merged or triangle flattened by\n"
    "rounding, and, unless --no-self-check, no self-intersection) before it is written,\n"
    "atomically. Exact degenerate contacts (a vertex on the other surface, edges crossing\n"
    "exactly, coplanar faces) are resolved exactly; where the exact result is not a manifold\n"
    "solid (e.g. parts touching along an edge), A is nudged by at most about 1 um and the\n"
    "summary says so. The work is bounded: surfaces that nearly coincide over a large area\n"
    "(long thin CAD triangles over dense ones) can pair every triangle with every other near\n"
    "it; past --max-pairs candidate pairs the run stops with an error saying so.\n";

const char kPrepareUsage[] =
    "usage: splintcore prepare IN -o OUT.stl [--min-island MM2] [--min-island-triangles N]\n"
    "                         [--max-hole-edges N] [--occlusal X,Y,Z] [--ascii] [--json]\n"
    "                         [--memory-cap SIZE] [--threads N]\n"
    "\n"
    "Scan preparation: reads an intraoral scan (STL, PLY or OBJ) and, in this order, removes\n"
    "duplicate and degenerate (zero-area, exact) triangles, resolves edges with 3+ triangles\n"
    "(the two best connected stay), splits non-manifold vertices, removes islands under\n"
    "--min-island mm^2 (default 10; or --min-island-triangles N), orients every component\n"
    "consistently (the input's majority winding; --occlusal turns the whole mesh so its net\n"
    "normal points that way), fills holes of at most --max-hole-edges boundary edges (default\n"
    "32; a triangle, or a fan from the hole's centroid) and drops unused vertices. Prints\n"
    "each step's count and the result's check; writes OUT.stl atomically. The scan's own\n"
    "border (hundreds of edges) stays open. The output depends only on the input's bytes.\n";

const char kPhantomUsage[] =
    "usage: splintcore phantom --triangles N -o DIR [--json]\n"
    "       splintcore phantom --scan [--seed N] -o DIR [--json]\n"
    "\n"
    "Writes DIR/maxilla.stl and DIR/mandible.stl: synthetic dental-arch jaws (a gum ridge and\n"
    "14 big-end-up crowns with cusps each, one closed genus-0 shell per jaw, float32-exact), N\n"
    "triangles per jaw (2000..16000000, within 1%), in occlusion, in the frame of\n"
    "fixtures/cases/paper_scale.json: with that case's mandible transform (2 mm down) its base\n"
    "cuts 1.3-1.5 mm into every crown. Also DIR/case.json, that case for these jaws (design\n"
    "it with `splintcore design DIR/case.json -o OUT`). The bytes depend only on N.\n"
    "With --scan: open, scan-like jaws instead (tools/common/phantom.h): DIR/maxilla_scan and\n"
    "DIR/mandible_scan, each as .stl (binary) and .ply (binary, per-vertex colours): crowns on\n"
    "a band of gum with a ragged border, 3 holes (4-8 edges), 3 loose islands, 2 non-manifold\n"
    "flaps, 2 duplicate triangles, a patch wound the other way and 0.05 mm of noise, placed by\n"
    "--seed (default 1); the summary lists what was planted. The bytes depend only on the seed.\n";

const char kOutlineUsage[] =
    "usage: splintcore outline CASE.json -o RESOLVED.json [--json] [--memory-cap SIZE]\n"
    "                         [--threads N] [--max-input-bytes SIZE]\n"
    "\n"
    "The automatic outline of a case whose base is {\"auto\": {...}} (docs/case-format.md),\n"
    "without designing: finds the occlusal plane, the dental arch, the picks with their\n"
    "directions and lengths, the wafer's heights for the indentation depth and, with\n"
    "\"bite_opening_mm\", the mandible's move; writes them as a complete case with explicit\n"
    "picks to RESOLVED.json (atomically). Edit a pick and design that file: it gives the same\n"
    "splint as the auto case when left as written. Jaw paths stay as the case gives them when\n"
    "RESOLVED.json is in the case's folder, else they are written absolute.\n";

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
    "A case with \"plan\" (two-jaw surgery) gives two splints, OUTDIR/intermediate.stl and\n"
    "OUTDIR/final.stl, the mandible turned about the plan's hinge axis to each opening, a\n"
    "preview of each and one report.json for both.\n"
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
    "usage: splintcore blockout SPLINT.stl JAW.stl [JAW2.stl ...] --direction X,Y,Z\n"
    "                          (--voxel H [--close R] [--inset D] | --exact) -o OUT.stl\n"
    "                          [--ascii] [--no-self-check] [--json] [--memory-cap SIZE]\n"
    "                          [--threads N]\n"
    "\n"
    "Interference elimination: the splint minus the jaws' swept volume along the direction,\n"
    "subtracted by the exact Boolean and checked (closed, manifold, outward, float32, no\n"
    "self-intersection unless --no-self-check) before it is written, atomically. The direction\n"
    "is the one the splint is seated along for these jaws (for a wafer: the maxilla's is the\n"
    "mandible's reversed; run once per jaw). With --voxel the swept volume is sampled (as\n"
    "`sweep`, cut to the splint's bounds) and taken --inset D mm inside (default H / 2): the\n"
    "splint already holds the jaw's imprint, which the swept volume reproduces to within the\n"
    "voxel error, and the inset keeps the two apart; at most D of undercut is left. With\n"
    "--exact it is the exact boundary instead, the jaws' own front triangles (facing against\n"
    "the direction) and walls along it, with no voxels and no inset (the jaw files are joined\n"
    "as one jaw). It holds the jaw itself, so give it the splint before the jaws are\n"
    "subtracted (a cut splint's imprint coincides with it, which the Boolean can only nudge\n"
    "apart). A jaw whose swept surface would cross itself inside the splint, or whose\n"
    "folds would leave more than 0.05 mm of undercut (an overhang), is refused with where\n"
    "(docs/case-format.md, blockout \"method\").\n";

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

// The commands, in the order `splintcore --help` lists them: the one table the dispatch, the
// help text and the tests (tests/tools/cli_test.sh: README and --help agree with it) read.
const Command kCommands[] = {
    {"check", run_check, kCheckUsage, "check a mesh is a printable solid"},
    {"convert", run_convert, kConvertUsage, "read, weld, check and rewrite an STL"},
    {"prepare", run_prepare, kPrepareUsage, "scan preparation: islands, holes, orientation"},
    {"base", run_base, kBaseUsage, "build the initial splint base from the picks"},
    {"distance", run_distance, kDistanceUsage, "closest point, signed distance, winding number"},
    {"boolean", run_boolean, kBooleanUsage, "splint base minus jaws (or --union, --intersection)"},
    {"phantom", run_phantom, kPhantomUsage,
     "synthetic maxilla.stl, mandible.stl and case.json (--scan: open scans)"},
    {"outline", run_outline, kOutlineUsage, "the automatic outline as a case with explicit picks"},
    {"autorotate", run_autorotate, kAutorotateUsage,
     "the mandible turned about the hinge axis to an opening"},
    {"register", run_register, kRegisterUsage, "scan-CT fusion: a scan placed onto a CT jaw"},
    {"design", run_design, kDesignUsage,
     "the splint from a case: splint.stl, report.json, preview.png"},
    {"sweep", run_sweep, kSweepUsage, "the jaws' swept volume (the blocked-out model)"},
    {"blockout", run_blockout, kBlockoutUsage,
     "interference elimination: splint minus the swept volume"},
    {"ct-phantom", run_ct_phantom, kCtPhantomUsage, "synthetic skull CT (dicom, nrrd or mha)"},
    {"reconstruct", run_reconstruct, kReconstructUsage, "CT in, maxilla.stl and mandible.stl out"},
    {"compare", run_compare, kCompareUsage, "surface deviation (mean/max/RMS, Hausdorff)"},
    {"render", run_render, kRenderUsage, "PNG preview: front, top, right and iso views"},
};

void print_usage(std::FILE* out) {
  std::fputs(kUsageHead, out);
  for (const Command& c : kCommands) std::fprintf(out, "  %-12s %s\n", c.name, c.summary);
  std::fputs("\noptions of every command:\n", out);
  CommonArgs unused;
  print_options(out, common_options(&unused));
  std::fputs(kUsageTail, out);
}

}  // namespace
}  // namespace tool
}  // namespace splintcore

namespace splintcore {
namespace tool {
namespace {

int run_command(int argc, char** argv) {
  if (argc < 2) {
    print_usage(stderr);
    return kExitUsage;
  }
  const char* command = argv[1];
  if (std::strcmp(command, "--help") == 0 || std::strcmp(command, "-h") == 0 ||
      std::strcmp(command, "help") == 0) {
    print_usage(stdout);
    return kExitOk;
  }
  for (const Command& c : kCommands) {
    if (std::strcmp(command, c.name) == 0) return c.run(c, argc - 2, argv + 2);
  }
  std::fprintf(stderr, "splintcore: unknown command '%s'\n\n", command);
  print_usage(stderr);
  return kExitUsage;
}

// What the command printed must have reached the standard output (a full disk, a closed
// descriptor): else the run fails, so that a reader of --json never takes a cut-off object
// for the whole one (as GNU programs check at exit).
int with_output_checked(int code) {
  errno = 0;
  if (std::fflush(stdout) == 0 && std::ferror(stdout) == 0) return code;
  std::fprintf(stderr, "splintcore: error: cannot write the standard output%s%s\n",
               errno != 0 ? ": " : "", errno != 0 ? std::strerror(errno) : "");
  return code == kExitOk ? kExitRejected : code;
}

}  // namespace
}  // namespace tool
}  // namespace splintcore

int main(int argc, char** argv) {
  using namespace splintcore::tool;
  // Stopped by a signal (Ctrl-C, kill, a closed pipe) or past `ulimit -f`: no half-written
  // output left behind (platform.h).
  splintcore::remove_temporary_outputs_on_signals();
  return with_output_checked(run_command(argc, argv));
}
