// splintcore design: the case file (format in docs/case-format.md), the whole design pipeline
// and its audit report (docs/report-format.md).
#ifndef SPLINTCORE_DESIGN_H
#define SPLINTCORE_DESIGN_H

#include "splintcore/blockout.h"
#include "splintcore/boolean.h"
#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/json.h"
#include "splintcore/label.h"
#include "splintcore/outline.h"
#include "splintcore/printer.h"
#include "splintcore/registration.h"
#include "splintcore/remesh.h"
#include "splintcore/segment.h"
#include "splintcore/spline.h"

namespace splintcore {

constexpr uint32_t kCaseFormatVersion = 1;

// An intraoral scan fused into a jaw ("scan" in a jaw, docs/case-format.md, "Scan-CT fusion"):
// design registers it onto the jaw's mesh (register_rigid, trimmed point-to-plane ICP) and the
// registered scan is the jaw's surface for the imprint.
struct CaseScan {
  const char* path = nullptr;          // the scan's mesh file, relative to the case file
  Span<const LandmarkPair> landmarks;  // "landmarks": [[scan xyz, jaw xyz], ...] (3 or more)
  double trim = 0.6;                   // RegisterOptions::overlap: the fraction the ICP keeps
  double min_overlap = 0.3;            // at least this fraction of the scan within crowns_within_mm
  double max_rms_mm = 0.3;             // RegisterOptions::max_rms_mm
  double crowns_within_mm = 0.5;       // RegisterOptions::inlier_mm: the crowns' distance
};

struct CaseJaw {
  const char* role = "";       // "maxilla" or "mandible"
  const char* mesh = nullptr;  // path, relative to the case file's folder
  RigidTransform transform;    // the surgical plan's repositioning (identity if not given)
  // A jaw from the case's CT ("seed" instead of "mesh"): a point of it, patient mm.
  bool has_seed = false;
  Vec3 seed{};
  // An intraoral scan of this jaw's teeth, fused in by design_splint (CaseScan).
  bool has_scan = false;
  CaseScan scan;
};

// The surgical plan of two-jaw surgery ("plan", docs/case-format.md): the case's jaws are the
// preoperative ones in occlusion, these are the planned rigid moves (patient mm), and the
// mandible turns about the hinge axis through the two condyles (which stay where they are).
struct CasePlan {
  bool mandible_first = false;         // "sequence": "maxilla_first" (false) or "mandible_first"
  RigidTransform maxilla;              // the maxilla's planned move
  RigidTransform mandible;             // the mandible's planned move
  Vec3 hinge[2] = {};                  // the condylar points, at least 1 mm apart
  double intermediate_opening_mm = 0;  // [0, 10]
  double final_opening_mm = 0;         // [0, 10]
  // "picks": each splint's own picks ([0] the intermediate's, [1] the final's), each pair of
  // lists as "base"'s "upper" and "lower", on the jaws where that splint holds them. Without
  // them the base's picks serve both splints, or "auto" outlines each splint on its own.
  bool has_picks = false;
  Span<const Pick> upper[2];
  Span<const Pick> lower[2];
};

// How a case's blockout sweeps each jaw (CaseFile::blockout_method says each).
// kHeightfield: the swept volume as a height field over the voxel grid (blockout.h,
// sweep_heightfield_mesh), no inset, nothing left undercut.
enum class BlockoutMethod : uint8_t { kAuto = 0, kExact = 1, kVoxel = 2, kHeightfield = 4 };

// The case file's name of a method: "auto", "exact", "voxel", "heightfield".
const char* blockout_method_name(BlockoutMethod m);

// A parsed case. Strings and arrays live in the arena the case was parsed into.
struct CaseFile {
  uint32_t version = 0;
  const char* case_id = "";
  char sha256[65] = {};  // of the case file's text, 64 lower-case hex digits (parse_case)
  Span<const CaseJaw> jaws;
  // The base ("base" object).
  Vec3 occlusal_normal{0, 0, 1};
  BaseParams base;
  Span<const Pick> upper;
  Span<const Pick> lower;
  // The automatic outline ("base": {"auto": {...}} instead of "upper" and "lower"): design
  // computes the picks, the occlusal normal, the bite opening (a move of the mandible composed
  // after its transform) and, unless the case gives one, the insertion direction (outline.h,
  // resolve_case_outline).
  bool has_auto_outline = false;
  OutlineOptions outline;
  // Later stages.
  Vec3 insertion_direction{0, 0, 1};
  bool has_insertion_direction = false;
  // Interference elimination ("blockout" object; needs insertion_direction): each jaw's
  // swept volume is subtracted, the maxilla's along the insertion direction, the mandible's
  // along its reverse (design_splint sets blockout.direction per jaw). The case sets voxel,
  // inset (default: half the voxel), closing_radius and offset: the spacer between teeth
  // and splint ("clearance", mm, 0: none), with which the splint's imprint is the offset
  // surface of each jaw's swept volume instead of the jaw's own triangles (the inset is then 0).
  bool has_blockout = false;
  SweepOptions blockout;
  // "method" (the blockout's sweep):
  // - kExact, "exact" (blockout.h, BlockoutOptions::exact): each jaw's swept volume is its
  //   exact boundary, the jaw's own front triangles and walls along the direction; the imprint
  //   is then made by the blockout alone (the Boolean base minus jaws is not run), and voxel,
  //   inset, closing_radius and clearance do not apply. Where a jaw's swept surface would cross
  //   itself (an overhang along the direction further than the sweep's fold rounds reach) the
  //   design is refused (kUnsupported, with where).
  // - kVoxel, "voxel": the sampled sweep above (voxel, inset, closing_radius, clearance).
  // - kHeightfield, "heightfield": the swept volume's height field on a grid of `voxel`
  //   (BlockoutOptions::heightfield; with a clearance, that of its offset); no inset, no
  //   closing.
  // - kAuto, "auto": kExact, and a jaw whose exact sweep is refused is made with kHeightfield
  //   instead, after the others (on the voxel's grid; the height field holds the jaw, so no
  //   jaw is subtracted); the other jaws stay exact (DesignReport::blockout_exact,
  //   blockout_heightfield). When every jaw is refused, the whole design again with
  //   kHeightfield from the base (the bytes of kHeightfield). The first refusal is kept in
  //   DesignReport::blockout_fallback. Inset, closing radius and clearance are refused.
  // A case file without "method" is kVoxel when the object names inset or closing_radius,
  // else kHeightfield when it names clearance (the spacer), else kAuto ("blockout": {} and
  // {"voxel": 0.1} are kAuto).
  BlockoutMethod blockout_method = BlockoutMethod::kAuto;
  // The wall-thickness check ("min_thickness", mm; 0: not run): thin spots are reported
  // (DesignReport::thickness), not refused.
  double min_thickness = 0;
  // The side-wall check (DesignReport::walls) runs on every design; with "max_wall_crossing" (a
  // share of the arch, 0 to 1) a jaw that crosses the base's outer or inner wall along more
  // than that share of the base's length along the arch is refused. The default, 1, never
  // refuses: a base narrower than the teeth crosses its walls as a misplaced jaw does.
  static constexpr double kDefaultMaxWallCrossing = 1.0;
  double max_wall_crossing = kDefaultMaxWallCrossing;
  // "max_sideways_crossing" (0 to 1): a jaw crossing the outer wall in one half of the arch and
  // the inner wall in the other (WallCrossing::sideways_mm) along more than this share of the
  // arch is refused: it sits to one side of the outline, as a jaw moved sideways by a wrong
  // transform does (3 mm on the real dentition: 11-15%), which a narrow base does not (its
  // teeth cross the same wall on both halves). 1 never refuses.
  static constexpr double kDefaultMaxSidewaysCrossing = 0.05;
  double max_sideways_crossing = kDefaultMaxSidewaysCrossing;
  // "placement": "case" (false: the splint stays in the case's frame) or "tray" (true: the
  // whole case is moved onto the printer's build tray first; DesignReport::tray_translation).
  bool place_on_tray = false;
  // The case label ("label" object, label.h): text in the built-in stroke font, engraved into
  // the outer (buccal) wall at the middle of the arch, or embossed on it. The case sets text,
  // mode, height_mm, stroke_width_mm and depth_mm; the rest are LabelOptions' defaults.
  bool has_label = false;
  LabelOptions label;
  // The CT ("ct" object) the jaws given by "seed" are reconstructed from (segment.h).
  const char* ct_volume = nullptr;  // path (file or DICOM folder), relative to the case file
  HuWindow ct_window;               // [300, 4000] HU by default
  RegionGrowOptions ct_grow;        // connectivity 6 (the default) or 26; no split plane
  TaubinOptions ct_smooth{0};       // iterations (0: none); max_displacement: see below
  DecimateOptions ct_decimate;      // target_triangles per jaw (0: none)
  // Two-jaw surgery ("plan"): design_plan() makes the intermediate and the final splint.
  bool has_plan = false;
  CasePlan plan;
  const char* printer = "eden260";
  uint64_t memory_cap =
      0;  // bytes; 0: the tool's default (`splintcore design` sizes its arena by it)
  const char* output_splint = nullptr;
  const char* output_report = nullptr;
  // "output": {"job": NAME}: a 3MF print job (the plan's: default "job.3mf"; one splint's:
  // written only when named).
  const char* output_job = nullptr;
};

// Parses and validates a case file (strict: unknown keys, wrong types, missing required keys
// and out-of-range values are errors with line and column). `name` is used in messages.
// Errors: kParseError, kInvalidArgument, kLimitExceeded, kUnsupported (a newer version),
// kArenaExhausted. On failure the arena is rewound to where it was and *out is empty; on
// success the parsed document stays in the arena (the CaseFile's strings point into it).
// Output names ("output": "splint", "report") must be plain file names (is_plain_name, at
// most 128 characters): a case cannot name a file outside the output folder.
// Arena: at most parse_case_bound(length), of which the document and the lists stay.
uint64_t parse_case_bound(uint64_t length);
Status parse_case(const Context& ctx, const char* text, size_t length, const char* name,
                  CaseFile* out);

// Jaws from CT: what reconstruct_case_jaws() did.
struct CaseCtReport {
  static constexpr uint32_t kMaxJaws = 8;
  uint32_t jaws_reconstructed = 0;
  ThresholdStats threshold;
  RegionStats regions;
  ReconstructStats jaws[kMaxJaws];  // per jaw in case order (those with a seed)
  uint64_t triangles[kMaxJaws] = {};
  double volume_mm3[kMaxJaws] = {};
};

// The jaws the case gives by "seed", reconstructed from `volume` (the case's "ct"): threshold
// [ct_hu_min, ct_hu_max], competitive region growing from all seeds at once (label j + 1 for
// jaw j), each region meshed (reconstruct_region), then ct_smooth.iterations Taubin iterations
// (clamped to half the smallest voxel spacing) and decimation to ct_decimate.target_triangles when
// asked, rounded to float32 and checked closed and outward. jaws[j] (for jaws with a seed) must be
// empty and receives the mesh; other entries are left alone. Only the meshes stay in the arena
// (moved down over the labels and temporaries). Errors: those of the stages, prefixed with the
// stage ("ct: region growing: ..."); kInvalidArgument (jaw count, a non-empty mesh);
// kLimitExceeded (more than kMaxJaws jaws). On an error the arena is back where it was and the
// reconstructed entries are empty.
Status reconstruct_case_jaws(const Context& ctx, const CaseFile& c, const CtVolume& volume,
                             Span<Mesh> jaws, CaseCtReport* report);

// The case file's numbers: one table of their places, units, ranges and defaults. The parser,
// the C API (sc_case_set_params) and docs/case-format.md (its "Numbers" table, which a test
// compares with this one) take them from here.
struct CaseNumber {
  const char* key;           // where it stands in the file: "base.spacing_mm"
  const char* unit;          // "mm", "HU", "voxels", "iterations", "triangles", "bytes", ""
  double lo, hi;             // the range, inclusive; in blockout voxels when per_voxel
  bool per_voxel;            // lo and hi are multiples of "blockout.voxel"
  double max_mm;             // with per_voxel: also at most this many mm (0: no such cap)
  bool integer;              // a whole number
  const char* default_text;  // the default as the documentation states it
  const char* rule;          // a further rule ("" when none)
};
Span<const CaseNumber> case_numbers();
// The entry for `key` ("base.spacing_mm"), or nullptr.
const CaseNumber* find_case_number(const char* key);
// The number's range in the file's units for a blockout voxel of `voxel` mm.
void case_number_range(const CaseNumber& n, double voxel, double* lo, double* hi);

// Picks -> lines -> base, as the case says. `out` must be empty. Arena: the lines (88 bytes a
// pick, left in place below the mesh) and at most splint_base_bound(): together
// case_base_bound(), which takes the section count of a first run (BaseReport, as
// splint_base_bound() does). Errors: make_lines()'s and build_splint_base()'s. On an error the
// arena is as it was and `out` is empty.
uint64_t case_base_bound(const CaseFile& c, uint64_t sections, uint32_t points_per_section);
Status build_case_base(const Context& ctx, const CaseFile& c, Mesh* out, BaseReport* report);

// The automatic outline of a case with "base": {"auto": ...}: the maxilla and the mandible
// (exactly one of each) moved by their transforms and rounded to float32 as design_splint
// moves them, then compute_outline(). *resolved is the case with everything the outline
// decided written in: the picks, the occlusal normal, the mandible's transform composed with
// the bite opening's move, the insertion direction (the occlusal normal, unless the case gives
// one); has_auto_outline is false in it, so designing it gives the same splint. `outline`
// receives the report and the arch (may be null). The resolved lists stay in the arena, the
// rest is returned. Errors: first a jaw that is no jaw, as design_splint() names it (a triangle
// soup, flat, in other units than mm, two jaws that are one); compute_outline()'s, prefixed
// "outline: "; kInvalidArgument (not an auto case, not one maxilla and one mandible, jaw count
// differs from the case).
Status resolve_case_outline(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                            CaseFile* resolved, Outline* outline);

// Writes `c` as a case file (format version 1, every key it uses, numbers as the shortest text
// that reads back to the same double), so that parse_case() of the text gives back `c`'s
// values and designing it gives the same splint. An auto case is written with its "auto"
// object; a resolved one with its picks (each with position, direction and both lengths); a
// plan case with its "plan" (and its jaws without "transform": the plan moves them).
// Errors: kIoError (the sink failed).
Status write_case(const CaseFile& c, const ByteSink& sink);

// ---------------------------------------------------------------------------------------------
// The design pipeline: the jaws (meshes, or reconstructed from the case's CT) repositioned by
// the plan, the base from the picks, the Boolean difference base minus jaws, interference
// elimination or a spacer (when the case has "blockout"), the label, the wall-thickness check,
// the printer check.

// ---------------------------------------------------------------------------------------------
// Wall thickness: the check a splint designer runs before printing.

struct ThicknessSpot {
  Vec3 position{};       // the thin triangle's centroid
  double thickness = 0;  // mm
  uint32_t triangle = 0;
};

struct ThicknessReport {
  static constexpr uint32_t kMaxSpots = 8;
  static constexpr double kSpotSpacing = 2.0;  // mm between reported spots
  double min_required = 0;                     // mm
  uint64_t triangles_checked = 0;
  uint64_t thin_triangles = 0;  // thickness below min_required
  double thin_area_mm2 = 0;
  double thinnest = 0;      // mm (min_required when nothing is thinner)
  uint32_t spot_count = 0;  // the thinnest places, at least kSpotSpacing apart
  ThicknessSpot spots[kMaxSpots];
};

// Local wall thickness of a closed, outward mesh: from each triangle's centroid a ray along
// the inward normal (ray_intersect, distance.h) to the first surface it meets, measured up to
// `min_thickness` (mm). Triangles thinner than that are counted with their area, and the
// thinnest places are reported (thinnest first; ties by triangle id). Where a surface meets
// another at a sharp edge the material is a thin wedge by nature (e.g. where a tooth's imprint
// leaves the splint at a shallow angle): those count too, so read the spots, not only the
// count. Arena: a distance index of the mesh (distance_index_bound) and 16 bytes per thin
// triangle and as much again to sort them, at most check_wall_thickness_bound(V, T), all
// returned. Errors: kInvalidArgument (min_thickness not in (0, 1000]), those of
// build_distance_index, kArenaExhausted, kCancelled (progress "thickness").
uint64_t check_wall_thickness_bound(uint64_t vertex_count, uint64_t triangle_count);
Status check_wall_thickness(const Context& ctx, const Mesh& mesh, double min_thickness,
                            ThicknessReport* report);

// One jaw's scan-CT fusion: the registration of the scan onto the jaw as given.
struct FusionReport {
  RegisterResult registration;  // transform: scan -> the jaw's mesh frame
  RigidTransform applied;       // the scan's transform in the design: the jaw's after that one
  uint64_t scan_triangles = 0;
};

// Where a jaw, placed, crosses the base's side walls (BaseSide::kOuter, kInner): along the arch
// its imprint would open through the splint's side there, the teeth not held by it. Lengths
// along the arch: the base's section centres (the mean of a section's points) joined in order;
// a stretch between two sections counts when the jaw meets a wall triangle of it (exactly).
struct WallCrossing {
  double arch_mm = 0;          // the base's whole length along the arch
  double outer_mm = 0;         // where the jaw crosses the outer (buccal) wall
  double inner_mm = 0;         // the inner (lingual) wall
  double either_mm = 0;        // either wall
  uint32_t stretches = 0;      // the base's stretches (sections - 1)
  uint32_t crossed = 0;        // of them, those where the jaw crosses either wall
  uint32_t first_stretch = 0;  // the first crossed (between sections k and k + 1), if any
  Vec3 first_at{};             // its centre: the mean of its two section centres (mm)
  // outer_mm and inner_mm split between the arch's halves in section order (a stretch belongs
  // to the half its middle lies in, along the arch's length).
  double half_outer_mm[2] = {0, 0};
  double half_inner_mm[2] = {0, 0};
  // either_mm / arch_mm (0 for no arch): what max_wall_crossing bounds and the report gives.
  double share() const { return arch_mm > 0 ? either_mm / arch_mm : 0.0; }
  // The outer wall crossed in one half and the inner in the other, the lesser of the two (the
  // larger such pair): a jaw to one side of the outline. A base narrower (or wider) than the
  // teeth gives the same wall on both halves, and 0 here.
  double sideways_mm() const {
    const double a = half_outer_mm[0] < half_inner_mm[1] ? half_outer_mm[0] : half_inner_mm[1];
    const double b = half_inner_mm[0] < half_outer_mm[1] ? half_inner_mm[0] : half_outer_mm[1];
    return a > b ? a : b;
  }
  // sideways_mm() / arch_mm: what max_sideways_crossing bounds.
  double sideways_share() const { return arch_mm > 0 ? sideways_mm() / arch_mm : 0.0; }
};

struct DesignReport {
  uint64_t jaw_triangles = 0;  // all jaws together, as given
  // Scan-CT fusion: per jaw in case order (fused[j]: jaw j has a scan), at most kMaxFusedJaws.
  static constexpr uint32_t kMaxFusedJaws = 8;
  bool fused[kMaxFusedJaws] = {};
  FusionReport fusion[kMaxFusedJaws];
  // The case's "auto" outline, when it had one (resolve_case_outline).
  bool outlined = false;
  OutlineReport outline;
  BaseReport base;
  BooleanStats boolean;
  // Interference elimination, when the case asks for it: per jaw in case order (at most 8).
  static constexpr uint32_t kMaxBlockoutJaws = 8;
  uint32_t blockout_jaws = 0;
  BlockoutStats blockout[kMaxBlockoutJaws];
  double blockout_removed_mm3[kMaxBlockoutJaws] = {};
  // With a clearance the imprint is the swept volumes' offset surface: the Boolean base minus
  // jaws is not run (the jaws lie inside what the blockout removes) and `boolean` stays zero.
  bool imprint_offset = false;
  // With "method": "exact" or "auto" likewise: the imprint is the jaws' exact swept boundary
  // (their front triangles and walls), made by the blockout alone (`boolean` stays zero), and
  // the height field's surface where kAuto made a jaw with it.
  bool imprint_swept = false;
  // With "method": "heightfield" likewise: the imprint is the height field's surface (also
  // when kAuto made every jaw with it).
  bool imprint_heightfield = false;
  // Per jaw in case order: its blockout used the exact sweep; kAuto made it with the height
  // field after its exact sweep was refused (imprint_swept is then still true). Neither: the
  // sampled sweep, or the height field of the whole design (imprint_heightfield).
  bool blockout_exact[kMaxBlockoutJaws] = {};
  bool blockout_heightfield[kMaxBlockoutJaws] = {};
  // kAuto made a jaw with the height field: why its exact sweep was refused (the first such
  // jaw's status message, naming where); "" otherwise.
  char blockout_fallback[Status::kMessageCapacity] = {};
  bool labelled = false;  // the case has "label"
  LabelStats label;
  // The side-wall check: per jaw in case order, the first kMaxBlockoutJaws of them.
  uint32_t wall_jaws = 0;
  WallCrossing walls[kMaxBlockoutJaws];
  bool thickness_checked = false;  // the case has "min_thickness"
  ThicknessReport thickness;
  // "placement": "tray": the case was moved by this translation (mm, a multiple of 1/64)
  // before the design, so the splint comes out on the tray (centred, bottom at z = 0).
  bool placed_on_tray = false;
  Vec3 tray_translation{};
  // The splint's shells under the printer's min_wall_mm cubed, all but the largest, taken out
  // before the printer check (remove_small_shells): crumbs a Boolean can leave.
  SmallShells crumbs;
  PrintCheck print;
  const char* printer = "";  // the profile used
  // The splint as returned was checked exactly for self-intersections, and has none, by the
  // last stage that made it: "boolean", "blockout" or "label" (its Boolean's final check);
  // "" when no stage checked it (then self_intersection_checked is false).
  bool self_intersection_checked = false;
  const char* self_intersection_checked_by = "";
  uint64_t self_intersection_candidates = 0;  // the pairs that check tested
};

// How many of report.blockout_jaws used their exact sweep (blockout_exact): all of them is an
// exact blockout, anything between a mixed one ("method": "auto": exact and height field).
uint32_t exact_blockout_jaws(const DesignReport& report);

// The splint for case `c` from its jaws (jaws[i] is the mesh of c.jaws[i], as read: it is not
// changed). Each jaw is moved by its transform and rounded to float32 (what a moved jaw's STL
// holds; the Boolean keeps these bits), the base is built, the jaws are subtracted (only their
// triangles that can touch the base: boolean_region, boolean.h), and the result is checked for
// the case's printer. It stays in the case's frame, unless the case asks
// for "placement": "tray": then the whole case is moved first (report->tray_translation) and
// the splint comes out on the printer's tray. With "blockout", each jaw's swept volume is
// subtracted after the Boolean (blockout.h; at most kMaxBlockoutJaws jaws). `splint` must be
// empty. Stage progress goes to ctx.progress, in this order, each stage only when the case
// asks for it: "design: fusion" (the overload with scans, below), "design: jaws", "design: base",
// "design: boolean", "design: blockout", "design: label", "design: thickness", "design: printer",
// then "design: done" (once the splint is made, too late to cancel). Before the thickness and
// printer checks, shells of the splint smaller than the printer's min_wall_mm cubed (all but
// the largest) are taken out: report->crumbs. Errors: those of the stages
// (naming the stage and, for a jaw, its index and role), kInvalidArgument (jaw count differs from
// the case, unknown printer, a case with "plan": design_plan() makes its splints), kNonFinite (a
// jaw vertex that is NaN or infinite), kLimitExceeded (a jaw moved beyond float32 range),
// kInvalidMesh for a jaw that is no jaw, named before anything runs ("design: jaw j (role) is a
// triangle soup", "is X x Y x Z across: too small (large) for a jaw in mm" or "has no teeth":
// fewer than 4 triangles per piece connected through shared corners, a longest side under 10
// mm or over 1000 mm (a file in other units: the message gives the factor to mm), or every
// vertex within 1 mm of one plane; 5 bytes of arena a vertex of the jaws and scans together,
// returned), kInvalidMesh for a jaw that does not reach the base once it is made ("design: jaw
// j (role) does not reach the base: placed, it spans [..] - [..] and the base [..] - [..] mm":
// no triangle of it within the Boolean's region of the base, so it could leave no imprint),
// kInvalidMesh for a jaw that crosses the base's side walls along more than the case's
// max_wall_crossing share of the arch ("design: jaw j (role) crosses the base's side walls
// along ..."; the crossing of every jaw is in report->walls, measured on every design) or
// sideways of it along more than max_sideways_crossing ("design: jaw j (role) sits to one side
// of the base: ..."),
// kInvalidArgument for two jaws that are one ("design: jaw k (role) is jaw j (role) again":
// the same triangles and vertices under the same transform, one file given twice),
// kInvalidArgument for a case with a blockout whose maxilla is not above its mandible along
// the insertion direction ("design: jaw j (maxilla) is below jaw k (mandible) along the
// insertion direction": swapped roles or a reversed direction, which would sweep each jaw back
// through the splint), and kInvalidMesh when the result is not printable
// (require_printable's reason).
Status design_splint(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, Mesh* splint,
                     DesignReport* report);

// The same for a case whose jaws have scans ("scan", CaseScan): scans[j] is the scan of
// c.jaws[j] as read (an empty mesh for a jaw without one); `scans` may be empty only when no
// jaw has one (the overload above passes none). After the outline and the tray placement, the
// stage "design: fusion" registers each scan onto its jaw's mesh as given (register_rigid with
// the case's landmarks, trim, max_rms_mm and crowns_within_mm as inlier_mm); the jaw's
// transform then applies after the registration's, and from there on the jaw is its
// registered scan: within the base the scan is the jaw's whole surface, so the imprint is the
// scan's own triangles (the jaw's mesh is used for the registration and the outline). The
// scan is open: its border must lie outside the base, else the Boolean's "B is open" error
// names the scan, its border vertex and where it lies, and what to do. report->fused[j] and
// report->fusion[j] give the registration. Errors, besides design_splint's (a scan that is no
// jaw among them: "design: the scan of jaw j (role) ..."): kInvalidArgument (scans do not
// match the case: a count other than the jaws', a scan for a jaw without "scan", two jaws of
// one role each with a scan: "two scans of the same jaw"; a wrong landmark pairing,
// register_rigid's option errors: "design: fusion: jaw j (role), scan PATH: ..."), kLimitExceeded
// (a fit whose RMS is above max_rms_mm or whose overlap is below min_overlap: the message gives
// both figures and both thresholds), kInvalidMesh (an empty scan, or register_rigid's). Arena:
// design_splint's plus register_rigid_bound() of the largest scan and its jaw, returned before the
// jaws are gathered.
Status design_splint(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                     Span<const Mesh> scans, Mesh* splint, DesignReport* report);

// ---------------------------------------------------------------------------------------------
// Two-jaw surgery: the two splints of the case's "plan" (docs/case-format.md, "Plan").
//
// intermediate: the jaw the sequence moves first in its planned position, the other as before
//   surgery, the mandible then turned about the hinge axis until the smallest distance between
//   the arches is intermediate_opening_mm (autorotate_mandible, outline.h). maxilla_first: the
//   maxilla moved, the preoperative mandible turned. mandible_first: the maxilla preoperative,
//   the planned mandible turned too: the surgeon fixes the mandible's segments with the teeth
//   wired into this splint, and a turn of the whole mandible about the condyles does not change
//   how its segments sit on each other, so the splint may hold it at the angle where the arches
//   are the opening apart (where the planned mandible meets or misses the unmoved maxilla).
// final: both jaws moved, the mandible turned to final_opening_mm.
// The mandible's transform as applied is the turn composed after its planned move (the turn is
// found on the jaws moved and rounded to float32, as design_splint moves them).
// With a case "label" each splint carries its own: "INT " (intermediate) or "FIN " (final)
// before the case's label text (so at most kLabelMaxCharacters - 4 characters), placed, meshed
// and applied as design_splint applies a label.
struct PlanSplintReport {
  char label_text[kLabelMaxCharacters + 1] = {};  // the label applied ("" without "label")
  RigidTransform maxilla;                         // the maxilla's transform as applied
  RigidTransform mandible;  // the mandible's: autorotation.transform after its planned move
  double opening_asked_mm = 0;
  AutorotateReport autorotation;  // angle_rad, the opening measured (opening), ...
  double angle_deg = 0;           // autorotation.angle_rad in degrees
  DesignReport design;            // design_splint's report of this splint
};

struct PlanReport {
  PlanSplintReport intermediate;
  PlanSplintReport final_splint;
};

// The case one splint of the plan (the final one when `final_splint`, else the intermediate)
// is designed from: `c` without its plan, the jaws' transforms set to `r`'s (maxilla,
// mandible), the label's text r.label_text (`out` points into `r`), and with the plan's
// "picks" that splint's picks. `jaws` (two entries, the caller's) holds its jaw list. Errors:
// kInvalidArgument (not a plan case, not one maxilla and one mandible, a case label but no
// r.label_text).
Status plan_splint_case(const CaseFile& c, const PlanSplintReport& r, bool final_splint,
                        CaseJaw jaws[2], CaseFile* out);

// Both splints of case `c` (c.has_plan; jaws[i] is the mesh of c.jaws[i], as read). Each is an
// ordinary design_splint() of plan_splint_case(): outline (automatic when the base is "auto"),
// blockout, label and checks as for one splint. `intermediate` and `final_splint` must be
// empty. Arena: sequential. Both autorotations come first, with one index of each jaw
// (distance_index_bound with autorotate_index_options) and, per splint, the two moved jaws (24
// bytes a vertex), their refit indexes (refit_distance_index_bound) and
// autorotate_mandible_indexed_bound(), all returned; then the intermediate splint stays, then
// the final one above it. At most the larger of that and the intermediate splint plus one
// design_splint run of a splint. With an executor of more than one thread the autorotations
// run in tasks when their slices fit (else as above; the same answers either way): both
// indexes' distance_index_bound() at once (the indexes then moved together, the rest
// returned), then a jaw both splints move alike moved and refit once and, at once, one slice a
// splint of its other moved jaws, their refit indexes and autorotate_mandible_indexed_bound()
// (each rounded up to 16 bytes). An autorotation's error is reported where it was before: the
// final's after the intermediate's design. Progress: "plan: intermediate", the design's
// stages, "plan: final", the design's.
// Errors: kInvalidArgument (no plan, jaw count or roles, a label text too long for the prefix:
// "plan: intermediate: label: ..."), autorotate_mandible's prefixed
// "plan: intermediate: autorotation: " (or final), design_splint's prefixed "plan:
// intermediate: " (or final); kArenaExhausted and kCancelled unchanged. On an error the arena
// is as it was and both meshes are empty.
Status design_plan(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, Mesh* intermediate,
                   Mesh* final_splint, PlanReport* report);

// The same for a plan case whose jaws have scans ("scan"; scans[j] as design_splint's overload
// with scans takes them: may be empty only when no jaw has one). The fusion comes first, once:
// progress "plan: fusion", each scan registered onto its preoperative jaw as given (as
// design_splint does), then everything of the plan sees a fused jaw as its registered scan,
// the registration first and the plan's move (and the autorotation) after it: the
// autorotation turns the mandible until the scans (or a scan and a jaw) are the opening apart,
// and each splint's imprint is the scans' triangles. Each splint's report (design) holds the
// same registration in fused[] and fusion[], `applied` there being its own moves after it.
// Errors, besides the overload's: design_splint's fusion errors prefixed "plan: " (a fit over
// the thresholds, a wrong landmark pairing, scans that do not match the case). Arena: the
// overload's plus register_rigid_bound() of the largest scan and its jaw, returned before the
// splints are made.
Status design_plan(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                   Span<const Mesh> scans, Mesh* intermediate, Mesh* final_splint,
                   PlanReport* report);

// The print job of a plan (job.3mf): both splints on the printer's tray (c.printer's profile),
// in a row kPlanJobGapMm apart box to box (arrange_on_tray, printer.h), each placed by its
// build item's translation (the splints' own float32 vertices are written as they are),
// named "INT " and "FIN " with the case id, with the SHA-256 of each splint's binary STL as
// metadata (sha256[k], 64 hex digits, when the caller has it; null: computed here), written
// by write_3mf (io.h). The same splints give the same bytes. `moves` (may be null) receives
// the two translations. Arena: at most plan_job_bound(), nothing stays. Errors: kInvalidArgument
// (unknown printer, an empty splint), arrange_on_tray's (kLimitExceeded: they do not fit the
// tray), write_3mf's, kArenaExhausted.
constexpr double kPlanJobGapMm = 5.0;
uint64_t plan_job_bound(const CaseFile& c, const Mesh& intermediate, const Mesh& final_splint);
Status write_plan_job(const Context& ctx, const CaseFile& c, const Mesh& intermediate,
                      const Mesh& final_splint, const char* const sha256[2], const ByteSink& sink,
                      Vec3 moves[2]);

// One splint's print job (a case's "output": {"job": NAME}): the splint on the printer's tray
// (arrange_on_tray), named by the case id ("splint" without one), with the SHA-256 of its
// binary STL (sha256, or null: computed here), as write_plan_job writes two. `move` (may be
// null) receives its translation. Arena: at most splint_job_bound(), nothing stays. Errors:
// write_plan_job's.
uint64_t splint_job_bound(const CaseFile& c, const Mesh& splint);
Status write_splint_job(const Context& ctx, const CaseFile& c, const Mesh& splint,
                        const char* sha256, const ByteSink& sink, Vec3* move);

// The SHA-256 (64 lower-case hex digits and a NUL) of the binary STL write_stl() writes of
// `splint`, without keeping the bytes. Arena: write_stl's buffer (64,000 bytes), returned.
// Errors: write_stl's.
Status splint_stl_sha256(const Context& ctx, const Mesh& splint, char out[65]);

// ---------------------------------------------------------------------------------------------
// The audit report (report.json): one writer for the command line and the C API.

// What the library cannot know about a design: the files as the caller names them and the
// hashes of their bytes. Every pointer may be null (that entry is left out).
struct DesignReportFiles {
  const char* case_path = nullptr;
  Span<const char* const> jaw_paths;    // per jaw of the case, in case order (or empty)
  Span<const char* const> jaw_sha256;   // of each jaw file's bytes (CT jaws: of the voxels)
  Span<const char* const> scan_paths;   // per jaw (those with "scan"), in case order (or empty)
  Span<const char* const> scan_sha256;  // of each scan file's bytes
  const char* ct_path = nullptr;        // the case's CT, when a jaw came from it
  uint32_t ct_size[3] = {0, 0, 0};      // its voxels per axis
  const CaseCtReport* ct = nullptr;     // reconstruct_case_jaws' report, when it ran
  const char* splint_path = nullptr;
  // The SHA-256 of the splint's binary STL as the caller wrote it (write_stl's bytes, 64 hex
  // digits): saves hashing it twice. Null: the report writer computes it.
  const char* splint_sha256 = nullptr;
  const char* preview_path = nullptr;
  const char* preview_sha256 = nullptr;
  const char* preview_error = nullptr;       // why there is no preview
  const char* resolved_case_path = nullptr;  // where the automatic outline's case was written
  // The print job, when written: a plan's (files[0] of write_plan_report: both splints in one
  // 3MF) or one splint's ("output": {"job": NAME}).
  const char* print_job_path = nullptr;
  const char* print_job_sha256 = nullptr;
};

// One stage of the design as a caller's progress callback timed it.
struct DesignStageTime {
  const char* stage = "";
  double seconds = 0;
  uint64_t peak_arena_bytes = 0;
};

// How the run went: the only part of the report that may differ between two runs of the same
// case with the same inputs (written last, as "run"). Null pointer: no "run" part.
struct DesignRunInfo {
  uint64_t memory_cap_bytes = 0;
  const char* memory_cap_from = "";  // "case", "command line", "default", "caller"
  uint32_t threads = 1;
  Span<const DesignStageTime> stages;
  double read_seconds = 0, design_seconds = 0, preview_seconds = 0, total_seconds = 0;
  uint64_t peak_arena_bytes = 0;
};

// Writes the report of a design_splint() run as one compact JSON object to `sink`: the library
// version, the case (id, SHA-256 of its text), the inputs (jaws, their transforms, triangle
// counts), every parameter as used, the checks as recorded by the stages (report), the output
// (the splint's SHA-256 of the binary STL write_stl gives, computed here unless `files` has
// it, its triangles, volume and extent), then `run`. Every value comes from `c`, `report`,
// `splint`, `files` or `run`; none is a constant. docs/report-format.md lists the keys. Arena:
// write_stl's buffer (64,000 bytes, only when it hashes the splint), returned. Errors: kIoError
// (the sink failed), kArenaExhausted, kInvalidArgument (jaws do not match the case).
Status write_design_report(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                           const Mesh& splint, const DesignReport& report,
                           const DesignReportFiles& files, const DesignRunInfo* run,
                           const ByteSink& sink);

// The report of a design_plan() run (report.json of a plan case): the case and the plan as
// given ("plan"), then per splint ("intermediate", "final") its transforms as applied, the
// autorotation and everything write_design_report() writes of a single splint, then `run`.
// files[0] and files[1] name the two splints' files. Arena and errors: write_design_report's.
Status write_plan_report(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                         const Mesh& intermediate, const Mesh& final_splint,
                         const PlanReport& report, const DesignReportFiles files[2],
                         const DesignRunInfo* run, const ByteSink& sink);

}  // namespace splintcore

#endif  // SPLINTCORE_DESIGN_H
