// libFuzzer target: a fuzzed case file through the whole design pipeline: parse_case ->
// design_splint (jaws moved by the case's transforms, build_case_base, mesh_boolean base minus
// jaws, printer check) with the smallest phantom jaws (tools/common/phantom.h, 2,000 triangles
// each, made once at start). Work is capped so each execution stays fast: at most 64 picks per
// list and about 600 sections (arch length / spacing); larger cases return early.
// Any crash, sanitizer report, kInternal status, or a splint that is returned but is not a
// closed, oriented, outward solid is a bug.
//   build/fuzz/tests/splintcore_fuzz_pipeline -max_total_time=60 fixtures/fuzz/pipeline
#include <cstdlib>
#include <cstring>
#include <initializer_list>

#include "common/phantom.h"
#include "splintcore/design.h"

namespace {

using namespace splintcore;

double estimated_sections(const CaseFile& c) {
  double longest = 0;
  for (const Span<const Pick>* list : {&c.upper, &c.lower}) {
    double total = 0;
    for (size_t i = 1; i < list->size(); ++i) {
      total += length((*list)[i].position - (*list)[i - 1].position);
    }
    if (total > longest) longest = total;
  }
  return longest / c.base.spacing_mm;
}

struct Jaws {
  phantom::JawMesh jaw[2];
  bool ok = false;
  Jaws() {
    phantom::PhantomOptions po;
    po.target_triangles = phantom::kMinTriangles;
    ok = phantom::make_jaw(phantom::Jaw::kMaxilla, po, &jaw[0]).is_ok() &&
         phantom::make_jaw(phantom::Jaw::kMandible, po, &jaw[1]).is_ok();
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Jaws jaws;
  static unsigned char memory[64 << 20];
  if (!jaws.ok) std::abort();
  Arena arena(memory, sizeof(memory));
  Context ctx(&arena);
  CaseFile c;
  Status s = parse_case(ctx, reinterpret_cast<const char*>(data), size, "fuzz.json", &c);
  if (!s.is_ok()) {
    if (s.code() == StatusCode::kInternal) std::abort();
    return 0;
  }
  if (c.upper.size() > 64 || !(estimated_sections(c) < 600.0)) return 0;
  // One phantom per jaw the case names, by role.
  Mesh meshes[2];
  if (c.jaws.size() > 2) return 0;
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    const phantom::JawMesh& m = jaws.jaw[std::strcmp(c.jaws[j].role, "maxilla") == 0 ? 0 : 1];
    meshes[j].bind(&arena);
    if (!meshes[j].vertices.reserve(m.vertices.size()) ||
        !meshes[j].triangles.reserve(m.triangles.size())) {
      return 0;
    }
    for (const Vec3& v : m.vertices) (void)meshes[j].vertices.push_back(v);
    for (const Triangle& t : m.triangles) (void)meshes[j].triangles.push_back(t);
  }
  Mesh splint;
  DesignReport report;
  s = design_splint(ctx, c, Span<const Mesh>(meshes, c.jaws.size()), &splint, &report);
  if (!s.is_ok()) {
    if (s.code() == StatusCode::kInternal) std::abort();
    if (!splint.triangles.empty()) std::abort();  // no partial output
    return 0;
  }
  MeshReport mr;
  if (!check_mesh(ctx, splint, &mr).is_ok()) return 0;
  if (!mr.closed() || !mr.edge_manifold() || !mr.oriented() || !mr.outward()) std::abort();
  return 0;
}
