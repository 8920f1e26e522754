// splintcore design: the case file (format in docs/case-format.md) and, as the issues land,
// the whole design pipeline. Floor 7: the only module that knows the case file.
#ifndef SPLINTCORE_DESIGN_H
#define SPLINTCORE_DESIGN_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/json.h"
#include "splintcore/spline.h"

namespace splintcore {

constexpr uint32_t kCaseFormatVersion = 1;

struct CaseJaw {
  const char* role = "";       // "maxilla" or "mandible"
  const char* mesh = nullptr;  // path, relative to the case file's folder
  RigidTransform transform;    // the surgical plan's repositioning (identity if not given)
};

// A parsed case. Strings and arrays live in the arena the case was parsed into.
struct CaseFile {
  uint32_t version = 0;
  const char* case_id = "";
  Span<const CaseJaw> jaws;
  // The base ("base" object).
  Vec3 occlusal_normal{0, 0, 1};
  BaseParams base;
  Span<const Pick> upper;
  Span<const Pick> lower;
  // Later stages.
  Vec3 insertion_direction{0, 0, 1};
  bool has_insertion_direction = false;
  const char* printer = "eden260";
  uint64_t memory_cap = 0;  // bytes; 0: the tool's default
  const char* output_splint = nullptr;
  const char* output_report = nullptr;
};

// Parses and validates a case file (strict: unknown keys, wrong types, missing required keys
// and out-of-range values are errors with line and column). `name` is used in messages.
// Errors: kParseError, kInvalidArgument, kLimitExceeded, kUnsupported (a newer version),
// kArenaExhausted.
Status parse_case(const Context& ctx, const char* text, size_t length, const char* name,
                  CaseFile* out);

// Picks -> lines -> base, as the case says. `out` must be empty.
Status build_case_base(const Context& ctx, const CaseFile& c, Mesh* out, BaseReport* report);

}  // namespace splintcore

#endif  // SPLINTCORE_DESIGN_H
