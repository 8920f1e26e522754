// Scan-CT fusion shared by the single design (pipeline.cpp) and two-jaw surgery (plan.cpp):
// the scans checked against the case, registered once onto the jaws as given, and a design
// that takes those registrations instead of registering again (the plan's two splints and its
// autorotation use the same fit).
#ifndef SPLINTCORE_DESIGN_FUSION_H
#define SPLINTCORE_DESIGN_FUSION_H

#include "splintcore/design.h"

namespace splintcore {
namespace design_detail {

// Scans as design_splint takes them: none when no jaw has "scan", else one entry per jaw, a
// mesh exactly for the jaws with "scan" (at most DesignReport::kMaxFusedJaws jaws).
Status check_case_scans(const CaseFile& c, Span<const Mesh> scans);

// Each jaw with a scan: its scan registered onto jaws[j] as given (the case's thresholds;
// errors name the jaw, its role and the scan), into fusion[j] with fused[j] set; `applied` is
// the registration alone. fused and fusion hold c.jaws.size() entries. Arena: register_rigid's,
// returned.
Status register_case_scans(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                           Span<const Mesh> scans, bool* fused, FusionReport* fusion);

// design_splint with scans, where `registered` (per jaw, or null: registered here) holds the
// registrations register_case_scans made on the same jaws as given; the jaws' transforms apply
// after them as usual. `vetted`: refuse_no_jaw already passed on these very jaws and scans
// (design_plan checks them once for both splints), so it is not run again.
Status design_splint_registered(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                                Span<const Mesh> scans, const FusionReport* registered, bool vetted,
                                Mesh* splint, DesignReport* report);

// resolve_case_outline without its refuse_no_jaw, for a design that ran it already.
Status resolve_case_outline_vetted(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                                   CaseFile* resolved, Outline* outline);

}  // namespace design_detail
}  // namespace splintcore

#endif  // SPLINTCORE_DESIGN_FUSION_H
