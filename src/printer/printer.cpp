// Printer profiles and the printability check: a valid solid (closed, edge-manifold,
// consistently and outward oriented, nothing degenerate) that fits the build volume.
#include "splintcore/printer.h"

namespace splintcore {

namespace {
const PrinterProfile kEden260{
    "eden260",
    "Stratasys Eden260-class PolyJet: tray 255 x 252 mm, 200 mm build height, 16 um layers",
    Vec3{255.0, 252.0, 200.0},
    0.016,
    0.6,
};

// Whole layers needed for a height; exact for the decimal layer sizes printers use, since the
// quotient is rounded up only when it is clearly above an integer.
uint64_t layers_for(double height, double layer) {
  if (!(height > 0.0) || !(layer > 0.0)) return 0;
  double q = height / layer;
  double whole = static_cast<double>(static_cast<uint64_t>(q));
  if (q - whole > 1e-9) whole += 1.0;
  return static_cast<uint64_t>(whole);
}
}  // namespace

const PrinterProfile& eden260_profile() { return kEden260; }

const PrinterProfile* find_printer_profile(const char* name) {
  if (name != nullptr && std::strcmp(name, kEden260.name) == 0) return &kEden260;
  return nullptr;
}

Status arrange_on_tray(const PrinterProfile& profile, Span<const Aabb> boxes, double gap_mm,
                       Vec3* translations) {
  if (boxes.empty()) return Status::error(StatusCode::kInvalidArgument, "tray: no parts to place");
  if (!(gap_mm >= 0.0) || !is_finite(Vec3{gap_mm, 0, 0})) {
    return make_error(StatusCode::kInvalidArgument, "tray: the gap must be 0 mm or more, not ",
                      gap_mm);
  }
  const Vec3& tray = profile.build_volume_mm;
  double row = 0;
  for (size_t k = 0; k < boxes.size(); ++k) {
    const Aabb& b = boxes[k];
    if (!is_finite(b.lo) || !is_finite(b.hi) || !(b.lo.x <= b.hi.x) || !(b.lo.y <= b.hi.y) ||
        !(b.lo.z <= b.hi.z)) {
      return make_error(StatusCode::kInvalidArgument, "tray: part ", k, " has no finite bounds")
          .at_index(k);
    }
    const Vec3 e = b.extent();
    if (e.y > tray.y || e.z > tray.z) {
      return make_error(StatusCode::kLimitExceeded, "tray: part ", k, " is ", e.y, " mm deep and ",
                        e.z, " mm high; the ", profile.name, " tray holds ", tray.y, " x ", tray.z,
                        " mm")
          .at_index(k);
    }
    row += e.x + (k > 0 ? gap_mm : 0.0);
  }
  if (row > tray.x) {
    return make_error(StatusCode::kLimitExceeded, "tray: ", boxes.size(), " parts ", gap_mm,
                      " mm apart make a row ", row, " mm long; the ", profile.name, " tray is ",
                      tray.x, " mm wide");
  }
  double x = 0.5 * (tray.x - row);
  for (size_t k = 0; k < boxes.size(); ++k) {
    const Aabb& b = boxes[k];
    translations[k] = Vec3{x - b.lo.x, 0.5 * tray.y - 0.5 * (b.lo.y + b.hi.y), -b.lo.z};
    x += (b.hi.x - b.lo.x) + gap_mm;
  }
  return Status::ok();
}

uint64_t check_printable_bound(uint64_t vertex_count, uint64_t triangle_count) {
  return check_mesh_bound(vertex_count, triangle_count);  // the mesh check is all it allocates
}

Status check_printable(const Context& ctx, const Mesh& mesh, const PrinterProfile& profile,
                       const PrintCheckOptions& options, PrintCheck* out) {
  *out = PrintCheck{};
  if (!(profile.build_volume_mm.x > 0.0) || !(profile.build_volume_mm.y > 0.0) ||
      !(profile.build_volume_mm.z > 0.0) || !(profile.layer_thickness_mm > 0.0)) {
    return make_error(StatusCode::kInvalidArgument, "printer profile '", profile.name,
                      "' has a non-positive build volume or layer thickness");
  }
  SPLINTCORE_RETURN_IF_ERROR(check_mesh(ctx, mesh, &out->mesh));
  const Aabb& box = out->mesh.bounds;
  out->extent = box.extent();
  const Vec3 e = out->extent;
  const double margin = options.margin_mm > 0.0 ? options.margin_mm : 0.0;
  const Vec3 room{profile.build_volume_mm.x - 2 * margin, profile.build_volume_mm.y - 2 * margin,
                  profile.build_volume_mm.z};
  out->fits = !box.empty() && e.x <= room.x && e.y <= room.y && e.z <= room.z;
  out->fits_rotated = !out->fits && !box.empty() && e.y <= room.x && e.x <= room.y && e.z <= room.z;
  if (options.place_on_tray && !box.empty()) {
    // Centre on the tray in x and y, bottom on the tray (z = 0).
    Vec3 c = box.center();
    out->placement = RigidTransform::translation(Vec3{
        profile.build_volume_mm.x * 0.5 - c.x, profile.build_volume_mm.y * 0.5 - c.y, -box.lo.z});
  }
  out->layers = layers_for(e.z, profile.layer_thickness_mm);
  const double longest = e.x > e.y ? (e.x > e.z ? e.x : e.z) : (e.y > e.z ? e.y : e.z);
  out->units_suspect = !box.empty() && (longest < 1.0 || longest > 1000.0);
  out->printable = out->mesh.is_valid_solid() && (out->fits || out->fits_rotated);
  return Status::ok();
}

Status require_printable(const PrintCheck& check, const PrinterProfile& profile) {
  SPLINTCORE_RETURN_IF_ERROR(require_valid_solid(check.mesh));
  if (!check.fits && !check.fits_rotated) {
    const Vec3& e = check.extent;
    Status s = make_error(StatusCode::kInvalidMesh, "part is ", e.x, " x ", e.y, " x ", e.z,
                          " mm and does not fit the ", profile.name, " build volume (",
                          profile.build_volume_mm.x, " x ", profile.build_volume_mm.y, " x ",
                          profile.build_volume_mm.z, " mm)");
    if (check.units_suspect) s.append("; the size suggests wrong units");
    return s;
  }
  return Status::ok();
}

}  // namespace splintcore
