// Two-jaw surgery's stages that the tests reach directly (plan.cpp): the scan-CT fusion a
// plan makes once and both splints' autorotations, serial or in tasks on the executor.
#ifndef SPLINTCORE_DESIGN_PLAN_INTERNAL_H
#define SPLINTCORE_DESIGN_PLAN_INTERNAL_H

#include "splintcore/design.h"

namespace splintcore {
namespace design_detail {

// The scan-CT fusion of a plan case, made once before either splint: the scans as given and
// their registrations onto the preoperative jaws (fused[j]: jaw j has a scan).
struct PlanFusion {
  Span<const Mesh> scans;
  bool fused[2] = {false, false};
  FusionReport fusion[2];
  bool any() const { return fused[0] || fused[1]; }
};

// Both splints' autorotations, before either design: into report->intermediate and
// report->final_splint (the plan's moves, the opening asked, autorotation). Each jaw's index
// is built once (not once a splint) and refit to each splint's moved jaws. Nothing stays in
// the arena. A splint's error goes to status[splint] (0: intermediate, 1: final), prefixed,
// for the caller to report where it did before (the final's after the intermediate's design);
// the final's is not looked for after the intermediate's, nor after running out or a cancel.
// With an executor of more than one thread the two indexes are built in two tasks and the two
// autorotations run in two tasks, each task in a slice of the arena (design_plan, design.h,
// says how much); when the slices do not fit, or a task fails, the serial order runs instead,
// so the answers (bits), the errors and their order are the same at every thread count.
void plan_autorotations(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                        const PlanFusion& f, PlanReport* report, Status status[2]);

}  // namespace design_detail
}  // namespace splintcore

#endif  // SPLINTCORE_DESIGN_PLAN_INTERNAL_H
