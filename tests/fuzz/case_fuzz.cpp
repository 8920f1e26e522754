// libFuzzer target: arbitrary bytes through parse_case (the case JSON schema over the strict
// parser), then, for a case that parses, make_lines and build_case_base when the base stays
// small (the pick lists are short and the spacing not tiny), under a capped arena. Any crash,
// sanitizer report or a status other than the documented codes is a bug.
//   build/fuzz/tests/splintcore_fuzz_case -max_total_time=60 fixtures/fuzz/case
#include <cstdlib>
#include <cstring>
#include <initializer_list>

#include "splintcore/design.h"

namespace {

// The arch's length (sum of pick-to-pick distances) over the spacing: about the number of
// sections the base will have. Bounds the work a fuzzed case can ask for.
double estimated_sections(const splintcore::CaseFile& c) {
  double longest = 0;
  for (const splintcore::Span<const splintcore::Pick>* list : {&c.upper, &c.lower}) {
    double total = 0;
    for (size_t i = 1; i < list->size(); ++i) {
      total += splintcore::length((*list)[i].position - (*list)[i - 1].position);
    }
    if (total > longest) longest = total;
  }
  return longest / c.base.spacing_mm;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace splintcore;
  static unsigned char memory[32 << 20];
  Arena arena(memory, sizeof(memory));
  Context ctx(&arena);
  CaseFile c;
  Status s = parse_case(ctx, reinterpret_cast<const char*>(data), size, "fuzz.json", &c);
  if (!s.is_ok()) {
    if (s.code() == StatusCode::kInternal || s.message()[0] == '\0') std::abort();
    return 0;
  }
  if (c.upper.size() != c.lower.size()) std::abort();  // parse_case promises they pair up
  if (c.upper.size() > 64 || !(estimated_sections(c) < 400.0)) return 0;
  Mesh base(&arena);
  BaseReport report;
  s = build_case_base(ctx, c, &base, &report);
  if (s.is_ok()) {
    // What the library promises about a base it returns: a closed, oriented solid.
    MeshReport mr;
    if (!check_mesh(ctx, base, &mr).is_ok()) return 0;
    // build_splint_base() documents: closed, edge-manifold, outward.
    if (!mr.closed() || !mr.edge_manifold() || !mr.oriented() || !mr.outward()) std::abort();
  } else if (s.code() == StatusCode::kInternal) {
    std::abort();
  }
  return 0;
}
