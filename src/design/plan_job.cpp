// The print jobs (design.h): two-jaw surgery's (write_plan_job), the intermediate and the
// final splint on one printer tray, and one splint's (write_splint_job), written as a 3MF
// package (io.h, write_3mf) with each splint placed by its build item (printer.h,
// arrange_on_tray), so the splints' own vertices, those of the STL files, are what the
// package holds.
#include <cstring>

#include "splintcore/design.h"
#include "splintcore/io.h"
#include "splintcore/printer.h"

namespace splintcore {

namespace {

constexpr size_t kNameBytes = 4 + 64 + 1;  // "INT " or "FIN ", a case id (at most 64), NUL
constexpr const char* kNoHash = "0000000000000000000000000000000000000000000000000000000000000000";

// One job's splints: their names are the prefix and the case id ("splint" for one splint of a
// case without an id), their title names what they are.
struct Job {
  const Mesh* splints[2] = {nullptr, nullptr};
  size_t count = 0;
  const char* prefix[2] = {"", ""};
  const char* title = "";
  const char* what[2] = {"", ""};  // for messages
  char names[2][kNameBytes] = {};

  void name(const CaseFile& c) {
    size_t n = std::strlen(c.case_id);
    if (n > 64) n = 64;
    for (size_t k = 0; k < count; ++k) {
      const size_t p = std::strlen(prefix[k]);
      std::memcpy(names[k], prefix[k], p);
      std::memcpy(names[k] + p, c.case_id, n);
      names[k][p + n] = '\0';
      if (n == 0 && p > 0) names[k][p - 1] = '\0';  // the prefix alone, without its space
      if (names[k][0] == '\0') std::memcpy(names[k], "splint", 7);
    }
  }
  // The objects as write_3mf takes them, naming this Job's names (the hashes and translations
  // are set by write_job).
  Span<const ThreeMfObject> objects(ThreeMfObject out[2]) const {
    for (size_t k = 0; k < count; ++k) {
      out[k].mesh = splints[k];
      out[k].name = names[k];
      out[k].sha256 = kNoHash;
    }
    return Span<const ThreeMfObject>(out, count);
  }
};

Job plan_job(const CaseFile& c, const Mesh& intermediate, const Mesh& final_splint) {
  Job j;
  j.splints[0] = &intermediate;
  j.splints[1] = &final_splint;
  j.count = 2;
  j.prefix[0] = "INT ";
  j.prefix[1] = "FIN ";
  j.what[0] = "intermediate";
  j.what[1] = "final";
  j.title = "intermediate and final splints";
  j.name(c);
  return j;
}

Job splint_job(const CaseFile& c, const Mesh& splint) {
  Job j;
  j.splints[0] = &splint;
  j.count = 1;
  j.what[0] = "";
  j.title = "splint";
  j.name(c);
  return j;
}

ThreeMfOptions job_options(const CaseFile& c, const Job& j) {
  ThreeMfOptions options;
  options.case_id = c.case_id;
  options.title = j.title;
  return options;
}

uint64_t job_bound(const CaseFile& c, const Job& j) {
  ThreeMfObject objects[2];
  const uint64_t job = write_3mf_bound(j.objects(objects), job_options(c, j));
  const uint64_t hash = uint64_t{StlWriteOptions{}.buffer_bytes} + Arena::kDefaultAlignment;
  return job > hash ? job : hash;  // the hashes are computed first, and returned
}

// The splints on the printer's tray, kPlanJobGapMm apart, as one 3MF package.
Status write_job(const Context& ctx, const CaseFile& c, const Job& j, const char* const* sha256,
                 const ByteSink& sink, Vec3* moves) {
  const PrinterProfile* profile = find_printer_profile(c.printer);
  if (profile == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "print job: unknown printer \"", c.printer,
                      "\" (known: eden260)");
  }
  Aabb boxes[2];
  char hashes[2][65] = {};
  for (size_t k = 0; k < j.count; ++k) {
    if (j.splints[k]->triangles.empty()) {
      return make_error(StatusCode::kInvalidArgument, "print job: the ", j.what[k],
                        j.what[k][0] != '\0' ? " " : "", "splint is empty");
    }
    for (const Vec3& p : j.splints[k]->vertices) boxes[k].add(p);
    if (sha256 != nullptr && sha256[k] != nullptr) {
      std::strncpy(hashes[k], sha256[k], 64);
    } else {
      SPLINTCORE_RETURN_IF_ERROR(splint_stl_sha256(ctx, *j.splints[k], hashes[k]));
    }
  }
  Vec3 placed[2];
  SPLINTCORE_RETURN_IF_ERROR(
      arrange_on_tray(*profile, Span<const Aabb>(boxes, j.count), kPlanJobGapMm, placed));
  ThreeMfObject objects[2];
  (void)j.objects(objects);
  for (size_t k = 0; k < j.count; ++k) {
    objects[k].sha256 = hashes[k];
    objects[k].translation = placed[k];
    if (moves != nullptr) moves[k] = placed[k];
  }
  return write_3mf(ctx, Span<const ThreeMfObject>(objects, j.count), job_options(c, j), sink);
}

}  // namespace

uint64_t plan_job_bound(const CaseFile& c, const Mesh& intermediate, const Mesh& final_splint) {
  return job_bound(c, plan_job(c, intermediate, final_splint));
}

Status write_plan_job(const Context& ctx, const CaseFile& c, const Mesh& intermediate,
                      const Mesh& final_splint, const char* const sha256[2], const ByteSink& sink,
                      Vec3 moves[2]) {
  return write_job(ctx, c, plan_job(c, intermediate, final_splint), sha256, sink, moves);
}

uint64_t splint_job_bound(const CaseFile& c, const Mesh& splint) {
  return job_bound(c, splint_job(c, splint));
}

Status write_splint_job(const Context& ctx, const CaseFile& c, const Mesh& splint,
                        const char* sha256, const ByteSink& sink, Vec3* move) {
  const char* const hashes[1] = {sha256};
  return write_job(ctx, c, splint_job(c, splint), hashes, sink, move);
}

}  // namespace splintcore
