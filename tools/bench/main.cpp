// splintcore-bench: our own benchmark harness (no dependency). Each benchmark runs once to warm
// up, then --repeat times; one line per result:
//   bench=NAME size=N median_s=T min_s=T max_s=T peak_arena_bytes=B
// Lines starting with '#' are derived figures (rates) and notes.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "../common/cli.h"
#include "../common/ct_files.h"
#include "../common/ct_phantom.h"
#include "../common/ct_write.h"
#include "../common/phantom.h"
#include "../common/preview.h"
#include "../common/realcase.h"
#include "../common/shapes.h"
#include "splintcore/blockout.h"
#include "splintcore/boolean.h"
#include "splintcore/compress.h"
#include "splintcore/core.h"
#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "splintcore/outline.h"
#include "splintcore/platform.h"
#include "splintcore/remesh.h"
#include "splintcore/segment.h"
#include "splintcore/volume.h"

namespace splintcore {
namespace {

struct Result {
  double median = 0, min = 0, max = 0;
  uint64_t peak_arena = 0;
};

struct Harness {
  int repeat = 7;
  std::string filter;
  bool failed = false;
  // --threads N (N > 1): the Booleans, outlines, autorotations and designs run on N threads
  // (the same results); the other entries and the default run on one.
  const Executor* executor = nullptr;
  unsigned threads = 1;

  bool wanted(const char* name) const {
    return filter.empty() || std::strstr(name, filter.c_str()) != nullptr;
  }

  // `body` runs one iteration on a rewound arena and returns its status.
  Result measure(const char* name, uint64_t size, Arena& arena,
                 const std::function<Status(Arena&)>& body) {
    Result r;
    std::vector<double> times;
    const Arena::Marker start = arena.mark();
    for (int i = 0; i < repeat + 1; ++i) {
      arena.rewind(start);
      arena.reset_high_water();
      double t0 = monotonic_seconds();
      Status s = body(arena);
      double t = monotonic_seconds() - t0;
      if (!s.is_ok()) {
        cli::print_error(s);
        failed = true;
        return r;
      }
      uint64_t peak = arena.high_water() - start.used;
      if (peak > r.peak_arena) r.peak_arena = peak;
      if (i > 0) times.push_back(t);  // the first run warms caches and pages
    }
    arena.rewind(start);
    std::sort(times.begin(), times.end());
    r.median = times[times.size() / 2];
    r.min = times.front();
    r.max = times.back();
    std::printf(
        "bench=%s size=%llu median_s=%.6f min_s=%.6f max_s=%.6f peak_arena_bytes=%llu "
        "threads=%u\n",
        name, static_cast<unsigned long long>(size), r.median, r.min, r.max,
        static_cast<unsigned long long>(r.peak_arena), threads);
    std::fflush(stdout);
    return r;
  }
};

std::vector<uint8_t> to_binary_stl(const std::vector<SoupTriangle>& soup) {
  std::vector<uint8_t> bytes(84 + 50 * soup.size(), 0);
  uint32_t n = static_cast<uint32_t>(soup.size());
  std::memcpy(bytes.data() + 80, &n, 4);  // little-endian hosts only (benchmark input)
  for (size_t t = 0; t < soup.size(); ++t) {
    std::memcpy(bytes.data() + 84 + 50 * t + 12, soup[t].p, 36);
  }
  return bytes;
}

// Empty when missing or over the mesh cap (cli::kMaxMeshBytes; the error is printed).
std::vector<uint8_t> read_whole(const std::string& path) {
  std::vector<uint8_t> out;
  const Status s = cli::read_whole_file(path, cli::kMaxMeshBytes, &out);
  if (s.code() == StatusCode::kLimitExceeded) cli::print_error(s);
  return out;
}

void bench_stl(Harness& h, Arena& arena, const char* label, const std::vector<uint8_t>& stl) {
  Context ctx(&arena);
  uint64_t triangles = (stl.size() - 84) / 50;
  std::string name = std::string("stl_read_weld") + label;
  if (h.wanted(name.c_str())) {
    h.measure(name.c_str(), triangles, arena, [&](Arena& a) {
      MemorySource ms{stl.data(), stl.size(), 0, 0};
      Mesh mesh(&a);
      return read_stl_mesh(ctx, memory_source(&ms), StlReadOptions{}, &mesh, nullptr);
    });
  }
  // The mesh the writers and checks use.
  Mesh mesh(&arena);
  MemorySource ms{stl.data(), stl.size(), 0, 0};
  Status s = read_stl_mesh(ctx, memory_source(&ms), StlReadOptions{}, &mesh, nullptr);
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    return;
  }
  std::vector<uint8_t> out(84 + 50 * mesh.triangles.size() + 1024);
  name = std::string("stl_write_binary") + label;
  if (h.wanted(name.c_str())) {
    Result r = h.measure(name.c_str(), mesh.triangles.size(), arena, [&](Arena& a) {
      MemorySink sink{out.data(), out.size(), 0, 0};
      Context c(&a);
      return write_stl(c, mesh, memory_sink(&sink), StlWriteOptions{});
    });
    double bytes = 84.0 + 50.0 * static_cast<double>(mesh.triangles.size());
    std::printf("# %s: %.2f GB/s (%.0f bytes per run, median)\n", name.c_str(),
                bytes / r.median / 1e9, bytes);
  }
  name = std::string("stl_write_ascii") + label;
  if (h.wanted(name.c_str())) {
    std::vector<uint8_t> text(400 * mesh.triangles.size() + 1024);
    uint64_t written = 0;
    Result r = h.measure(name.c_str(), mesh.triangles.size(), arena, [&](Arena& a) {
      MemorySink sink{text.data(), text.size(), 0, 0};
      Context c(&a);
      StlWriteOptions wo;
      wo.format = StlFormat::kAscii;
      Status st = write_stl(c, mesh, memory_sink(&sink), wo);
      written = sink.size;
      return st;
    });
    std::printf("# %s: %.2f GB/s (%llu bytes per run, median)\n", name.c_str(),
                static_cast<double>(written) / r.median / 1e9,
                static_cast<unsigned long long>(written));
  }
  name = std::string("mesh_check") + label;
  if (h.wanted(name.c_str())) {
    h.measure(name.c_str(), mesh.triangles.size(), arena, [&](Arena& a) {
      Context c(&a);
      MeshReport report;
      return check_mesh(c, mesh, &report);
    });
  }
  // What `splintcore check` does between its file and its report: read, weld, check.
  name = std::string("stl_read_check") + label;
  if (h.wanted(name.c_str())) {
    Result r = h.measure(name.c_str(), triangles, arena, [&](Arena& a) {
      Context c(&a);
      MemorySource m{stl.data(), stl.size(), 0, 0};
      Mesh read(&a);
      SPLINTCORE_RETURN_IF_ERROR(
          read_stl_mesh(c, memory_source(&m), StlReadOptions{}, &read, nullptr));
      MeshReport report;
      return check_mesh(c, read, &report);
    });
    std::printf("# %s: %.2f GB/s of STL (%zu bytes per run, median)\n", name.c_str(),
                static_cast<double>(stl.size()) / r.median / 1e9, stl.size());
  }
}

// The same mesh as a binary PLY and as an OBJ (the indexed formats intraoral scanners export),
// read and welded as `splintcore check` reads them (read_mesh with weld).
void bench_indexed_formats(Harness& h, Arena& arena, const char* label,
                           const std::vector<uint8_t>& stl) {
  const std::string ply_name = std::string("ply_read_weld") + label;
  const std::string obj_name = std::string("obj_read_weld") + label;
  if (!h.wanted(ply_name.c_str()) && !h.wanted(obj_name.c_str())) return;
  Context ctx(&arena);
  const Arena::Marker m = arena.mark();
  Mesh mesh(&arena);
  MemorySource ms{stl.data(), stl.size(), 0, 0};
  Status s = read_stl_mesh(ctx, memory_source(&ms), StlReadOptions{}, &mesh, nullptr);
  std::string ply;
  if (s.is_ok()) s = write_ply(mesh, Span<const uint8_t>(), cli::string_sink(&ply));
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    arena.rewind(m);
    return;
  }
  std::string obj;
  char line[128];
  for (const Vec3& v : mesh.vertices) {
    // %.9g: a float32 value's shortest exact decimal is at most 9 digits.
    obj.append(line, static_cast<size_t>(
                         std::snprintf(line, sizeof(line), "v %.9g %.9g %.9g\n", v.x, v.y, v.z)));
  }
  for (const Triangle& t : mesh.triangles) {
    obj.append(line, static_cast<size_t>(std::snprintf(line, sizeof(line), "f %u %u %u\n",
                                                       t.v[0] + 1, t.v[1] + 1, t.v[2] + 1)));
  }
  const uint64_t triangles = mesh.triangles.size();
  arena.rewind(m);
  for (const std::string* file : {&ply, &obj}) {
    const std::string& name = file == &ply ? ply_name : obj_name;
    if (!h.wanted(name.c_str())) continue;
    const uint8_t* bytes = reinterpret_cast<const uint8_t*>(file->data());
    Result r = h.measure(name.c_str(), triangles, arena, [&](Arena& a) {
      Context c(&a);
      MemorySource source{bytes, file->size(), 0, 0};
      MeshReadOptions options;
      options.weld = true;
      Mesh read(&a);
      return read_mesh(c, memory_source(&source), options, &read, nullptr);
    });
    std::printf("# %s: %.2f GB/s (%zu bytes per run, median)\n", name.c_str(),
                static_cast<double>(file->size()) / r.median / 1e9, file->size());
  }
}

// The phantom maxilla of `splintcore phantom --triangles 543530` (the paper's largest jaw) as
// the binary STL that command writes: read, weld and check at that size; then the same mesh
// read from PLY and OBJ.
void bench_stl_phantom(Harness& h, Arena& arena) {
  const char* label = "_phantom_543k";
  const char* names[5] = {"stl_read_weld_phantom_543k", "mesh_check_phantom_543k",
                          "stl_read_check_phantom_543k", "ply_read_weld_phantom_543k",
                          "obj_read_weld_phantom_543k"};
  if (std::none_of(names, names + 5, [&](const char* n) { return h.wanted(n); })) return;
  phantom::JawMesh jaw;
  phantom::PhantomOptions po;
  po.target_triangles = 543530;
  const Status s = phantom::make_jaw(phantom::Jaw::kMaxilla, po, &jaw);
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    return;
  }
  std::vector<SoupTriangle> soup(jaw.triangles.size());
  for (size_t t = 0; t < soup.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Vec3& v = jaw.vertices[jaw.triangles[t].v[k]];
      soup[t].p[k][0] = static_cast<float>(v.x);
      soup[t].p[k][1] = static_cast<float>(v.y);
      soup[t].p[k][2] = static_cast<float>(v.z);
    }
  }
  const Arena::Marker m = arena.mark();
  const std::vector<uint8_t> stl = to_binary_stl(soup);
  bench_stl(h, arena, label, stl);
  arena.rewind(m);
  bench_indexed_formats(h, arena, label, stl);
}

// The initial splint base at the paper's scale (fixtures/cases/paper_scale.json: 2,612
// triangles): generation alone (what the paper timed: 0.061-0.148 s) and with the exact
// self-intersection guarantee.
void bench_base(Harness& h, Arena& arena, const std::string& fixtures) {
  const std::string path = fixtures + "/cases/paper_scale.json";
  std::vector<uint8_t> text = read_whole(path);
  if (text.empty()) {
    std::printf("# %s not found: base benchmarks skipped\n", path.c_str());
    return;
  }
  Context ctx(&arena);
  CaseFile c;
  Status s =
      parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), path.c_str(), &c);
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    return;
  }
  for (bool guarantee : {false, true}) {
    const char* name = guarantee ? "base_build_checked" : "base_build";
    if (!h.wanted(name)) continue;
    CaseFile variant = c;
    variant.base.check_self_intersection = guarantee;
    size_t triangles = 0;
    h.measure(name, 2612, arena, [&](Arena& a) {
      Context cx(&a);
      Mesh m(&a);
      BaseReport r;
      Status st = build_case_base(cx, variant, &m, &r);
      triangles = m.triangles.size();
      return st;
    });
    std::printf("# %s: %zu triangles (closed, manifold, outward checked%s)\n", name, triangles,
                guarantee ? "; exact self-intersection test" : "");
  }
}

// issue 4's query points: a random triangle, a random point on it, moved along the normal by
// a uniform offset in [-2, 2] mm (fixed seed).
std::vector<Vec3> distance_queries(const Mesh& mesh, size_t count) {
  std::vector<Vec3> queries(count);
  const size_t nt = mesh.triangles.size();
  uint64_t state = 0x9e3779b97f4a7c15ull;
  auto next = [&]() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) * (1.0 / 9007199254740992.0);
  };
  const Vec3* v = mesh.vertices.data();
  for (Vec3& q : queries) {
    const Triangle& t = mesh.triangles[static_cast<size_t>(next() * static_cast<double>(nt)) % nt];
    double a = next(), b = next();
    if (a + b > 1) {
      a = 1 - a;
      b = 1 - b;
    }
    const Vec3 p = v[t.v[0]] + (v[t.v[1]] - v[t.v[0]]) * a + (v[t.v[2]] - v[t.v[0]]) * b;
    Vec3 n = cross(v[t.v[1]] - v[t.v[0]], v[t.v[2]] - v[t.v[0]]);
    const double len = length(n);
    n = len > 0 ? n * (1.0 / len) : Vec3{};
    q = p + n * (4.0 * next() - 2.0);
  }
  return queries;
}

// The narrow-band sampler as the tiled marching cubes calls it: every layer of a grid over the
// mesh's box and 1 mm around it, 0.5 mm apart, band 1 mm, one thread.
void bench_sdf_volume(Harness& h, Arena& arena, const std::string& sdf_name, const Mesh& mesh,
                      const DistanceIndex& index) {
  const Aabb box = mesh_bounds(mesh);
  SdfGrid grid;
  grid.spacing = 0.5;
  grid.band = 1.0;
  grid.origin = box.lo - Vec3{1, 1, 1};
  grid.nx = static_cast<uint32_t>((box.hi.x - box.lo.x + 2) / grid.spacing) + 1;
  grid.ny = static_cast<uint32_t>((box.hi.y - box.lo.y + 2) / grid.spacing) + 1;
  grid.nz = static_cast<uint32_t>((box.hi.z - box.lo.z + 2) / grid.spacing) + 1;
  std::vector<float> volume(size_t{grid.nx} * grid.ny * grid.nz);
  const Span<float> out(volume.data(), volume.size());
  Result r = h.measure(sdf_name.c_str(), volume.size(), arena, [&](Arena& a) {
    Context c(&a);
    return sample_sdf(c, index, grid, SignMethod::kAuto, 0, grid.nz, out);
  });
  size_t within = 0;
  for (float d : volume) within += std::fabs(d) < 1.0f ? size_t{1} : size_t{0};
  std::printf(
      "# %s: %ux%ux%u samples, %zu within the band: %.0f samples/s, %.0f within the "
      "band/s (one thread, %s)\n",
      sdf_name.c_str(), grid.nx, grid.ny, grid.nz, within,
      static_cast<double>(volume.size()) / r.median, static_cast<double>(within) / r.median,
      index.closed_manifold ? "pseudonormals" : "winding numbers");
}

// The distance engine (issue 4's protocol): build the index over a mesh, then answer
// 1,000,000 closest-point queries within 2 mm of the surface on one core: one at a time, and
// as a batch (Morton-ordered, seeded). Query points: a random triangle, a random point on it,
// moved along the normal by a uniform offset in [-2, 2] mm (fixed seed).
// With options.oriented_boxes the names carry "_oriented" (the index with BvhObb boxes).
void bench_distance(Harness& h, Arena& arena, const char* label, const Mesh& mesh,
                    const DistanceIndexOptions& options) {
  // Named as issue 4 asks ("octree_build"); the hierarchy is the BVH of distance.h.
  const std::string build_name = std::string("octree_build") + label;
  const std::string closest_name = std::string("closest_point") + label;
  const std::string batch_name = std::string("closest_point_batch") + label;
  const std::string signed_name = std::string("signed_distance") + label;
  const std::string sdf_name = std::string("sdf_volume") + label;
  if (!h.wanted(build_name.c_str()) && !h.wanted(closest_name.c_str()) &&
      !h.wanted(batch_name.c_str()) && !h.wanted(signed_name.c_str()) &&
      !h.wanted(sdf_name.c_str())) {
    return;
  }
  const size_t nt = mesh.triangles.size();
  if (h.wanted(build_name.c_str())) {
    Result r = h.measure(build_name.c_str(), nt, arena, [&](Arena& a) {
      Context c(&a);
      DistanceIndex index;
      return build_distance_index(c, mesh, options, &index);
    });
    (void)r;
  }
  Context ctx(&arena);
  const size_t before = arena.used();
  DistanceIndex index;
  Status s = build_distance_index(ctx, mesh, options, &index);
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    return;
  }
  std::printf("# %s: index keeps %zu bytes (%.1f MiB) for %zu triangles\n", build_name.c_str(),
              arena.used() - before, static_cast<double>(arena.used() - before) / 1048576.0, nt);
  const std::vector<Vec3> queries = distance_queries(mesh, 1000000);
  std::vector<ClosestPoint> results(queries.size());
  if (h.wanted(closest_name.c_str())) {
    Result r = h.measure(closest_name.c_str(), queries.size(), arena, [&](Arena&) {
      for (size_t i = 0; i < queries.size(); ++i) closest_point(index, queries[i], &results[i]);
      return Status::ok();
    });
    std::printf("# %s: %.0f queries/s\n", closest_name.c_str(),
                static_cast<double>(queries.size()) / r.median);
  }
  if (h.wanted(batch_name.c_str())) {
    Result r = h.measure(batch_name.c_str(), queries.size(), arena, [&](Arena& a) {
      Context c(&a);
      return batch_closest_points(c, index, Span<const Vec3>(queries.data(), queries.size()),
                                  Span<ClosestPoint>(results.data(), results.size()));
    });
    std::printf("# %s: %.0f queries/s (one thread)\n", batch_name.c_str(),
                static_cast<double>(queries.size()) / r.median);
  }
  if (h.wanted(signed_name.c_str())) {
    std::vector<double> d(queries.size());
    Result r = h.measure(signed_name.c_str(), queries.size(), arena, [&](Arena& a) {
      Context c(&a);
      return batch_signed_distances(c, index, Span<const Vec3>(queries.data(), queries.size()),
                                    SignMethod::kAuto, Span<double>(d.data(), d.size()));
    });
    std::printf("# %s: %.0f queries/s (one thread, %s)\n", signed_name.c_str(),
                static_cast<double>(queries.size()) / r.median,
                index.closed_manifold ? "pseudonormals" : "winding numbers");
  }
  if (h.wanted(sdf_name.c_str())) bench_sdf_volume(h, arena, sdf_name, mesh, index);
}

void bench_distance_sizes(Harness& h, Arena& arena) {
  // Tori of about the paper's three jaw sizes (86,866, 324,246 and 543,530 cells).
  const uint32_t sizes[3] = {209, 403, 521};
  const char* labels[3] = {"_87k", "_324k", "_543k"};
  for (int i = 0; i < 3; ++i) {
    Arena::Marker m = arena.mark();
    std::vector<SoupTriangle> soup = shapes::torus(sizes[i], sizes[i], 30.0, 8.0);
    Context ctx(&arena);
    Mesh mesh(&arena);
    Status s = weld_exact(ctx, Span<const SoupTriangle>(soup.data(), soup.size()), &mesh);
    if (!s.is_ok()) {
      cli::print_error(s);
      h.failed = true;
      return;
    }
    bench_distance(h, arena, labels[i], mesh, DistanceIndexOptions{});
    DistanceIndexOptions oriented;
    oriented.oriented_boxes = true;
    bench_distance(h, arena, (std::string("_oriented") + labels[i]).c_str(), mesh, oriented);
    arena.rewind(m);
  }
}

// The closest pair between the upper and the lower jaw at a few bite openings (the mandible
// moved down by `gap` mm, 0 for the jaws as given): one mesh_pair_distance() call per measurement,
// on the phantom jaws (87 k triangles each) and on the real dentition's two arches when present.
void bench_pair_jaws(Harness& h, Arena& arena, const char* label, const Mesh& upper,
                     const Mesh& lower) {
  const Arena::Marker m = arena.mark();
  const Context ctx(&arena);
  DistanceIndex iu, il;
  Status s = build_distance_index(ctx, upper, DistanceIndexOptions{}, &iu);
  if (s.is_ok()) s = build_distance_index(ctx, lower, DistanceIndexOptions{}, &il);
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    arena.rewind(m);
    return;
  }
  // 0: the jaws as given (the real arches as scanned interpenetrate slightly: distance 0).
  for (double gap : {0.0, 0.5, 2.0, 5.0}) {
    char name[96];
    std::snprintf(name, sizeof(name), "mesh_pair_distance%s_open%.1f", label, gap);
    MeshPairDistance r;
    h.measure(name, upper.triangles.size() + lower.triangles.size(), arena, [&](Arena& a) {
      return mesh_pair_distance(Context(&a), iu, il, Vec3{0, 0, -gap}, HUGE_VAL, &r);
    });
    std::printf("# %s: distance %.6f mm (triangles %u, %u)%s\n", name, r.distance, r.triangle_a,
                r.triangle_b, r.intersecting ? " intersecting" : "");
  }
  arena.rewind(m);
}

// The phantom's two jaws (`triangles` each, about) in `arena`, jaws[0] the maxilla; on an
// error it is printed, the harness marked failed and the arena rewound to `m`.
bool phantom_jaws(Harness& h, Arena& arena, const Arena::Marker& m, uint32_t triangles,
                  Mesh jaws[2]) {
  Status s;
  for (int j = 0; j < 2 && s.is_ok(); ++j) {
    phantom::JawMesh jm;
    phantom::PhantomOptions po;
    po.target_triangles = triangles;
    s = phantom::make_jaw(j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, po, &jm);
    jaws[j].bind(&arena);
    if (s.is_ok()) s = phantom::to_mesh(jm, &jaws[j]);
  }
  if (s.is_ok()) return true;
  cli::print_error(s);
  h.failed = true;
  arena.rewind(m);
  return false;
}

void bench_mesh_pair_distance(Harness& h, Arena& arena, const std::string& realdata) {
  if (!h.wanted("mesh_pair_distance")) return;
  const Arena::Marker m = arena.mark();
  Mesh jaws[2];
  if (!phantom_jaws(h, arena, m, 87000, jaws)) return;
  bench_pair_jaws(h, arena, "_phantom", jaws[0], jaws[1]);
  arena.rewind(m);
  realcase::RealCase rc;
  std::string error;
  if (!realcase::load(realdata, 0.0, 1.5, 6.0, &rc, &error)) {
    std::printf("# realdata not found (%s): mesh_pair_distance_realdata skipped\n", error.c_str());
    return;
  }
  for (int j = 0; j < 2; ++j) {
    jaws[j] = Mesh();
    jaws[j].bind(&arena);
    for (const realcase::Tooth& t : rc.teeth) {
      if ((t.number <= 16) != (j == 0)) continue;
      const uint32_t base = static_cast<uint32_t>(jaws[j].vertices.size());
      bool ok = true;
      for (const Vec3& v : t.vertices) ok = ok && jaws[j].vertices.push_back(v);
      for (const Triangle& tr : t.triangles) {
        ok = ok && jaws[j].triangles.push_back(
                       Triangle{{tr.v[0] + base, tr.v[1] + base, tr.v[2] + base}});
      }
      if (!ok) {
        cli::print_error(arena.exhausted_status());
        h.failed = true;
        arena.rewind(m);
        return;
      }
    }
  }
  bench_pair_jaws(h, arena, "_realdata", jaws[0], jaws[1]);
  arena.rewind(m);
}

// Stage times from the progress callback: the time from one stage's first report to the
// next stage's, summed over the runs (printed per run).
struct StageClock {
  std::vector<std::string> names;
  std::vector<double> seconds;
  std::string current;
  double since = 0;
  int runs = 0;
  static bool report(void* user, const char* stage, uint64_t, uint64_t) {
    StageClock* c = static_cast<StageClock*>(user);
    if (c->current == stage) return true;
    const double now = monotonic_seconds();
    if (!c->current.empty()) {
      size_t i = 0;
      while (i < c->names.size() && c->names[i] != c->current) ++i;
      if (i == c->names.size()) {
        c->names.push_back(c->current);
        c->seconds.push_back(0);
      }
      c->seconds[i] += now - c->since;
    }
    c->current = stage;
    c->since = now;
    if (c->current == "boolean: done") {
      c->current.clear();
      ++c->runs;
    }
    return true;
  }
  void print(const char* name) const {
    std::printf("# %s stages (ms per run):", name);
    for (size_t i = 0; i < names.size(); ++i) {
      std::printf(" %s %.2f;", names[i].c_str() + 9, 1e3 * seconds[i] / (runs > 0 ? runs : 1));
    }
    std::printf("\n");
  }
};

// The Boolean at the paper's Table 1 sizes: the base of fixtures/cases/paper_scale.json minus
// the phantom maxilla and mandible (the mandible opened by the case's 2 mm), B's two shells
// together holding 86,866, 324,246 and 543,530 triangles (half each).
void bench_boolean_phantom(Harness& h, Arena& arena, const std::string& fixtures) {
  if (!h.wanted("boolean_phantom_87k") && !h.wanted("boolean_phantom_324k") &&
      !h.wanted("boolean_phantom_543k")) {
    return;
  }
  const std::string path = fixtures + "/cases/paper_scale.json";
  std::vector<uint8_t> text = read_whole(path);
  if (text.empty()) return;
  const Arena::Marker m = arena.mark();
  Context ctx(&arena);
  CaseFile c;
  Mesh base(&arena);
  BaseReport br;
  Status s =
      parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), path.c_str(), &c);
  if (s.is_ok()) s = build_case_base(ctx, c, &base, &br);
  const uint64_t sizes[3] = {86866, 324246, 543530};
  const char* names[3] = {"boolean_phantom_87k", "boolean_phantom_324k", "boolean_phantom_543k"};
  for (int i = 0; i < 3 && s.is_ok(); ++i) {
    if (!h.wanted(names[i])) continue;
    phantom::JawMesh upper, lower;
    phantom::PhantomOptions po;
    po.target_triangles = sizes[i] / 2;
    s = phantom::make_jaw(phantom::Jaw::kMaxilla, po, &upper);
    if (s.is_ok()) s = phantom::make_jaw(phantom::Jaw::kMandible, po, &lower);
    if (!s.is_ok()) break;
    const Arena::Marker mj = arena.mark();
    Mesh jaws(&arena);
    if (!jaws.vertices.reserve(upper.vertices.size() + lower.vertices.size()) ||
        !jaws.triangles.reserve(upper.triangles.size() + lower.triangles.size())) {
      s = arena.exhausted_status();
      break;
    }
    for (const Vec3& v : upper.vertices) (void)jaws.vertices.push_back(v);
    for (const Triangle& t : upper.triangles) (void)jaws.triangles.push_back(t);
    const uint32_t off = static_cast<uint32_t>(upper.vertices.size());
    // The mandible opened by the case's 2 mm and rounded to float32, as its STL would hold it.
    for (const Vec3& v : lower.vertices) {
      Vec3 p{v.x, v.y, v.z - 2.0};
      (void)round_to_float32(&p);
      (void)jaws.vertices.push_back(p);
    }
    for (const Triangle& t : lower.triangles) {
      (void)jaws.triangles.push_back(Triangle{{t.v[0] + off, t.v[1] + off, t.v[2] + off}});
    }
    BooleanStats st;
    uint64_t out_tris = 0;
    double volume = 0;
    for (int checked = 0; checked < 2; ++checked) {
      BooleanOptions bo;
      bo.check_self_intersection = checked != 0;
      const std::string name = std::string(names[i]) + (checked != 0 ? "_checked" : "");
      StageClock clock;
      Progress progress;
      progress.report = &StageClock::report;
      progress.user = &clock;
      h.measure(name.c_str(), jaws.triangles.size(), arena, [&](Arena& a) {
        Mesh out;
        Status r = mesh_boolean(Context(&a, h.executor, &progress), base, jaws, bo, &out, &st);
        out_tris = out.triangles.size();
        if (r.is_ok()) volume = mesh_volume(out);
        return r;
      });
      clock.print(name.c_str());
    }
    std::printf(
        "# %s: base %zu triangles, jaws %zu triangles (%llu near), %llu crossing pairs "
        "of %llu candidates, output %llu triangles, volume %.6f mm3\n",
        names[i], base.triangles.size(), jaws.triangles.size(),
        static_cast<unsigned long long>(st.near_b_triangles),
        static_cast<unsigned long long>(st.intersecting_pairs),
        static_cast<unsigned long long>(st.candidate_pairs),
        static_cast<unsigned long long>(out_tris), volume);
    arena.rewind(mj);
  }
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
  }
  arena.rewind(m);
}

// The Boolean on the real case: the wafer minus the 31 teeth (bite opened 2 mm), the operation
// alone (meshes in memory, index build included, self-intersection check excluded) and with
// the exact self-intersection check of the result.
void bench_boolean_realdata(Harness& h, Arena& arena, const std::string& dir) {
  if (!h.wanted("boolean_realdata")) return;
  realcase::RealCase rc;
  std::string error;
  if (!realcase::load(dir, 2.0, 1.5, 6.0, &rc, &error)) {
    std::printf("# realdata not found (%s): boolean_realdata skipped\n", error.c_str());
    return;
  }
  const Arena::Marker m = arena.mark();
  Mesh teeth, wafer;
  BaseReport br;
  Status s = realcase::teeth_mesh(arena, rc, &teeth);
  if (s.is_ok()) s = realcase::wafer_mesh(arena, rc, 0.5, &wafer, &br);
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    arena.rewind(m);
    return;
  }
  BooleanStats st;
  uint64_t out_tris = 0;
  double volume = 0;
  for (int checked = 0; checked < 2; ++checked) {
    BooleanOptions bo;
    bo.check_self_intersection = checked != 0;
    const char* name = checked != 0 ? "boolean_realdata_checked" : "boolean_realdata";
    StageClock clock;
    Progress progress;
    progress.report = &StageClock::report;
    progress.user = &clock;
    h.measure(name, teeth.triangles.size(), arena, [&](Arena& a) {
      Mesh out;
      Status r = mesh_boolean(Context(&a, h.executor, &progress), wafer, teeth, bo, &out, &st);
      out_tris = out.triangles.size();
      if (r.is_ok()) volume = mesh_volume(out);
      return r;
    });
    clock.print(name);
  }
  std::printf(
      "# boolean_realdata: wafer %zu triangles, teeth %zu triangles (%llu near), %llu "
      "crossing pairs of %llu candidates, %llu points, output %llu triangles, volume %.6f mm3\n",
      wafer.triangles.size(), teeth.triangles.size(),
      static_cast<unsigned long long>(st.near_b_triangles),
      static_cast<unsigned long long>(st.intersecting_pairs),
      static_cast<unsigned long long>(st.candidate_pairs),
      static_cast<unsigned long long>(st.intersection_points),
      static_cast<unsigned long long>(out_tris), volume);
  arena.rewind(m);
}

// CT reconstruction at scan size (issue 7): a 512 x 512 x 300 skull phantom (0.3 mm voxels)
// through threshold, competitive region growing and reconstruction of both jaws, in an arena
// of a stated cap that also holds the volume (as the CT readers leave it).
// The CT phantom at the size: 512 x 512 x 300 voxels of 0.3 mm.
Status init_phantom_512(cli::CtPhantom* phantom) {
  cli::CtPhantomOptions po;
  po.nx = 512;
  po.ny = 512;
  po.nz = 300;
  po.spacing = Vec3{0.3, 0.3, 0.3};
  return phantom->init(po);
}

// The phantom's jaws out of a CT volume as `splintcore reconstruct` does: the HU window
// (300..4000) thresholded, both jaws grown from the phantom's seeds in competition, each meshed
// (in ctx's arena, returned after each jaw). lap(i) after each stage: 0 threshold, 1 region
// growing, 2 and 3 the maxilla and mandible meshed.
struct PhantomJaws {
  uint64_t in_window = 0, voxels[2] = {0, 0}, triangles[2] = {0, 0};
  uint32_t layers_per_tile = 0;
};
Status reconstruct_phantom_jaws(const Context& ctx, const CtVolume& volume,
                                const cli::CtPhantom& phantom, PhantomJaws* out,
                                const std::function<void(int)>& lap) {
  LabelVolume labels;
  ThresholdStats ts;
  SPLINTCORE_RETURN_IF_ERROR(threshold_window(ctx, volume, HuWindow{300, 4000}, &labels, &ts));
  lap(0);
  RegionSeed seeds[2];
  seeds[0].label = 1;
  seeds[0].patient_mm = phantom.seed_maxilla();
  seeds[1].label = 2;
  seeds[1].patient_mm = phantom.seed_mandible();
  RegionStats rs;
  SPLINTCORE_RETURN_IF_ERROR(grow_regions(ctx, volume, Span<const RegionSeed>(seeds, 2),
                                          RegionGrowOptions{}, &labels, &rs));
  lap(1);
  out->in_window = ts.in_window;
  out->voxels[0] = rs.voxels[1];
  out->voxels[1] = rs.voxels[2];
  for (int jaw = 0; jaw < 2; ++jaw) {
    ArenaScope scope(*ctx.arena);
    Mesh mesh(ctx.arena);
    ReconstructOptions ro;
    ro.label = static_cast<uint8_t>(jaw + 1);
    ReconstructStats st;
    SPLINTCORE_RETURN_IF_ERROR(reconstruct_region(ctx, volume, labels, ro, &mesh, &st));
    out->triangles[jaw] = mesh.triangles.size();
    out->layers_per_tile = st.marching.layers_per_tile;
    lap(2 + jaw);
  }
  return Status::ok();
}

// The 512^3 phantom's volume, its voxels in `arena`.
Status phantom_512_in(Arena& arena, cli::CtPhantom* phantom, CtVolume* volume) {
  SPLINTCORE_RETURN_IF_ERROR(init_phantom_512(phantom));
  std::vector<int16_t> hu;
  phantom->generate(&hu, volume);
  int16_t* in_arena = arena.allocate_array<int16_t>(hu.size());
  if (in_arena == nullptr) return arena.exhausted_status();
  std::memcpy(in_arena, hu.data(), hu.size() * sizeof(int16_t));
  volume->hu = in_arena;
  return Status::ok();
}

void bench_ct_reconstruct(Harness& h, Arena& arena) {
  const char* name = "ct_reconstruct_512";
  if (!h.wanted(name)) return;
  constexpr uint64_t kCap = uint64_t{512} << 20;
  const Arena::Marker outer = arena.mark();
  void* slice = arena.allocate(static_cast<size_t>(kCap));
  if (slice == nullptr) {
    cli::print_error(arena.exhausted_status());
    h.failed = true;
    return;
  }
  {
    Arena ct_arena(slice, static_cast<size_t>(kCap));
    cli::CtPhantom phantom;
    CtVolume volume;
    const double t0 = monotonic_seconds();
    const Status s = phantom_512_in(ct_arena, &phantom, &volume);
    if (!s.is_ok()) {
      cli::print_error(s);
      h.failed = true;
      arena.rewind(outer);
      return;
    }
    std::printf("# %s: phantom made in %.2f s (not timed below)\n", name, monotonic_seconds() - t0);
    double stage[5] = {0, 0, 0, 0, 0};
    uint64_t window = 0, triangles[2] = {0, 0}, voxels[2] = {0, 0};
    uint32_t layers = 0;
    // Time per progress stage ("threshold", "region growing", "reconstruct: region box",
    // "marching cubes"), last run: where reconstruction's time goes.
    StageClock clock;
    Progress progress;
    progress.report = &StageClock::report;
    progress.user = &clock;
    h.measure(name, volume.voxel_count(), ct_arena, [&](Arena& a) {
      Context ctx(&a, nullptr, &progress);
      clock.names.clear();
      clock.seconds.clear();
      clock.current.clear();
      double t = monotonic_seconds();
      auto lap = [&](int i) {
        const double now = monotonic_seconds();
        stage[i] = now - t;
        t = now;
      };
      PhantomJaws jaws;
      SPLINTCORE_RETURN_IF_ERROR(
          reconstruct_phantom_jaws(ctx, volume, phantom, &jaws, [&](int stage_index) {
            if (stage_index >= 2) StageClock::report(&clock, "reconstruct: returned", 0, 0);
            lap(stage_index);
          }));
      window = jaws.in_window;
      voxels[0] = jaws.voxels[0];
      voxels[1] = jaws.voxels[1];
      triangles[0] = jaws.triangles[0];
      triangles[1] = jaws.triangles[1];
      layers = jaws.layers_per_tile;
      return Status::ok();
    });
    std::printf(
        "# %s: cap %llu bytes (the 150 MiB volume included, outside the peak above); "
        "%llu window voxels; maxilla %llu voxels %llu triangles, mandible %llu voxels "
        "%llu triangles; %u layers per slab\n",
        name, static_cast<unsigned long long>(kCap), static_cast<unsigned long long>(window),
        static_cast<unsigned long long>(voxels[0]), static_cast<unsigned long long>(triangles[0]),
        static_cast<unsigned long long>(voxels[1]), static_cast<unsigned long long>(triangles[1]),
        layers);
    std::printf(
        "# %s stages (s, last run): threshold %.3f; region growing %.3f; reconstruct "
        "maxilla %.3f; reconstruct mandible %.3f\n",
        name, stage[0], stage[1], stage[2], stage[3]);
    std::printf(
        "# %s progress stages (s, last run, both jaws; a stage runs until the next "
        "one's first report):",
        name);
    for (size_t i = 0; i < clock.names.size(); ++i) {
      std::printf(" %s %.3f;", clock.names[i].c_str(), clock.seconds[i]);
    }
    std::printf("\n");
  }
  arena.rewind(outer);
}

// Smoothing and decimation at CT scale (issue 7): a marching-tetrahedra sphere (radius 30 mm,
// 0.225 mm voxels: about 2,000,000 triangles) decimated to 100,000 triangles, and 10 Taubin
// iterations on it, on one core; then the same on a torus.
struct RemeshSphere {
  Vec3 center;
  double radius = 0, tube = 0;  // tube > 0: a torus (radius: its ring)
  VolumeGrid grid;
  static Status fill(void* user, uint32_t z0, uint32_t z1, Span<float> out) {
    const RemeshSphere& s = *static_cast<const RemeshSphere*>(user);
    size_t i = 0;
    for (uint32_t z = z0; z < z1; ++z) {
      for (uint32_t y = 0; y < s.grid.ny; ++y) {
        for (uint32_t x = 0; x < s.grid.nx; ++x, ++i) {
          const Vec3 q = s.grid.origin +
                         Vec3{s.grid.spacing.x * x, s.grid.spacing.y * y, s.grid.spacing.z * z} -
                         s.center;
          double d;
          if (s.tube > 0) {
            const double ring = std::sqrt(q.x * q.x + q.y * q.y) - s.radius;
            d = std::sqrt(ring * ring + q.z * q.z) - s.tube;
          } else {
            d = length(q) - s.radius;
          }
          out[i] = static_cast<float>(d);
        }
      }
    }
    return Status::ok();
  }
};

void bench_remesh(Harness& h, Arena& arena) {
  for (int shape = 0; shape < 2; ++shape) {
    const std::string suffix = shape == 0 ? "_2m" : "_torus_2m";
    const std::string dname = "decimate" + suffix, tname = "taubin" + suffix;
    if (!h.wanted(dname.c_str()) && !h.wanted(tname.c_str())) continue;
    const Arena::Marker m = arena.mark();
    RemeshSphere s;
    double extent_xy = 0, extent_z = 0, voxel = 0;
    if (shape == 0) {
      s.radius = 30.0;
      voxel = 0.225;
      extent_xy = extent_z = 2 * s.radius;
    } else {
      s.radius = 30.0;
      s.tube = 8.0;
      voxel = 0.206;
      extent_xy = 2 * (s.radius + s.tube);
      extent_z = 2 * s.tube;
    }
    s.grid.spacing = Vec3{voxel, voxel, voxel};
    s.grid.nx = s.grid.ny = static_cast<uint32_t>(extent_xy / voxel) + 6;
    s.grid.nz = static_cast<uint32_t>(extent_z / voxel) + 6;
    s.grid.origin = Vec3{101.3, -40.7, 250.1};  // CT-like coordinates, off the origin
    s.center =
        s.grid.origin + Vec3{voxel * s.grid.nx * 0.5 + 0.0137, voxel * s.grid.ny * 0.5 - 0.0211,
                             voxel * s.grid.nz * 0.5 + 0.0093};
    Context ctx(&arena);
    Mesh mesh(&arena);
    LayerSource source;
    source.fill = &RemeshSphere::fill;
    source.user = &s;
    const double t0 = monotonic_seconds();
    Status st = marching_cubes_mesh(ctx, s.grid, source, MarchingCubesOptions{}, &mesh);
    if (!st.is_ok()) {
      cli::print_error(st);
      h.failed = true;
      arena.rewind(m);
      return;
    }
    std::printf("# %s input: %zu triangles, %zu vertices (marching tetrahedra, %.1f s to make)\n",
                suffix.c_str() + 1, mesh.triangles.size(), mesh.vertices.size(),
                monotonic_seconds() - t0);
    if (h.wanted(dname.c_str())) {
      DecimateOptions options;
      options.target_triangles = 100000;
      DecimateStats stats;
      Mesh out;
      double volume = 0;
      h.measure(dname.c_str(), mesh.triangles.size(), arena, [&](Arena& a) {
        Context c(&a);
        out.bind(&a);
        Status r = decimate_qem(c, mesh, options, &out, &stats);
        if (r.is_ok()) volume = mesh_volume(out);
        return r;
      });
      std::printf(
          "# %s: %llu triangles, %llu vertices, %llu collapses (refused: %llu link, %llu "
          "flip, %llu flat; %u rounds), max error %.4f mm, volume %.1f -> %.1f mm3, "
          "bound %llu bytes\n",
          dname.c_str(), static_cast<unsigned long long>(stats.output_triangles),
          static_cast<unsigned long long>(stats.output_vertices),
          static_cast<unsigned long long>(stats.collapses),
          static_cast<unsigned long long>(stats.rejected_link),
          static_cast<unsigned long long>(stats.rejected_flip),
          static_cast<unsigned long long>(stats.rejected_degenerate), stats.rounds, stats.max_error,
          mesh_volume(mesh), volume,
          static_cast<unsigned long long>(
              decimate_qem_bound(mesh.vertices.size(), mesh.triangles.size())));
    }
    if (h.wanted(tname.c_str())) {
      TaubinOptions options;
      options.iterations = 10;
      TaubinStats stats;
      h.measure(tname.c_str(), mesh.triangles.size(), arena,
                [&](Arena& a) { return taubin_smooth(Context(&a), &mesh, options, &stats); });
      std::printf(
          "# %s: 10 iterations (lambda 0.5, mu -0.53), %llu edges, volume change of the "
          "last run %.3g mm3 (%.3g%%), bound %llu bytes\n",
          tname.c_str(), static_cast<unsigned long long>(stats.edges),
          stats.volume_after - stats.volume_before,
          100.0 * (stats.volume_after - stats.volume_before) / stats.volume_before,
          static_cast<unsigned long long>(
              taubin_smooth_bound(mesh.vertices.size(), mesh.triangles.size())));
    }
    arena.rewind(m);
  }
}

// The extractor on a dense 512^3 grid (a sphere's distance, 0.4 n radius), one core, streamed
// to a counter: voxels per second of the extraction itself. The field is computed once into
// a table beforehand, so the fill is a copy (as flying edges' figures in ../shared/peers.md
// exclude making the volume).
void bench_marching_cubes(Harness& h, Arena& arena) {
  const char* name = "marching_cubes_512";
  if (!h.wanted(name)) return;
  const uint32_t n = 512;
  std::vector<float> field(size_t{n} * n * n);
  const double c = n * 0.5, r = n * 0.4;
  size_t i = 0;
  for (uint32_t z = 0; z < n; ++z) {
    for (uint32_t y = 0; y < n; ++y) {
      for (uint32_t x = 0; x < n; ++x, ++i) {
        const double dx = x - c + 0.13, dy = y - c - 0.21, dz = z - c + 0.07;
        field[i] = static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz) - r);
      }
    }
  }
  struct Table {
    const float* data;
    size_t layer;
    static Status fill(void* user, uint32_t z0, uint32_t z1, Span<float> out) {
      const Table& t = *static_cast<Table*>(user);
      std::memcpy(out.data(), t.data + t.layer * z0, t.layer * (z1 - z0) * sizeof(float));
      return Status::ok();
    }
  } table{field.data(), size_t{n} * n};
  VolumeGrid grid;
  grid.spacing = Vec3{1, 1, 1};
  grid.nx = grid.ny = grid.nz = n;
  uint64_t triangles = 0;
  const Result r0 = h.measure(name, uint64_t{n} * n * n, arena, [&](Arena& a) {
    Context ctx(&a);
    MarchingCubesVisitor none;
    MarchingCubesStats st;
    Status s = marching_cubes(ctx, grid, LayerSource{Table::fill, &table}, MarchingCubesOptions{},
                              none, &st);
    triangles = st.triangles;
    return s;
  });
  if (r0.median > 0) {
    std::printf("# %s: %.0f M voxels/s (median), %llu triangles\n", name,
                static_cast<double>(n) * n * n / r0.median / 1e6,
                static_cast<unsigned long long>(triangles));
  }
}

// The swept volume of both phantom jaws (87 k triangles each) along +z, streamed to a
// counter, at 0.1 mm (and 0.05 mm under a 64 MiB cap: sweep_phantom_005_64m).
void bench_sweep(Harness& h, Arena& arena) {
  const bool fine = h.wanted("sweep_phantom_005_64m");
  if (!h.wanted("sweep_phantom_01") && !fine) return;
  Mesh jaws[2];
  const Arena::Marker m = arena.mark();
  if (!phantom_jaws(h, arena, m, 87000, jaws)) return;
  struct Counter {
    uint64_t triangles = 0;
    static Status triangle(void* user, const Triangle&, const Vec3&, const Vec3&, const Vec3&) {
      ++static_cast<Counter*>(user)->triangles;
      return Status::ok();
    }
  };
  auto run = [&](const char* name, double voxel, uint64_t cap) {
    if (!h.wanted(name)) return;
    SweepOptions o;
    o.direction = Vec3{0, 0, 1};
    o.voxel = voxel;
    o.extent = 30.0;  // about 50 mm tall in all, as issue 6's full-arch case
    SweepStats st;
    Counter count;
    const Result r = h.measure(name, 0, arena, [&](Arena& a) {
      // Within a capped slice of the arena, as a caller with that budget would run it.
      void* slice = a.allocate(static_cast<size_t>(cap));
      if (slice == nullptr) return a.exhausted_status();
      Arena capped(slice, static_cast<size_t>(cap));
      Context ctx(&capped);
      MarchingCubesVisitor v;
      v.triangle = Counter::triangle;
      v.user = &count;
      count.triangles = 0;
      Status s = sweep_volume(ctx, Span<const Mesh>(jaws, 2), o, v, &st);
      if (s.is_ok())
        std::printf("# %s: cap peak %llu bytes\n", name,
                    static_cast<unsigned long long>(capped.high_water()));
      return s;
    });
    if (r.median > 0) {
      std::printf(
          "# %s: %u x %u x %u = %.3f G voxels of %.2f mm, %llu triangles, %llu column "
          "tests\n",
          name, st.nx, st.ny, st.nz, static_cast<double>(st.voxels) / 1e9, voxel,
          static_cast<unsigned long long>(count.triangles),
          static_cast<unsigned long long>(st.segment_tests));
    }
  };
  run("sweep_phantom_01", 0.1, uint64_t{1} << 30);
  run("sweep_phantom_005_64m", 0.05, uint64_t{64} << 20);
  arena.rewind(m);
}

// Interference elimination of the paper-scale splint (phantom jaws, 87 k triangles each):
// design_splint with "blockout" at 0.1 mm, both jaws.
void bench_blockout(Harness& h, Arena& arena, const std::string& fixtures) {
  const char* name = "blockout_phantom_87k";
  if (!h.wanted(name)) return;
  const std::string path = fixtures + "/cases/paper_scale.json";
  std::vector<uint8_t> text = read_whole(path);
  if (text.empty()) return;
  const Arena::Marker m = arena.mark();
  Context ctx(&arena);
  CaseFile c;
  Status s =
      parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), path.c_str(), &c);
  Mesh jaws[2];
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    arena.rewind(m);
    return;
  }
  if (!phantom_jaws(h, arena, m, 87000, jaws)) return;
  c.has_blockout = true;
  c.blockout_method = BlockoutMethod::kVoxel;
  c.blockout.voxel = 0.1;
  c.blockout.inset = 0.05;
  DesignReport report;
  uint64_t triangles = 0;
  h.measure(name, 0, arena, [&](Arena& a) {
    Mesh splint;
    Status st = design_splint(Context(&a, h.executor, nullptr), c, Span<const Mesh>(jaws, 2),
                              &splint, &report);
    triangles = splint.triangles.size();
    return st;
  });
  std::printf(
      "# %s: splint %llu triangles; removed %.3f + %.3f mm^3; swept %llu + %llu "
      "triangles; attempts %u + %u\n",
      name, static_cast<unsigned long long>(triangles), report.blockout_removed_mm3[0],
      report.blockout_removed_mm3[1],
      static_cast<unsigned long long>(report.blockout[0].swept_triangles),
      static_cast<unsigned long long>(report.blockout[1].swept_triangles),
      report.blockout[0].attempts, report.blockout[1].attempts);
  arena.rewind(m);
}

// The real dentition's two jaws (teeth 1-16, 17-32) as one mesh each, in `arena`.
Status real_jaws(Arena& arena, const realcase::RealCase& rc, Mesh jaws[2]) {
  for (int j = 0; j < 2; ++j) {
    jaws[j] = Mesh();
    jaws[j].bind(&arena);
    for (const realcase::Tooth& t : rc.teeth) {
      if ((t.number <= 16) != (j == 0)) continue;
      const uint32_t base = static_cast<uint32_t>(jaws[j].vertices.size());
      bool ok = true;
      for (const Vec3& v : t.vertices) ok = ok && jaws[j].vertices.push_back(v);
      for (const Triangle& tr : t.triangles) {
        ok = ok && jaws[j].triangles.push_back(
                       Triangle{{tr.v[0] + base, tr.v[1] + base, tr.v[2] + base}});
      }
      if (!ok) return arena.exhausted_status();
    }
  }
  return Status::ok();
}

// FNV-1a over the outline's doubles (picks, arch, the move and the normal): the same value
// before and after a change that must not move the output bits.
uint64_t outline_hash(const Outline& o) {
  uint64_t hash = 14695981039346656037ull;
  auto add = [&](const void* data, size_t bytes) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  };
  add(o.upper.data(), o.upper.size() * sizeof(Pick));
  add(o.lower.data(), o.lower.size() * sizeof(Pick));
  add(o.arch.data(), o.arch.size() * sizeof(Vec3));
  add(&o.report.mandible_translation, sizeof(Vec3));
  add(&o.report.occlusal_normal, sizeof(Vec3));
  add(&o.report.opening, sizeof(double));
  add(&o.report.gap_as_given, sizeof(double));
  return hash;
}

// compute_outline on two jaws already in memory (the call only).
void bench_outline_jaws(Harness& h, Arena& arena, const char* name, const Mesh& upper,
                        const Mesh& lower, const OutlineOptions& options) {
  Outline o;
  uint64_t hash = 0;
  h.measure(name, upper.triangles.size() + lower.triangles.size(), arena, [&](Arena& a) {
    Status s = compute_outline(Context(&a, h.executor, nullptr), upper, lower, options, &o);
    if (s.is_ok()) hash = outline_hash(o);  // before the harness rewinds the arena
    return s;
  });
  std::printf("# %s: %u picks, opening %.12f mm in %u steps, arch %.3f mm, output hash %016llx\n",
              name, o.report.picks, o.report.opening, o.report.opening_steps,
              o.report.arch_length_mm, static_cast<unsigned long long>(hash));
}

// The automatic outline (issue 28: under 50 ms on the real dentition): the real jaws as
// scanned (they touch) opened by 2 mm, and the 87 k phantom jaws (the mandible 2 mm down).
void bench_outline(Harness& h, Arena& arena, const std::string& realdata) {
  const Arena::Marker m = arena.mark();
  Mesh jaws[2];
  if (h.wanted("outline_phantom")) {
    if (!phantom_jaws(h, arena, m, 87000, jaws)) return;
    for (Vec3& v : jaws[1].vertices) v.z -= 2.0;
    bench_outline_jaws(h, arena, "outline_phantom", jaws[0], jaws[1], OutlineOptions{});
    arena.rewind(m);
  }
  if (!h.wanted("outline_realdata")) return;
  realcase::RealCase rc;
  std::string error;
  if (!realcase::load(realdata, 0.0, 1.5, 6.0, &rc, &error)) {
    std::printf("# realdata not found (%s): outline_realdata skipped\n", error.c_str());
    return;
  }
  const Status s = real_jaws(arena, rc, jaws);
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    arena.rewind(m);
    return;
  }
  OutlineOptions options;
  options.has_bite_opening = true;
  options.bite_opening_mm = 2.0;
  bench_outline_jaws(h, arena, "outline_realdata", jaws[0], jaws[1], options);
  arena.rewind(m);
}

// Hinge-axis autorotation (issue 32): the mandible turned about a hinge behind and above the
// teeth to a 2 mm opening, on the 87 k phantom jaws (in occlusion: opened first, then closed)
// and the real jaws as scanned; and, for the choice of a rigid pair search over one index per
// jaw, one pairs_only index build of the mandible (what rebuilding per step would cost each
// step).
void bench_autorotate_jaws(Harness& h, Arena& arena, const char* name, const Mesh& upper,
                           const Mesh& lower, const Vec3& h0, const Vec3& h1) {
  AutorotateOptions o;
  o.hinge[0] = h0;
  o.hinge[1] = h1;
  o.opening_mm = 2.0;
  AutorotateReport r;
  h.measure(name, upper.triangles.size() + lower.triangles.size(), arena, [&](Arena& a) {
    return autorotate_mandible(Context(&a, h.executor, nullptr), upper, lower, o, &r);
  });
  std::printf("# %s: %.12f rad, opening %.12f mm, %u distance evaluations, start %.6f rad\n", name,
              r.angle_rad, r.opening, r.steps, r.start_angle_rad);
  std::string build_name = std::string(name) + "_index_build";
  DistanceIndexOptions io;
  io.pairs_only = true;
  h.measure(build_name.c_str(), lower.triangles.size(), arena, [&](Arena& a) {
    DistanceIndex index;
    return build_distance_index(Context(&a), lower, io, &index);
  });
}

void bench_autorotate(Harness& h, Arena& arena, const std::string& realdata) {
  const Arena::Marker m = arena.mark();
  Mesh jaws[2];
  if (h.wanted("autorotate_phantom")) {
    if (!phantom_jaws(h, arena, m, 87000, jaws)) return;
    bench_autorotate_jaws(h, arena, "autorotate_phantom", jaws[0], jaws[1], Vec3{-50, -55, 25},
                          Vec3{50, -55, 25});
    arena.rewind(m);
  }
  if (!h.wanted("autorotate_realdata")) return;
  realcase::RealCase rc;
  std::string error;
  if (!realcase::load(realdata, 0.0, 1.5, 6.0, &rc, &error)) {
    std::printf("# realdata not found (%s): autorotate_realdata skipped\n", error.c_str());
    return;
  }
  const Status s = real_jaws(arena, rc, jaws);
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    arena.rewind(m);
    return;
  }
  bench_autorotate_jaws(h, arena, "autorotate_realdata", jaws[0], jaws[1], Vec3{4, 90, 80},
                        Vec3{104, 90, 80});
  arena.rewind(m);
}

// One stage of design_auto_realdata: reads a mesh file as the CLI does (read_mesh, welded).
Status read_mesh_path(const Context& ctx, const std::string& path, Mesh* mesh) {
  FileSource file;
  SPLINTCORE_RETURN_IF_ERROR(file.open(path.c_str()));
  MeshReadOptions options;
  options.weld = true;
  return read_mesh(ctx, file.source(), options, mesh, nullptr);
}

// The union of the pair from Manifold's bug reports (realdata/manifold-bugreports, issue 29:
// "should answer, either way, in under a second"): meshes in memory, the time to the answer.
// Today the answer is the work bound's kLimitExceeded (printed, not counted as a failure).
void bench_boolean_manifold_twin(Harness& h, Arena& arena, const std::string& realdata) {
  const char* name = "boolean_manifold_twin";
  if (!h.wanted(name)) return;
  const std::string dir = realdata + "/../manifold-bugreports/";
  const Arena::Marker m = arena.mark();
  const Context ctx(&arena);
  Mesh a, b;
  Status s = read_mesh_path(ctx, dir + "Generic_Twin_7081.1.t0_left.obj", &a);
  if (s.is_ok()) s = read_mesh_path(ctx, dir + "Generic_Twin_7081.1.t0_right.obj", &b);
  if (!s.is_ok()) {
    std::printf("# manifold-bugreports not read (%s): %s skipped\n", s.message(), name);
    arena.rewind(m);
    return;
  }
  BooleanOptions bo;
  bo.op = BooleanOp::kUnion;
  BooleanStats st;
  Status answer;
  h.measure(name, a.triangles.size() + b.triangles.size(), arena, [&](Arena& ar) {
    Mesh out;
    answer = mesh_boolean(Context(&ar), a, b, bo, &out, &st);
    return Status::ok();  // either answer is one; the time to it is what is measured
  });
  std::printf("# %s: %zu + %zu triangles, %llu candidate pairs, %u attempt(s): %s\n", name,
              a.triangles.size(), b.triangles.size(),
              static_cast<unsigned long long>(st.candidate_pairs), st.attempts,
              answer.is_ok() ? "a valid union" : answer.message());
  arena.rewind(m);
}

// The whole auto design of the real case, file to file (issue 28: under 0.5 s): the case
// folder (the teeth as scanned in maxilla.stl and mandible.stl, an auto case.json opening the
// bite by 2 mm) written once to a temporary folder; timed: reading the case and both STL
// files, design_splint, writing the splint's binary STL.
void bench_design_auto_realdata(Harness& h, Arena& arena, const std::string& realdata) {
  const char* name = "design_auto_realdata";
  if (!h.wanted(name)) return;
  realcase::RealCase rc;
  std::string error;
  if (!realcase::load(realdata, 0.0, 1.5, 6.0, &rc, &error)) {
    std::printf("# realdata not found (%s): %s skipped\n", error.c_str(), name);
    return;
  }
  char dir[] = "/tmp/splintcore-bench-XXXXXX";
  if (::mkdtemp(dir) == nullptr || !realcase::write_case_folder(rc, dir, 0.5, &error)) {
    std::printf("# %s: cannot write the case folder (%s): skipped\n", name, error.c_str());
    return;
  }
  const std::string folder = dir;
  const std::string json =
      "{\"splintcore_case\": 1, \"case_id\": \"realdata-auto\", \"units\": \"mm\", \"jaws\": ["
      "{\"role\": \"maxilla\", \"mesh\": \"maxilla.stl\"}, "
      "{\"role\": \"mandible\", \"mesh\": \"mandible.stl\"}], "
      "\"base\": {\"spacing_mm\": 0.5, \"auto\": {\"bite_opening_mm\": 2}}, "
      "\"output\": {\"splint\": \"splint.stl\"}}\n";
  FILE* f = std::fopen((folder + "/case.json").c_str(), "wb");
  const bool written = f != nullptr && std::fwrite(json.data(), 1, json.size(), f) == json.size();
  if (f == nullptr || std::fclose(f) != 0 || !written) {
    std::printf("# %s: cannot write case.json: skipped\n", name);
    return;
  }
  double stage[4] = {0, 0, 0, 0};  // read, outline + design, write; summed over the runs
  int runs = 0;
  DesignReport report;
  uint64_t triangles = 0;
  h.measure(name, 0, arena, [&](Arena& a) {
    const Context ctx(&a);
    const double t0 = monotonic_seconds();
    Span<uint8_t> text;
    SPLINTCORE_RETURN_IF_ERROR(read_file(a, (folder + "/case.json").c_str(), 1 << 20, &text));
    CaseFile c;
    SPLINTCORE_RETURN_IF_ERROR(
        parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), "case.json", &c));
    Mesh jaws[2];
    SPLINTCORE_RETURN_IF_ERROR(read_mesh_path(ctx, folder + "/maxilla.stl", &jaws[0]));
    SPLINTCORE_RETURN_IF_ERROR(read_mesh_path(ctx, folder + "/mandible.stl", &jaws[1]));
    const double t1 = monotonic_seconds();
    Mesh splint;
    SPLINTCORE_RETURN_IF_ERROR(design_splint(ctx, c, Span<const Mesh>(jaws, 2), &splint, &report));
    const double t2 = monotonic_seconds();
    AtomicFile out;
    SPLINTCORE_RETURN_IF_ERROR(out.open((folder + "/splint.stl").c_str()));
    SPLINTCORE_RETURN_IF_ERROR(write_stl(ctx, splint, out.sink(), StlWriteOptions{}));
    SPLINTCORE_RETURN_IF_ERROR(out.commit());
    const double t3 = monotonic_seconds();
    triangles = splint.triangles.size();
    stage[0] += t1 - t0;
    stage[1] += t2 - t1;
    stage[2] += t3 - t2;
    stage[3] += t3 - t0;
    ++runs;
    return Status::ok();
  });
  if (runs > 0 && stage[3] > 0) {
    std::printf(
        "# %s: splint %llu triangles, %u picks, opening %.12f mm in %u steps; per run %.1f ms: "
        "read %.1f ms (%.0f%%), design %.1f ms (%.0f%%), write %.1f ms (%.0f%%)\n",
        name, static_cast<unsigned long long>(triangles), report.outline.picks,
        report.outline.opening, report.outline.opening_steps, 1e3 * stage[3] / runs,
        1e3 * stage[0] / runs, 100 * stage[0] / stage[3], 1e3 * stage[1] / runs,
        100 * stage[1] / stage[3], 1e3 * stage[2] / runs, 100 * stage[2] / stage[3]);
  }
  for (const char* file : {"/maxilla.stl", "/mandible.stl", "/case.json", "/splint.stl"}) {
    std::remove((folder + file).c_str());
  }
  ::rmdir(dir);
}

// Inflate of CT-like 16-bit data (issue 31), MB/s of inflated bytes. inflate_ct16_own: the
// CT phantom (256 x 256 x 32 int16 at 0.5 x 0.5 x 1.5 mm, 4 MiB, noise and streaks) deflated at
// bench time by our own encoder (one fixed-Huffman block); inflate_ct16_zlib6: a zlib stream given
// with
// --inflate-input (tools/bench/make_inflate_input.py writes one: Python's zlib at level 6,
// dynamic Huffman blocks), when given.
void bench_inflate(Harness& h, Arena& arena, const std::string& zlib_file) {
  struct Input {
    const char* name;
    std::vector<uint8_t> compressed;
  };
  std::vector<Input> inputs;
  if (h.wanted("inflate_ct16_own")) {
    cli::CtPhantomOptions po;
    po.nx = 256;
    po.ny = 256;
    po.nz = 32;
    po.spacing = Vec3{0.5, 0.5, 1.5};  // the jaws need 39 mm along z
    cli::CtPhantom phantom;
    CtVolume volume;
    std::vector<int16_t> hu;
    Status s = phantom.init(po);
    if (s.is_ok()) phantom.generate(&hu, &volume);
    std::vector<uint8_t> plain(hu.size() * 2);
    for (size_t i = 0; i < hu.size(); ++i) {  // little-endian bytes, as files hold them
      plain[2 * i] = static_cast<uint8_t>(static_cast<uint16_t>(hu[i]));
      plain[2 * i + 1] = static_cast<uint8_t>(static_cast<uint16_t>(hu[i]) >> 8);
    }
    ArenaScope scope(arena);
    DeflateWorkspace ws;
    if (s.is_ok()) s = deflate_workspace(arena, 65536, &ws);
    Input in{"inflate_ct16_own", {}};
    CompressSink sink;
    sink.user = &in.compressed;
    sink.write = [](void* user, const uint8_t* d, size_t n) {
      auto* v = static_cast<std::vector<uint8_t>*>(user);
      v->insert(v->end(), d, d + n);
      return true;
    };
    if (s.is_ok()) s = deflate_fixed(ws, ZFormat::kZlib, plain.data(), plain.size(), sink);
    if (!s.is_ok()) {
      cli::print_error(s);
      h.failed = true;
      return;
    }
    inputs.push_back(in);
  }
  if (!zlib_file.empty() && h.wanted("inflate_ct16_zlib6")) {
    Input in{"inflate_ct16_zlib6", {}};
    const Status s = cli::read_whole_file(zlib_file, uint64_t{1} << 30, &in.compressed);
    if (!s.is_ok()) {
      cli::print_error(s);
      h.failed = true;
      return;
    }
    inputs.push_back(in);
  }
  for (const Input& in : inputs) {
    std::vector<uint8_t> out(size_t{64} << 20);
    size_t produced = 0;
    const Result r = h.measure(in.name, in.compressed.size(), arena, [&](Arena& a) {
      return inflate_buffer(a, ZFormat::kZlib, in.compressed.data(), in.compressed.size(),
                            out.data(), out.size(), &produced);
    });
    if (r.median > 0) {
      std::printf("# %s: %zu -> %zu bytes, %.1f MB/s of inflated data\n", in.name,
                  in.compressed.size(), produced, static_cast<double>(produced) / r.median / 1e6);
    }
  }
}

// The print job (issue 32): write_3mf of the two phantom jaws (87k triangles each, as two
// objects) into memory, deflated: the 3D model's text, its deflate and the ZIP's CRC-32. MB/s
// of the model's text is printed with the package's size.
void bench_write_3mf(Harness& h, Arena& arena) {
  if (!h.wanted("write_3mf_phantom")) return;
  const Arena::Marker m = arena.mark();
  Mesh jaws[2];
  if (!phantom_jaws(h, arena, m, 87000, jaws)) return;
  ThreeMfObject objects[2];
  for (int j = 0; j < 2; ++j) {
    objects[j].mesh = &jaws[j];
    objects[j].name = j == 0 ? "maxilla" : "mandible";
    objects[j].translation = Vec3{0, 80.0 * j, 0};
  }
  std::vector<uint8_t> out;
  ByteSink sink;
  sink.user = &out;
  sink.write = [](void* user, const uint8_t* d, size_t n) {
    auto* v = static_cast<std::vector<uint8_t>*>(user);
    v->insert(v->end(), d, d + n);
    return true;
  };
  const Result r =
      h.measure("write_3mf_phantom", jaws[0].triangles.size() + jaws[1].triangles.size(), arena,
                [&](Arena& a) {
                  out.clear();
                  return write_3mf(Context(&a), Span<const ThreeMfObject>(objects, 2),
                                   ThreeMfOptions{}, sink);
                });
  if (r.median > 0) {
    std::printf("# write_3mf_phantom: %zu bytes, SHA-256 %s\n", out.size(),
                cli::sha256_hex(out).c_str());
  }
  arena.rewind(m);
}

// One compressed DICOM slice read (issue 31: a 512 x 512 x 300 series should decode in well
// under 3 s), whole read_dicom_series of the file from memory: header, fragments, decoding,
// HU conversion. --dicom-input FILE; e.g. a JPEG-LS slice made with dcmcjpls of a slice of
// `splintcore ct-phantom --format dicom --size 512,512,16 --spacing 0.4,0.4,4`.
void bench_dicom_input(Harness& h, Arena& arena, const std::string& file) {
  if (file.empty() || !h.wanted("dicom_read_slice")) return;
  std::vector<uint8_t> bytes;
  const Status s = cli::read_whole_file(file, uint64_t{1} << 30, &bytes);
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
    return;
  }
  CtMemoryFile one{"slice.dcm", bytes.data(), bytes.size()};
  CtInfo info;
  uint64_t voxels = 0;
  std::vector<uint8_t> hu;  // the last run's HU, hashed: the same figure before and after a change
  const Result r = h.measure("dicom_read_slice", bytes.size(), arena, [&](Arena& a) {
    CtMemoryFiles m{&one, 1, 0, {}};
    Context ctx(&a);
    CtVolume volume;
    const Status st = read_dicom_series(ctx, ct_memory_series(&m), CtReadOptions(), &volume, &info);
    voxels = volume.voxel_count();
    if (st.is_ok()) {
      const uint8_t* v = reinterpret_cast<const uint8_t*>(volume.hu);
      hu.assign(v, v + voxels * sizeof(int16_t));
    }
    return st;
  });
  if (r.median > 0) {
    std::printf(
        "# dicom_read_slice: %s, %llu voxels, %.2f ms a slice, %.1f Mvoxel/s, HU SHA-256 %s\n",
        info.transfer_syntax, static_cast<unsigned long long>(voxels), 1e3 * r.median,
        static_cast<double>(voxels) / r.median / 1e6, cli::sha256_hex(hu).c_str());
  }
}

// The speed proof of issue 31: "a 512 x 512 x 300 JPEG lossless series decoded and
// reconstructed under 3 s on one core". The CT phantom (512 x 512 x 300 at 0.3 mm, noise and
// streak) is written once, untimed, as a JPEG lossless DICOM series (1.2.840.10008.1.2.4.70,
// one file a slice) into a temporary folder; each run is what `splintcore reconstruct FOLDER`
// does before writing: the folder listed and read (files, DICOM parsing, JPEG decoding, HU),
// the HU window thresholded, both jaws grown from their seeds and meshed.
void bench_dicom_jpeg_series(Harness& h, Arena& arena) {
  const char* name = "dicom_jpeg_series_512";
  if (!h.wanted(name)) return;
  char dir[] = "/tmp/splintcore-bench-XXXXXX";
  if (::mkdtemp(dir) == nullptr) {
    std::fprintf(stderr, "splintcore-bench: cannot create a temporary folder\n");
    h.failed = true;
    return;
  }
  const std::string folder = std::string(dir) + "/series";
  cli::CtPhantom phantom;
  Status s = init_phantom_512(&phantom);
  const double t0 = monotonic_seconds();
  uint64_t compressed = 0;
  if (s.is_ok()) {
    std::vector<int16_t> hu;
    CtVolume volume;
    phantom.generate(&hu, &volume);
    cli::CtWriteOptions wo;
    wo.dicom_jpeg_lossless = true;
    s = cli::write_dicom_series(volume, folder, wo);
  }
  std::vector<std::string> files;
  if (s.is_ok()) s = cli::list_dicom_folder(folder, &files);
  if (!s.is_ok()) {
    cli::print_error(s);
    h.failed = true;
  } else {
    for (const std::string& f : files) {
      struct stat st;
      if (::stat(f.c_str(), &st) == 0) compressed += static_cast<uint64_t>(st.st_size);
    }
    std::printf("# %s: %zu files, %llu bytes (%.2f bits a voxel), written in %.1f s (not timed)\n",
                name, files.size(), static_cast<unsigned long long>(compressed),
                8.0 * static_cast<double>(compressed) / (512.0 * 512.0 * 300.0),
                monotonic_seconds() - t0);
    double stage[4] = {0, 0, 0, 0};
    uint64_t triangles[2] = {0, 0};
    const char* syntax = "";
    const Result r = h.measure(name, uint64_t{512} * 512 * 300, arena, [&](Arena& a) {
      const Context ctx(&a);
      double t = monotonic_seconds();
      auto lap = [&](int i) {
        const double now = monotonic_seconds();
        stage[i] = now - t;
        t = now;
      };
      CtVolume volume;
      CtInfo info;
      SPLINTCORE_RETURN_IF_ERROR(cli::read_ct_path(ctx, folder, CtReadOptions{}, &volume, &info));
      syntax = info.transfer_syntax;
      lap(0);
      PhantomJaws jaws;
      SPLINTCORE_RETURN_IF_ERROR(reconstruct_phantom_jaws(ctx, volume, phantom, &jaws, [&](int i) {
        if (i != 2) lap(i == 3 ? 3 : i + 1);  // the two jaws as one stage
      }));
      triangles[0] = jaws.triangles[0];
      triangles[1] = jaws.triangles[1];
      return Status::ok();
    });
    if (r.median > 0) {
      std::printf(
          "# %s: %s; last run: read and decode %.3f s (%.2f ms a slice), threshold %.3f s, "
          "region growing %.3f s, reconstruct %.3f s (maxilla %llu, mandible %llu "
          "triangles); the goal is under 3 s\n",
          name, syntax, stage[0], 1e3 * stage[0] / 300, stage[1], stage[2], stage[3],
          static_cast<unsigned long long>(triangles[0]),
          static_cast<unsigned long long>(triangles[1]));
    }
  }
  for (const std::string& f : files) std::remove(f.c_str());
  ::rmdir(folder.c_str());
  ::rmdir(dir);
}

// The command line's settings.
struct BenchArgs {
  std::string realdata = "../shared/realdata/open-full-jaw-patient26";
  std::string fixtures = "fixtures";
  std::string inflate_input;         // a zlib stream for inflate_ct16_zlib6
  std::string dicom_input;           // a DICOM slice for dicom_read_slice
  const char* export_dir = nullptr;  // --export-realcase
  uint64_t cap = uint64_t{4} << 30;
};

// The arguments into `args` and `h`: -1 to go on, else the exit code (usage or --help).
int parse_bench_args(int argc, char** argv, BenchArgs* args, Harness* h) {
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    uint64_t v = 0;
    if (a == "--filter" && i + 1 < argc) {
      h->filter = argv[++i];
    } else if (a == "--repeat" && i + 1 < argc && cli::parse_unsigned(argv[i + 1], &v) && v > 0) {
      h->repeat = static_cast<int>(v);
      ++i;
    } else if (a == "--realdata" && i + 1 < argc) {
      args->realdata = argv[++i];
    } else if (a == "--fixtures" && i + 1 < argc) {
      args->fixtures = argv[++i];
    } else if (a == "--inflate-input" && i + 1 < argc) {
      args->inflate_input = argv[++i];
    } else if (a == "--dicom-input" && i + 1 < argc) {
      args->dicom_input = argv[++i];
    } else if (a == "--memory-cap" && i + 1 < argc && cli::parse_size(argv[i + 1], &args->cap)) {
      ++i;
    } else if (a == "--threads" && i + 1 < argc && cli::parse_unsigned(argv[i + 1], &v) && v > 0 &&
               v <= ThreadExecutor::kMaxThreads) {
      h->threads = static_cast<unsigned>(v);
      ++i;
    } else if (a == "--export-realcase" && i + 1 < argc) {
      args->export_dir = argv[++i];
      return -1;  // as before: what follows it is not read
    } else {
      std::fprintf(stderr,
                   "usage: splintcore-bench [--filter SUBSTRING] [--repeat N] "
                   "[--realdata DIR] [--fixtures DIR] [--memory-cap SIZE] [--threads N] "
                   "[--inflate-input ZLIB_FILE] [--dicom-input DICOM_FILE]\n"
                   "       splintcore-bench [--realdata DIR] --export-realcase DIR\n");
      return a == "--help" ? 0 : 2;
    }
  }
  return -1;
}

// The real case as a folder `splintcore design` takes (tools/bench/table1.sh).
int export_realcase(const std::string& realdata, const char* dir) {
  realcase::RealCase rc;
  std::string error;
  if (::mkdir(dir, 0777) != 0 && errno != EEXIST) {
    std::fprintf(stderr, "splintcore-bench: cannot create %s: %s\n", dir, std::strerror(errno));
    return 1;
  }
  if (!realcase::load(realdata, 2.0, 1.5, 6.0, &rc, &error) ||
      !realcase::write_case_folder(rc, dir, 0.5, &error)) {
    std::fprintf(stderr, "splintcore-bench: %s\n", error.c_str());
    return 1;
  }
  std::printf("%s/case.json\n", dir);
  return 0;
}

// The real CBCT dentition, all 31 teeth in one soup: read and distance (skipped when absent).
void bench_realdata_soup(Harness& h, Arena& arena, const std::string& realdata) {
  std::vector<uint8_t> all;
  uint32_t count = 0;
  for (int tooth = 1; tooth <= 32; ++tooth) {
    std::string dir = tooth <= 16 ? "/maxilla/" : "/mandible/";
    std::vector<uint8_t> one =
        read_whole(realdata + dir + "tooth_" + std::to_string(tooth) + ".stl");
    if (one.size() < 84) continue;
    if (all.empty()) all.assign(84, 0);
    all.insert(all.end(), one.begin() + 84, one.end());
    count += static_cast<uint32_t>((one.size() - 84) / 50);
  }
  if (all.empty()) {
    std::printf("# realdata not found at %s: skipped\n", realdata.c_str());
    return;
  }
  std::memcpy(all.data() + 80, &count, 4);
  bench_stl(h, arena, "_realdata", all);
  Arena::Marker m = arena.mark();
  Context ctx(&arena);
  Mesh mesh(&arena);
  MemorySource ms{all.data(), all.size(), 0, 0};
  Status s = read_stl_mesh(ctx, memory_source(&ms), StlReadOptions{}, &mesh, nullptr);
  if (s.is_ok()) {
    bench_distance(h, arena, "_realdata", mesh, DistanceIndexOptions{});
    DistanceIndexOptions oriented;
    oriented.oriented_boxes = true;
    bench_distance(h, arena, "_oriented_realdata", mesh, oriented);
  }
  arena.rewind(m);
}

int run(int argc, char** argv) {
  remove_temporary_outputs_on_signals();  // (--export-realcase writes files)
  Harness h;
  BenchArgs args;
  const int early = parse_bench_args(argc, argv, &args, &h);
  if (early >= 0) return early;
  if (args.export_dir != nullptr) return export_realcase(args.realdata, args.export_dir);
  const std::string& realdata = args.realdata;
  const std::string& fixtures = args.fixtures;
  const uint64_t cap = args.cap;
  void* buffer = std::malloc(static_cast<size_t>(cap));
  if (buffer == nullptr) {
    std::fprintf(stderr, "splintcore-bench: cannot reserve %llu bytes\n",
                 static_cast<unsigned long long>(cap));
    return 1;
  }
  {
    ThreadExecutor pool(h.threads);
    if (h.threads > 1) h.executor = &pool.executor();
    Arena arena(buffer, static_cast<size_t>(cap));
    bench_base(h, arena, fixtures);
    bench_boolean_phantom(h, arena, fixtures);
    bench_boolean_realdata(h, arena, realdata);
    bench_distance_sizes(h, arena);
    bench_mesh_pair_distance(h, arena, realdata);
    bench_remesh(h, arena);
    bench_ct_reconstruct(h, arena);
    bench_inflate(h, arena, args.inflate_input);
    bench_dicom_input(h, arena, args.dicom_input);
    bench_dicom_jpeg_series(h, arena);
    bench_write_3mf(h, arena);
    bench_marching_cubes(h, arena);
    bench_sweep(h, arena);
    bench_blockout(h, arena, fixtures);
    bench_outline(h, arena, realdata);
    bench_autorotate(h, arena, realdata);
    bench_design_auto_realdata(h, arena, realdata);
    bench_boolean_manifold_twin(h, arena, realdata);
    // A torus of 2 x 521 x 521 = 542,882 triangles: the size of the paper's largest jaw.
    std::vector<uint8_t> torus = to_binary_stl(shapes::torus(521, 521, 30.0, 8.0));
    bench_stl(h, arena, "", torus);
    bench_stl_phantom(h, arena);
    bench_realdata_soup(h, arena, realdata);
  }
  std::free(buffer);
  return h.failed ? 1 : 0;
}

}  // namespace
}  // namespace splintcore

int main(int argc, char** argv) { return splintcore::run(argc, argv); }
