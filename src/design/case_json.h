// The case's JSON pieces that the case writer (write_case, auto_outline.cpp) and the report
// (report.cpp) both write: a rigid transform as a row-major 4x4 and the surgical plan.
#ifndef SPLINTCORE_DESIGN_CASE_JSON_H
#define SPLINTCORE_DESIGN_CASE_JSON_H

#include "splintcore/design.h"
#include "splintcore/json.h"

namespace splintcore {
namespace design_detail {

// `key`: [r00, r01, r02, tx, r10, ..., 0, 0, 0, 1].
void write_transform(JsonWriter& w, const RigidTransform& t, const char* key = "transform");

// A jaw's "scan" with every key (the defaults written out), as the case gives it.
void write_scan(JsonWriter& w, const CaseScan& s);

// A pick list (`key`: "upper" or "lower") with every pick's lengths written out.
void write_picks(JsonWriter& w, const char* key, Span<const Pick> picks);

// "plan" with every key (all are required; "picks" when it has them), as the case gives it.
void write_plan(JsonWriter& w, const CasePlan& p);

}  // namespace design_detail
}  // namespace splintcore

#endif  // SPLINTCORE_DESIGN_CASE_JSON_H
