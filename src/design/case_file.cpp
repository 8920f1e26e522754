// The case file: strict schema over the strict JSON parser (format: docs/case-format.md).
// Every object rejects keys it does not know, every value is type- and range-checked, and
// every error names the line and column of the offending value.
#include <cstring>

#include "splintcore/design.h"

namespace splintcore {

namespace {

constexpr double kNoCap = 0;
const CaseNumber kCaseNumbers[] = {
    {"splintcore_case", "", 1, 1e6, false, kNoCap, true, "required", "the format version: 1"},
    {"jaws[].transform", "mm", -1e6, 1e6, false, kNoCap, false, "identity",
     "each of the 16 entries; rigid (see Jaw)"},
    {"jaws[].scan.landmarks", "mm", -1e6, 1e6, false, kNoCap, false, "none (automatic)",
     "3 to 64 pairs, not collinear"},
    {"jaws[].scan.trim", "", 0.05, 1, false, kNoCap, false, "0.6", ""},
    {"jaws[].scan.min_overlap", "", 0, 1, false, kNoCap, false, "0.3", ""},
    {"jaws[].scan.max_rms_mm", "mm", 0.001, 10, false, kNoCap, false, "0.3", ""},
    {"jaws[].scan.crowns_within_mm", "mm", 0.01, 10, false, kNoCap, false, "0.5", ""},
    {"base.spacing_mm", "mm", 0.01, 50, false, kNoCap, false, "0.5", ""},
    {"base.corner_radius_mm", "mm", 0, 20, false, kNoCap, false, "0", ""},
    {"base.corner_segments", "", 1, 16, false, kNoCap, true, "4", "1, 2, 4, 8 or 16"},
    {"base.inner_length_mm", "mm", 0, 100, false, kNoCap, false, "3", ""},
    {"base.outside_length_mm", "mm", 0, 100, false, kNoCap, false, "3", ""},
    {"base.auto.indentation_depth_mm", "mm", 0.1, 5, false, kNoCap, false, "2", ""},
    {"base.auto.overhang_mm", "mm", 0, 10, false, kNoCap, false, "2", ""},
    {"base.auto.pick_spacing_mm", "mm", 2, 20, false, kNoCap, false, "3", ""},
    {"base.auto.bite_opening_mm", "mm", 0.1, 10, false, kNoCap, false, "none (the jaws as given)",
     ""},
    {"pick.inner_length_mm", "mm", 0, 100, false, kNoCap, false, "the base's", ""},
    {"pick.outside_length_mm", "mm", 0, 100, false, kNoCap, false, "the base's", ""},
    {"ct.hu_min", "HU", -32768, 32767, false, kNoCap, true, "300", "at most hu_max"},
    {"ct.hu_max", "HU", -32768, 32767, false, kNoCap, true, "4000", ""},
    {"ct.connectivity", "", 6, 26, false, kNoCap, true, "6", "6 or 26"},
    {"ct.smooth", "iterations", 0, 1000, false, kNoCap, true, "0", ""},
    {"ct.decimate", "triangles", 4, 1e9, false, kNoCap, true, "none", ""},
    {"blockout.voxel", "mm", 0.01, 1, false, kNoCap, false, "0.1", ""},
    {"blockout.inset", "mm", 0, 1.99, true, kNoCap, false, "half the voxel (0 with clearance)",
     "only with \"voxel\", not with clearance"},
    {"blockout.closing_radius", "mm", 0, 10, true, kNoCap, false, "0", "0 or at least 2 voxels"},
    {"blockout.clearance", "mm", 0, 20, true, 2.0, false, "0", ""},
    {"label.height_mm", "mm", 0.5, 20, false, kNoCap, false, "2.5", ""},
    {"label.stroke_mm", "mm", 0.05, 5, false, kNoCap, false, "0.35", ""},
    {"label.depth_mm", "mm", 0.05, 5, false, kNoCap, false, "0.4", ""},
    {"min_thickness", "mm", 0.05, 20, false, kNoCap, false, "not checked", ""},
    {"max_wall_crossing", "", 0, 1, false, kNoCap, false, "1 (not refused)", "a share of the arch"},
    {"max_sideways_crossing", "", 0, 1, false, kNoCap, false, "0.05", "a share of the arch"},
    {"plan.maxilla", "mm", -1e6, 1e6, false, kNoCap, false, "required",
     "each of the 16 entries; rigid (see Jaw)"},
    {"plan.mandible", "mm", -1e6, 1e6, false, kNoCap, false, "required",
     "each of the 16 entries; rigid (see Jaw)"},
    {"plan.hinge_axis", "mm", -1e6, 1e6, false, kNoCap, false, "required",
     "two points at least 1 mm apart"},
    {"plan.intermediate_opening_mm", "mm", 0, 10, false, kNoCap, false, "required", ""},
    {"plan.final_opening_mm", "mm", 0, 10, false, kNoCap, false, "required", ""},
    {"memory_cap", "bytes", 1, 1099511627776.0, false, kNoCap, true, "the tool's (1G)",
     "or a string such as \"256M\""},
};

const CaseNumber& number_spec(const char* key) {
  const CaseNumber* n = find_case_number(key);
  SPLINTCORE_ASSERT(n != nullptr);
  return *n;
}

struct Reader {
  const JsonDocument* doc;
  Arena* arena;

  Status fail(const JsonValue& at, StatusCode code, const char* a, const char* b = "",
              const char* c = "") const {
    Status s = json_error(*doc, at, code, a);
    s.append(b).append(c);
    return s;
  }

  // Rejects keys not in `allowed` (a null-terminated list).
  Status known_keys(const JsonValue& object, const char* const* allowed, const char* what) const {
    for (uint32_t k = object.first_child; k != kJsonNone; k = doc->at(k).next_sibling) {
      const JsonValue& member = doc->at(k);
      bool ok = false;
      for (const char* const* a = allowed; *a != nullptr; ++a)
        ok = ok || std::strcmp(*a, member.key) == 0;
      if (!ok) {
        Status s = json_error(*doc, member, StatusCode::kInvalidArgument, "unknown key \"");
        s.append(member.key).append("\" in ").append(what).append(" (allowed:");
        for (const char* const* a = allowed; *a != nullptr; ++a) s.append(" ").append(*a);
        return s.append(")");
      }
    }
    return Status::ok();
  }

  Status expect_type(const JsonValue& v, JsonType type, const char* key) const {
    if (v.type == type) return Status::ok();
    Status s = json_error(*doc, v, StatusCode::kInvalidArgument, "\"");
    return s.append(key)
        .append("\" must be ")
        .append(json_type_name(type))
        .append(", not ")
        .append(json_type_name(v.type));
  }

  Status number(const JsonValue& v, const char* key, double lo, double hi, double* out) const {
    SPLINTCORE_RETURN_IF_ERROR(expect_type(v, JsonType::kNumber, key));
    if (!(v.number >= lo && v.number <= hi)) {
      Status s = json_error(*doc, v, StatusCode::kInvalidArgument, "\"");
      return s.append(key)
          .append("\" is ")
          .append_f64(v.number)
          .append(", outside [")
          .append_f64(lo)
          .append(", ")
          .append_f64(hi)
          .append("]");
    }
    *out = v.number;
    return Status::ok();
  }

  // A number of the table (kCaseNumbers), named in messages by its last key; `voxel` scales
  // a per-voxel range.
  Status number(const JsonValue& v, const char* path, double voxel, double* out) const {
    const CaseNumber& n = number_spec(path);
    const char* dot = std::strrchr(n.key, '.');
    double lo = 0, hi = 0;
    case_number_range(n, voxel, &lo, &hi);
    return number(v, dot != nullptr ? dot + 1 : n.key, lo, hi, out);
  }

  Status vec3(const JsonValue& v, const char* key, Vec3* out) const {
    SPLINTCORE_RETURN_IF_ERROR(expect_type(v, JsonType::kArray, key));
    if (v.child_count != 3) {
      Status s = json_error(*doc, v, StatusCode::kInvalidArgument, "\"");
      return s.append(key).append("\" needs 3 numbers, has ").append_u64(v.child_count);
    }
    uint32_t k = v.first_child;
    for (int a = 0; a < 3; ++a, k = doc->at(k).next_sibling) {
      double x = 0;
      SPLINTCORE_RETURN_IF_ERROR(number(doc->at(k), key, -1e6, 1e6, &x));
      (*out)[a] = x;
    }
    return Status::ok();
  }

  Status unit_vector(const JsonValue& v, const char* key, Vec3* out) const {
    SPLINTCORE_RETURN_IF_ERROR(vec3(v, key, out));
    if (!(length(*out) > 1e-12)) {
      Status s = json_error(*doc, v, StatusCode::kInvalidArgument, "\"");
      return s.append(key).append("\" must not be the zero vector");
    }
    return Status::ok();
  }

  // A rigid move: a row-major 4x4 of 16 numbers (each in the table's range under `path`),
  // orthonormal rotation within 1e-6, determinant +1, last row 0 0 0 1 (rigid_from_matrix).
  Status transform(const JsonValue& t, const char* key, const char* path,
                   RigidTransform* out) const {
    SPLINTCORE_RETURN_IF_ERROR(expect_type(t, JsonType::kArray, key));
    if (t.child_count != 16) {
      return fail(t, StatusCode::kInvalidArgument, "\"", key,
                  "\" needs 16 numbers (a row-major 4x4 matrix)");
    }
    double m[16];
    uint32_t e = t.first_child;
    for (int a = 0; a < 16; ++a, e = doc->at(e).next_sibling) {
      SPLINTCORE_RETURN_IF_ERROR(number(doc->at(e), path, 0, &m[a]));
    }
    Status s = rigid_from_matrix(m, 1e-6, out);
    if (!s.is_ok()) return fail(t, s.code(), "\"", key, "\": ").append(s.message());
    return Status::ok();
  }

  Status string(const JsonValue& v, const char* key, const char** out) const {
    SPLINTCORE_RETURN_IF_ERROR(expect_type(v, JsonType::kString, key));
    if (v.length == 0 || std::strlen(v.string) != v.length) {
      Status s = json_error(*doc, v, StatusCode::kInvalidArgument, "\"");
      return s.append(key).append("\" must be a non-empty string");
    }
    *out = v.string;
    return Status::ok();
  }

  // A file's path: a string without control characters. One would reach a terminal as it is
  // wherever the tools print the path (in a message, a summary); the other strings are names
  // and words checked against their own rules (a plain name, a known printer).
  Status path(const JsonValue& v, const char* key, const char** out) const {
    SPLINTCORE_RETURN_IF_ERROR(string(v, key, out));
    for (uint32_t i = 0; i < v.length; ++i) {
      const unsigned char c = static_cast<unsigned char>(v.string[i]);
      if (c < 0x20 || c == 0x7F) {
        Status s = json_error(*doc, v, StatusCode::kInvalidArgument, "\"");
        s.append(key).append("\" holds a control character (byte ").append_u64(c);
        return s.append(" at character ").append_u64(i).append("): a file's path has none");
      }
    }
    return Status::ok();
  }
};

Status parse_picks(const Reader& r, const JsonValue& list, const char* key, double inner_default,
                   double outside_default, Span<const Pick>* out) {
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(list, JsonType::kArray, key));
  Pick* picks = r.arena->allocate_array<Pick>(list.child_count);
  if (picks == nullptr && list.child_count > 0) return r.arena->exhausted_status();
  static const char* const kPickKeys[] = {
      "position", "normal", "direction", "inner_length_mm", "outside_length_mm", nullptr};
  uint32_t i = 0;  // (the children number child_count: the bound only states it)
  for (uint32_t k = list.first_child; k != kJsonNone && i < list.child_count;
       k = r.doc->at(k).next_sibling, ++i) {
    const JsonValue& p = r.doc->at(k);
    SPLINTCORE_RETURN_IF_ERROR(r.expect_type(p, JsonType::kObject, key));
    SPLINTCORE_RETURN_IF_ERROR(r.known_keys(p, kPickKeys, "a pick"));
    Pick pick;
    pick.inner_length = inner_default;
    pick.outside_length = outside_default;
    const JsonValue* position = r.doc->member(p, "position");
    if (position == nullptr) {
      return r.fail(p, StatusCode::kInvalidArgument, "pick without \"position\" in \"", key, "\"");
    }
    SPLINTCORE_RETURN_IF_ERROR(r.vec3(*position, "position", &pick.position));
    if (const JsonValue* v = r.doc->member(p, "normal")) {
      SPLINTCORE_RETURN_IF_ERROR(r.unit_vector(*v, "normal", &pick.normal));
    }
    if (const JsonValue* v = r.doc->member(p, "direction")) {
      SPLINTCORE_RETURN_IF_ERROR(r.unit_vector(*v, "direction", &pick.direction));
    }
    if (const JsonValue* v = r.doc->member(p, "inner_length_mm")) {
      SPLINTCORE_RETURN_IF_ERROR(r.number(*v, "pick.inner_length_mm", 0, &pick.inner_length));
    }
    if (const JsonValue* v = r.doc->member(p, "outside_length_mm")) {
      SPLINTCORE_RETURN_IF_ERROR(r.number(*v, "pick.outside_length_mm", 0, &pick.outside_length));
    }
    picks[i] = pick;
  }
  *out = Span<const Pick>(picks, list.child_count);
  return Status::ok();
}

// A jaw's intraoral scan ("scan": path, landmarks, trim, min_overlap, max_rms_mm,
// crowns_within_mm; CaseScan).
Status parse_scan(const Reader& r, const JsonValue& v, CaseScan* out) {
  const JsonDocument& doc = *r.doc;
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(v, JsonType::kObject, "scan"));
  static const char* const kScanKeys[] = {"path",       "landmarks",        "trim", "min_overlap",
                                          "max_rms_mm", "crowns_within_mm", nullptr};
  SPLINTCORE_RETURN_IF_ERROR(r.known_keys(v, kScanKeys, "\"scan\""));
  const JsonValue* path = doc.member(v, "path");
  if (path == nullptr) {
    return r.fail(v, StatusCode::kInvalidArgument, "\"scan\" needs \"path\" (the scan's mesh)");
  }
  SPLINTCORE_RETURN_IF_ERROR(r.path(*path, "path", &out->path));
  if (const JsonValue* l = doc.member(v, "landmarks")) {
    SPLINTCORE_RETURN_IF_ERROR(r.expect_type(*l, JsonType::kArray, "landmarks"));
    if (l->child_count < 3 || l->child_count > 64) {
      return r.fail(*l, StatusCode::kInvalidArgument,
                    "\"landmarks\" needs 3 to 64 pairs [[scan x, y, z], [jaw x, y, z]]");
    }
    LandmarkPair* pairs = r.arena->allocate_array<LandmarkPair>(l->child_count);
    if (pairs == nullptr) return r.arena->exhausted_status();
    uint32_t i = 0;
    for (uint32_t k = l->first_child; k != kJsonNone; k = doc.at(k).next_sibling, ++i) {
      const JsonValue& pair = doc.at(k);
      SPLINTCORE_RETURN_IF_ERROR(r.expect_type(pair, JsonType::kArray, "landmarks"));
      if (pair.child_count != 2) {
        return r.fail(pair, StatusCode::kInvalidArgument,
                      "a landmark pair is [[scan x, y, z], [jaw x, y, z]]");
      }
      SPLINTCORE_RETURN_IF_ERROR(r.vec3(doc.at(pair.first_child), "landmarks", &pairs[i].scan));
      SPLINTCORE_RETURN_IF_ERROR(
          r.vec3(doc.at(doc.at(pair.first_child).next_sibling), "landmarks", &pairs[i].ct));
    }
    out->landmarks = Span<const LandmarkPair>(pairs, l->child_count);
  }
  if (const JsonValue* e = doc.member(v, "trim")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*e, "jaws[].scan.trim", 0, &out->trim));
  }
  if (const JsonValue* e = doc.member(v, "min_overlap")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*e, "jaws[].scan.min_overlap", 0, &out->min_overlap));
  }
  if (const JsonValue* e = doc.member(v, "max_rms_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*e, "jaws[].scan.max_rms_mm", 0, &out->max_rms_mm));
  }
  if (const JsonValue* e = doc.member(v, "crowns_within_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(
        r.number(*e, "jaws[].scan.crowns_within_mm", 0, &out->crowns_within_mm));
  }
  return Status::ok();
}

// The jaws ("jaws": role, mesh or seed, transform, scan).
Status parse_jaws(const Reader& r, const JsonValue* jaws, CaseFile* out) {
  const JsonDocument& doc = *r.doc;
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(*jaws, JsonType::kArray, "jaws"));
  CaseJaw* list = r.arena->allocate_array<CaseJaw>(jaws->child_count);
  if (list == nullptr && jaws->child_count > 0) return r.arena->exhausted_status();
  static const char* const kJawKeys[] = {"role", "mesh", "seed", "transform", "scan", nullptr};
  uint32_t i = 0;
  for (uint32_t k = jaws->first_child; k != kJsonNone; k = doc.at(k).next_sibling, ++i) {
    const JsonValue& j = doc.at(k);
    SPLINTCORE_RETURN_IF_ERROR(r.expect_type(j, JsonType::kObject, "jaws"));
    SPLINTCORE_RETURN_IF_ERROR(r.known_keys(j, kJawKeys, "a jaw"));
    CaseJaw jaw;
    const JsonValue* role = doc.member(j, "role");
    const JsonValue* mesh = doc.member(j, "mesh");
    const JsonValue* seed = doc.member(j, "seed");
    if (role == nullptr || (mesh == nullptr) == (seed == nullptr)) {
      return r.fail(j, StatusCode::kInvalidArgument,
                    "a jaw needs \"role\" and either \"mesh\" (a file) or \"seed\" (a point "
                    "of it in the case's \"ct\", mm)");
    }
    SPLINTCORE_RETURN_IF_ERROR(r.string(*role, "role", &jaw.role));
    if (std::strcmp(jaw.role, "maxilla") != 0 && std::strcmp(jaw.role, "mandible") != 0) {
      return r.fail(*role, StatusCode::kInvalidArgument,
                    "\"role\" must be \"maxilla\" or \"mandible\"");
    }
    if (mesh != nullptr) {
      SPLINTCORE_RETURN_IF_ERROR(r.path(*mesh, "mesh", &jaw.mesh));
    } else {
      SPLINTCORE_RETURN_IF_ERROR(r.vec3(*seed, "seed", &jaw.seed));
      jaw.has_seed = true;
    }
    if (const JsonValue* t = doc.member(j, "transform")) {
      SPLINTCORE_RETURN_IF_ERROR(r.transform(*t, "transform", "jaws[].transform", &jaw.transform));
    }
    if (const JsonValue* sc = doc.member(j, "scan")) {
      if (sc->type == JsonType::kArray) {  // several scans of this jaw
        return r.fail(*sc, StatusCode::kInvalidArgument,
                      "\"scan\" is a list: a jaw takes one scan (an object); merge the scans of "
                      "this jaw into one mesh (or choose one)");
      }
      SPLINTCORE_RETURN_IF_ERROR(parse_scan(r, *sc, &jaw.scan));
      jaw.has_scan = true;
    }
    for (uint32_t e = 0; e < i; ++e) {
      if (std::strcmp(list[e].role, jaw.role) != 0) continue;
      Status twice = r.fail(*role, StatusCode::kInvalidArgument, "two jaws with the role \"",
                            jaw.role, "\" (jaws[");
      twice.append_u64(e).append("] and jaws[").append_u64(i).append("])");
      if (list[e].has_scan && jaw.has_scan) {  // two scans of the same jaw
        return twice.append(", each with a \"scan\": two scans of the ")
            .append(jaw.role)
            .append("; a case takes one scan per jaw: merge them into one mesh (or choose one) ")
            .append("and give the jaw once");
      }
      return twice.append(": give each jaw once");
    }
    list[i] = jaw;
  }
  out->jaws = Span<const CaseJaw>(list, jaws->child_count);
  return Status::ok();
}

// The automatic outline ("base": {"auto": {...}}, outline.h).
Status parse_auto(const Reader& r, const JsonValue& a, CaseFile* out) {
  const JsonDocument& doc = *r.doc;
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(a, JsonType::kObject, "auto"));
  static const char* const kAutoKeys[] = {
      "indentation_depth_mm", "overhang_mm", "pick_spacing_mm", "bite_opening_mm", "survey",
      "distal_ends",          nullptr};
  SPLINTCORE_RETURN_IF_ERROR(r.known_keys(a, kAutoKeys, "\"auto\""));
  OutlineOptions& o = out->outline;
  if (const JsonValue* v = doc.member(a, "indentation_depth_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(
        r.number(*v, "base.auto.indentation_depth_mm", 0, &o.indentation_depth_mm));
  }
  if (const JsonValue* v = doc.member(a, "overhang_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*v, "base.auto.overhang_mm", 0, &o.overhang_mm));
  }
  if (const JsonValue* v = doc.member(a, "pick_spacing_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*v, "base.auto.pick_spacing_mm", 0, &o.pick_spacing_mm));
  }
  if (const JsonValue* v = doc.member(a, "bite_opening_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*v, "base.auto.bite_opening_mm", 0, &o.bite_opening_mm));
    o.has_bite_opening = true;
  }
  if (const JsonValue* v = doc.member(a, "survey")) {
    if (v->type != JsonType::kBool) {
      return r.fail(*v, StatusCode::kInvalidArgument, "\"survey\" must be true or false");
    }
    o.survey = v->boolean;
  }
  if (const JsonValue* v = doc.member(a, "distal_ends")) {
    SPLINTCORE_RETURN_IF_ERROR(r.expect_type(*v, JsonType::kArray, "distal_ends"));
    if (v->child_count != 2) {
      return r.fail(*v, StatusCode::kInvalidArgument,
                    "\"distal_ends\" needs 2 points, one a side of the arch");
    }
    const uint32_t second = doc.at(v->first_child).next_sibling;
    SPLINTCORE_RETURN_IF_ERROR(r.vec3(doc.at(v->first_child), "distal_ends", &o.distal_ends[0]));
    SPLINTCORE_RETURN_IF_ERROR(r.vec3(doc.at(second), "distal_ends", &o.distal_ends[1]));
    o.has_distal_ends = true;
  }
  out->has_auto_outline = true;
  return Status::ok();
}

// An "upper" and a "lower" pick list that pair up, from object `o` (the base, or one splint of
// the plan's "picks", named by `where` when a list is missing).
Status parse_pick_pair(const Reader& r, const JsonValue& o, const char* where, double inner_default,
                       double outside_default, Span<const Pick>* upper_out,
                       Span<const Pick>* lower_out) {
  const JsonValue* upper = r.doc->member(o, "upper");
  const JsonValue* lower = r.doc->member(o, "lower");
  if (upper == nullptr || lower == nullptr) {
    return r.fail(o, StatusCode::kInvalidArgument, where,
                  " needs \"upper\" and \"lower\" pick lists",
                  std::strcmp(where, "\"base\"") == 0 ? ", or \"auto\"" : "");
  }
  SPLINTCORE_RETURN_IF_ERROR(
      parse_picks(r, *upper, "upper", inner_default, outside_default, upper_out));
  SPLINTCORE_RETURN_IF_ERROR(
      parse_picks(r, *lower, "lower", inner_default, outside_default, lower_out));
  if (upper_out->size() != lower_out->size()) {
    Status s =
        r.fail(*lower, StatusCode::kInvalidArgument, "upper and lower pick lists do not pair up: ");
    return s.append_u64(upper_out->size())
        .append(" upper, ")
        .append_u64(lower_out->size())
        .append(" lower (the i-th upper pick pairs with the i-th lower pick)");
  }
  return Status::ok();
}

// The plan's "picks" (each splint's own: {"intermediate": {"upper", "lower"}, "final": {...}})
// with the base's pick defaults; the base then gives no picks and no "auto".
Status parse_plan_picks(const Reader& r, const JsonValue& base, const JsonValue& picks,
                        double inner_default, double outside_default, CaseFile* out) {
  const JsonDocument& doc = *r.doc;
  static const char* const kBasePicks[] = {"upper", "lower", "auto"};
  for (const char* key : kBasePicks) {
    if (doc.member(base, key) != nullptr) {
      return r.fail(*doc.member(base, key), StatusCode::kInvalidArgument,
                    "\"plan\" gives each splint its \"picks\": leave \"", key,
                    "\" out of \"base\" (one source of picks)");
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(picks, JsonType::kObject, "picks"));
  static const char* const kSplints[] = {"intermediate", "final", nullptr};
  SPLINTCORE_RETURN_IF_ERROR(r.known_keys(picks, kSplints, "\"plan\"'s \"picks\""));
  for (int k = 0; k < 2; ++k) {
    const JsonValue* splint = doc.member(picks, kSplints[k]);
    if (splint == nullptr) {
      return r.fail(picks, StatusCode::kInvalidArgument, "\"plan\"'s \"picks\" needs \"",
                    kSplints[k], "\" (each splint's upper and lower picks)");
    }
    SPLINTCORE_RETURN_IF_ERROR(r.expect_type(*splint, JsonType::kObject, kSplints[k]));
    static const char* const kLists[] = {"upper", "lower", nullptr};
    SPLINTCORE_RETURN_IF_ERROR(r.known_keys(*splint, kLists, kSplints[k]));
    SPLINTCORE_RETURN_IF_ERROR(parse_pick_pair(
        r, *splint, k == 0 ? "the intermediate splint's \"picks\"" : "the final splint's \"picks\"",
        inner_default, outside_default, &out->plan.upper[k], &out->plan.lower[k]));
  }
  out->plan.has_picks = true;
  return Status::ok();
}

// The base ("base": the occlusal normal, spacing, corners, default line lengths, the picks, or
// the plan's picks for each splint).
Status parse_base(const Reader& r, const JsonValue& root, CaseFile* out) {
  const JsonDocument& doc = *r.doc;
  const JsonValue* base = doc.member(root, "base");
  if (base == nullptr) return r.fail(root, StatusCode::kInvalidArgument, "no \"base\" object");
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(*base, JsonType::kObject, "base"));
  static const char* const kBaseKeys[] = {"occlusal_normal",
                                          "spacing_mm",
                                          "corner_radius_mm",
                                          "corner_segments",
                                          "inner_length_mm",
                                          "outside_length_mm",
                                          "upper",
                                          "lower",
                                          "auto",
                                          nullptr};
  SPLINTCORE_RETURN_IF_ERROR(r.known_keys(*base, kBaseKeys, "\"base\""));
  if (const JsonValue* a = doc.member(*base, "auto")) {
    if (doc.member(*base, "upper") != nullptr || doc.member(*base, "lower") != nullptr ||
        doc.member(*base, "occlusal_normal") != nullptr) {
      return r.fail(*a, StatusCode::kInvalidArgument,
                    "\"auto\" finds the picks and the occlusal normal: give either \"auto\" or "
                    "\"upper\" and \"lower\" (and \"occlusal_normal\")");
    }
    SPLINTCORE_RETURN_IF_ERROR(parse_auto(r, *a, out));
  }
  if (const JsonValue* o = doc.member(*base, "occlusal_normal")) {
    SPLINTCORE_RETURN_IF_ERROR(r.unit_vector(*o, "occlusal_normal", &out->occlusal_normal));
  }
  if (const JsonValue* s = doc.member(*base, "spacing_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*s, "base.spacing_mm", 0, &out->base.spacing_mm));
  }
  if (const JsonValue* s = doc.member(*base, "corner_radius_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(
        r.number(*s, "base.corner_radius_mm", 0, &out->base.corner_radius_mm));
  }
  if (const JsonValue* s = doc.member(*base, "corner_segments")) {
    double segs = 0;
    SPLINTCORE_RETURN_IF_ERROR(r.number(*s, "base.corner_segments", 0, &segs));
    uint32_t u = static_cast<uint32_t>(segs);
    if (static_cast<double>(u) != segs || (u & (u - 1)) != 0) {
      return r.fail(*s, StatusCode::kInvalidArgument,
                    "\"corner_segments\" must be 1, 2, 4, 8 or 16");
    }
    out->base.corner_segments = u;
  }
  double inner_default = 3.0, outside_default = 3.0;
  if (const JsonValue* s = doc.member(*base, "inner_length_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*s, "base.inner_length_mm", 0, &inner_default));
  }
  if (const JsonValue* s = doc.member(*base, "outside_length_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*s, "base.outside_length_mm", 0, &outside_default));
  }
  const JsonValue* plan = doc.member(root, "plan");
  if (plan != nullptr && plan->type == JsonType::kObject) {
    if (const JsonValue* picks = doc.member(*plan, "picks")) {
      return parse_plan_picks(r, *base, *picks, inner_default, outside_default, out);
    }
  }
  if (out->has_auto_outline) return Status::ok();
  return parse_pick_pair(r, *base, "\"base\"", inner_default, outside_default, &out->upper,
                         &out->lower);
}

// The CT the seeded jaws come from ("ct").
Status parse_ct(const Reader& r, const JsonValue* ct, CaseFile* out) {
  const JsonDocument& doc = *r.doc;
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(*ct, JsonType::kObject, "ct"));
  static const char* const kCtKeys[] = {"volume", "hu_min",   "hu_max", "connectivity",
                                        "smooth", "decimate", nullptr};
  SPLINTCORE_RETURN_IF_ERROR(r.known_keys(*ct, kCtKeys, "\"ct\""));
  const JsonValue* vol = doc.member(*ct, "volume");
  if (vol == nullptr) {
    return r.fail(*ct, StatusCode::kInvalidArgument,
                  "\"ct\" needs \"volume\" (a .nrrd/.mha/.mhd file or a DICOM folder)");
  }
  SPLINTCORE_RETURN_IF_ERROR(r.path(*vol, "volume", &out->ct_volume));
  double x = 0;
  if (const JsonValue* e = doc.member(*ct, "hu_min")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*e, "ct.hu_min", 0, &x));
    out->ct_window.lo = static_cast<int32_t>(x);
    if (static_cast<double>(out->ct_window.lo) != x) {
      return r.fail(*e, StatusCode::kInvalidArgument, "\"hu_min\" must be an integer");
    }
  }
  if (const JsonValue* e = doc.member(*ct, "hu_max")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*e, "ct.hu_max", 0, &x));
    out->ct_window.hi = static_cast<int32_t>(x);
    if (static_cast<double>(out->ct_window.hi) != x) {
      return r.fail(*e, StatusCode::kInvalidArgument, "\"hu_max\" must be an integer");
    }
  }
  if (out->ct_window.lo > out->ct_window.hi) {
    return r.fail(*ct, StatusCode::kInvalidArgument, "\"hu_min\" is above \"hu_max\"");
  }
  if (const JsonValue* e = doc.member(*ct, "connectivity")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*e, "ct.connectivity", 0, &x));
    if (x != 6 && x != 26) {
      return r.fail(*e, StatusCode::kInvalidArgument, "\"connectivity\" must be 6 or 26");
    }
    out->ct_grow.connectivity = x == 26 ? Connectivity::k26 : Connectivity::k6;
  }
  if (const JsonValue* e = doc.member(*ct, "smooth")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*e, "ct.smooth", 0, &x));
    out->ct_smooth.iterations = static_cast<uint32_t>(x);
    if (static_cast<double>(out->ct_smooth.iterations) != x) {
      return r.fail(*e, StatusCode::kInvalidArgument, "\"smooth\" must be an integer");
    }
  }
  if (const JsonValue* e = doc.member(*ct, "decimate")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*e, "ct.decimate", 0, &x));
    out->ct_decimate.target_triangles = static_cast<uint64_t>(x);
    if (static_cast<double>(out->ct_decimate.target_triangles) != x) {
      return r.fail(*e, StatusCode::kInvalidArgument, "\"decimate\" must be an integer");
    }
  }
  return Status::ok();
}

// Interference elimination ("blockout"; needs insertion_direction).
Status parse_blockout(const Reader& r, const JsonValue* b, CaseFile* out) {
  const JsonDocument& doc = *r.doc;
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(*b, JsonType::kObject, "blockout"));
  static const char* const kBlockoutKeys[] = {"voxel",     "inset",  "closing_radius",
                                              "clearance", "method", nullptr};
  SPLINTCORE_RETURN_IF_ERROR(r.known_keys(*b, kBlockoutKeys, "\"blockout\""));
  if (!out->has_insertion_direction && !out->has_auto_outline) {
    return r.fail(*b, StatusCode::kInvalidArgument,
                  "\"blockout\" needs \"insertion_direction\" (the splint is seated along it) "
                  "or the automatic outline");
  }
  out->has_blockout = true;
  static const char* const kVoxelKeys[] = {"voxel", "inset", "closing_radius", "clearance"};
  // Without "method": "voxel" when a key only it takes is named, the height field's spacer
  // with a clearance, else "auto" (whose fallback, the height field, takes the voxel as grid).
  const bool voxel_only =
      doc.member(*b, "inset") != nullptr || doc.member(*b, "closing_radius") != nullptr;
  out->blockout_method = voxel_only                               ? BlockoutMethod::kVoxel
                         : doc.member(*b, "clearance") != nullptr ? BlockoutMethod::kHeightfield
                                                                  : BlockoutMethod::kAuto;
  if (const JsonValue* m = doc.member(*b, "method")) {
    SPLINTCORE_RETURN_IF_ERROR(r.expect_type(*m, JsonType::kString, "blockout.method"));
    const BlockoutMethod methods[] = {BlockoutMethod::kAuto, BlockoutMethod::kExact,
                                      BlockoutMethod::kVoxel, BlockoutMethod::kHeightfield};
    bool known = false;
    for (BlockoutMethod x : methods) {
      if (std::strcmp(m->string, blockout_method_name(x)) != 0) continue;
      out->blockout_method = x;
      known = true;
    }
    if (!known) {
      return r.fail(*m, StatusCode::kInvalidArgument,
                    "\"blockout.method\" must be \"auto\", \"exact\", \"voxel\" or "
                    "\"heightfield\"");
    }
    for (const char* key : kVoxelKeys) {
      const JsonValue* v = doc.member(*b, key);
      if (out->blockout_method == BlockoutMethod::kExact && v != nullptr) {
        return r.fail(*v, StatusCode::kInvalidArgument, "\"blockout.", key,
                      "\" is for the voxel method (\"method\": \"exact\" has no voxels)");
      }
      // Inset and closing radius: the height field (auto's fallback too) has neither.
      const bool field = out->blockout_method == BlockoutMethod::kHeightfield;
      if ((field || out->blockout_method == BlockoutMethod::kAuto) && v != nullptr &&
          std::strcmp(key, "voxel") != 0 && std::strcmp(key, "clearance") != 0) {
        return r.fail(*v, StatusCode::kInvalidArgument, "\"blockout.", key,
                      field ? "\" is for the voxel method (\"method\": \"heightfield\" takes "
                              "only \"voxel\", its grid, and \"clearance\")"
                            : "\" is for the voxel method (\"method\": \"auto\" falls back to "
                              "the height field, which takes only \"voxel\", its grid)");
      }
    }
    const JsonValue* clearance = doc.member(*b, "clearance");
    if (out->blockout_method == BlockoutMethod::kAuto && clearance != nullptr) {
      return r.fail(*clearance, StatusCode::kInvalidArgument,
                    "\"blockout.clearance\" needs a method with a spacer: say \"method\": "
                    "\"voxel\" or \"heightfield\"");
    }
  }
  if (const JsonValue* bv = doc.member(*b, "voxel")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*bv, "blockout.voxel", 0, &out->blockout.voxel));
  }
  if (const JsonValue* bl = doc.member(*b, "clearance")) {
    // The spacer: the offset surface of the swept volume (blockout.h, SweepOptions::offset).
    SPLINTCORE_RETURN_IF_ERROR(
        r.number(*bl, "blockout.clearance", out->blockout.voxel, &out->blockout.offset));
  }
  out->blockout.inset = out->blockout_method == BlockoutMethod::kVoxel && out->blockout.offset == 0
                            ? 0.5 * out->blockout.voxel
                            : 0;
  if (const JsonValue* bi = doc.member(*b, "inset")) {
    SPLINTCORE_RETURN_IF_ERROR(
        r.number(*bi, "blockout.inset", out->blockout.voxel, &out->blockout.inset));
    if (out->blockout.inset > 0 && out->blockout.offset > 0) {
      return r.fail(*bi, StatusCode::kInvalidArgument,
                    "\"inset\" and \"clearance\" exclude "
                    "each other (a clearance takes the surface outside the swept volume)");
    }
  }
  if (const JsonValue* bc = doc.member(*b, "closing_radius")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*bc, "blockout.closing_radius", out->blockout.voxel,
                                        &out->blockout.closing_radius));
    if (out->blockout.closing_radius != 0 &&
        out->blockout.closing_radius < 2 * out->blockout.voxel) {
      return r.fail(*bc, StatusCode::kInvalidArgument,
                    "\"closing_radius\" must be 0 or at least two voxels");
    }
  }
  return Status::ok();
}

// The label ("label").
Status parse_label(const Reader& r, const JsonValue* lb, CaseFile* out) {
  const JsonDocument& doc = *r.doc;
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(*lb, JsonType::kObject, "label"));
  static const char* const kLabelKeys[] = {"text",      "mode",     "height_mm",
                                           "stroke_mm", "depth_mm", nullptr};
  SPLINTCORE_RETURN_IF_ERROR(r.known_keys(*lb, kLabelKeys, "\"label\""));
  const JsonValue* label_text = doc.member(*lb, "text");
  if (label_text == nullptr) {
    return r.fail(*lb, StatusCode::kInvalidArgument,
                  "\"label\" needs \"text\" (the case id "
                  "or any text of the stroke font: A-Z 0-9 space - _ . / # + ( ) :)");
  }
  SPLINTCORE_RETURN_IF_ERROR(r.string(*label_text, "text", &out->label.text));
  out->has_label = true;
  if (const JsonValue* m = doc.member(*lb, "mode")) {
    const char* mode = "";
    SPLINTCORE_RETURN_IF_ERROR(r.string(*m, "mode", &mode));
    if (std::strcmp(mode, "emboss") == 0) {
      out->label.mode = LabelMode::kEmboss;
    } else if (std::strcmp(mode, "engrave") != 0) {
      return r.fail(*m, StatusCode::kInvalidArgument,
                    "\"mode\" must be \"engrave\" (cut into the wall) or \"emboss\" (raised)");
    }
  }
  if (const JsonValue* h = doc.member(*lb, "height_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*h, "label.height_mm", 0, &out->label.height_mm));
  }
  if (const JsonValue* w = doc.member(*lb, "stroke_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*w, "label.stroke_mm", 0, &out->label.stroke_width_mm));
  }
  if (const JsonValue* d = doc.member(*lb, "depth_mm")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*d, "label.depth_mm", 0, &out->label.depth_mm));
  }
  return Status::ok();
}

// The surgical plan ("plan", two-jaw surgery): the sequence, the two planned moves, the hinge
// axis and the two openings, all required. The jaws are the preoperative ones: one maxilla and
// one mandible, with no "transform" of their own (the plan moves them), and the bite is the
// plan's (autorotation), so the automatic outline's "bite_opening_mm" is refused.
Status parse_plan(const Reader& r, const JsonValue& root, const JsonValue& p, CaseFile* out) {
  const JsonDocument& doc = *r.doc;
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(p, JsonType::kObject, "plan"));
  static const char* const kPlanKeys[] = {
      "sequence",         "maxilla", "mandible", "hinge_axis", "intermediate_opening_mm",
      "final_opening_mm", "picks",   nullptr};
  SPLINTCORE_RETURN_IF_ERROR(r.known_keys(p, kPlanKeys, "\"plan\""));
  for (const char* const* k = kPlanKeys; *k != nullptr && std::strcmp(*k, "picks") != 0; ++k) {
    if (doc.member(p, *k) == nullptr) {
      return r.fail(p, StatusCode::kInvalidArgument, "\"plan\" needs \"", *k,
                    "\" (a plan gives sequence, maxilla, mandible, hinge_axis, "
                    "intermediate_opening_mm and final_opening_mm)");
    }
  }
  CasePlan& plan = out->plan;
  const JsonValue& sequence = *doc.member(p, "sequence");
  const char* seq = "";
  SPLINTCORE_RETURN_IF_ERROR(r.string(sequence, "sequence", &seq));
  if (std::strcmp(seq, "mandible_first") == 0) {
    plan.mandible_first = true;
  } else if (std::strcmp(seq, "maxilla_first") != 0) {
    return r.fail(sequence, StatusCode::kInvalidArgument,
                  "\"sequence\" must be \"maxilla_first\" or \"mandible_first\" (which jaw "
                  "the surgeon moves first: the intermediate splint holds it)");
  }
  SPLINTCORE_RETURN_IF_ERROR(
      r.transform(*doc.member(p, "maxilla"), "maxilla", "plan.maxilla", &plan.maxilla));
  SPLINTCORE_RETURN_IF_ERROR(
      r.transform(*doc.member(p, "mandible"), "mandible", "plan.mandible", &plan.mandible));
  const JsonValue& hinge = *doc.member(p, "hinge_axis");
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(hinge, JsonType::kArray, "hinge_axis"));
  if (hinge.child_count != 2) {
    return r.fail(hinge, StatusCode::kInvalidArgument,
                  "\"hinge_axis\" needs 2 points [[x, y, z], [x, y, z]]: the two condyles");
  }
  const uint32_t second = doc.at(hinge.first_child).next_sibling;
  SPLINTCORE_RETURN_IF_ERROR(r.vec3(doc.at(hinge.first_child), "hinge_axis", &plan.hinge[0]));
  SPLINTCORE_RETURN_IF_ERROR(r.vec3(doc.at(second), "hinge_axis", &plan.hinge[1]));
  const double apart = length(plan.hinge[1] - plan.hinge[0]);
  if (!(apart >= 1.0)) {
    Status s = r.fail(hinge, StatusCode::kInvalidArgument, "\"hinge_axis\": the condyles are ");
    return s.append_f64(apart).append(" mm apart; at least 1 mm (one point on each condyle)");
  }
  SPLINTCORE_RETURN_IF_ERROR(r.number(*doc.member(p, "intermediate_opening_mm"),
                                      "plan.intermediate_opening_mm", 0,
                                      &plan.intermediate_opening_mm));
  SPLINTCORE_RETURN_IF_ERROR(r.number(*doc.member(p, "final_opening_mm"), "plan.final_opening_mm",
                                      0, &plan.final_opening_mm));
  if (out->jaws.size() != 2) {
    return r.fail(p, StatusCode::kInvalidArgument,
                  "\"plan\" needs \"jaws\" with the preoperative maxilla and mandible");
  }
  const JsonValue* jaws = doc.member(root, "jaws");
  for (uint32_t k = jaws->first_child; k != kJsonNone; k = doc.at(k).next_sibling) {
    if (const JsonValue* t = doc.member(doc.at(k), "transform")) {
      return r.fail(*t, StatusCode::kInvalidArgument,
                    "a jaw's \"transform\" and \"plan\" both move it: with a plan the jaws are "
                    "the preoperative ones and the plan's \"maxilla\" and \"mandible\" move "
                    "them");
    }
  }
  if (out->outline.has_bite_opening) {
    return r.fail(p, StatusCode::kInvalidArgument,
                  "\"plan\" sets the bite (the mandible turned about the hinge axis to each "
                  "opening): leave \"bite_opening_mm\" out of \"auto\"");
  }
  if (out->has_label && std::strlen(out->label.text) + 4 > kLabelMaxCharacters) {
    // Each splint's label is "INT " or "FIN " and this text (design_plan).
    Status s = r.fail(*doc.member(*doc.member(root, "label"), "text"), StatusCode::kInvalidArgument,
                      "with \"plan\" the label's \"text\" is at most ");
    return s.append_u64(kLabelMaxCharacters - 4)
        .append(" characters: each splint's label is \"INT \" or \"FIN \" and the text");
  }
  out->has_plan = true;
  return Status::ok();
}

// The memory cap ("memory_cap": "256M" or a byte count).
Status parse_memory_cap(const Reader& r, const JsonValue* m, CaseFile* out) {
  if (m->type == JsonType::kString) {
    if (!parse_byte_size(m->string, &out->memory_cap) || out->memory_cap == 0) {
      return r.fail(*m, StatusCode::kInvalidArgument,
                    "\"memory_cap\" must be a size such as \"256M\", \"2G\" or a byte count");
    }
  } else if (m->type != JsonType::kNumber) {
    return r.fail(*m, StatusCode::kInvalidArgument,
                  "\"memory_cap\" must be a string such as \"256M\" or a number of bytes");
  } else {
    double bytes = 0;
    SPLINTCORE_RETURN_IF_ERROR(r.number(*m, "memory_cap", 0, &bytes));
    // A fraction of a byte is a mistake in the file: refused, not silently cut off.
    if (bytes != static_cast<double>(static_cast<uint64_t>(bytes))) {
      return r.fail(*m, StatusCode::kInvalidArgument,
                    "\"memory_cap\" must be a whole number of bytes");
    }
    out->memory_cap = static_cast<uint64_t>(bytes);
  }
  return Status::ok();
}

// The output names ("output").
Status parse_output(const Reader& r, const JsonValue* o, CaseFile* out) {
  const JsonDocument& doc = *r.doc;
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(*o, JsonType::kObject, "output"));
  static const char* const kOutputKeys[] = {"splint", "report", "job", nullptr};
  SPLINTCORE_RETURN_IF_ERROR(r.known_keys(*o, kOutputKeys, "\"output\""));
  // Output names are file names inside the output folder the user chose: a case from
  // elsewhere must not be able to write outside it ("../x", "/etc/x").
  static const char* const kOutputNameRule =
      "\" must be a file name in the output folder: 1-128 letters, digits, '_', '-' or '.'";
  if (const JsonValue* s = doc.member(*o, "splint")) {
    SPLINTCORE_RETURN_IF_ERROR(r.string(*s, "splint", &out->output_splint));
    if (!is_plain_name(out->output_splint, 128)) {
      return r.fail(*s, StatusCode::kInvalidArgument, "\"splint", kOutputNameRule);
    }
  }
  if (const JsonValue* s = doc.member(*o, "report")) {
    SPLINTCORE_RETURN_IF_ERROR(r.string(*s, "report", &out->output_report));
    if (!is_plain_name(out->output_report, 128)) {
      return r.fail(*s, StatusCode::kInvalidArgument, "\"report", kOutputNameRule);
    }
  }
  if (const JsonValue* s = doc.member(*o, "job")) {
    SPLINTCORE_RETURN_IF_ERROR(r.string(*s, "job", &out->output_job));
    if (!is_plain_name(out->output_job, 128)) {
      return r.fail(*s, StatusCode::kInvalidArgument, "\"job", kOutputNameRule);
    }
  }
  return Status::ok();
}

JsonLimits case_json_limits() {
  JsonLimits limits;
  limits.max_bytes = 16 << 20;
  return limits;
}

// "splintcore_case" (the format's version, required), "case_id" and "units".
Status parse_version_and_id(const Reader& r, const JsonValue& root, const char* name,
                            CaseFile* out) {
  const JsonDocument& doc = *r.doc;
  const JsonValue* version = doc.member(root, "splintcore_case");
  if (version == nullptr) {
    return r.fail(root, StatusCode::kInvalidArgument,
                  "not a splintcore case file: no \"splintcore_case\" version key");
  }
  double v = 0;
  SPLINTCORE_RETURN_IF_ERROR(r.number(*version, "splintcore_case", 0, &v));
  if (v != static_cast<double>(static_cast<uint32_t>(v))) {
    return r.fail(*version, StatusCode::kInvalidArgument, "\"splintcore_case\" must be an integer");
  }
  if (v > kCaseFormatVersion) {
    return make_error(StatusCode::kUnsupported, "case format version ", static_cast<uint64_t>(v),
                      " is newer than this splintcore reads (", kCaseFormatVersion, ")")
        .at_line(version->line, version->column)
        .in_file(name);
  }
  out->version = static_cast<uint32_t>(v);

  if (const JsonValue* id = doc.member(root, "case_id")) {
    SPLINTCORE_RETURN_IF_ERROR(r.string(*id, "case_id", &out->case_id));
    if (!is_plain_name(out->case_id, 64)) {
      return r.fail(*id, StatusCode::kInvalidArgument,
                    "\"case_id\" must be 1-64 letters, digits, '_', '-' or '.'");
    }
  }
  if (const JsonValue* units = doc.member(root, "units")) {
    const char* u = nullptr;
    SPLINTCORE_RETURN_IF_ERROR(r.string(*units, "units", &u));
    if (std::strcmp(u, "mm") != 0) {
      return r.fail(*units, StatusCode::kInvalidArgument, "\"units\" must be \"mm\" (got \"", u,
                    "\"): convert the meshes and the case to millimetres");
    }
  }
  return Status::ok();
}

// "placement": "case" (the default) or "tray".
Status parse_placement(const Reader& r, const JsonValue& pl, CaseFile* out) {
  const char* placement = "";
  SPLINTCORE_RETURN_IF_ERROR(r.string(pl, "placement", &placement));
  if (std::strcmp(placement, "tray") == 0) {
    out->place_on_tray = true;
  } else if (std::strcmp(placement, "case") != 0) {
    return r.fail(pl, StatusCode::kInvalidArgument,
                  "\"placement\" must be \"case\" (the splint stays in the case's frame) or "
                  "\"tray\" (moved onto the printer's build tray)");
  }
  return Status::ok();
}

Status parse_case_document(const Context& ctx, const char* text, size_t length, const char* name,
                           CaseFile* out) {
  JsonDocument doc;
  SPLINTCORE_RETURN_IF_ERROR(parse_json(ctx, text, length, case_json_limits(), name, &doc));
  Reader r{&doc, ctx.arena};
  const JsonValue& root = doc.root();
  SPLINTCORE_RETURN_IF_ERROR(r.expect_type(root, JsonType::kObject, "the case"));
  static const char* const kRootKeys[] = {"splintcore_case",
                                          "case_id",
                                          "units",
                                          "jaws",
                                          "base",
                                          "insertion_direction",
                                          "blockout",
                                          "ct",
                                          "printer",
                                          "memory_cap",
                                          "min_thickness",
                                          "max_wall_crossing",
                                          "max_sideways_crossing",
                                          "placement",
                                          "label",
                                          "output",
                                          "plan",
                                          nullptr};
  SPLINTCORE_RETURN_IF_ERROR(r.known_keys(root, kRootKeys, "the case"));

  SPLINTCORE_RETURN_IF_ERROR(parse_version_and_id(r, root, name, out));

  if (const JsonValue* jaws = doc.member(root, "jaws")) {
    SPLINTCORE_RETURN_IF_ERROR(parse_jaws(r, jaws, out));
  }

  SPLINTCORE_RETURN_IF_ERROR(parse_base(r, root, out));

  if (const JsonValue* d = doc.member(root, "insertion_direction")) {
    if (out->outline.survey) {
      return r.fail(*d, StatusCode::kInvalidArgument,
                    "\"insertion_direction\" and \"auto\": {\"survey\": true} both choose the "
                    "direction: give one of them");
    }
    SPLINTCORE_RETURN_IF_ERROR(r.unit_vector(*d, "insertion_direction", &out->insertion_direction));
    out->has_insertion_direction = true;
  }
  if (const JsonValue* ct = doc.member(root, "ct")) {
    SPLINTCORE_RETURN_IF_ERROR(parse_ct(r, ct, out));
  }
  for (const CaseJaw& jaw : out->jaws) {
    if (jaw.has_seed && out->ct_volume == nullptr) {
      return r.fail(root, StatusCode::kInvalidArgument,
                    "a jaw is given by \"seed\" but the case "
                    "has no \"ct\" to reconstruct it from");
    }
  }
  if (const JsonValue* b = doc.member(root, "blockout")) {
    SPLINTCORE_RETURN_IF_ERROR(parse_blockout(r, b, out));
  }
  if (const JsonValue* lb = doc.member(root, "label")) {
    SPLINTCORE_RETURN_IF_ERROR(parse_label(r, lb, out));
  }
  if (const JsonValue* t = doc.member(root, "min_thickness")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*t, "min_thickness", 0, &out->min_thickness));
  }
  if (const JsonValue* w = doc.member(root, "max_wall_crossing")) {
    SPLINTCORE_RETURN_IF_ERROR(r.number(*w, "max_wall_crossing", 0, &out->max_wall_crossing));
  }
  if (const JsonValue* w = doc.member(root, "max_sideways_crossing")) {
    SPLINTCORE_RETURN_IF_ERROR(
        r.number(*w, "max_sideways_crossing", 0, &out->max_sideways_crossing));
  }
  if (const JsonValue* pl = doc.member(root, "placement")) {
    SPLINTCORE_RETURN_IF_ERROR(parse_placement(r, *pl, out));
  }
  if (const JsonValue* p = doc.member(root, "printer")) {
    SPLINTCORE_RETURN_IF_ERROR(r.string(*p, "printer", &out->printer));
  }
  if (const JsonValue* m = doc.member(root, "memory_cap")) {
    SPLINTCORE_RETURN_IF_ERROR(parse_memory_cap(r, m, out));
  }
  if (const JsonValue* o = doc.member(root, "output")) {
    SPLINTCORE_RETURN_IF_ERROR(parse_output(r, o, out));
  }
  if (const JsonValue* p = doc.member(root, "plan")) {
    SPLINTCORE_RETURN_IF_ERROR(parse_plan(r, root, *p, out));
    if (out->output_splint != nullptr) {
      return r.fail(*p, StatusCode::kInvalidArgument,
                    "a case with \"plan\" writes intermediate.stl and final.stl: leave "
                    "\"splint\" out of \"output\"");
    }
  }
  return Status::ok();
}

}  // namespace

Span<const CaseNumber> case_numbers() {
  return Span<const CaseNumber>(kCaseNumbers, sizeof(kCaseNumbers) / sizeof(kCaseNumbers[0]));
}

const CaseNumber* find_case_number(const char* key) {
  for (const CaseNumber& n : kCaseNumbers) {
    if (std::strcmp(n.key, key) == 0) return &n;
  }
  return nullptr;
}

void case_number_range(const CaseNumber& n, double voxel, double* lo, double* hi) {
  *lo = n.per_voxel ? n.lo * voxel : n.lo;
  *hi = n.per_voxel ? n.hi * voxel : n.hi;
  if (n.per_voxel && n.max_mm > 0 && *hi > n.max_mm) *hi = n.max_mm;
}

// The document, then the two pick lists and the jaws. Each entry of those arrays is a value of
// the document, so together they hold at most as many entries as parse_json_bound() counts
// values (its reasoning, json.cpp), each entry at most the larger of a Pick and a CaseJaw.
uint64_t parse_case_bound(uint64_t length) {
  const JsonLimits limits = case_json_limits();
  uint64_t values = (length + 1 + limits.max_depth) / 2 + 1;
  if (values > limits.max_values) values = limits.max_values;
  constexpr uint64_t kEntry = sizeof(Pick) > sizeof(CaseJaw) ? sizeof(Pick) : sizeof(CaseJaw);
  return parse_json_bound(length, limits) + values * kEntry + 3 * (Arena::kDefaultAlignment - 1);
}

Status parse_case(const Context& ctx, const char* text, size_t length, const char* name,
                  CaseFile* out) {
  *out = CaseFile{};
  // On failure nothing stays: the arena is rewound and *out is empty again.
  ArenaScope scope(*ctx.arena);
  Status s = parse_case_document(ctx, text, length, name, out);
  if (!s.is_ok()) {
    *out = CaseFile{};
    return s;
  }
  scope.commit();
  Sha256 hash;  // the report names the case by the hash of its bytes
  hash.update(text, length);
  uint8_t digest[32];
  hash.finish(digest);
  Sha256::to_hex(digest, out->sha256);
  return s;
}

uint64_t case_base_bound(const CaseFile& c, uint64_t sections, uint32_t points_per_section) {
  return arena_array_bound<Line>(c.upper.size()) + arena_array_bound<Line>(c.lower.size()) +
         splint_base_bound(sections, points_per_section);
}

Status build_case_base(const Context& ctx, const CaseFile& c, Mesh* out, BaseReport* report) {
  // The lines are temporaries; the mesh must sit below them, so the lines are made first into
  // arena memory that is then left in place (a few KB), and the mesh grows above.
  // On an error the arena goes back to its top at entry (`out` stays empty).
  ArenaScope scope(*ctx.arena);
  ArenaArray<Line> upper(ctx.arena), lower(ctx.arena);
  SPLINTCORE_RETURN_IF_ERROR(make_lines(ctx, c.upper, c.occlusal_normal, "upper", &upper));
  SPLINTCORE_RETURN_IF_ERROR(make_lines(ctx, c.lower, c.occlusal_normal, "lower", &lower));
  SPLINTCORE_RETURN_IF_ERROR(
      build_splint_base(ctx, upper.span(), lower.span(), c.base, out, report));
  scope.commit();
  return Status::ok();
}

const char* blockout_method_name(BlockoutMethod m) {
  switch (m) {
    case BlockoutMethod::kAuto: return "auto";
    case BlockoutMethod::kExact: return "exact";
    case BlockoutMethod::kVoxel: return "voxel";
    case BlockoutMethod::kHeightfield: return "heightfield";
  }
  return "unknown";
}

}  // namespace splintcore
