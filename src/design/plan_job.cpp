// Two-jaw surgery's print job (design.h, write_plan_job): the intermediate and the final
// splint on one printer tray, written as a 3MF package (io.h, write_3mf) with each splint
// placed by its build item (printer.h, arrange_on_tray), so the splints' own vertices, those
// of intermediate.stl and final.stl, are what the package holds.
#include <cstring>

#include "splintcore/design.h"
#include "splintcore/io.h"
#include "splintcore/printer.h"

namespace splintcore {

namespace {

constexpr size_t kNameBytes = 4 + 64 + 1;  // "INT " or "FIN ", a case id (at most 64), NUL

// "INT <case id>" and "FIN <case id>" (the prefix alone without a case id).
void job_names(const CaseFile& c, char names[2][kNameBytes]) {
  static const char* const kPrefix[2] = {"INT ", "FIN "};
  size_t n = std::strlen(c.case_id);
  if (n > 64) n = 64;
  for (int k = 0; k < 2; ++k) {
    std::memcpy(names[k], kPrefix[k], 4);
    std::memcpy(names[k] + 4, c.case_id, n);
    names[k][4 + n] = '\0';
    if (n == 0) names[k][3] = '\0';
  }
}

// The objects as write_3mf takes them (the hashes and translations left for the caller).
void job_objects(const Mesh* splints[2], char names[2][kNameBytes], ThreeMfObject objects[2]) {
  for (int k = 0; k < 2; ++k) {
    objects[k].mesh = splints[k];
    objects[k].name = names[k];
    objects[k].sha256 = "0000000000000000000000000000000000000000000000000000000000000000";
  }
}

ThreeMfOptions job_options(const CaseFile& c) {
  ThreeMfOptions options;
  options.case_id = c.case_id;
  options.title = "intermediate and final splints";
  return options;
}

}  // namespace

uint64_t plan_job_bound(const CaseFile& c, const Mesh& intermediate, const Mesh& final_splint) {
  char names[2][kNameBytes];
  job_names(c, names);
  const Mesh* splints[2] = {&intermediate, &final_splint};
  ThreeMfObject objects[2];
  job_objects(splints, names, objects);
  const uint64_t job = write_3mf_bound(Span<const ThreeMfObject>(objects, 2), job_options(c));
  const uint64_t hash = uint64_t{StlWriteOptions{}.buffer_bytes} + Arena::kDefaultAlignment;
  return job > hash ? job : hash;  // the hashes are computed first, and returned
}

Status write_plan_job(const Context& ctx, const CaseFile& c, const Mesh& intermediate,
                      const Mesh& final_splint, const char* const sha256[2], const ByteSink& sink,
                      Vec3 moves[2]) {
  const PrinterProfile* profile = find_printer_profile(c.printer);
  if (profile == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "print job: unknown printer \"", c.printer,
                      "\" (known: eden260)");
  }
  const Mesh* splints[2] = {&intermediate, &final_splint};
  Aabb boxes[2];
  char hashes[2][65] = {};
  for (int k = 0; k < 2; ++k) {
    if (splints[k]->triangles.empty()) {
      return make_error(StatusCode::kInvalidArgument, "print job: the ",
                        k == 0 ? "intermediate" : "final", " splint is empty");
    }
    for (const Vec3& p : splints[k]->vertices) boxes[k].add(p);
    if (sha256 != nullptr && sha256[k] != nullptr) {
      std::strncpy(hashes[k], sha256[k], 64);
    } else {
      SPLINTCORE_RETURN_IF_ERROR(splint_stl_sha256(ctx, *splints[k], hashes[k]));
    }
  }
  Vec3 placed[2];
  SPLINTCORE_RETURN_IF_ERROR(
      arrange_on_tray(*profile, Span<const Aabb>(boxes, 2), kPlanJobGapMm, placed));
  char names[2][kNameBytes];
  job_names(c, names);
  ThreeMfObject objects[2];
  job_objects(splints, names, objects);
  for (int k = 0; k < 2; ++k) {
    objects[k].sha256 = hashes[k];
    objects[k].translation = placed[k];
    if (moves != nullptr) moves[k] = placed[k];
  }
  return write_3mf(ctx, Span<const ThreeMfObject>(objects, 2), job_options(c), sink);
}

}  // namespace splintcore
