// splintcore printer: printer profiles and the printability check.
#ifndef SPLINTCORE_PRINTER_H
#define SPLINTCORE_PRINTER_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {

// A printer as the checks need it. Define your own for other machines.
struct PrinterProfile {
  const char* name = "";
  const char* description = "";
  Vec3 build_volume_mm{};  // usable tray x, y and build height z
  double layer_thickness_mm = 0;
  double min_wall_mm = 0;  // the thinnest wall the process makes reliably (advisory)
};

// Stratasys Eden260-class PolyJet: tray 255 x 252 mm, 200 mm high, 16 um layers.
const PrinterProfile& eden260_profile();

// Looks a built-in profile up by name ("eden260"); nullptr when unknown.
const PrinterProfile* find_printer_profile(const char* name);

// Several parts on one tray (a print job): in a row along x, in order, `gap_mm` apart (box to
// box), the row centred on the tray in x, each part centred in y, each bottom at z = 0.
// translations[k] moves part k (whose bounds are boxes[k]) there. No memory. Errors:
// kInvalidArgument (no parts, an empty or non-finite box, a negative gap), kLimitExceeded (the
// row, a part's depth or height does not fit the profile's build volume: the sizes named).
Status arrange_on_tray(const PrinterProfile& profile, Span<const Aabb> boxes, double gap_mm,
                       Vec3* translations);

struct PrintCheckOptions {
  bool place_on_tray = true;  // translate so the part sits centred on the tray, z from 0
  double margin_mm = 5.0;     // clearance kept from the tray edges when fitting
};

struct PrintCheck {
  MeshReport mesh;
  Vec3 extent{};               // of the part, mm
  bool fits = false;           // within the tray (with margins) as placed
  bool fits_rotated = false;   // fits after a 90 degree turn about z (when !fits)
  RigidTransform placement;    // to put the part on the tray (identity when not placing)
  uint64_t layers = 0;         // ceil(height / layer thickness)
  bool units_suspect = false;  // extent under 1 mm or over 1 m: probably metres or microns
  bool printable = false;      // valid solid and fits (possibly rotated)
};

// Checks a mesh against a profile. Returns ok when the check ran (read `printable`), or an
// error when it could not (kArenaExhausted, kInvalidMesh for out-of-range indices). Arena:
// check_mesh()'s temporaries, at most check_printable_bound(V, T), all returned.
uint64_t check_printable_bound(uint64_t vertex_count, uint64_t triangle_count);
Status check_printable(const Context& ctx, const Mesh& mesh, const PrinterProfile& profile,
                       const PrintCheckOptions& options, PrintCheck* out);

// The first reason a checked mesh is not printable, as an error status, or ok.
Status require_printable(const PrintCheck& check, const PrinterProfile& profile);

}  // namespace splintcore

#endif  // SPLINTCORE_PRINTER_H
