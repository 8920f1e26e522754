// CT (issue 7): the skull phantom (ct-phantom) and the jaws reconstructed from a CT volume
// (reconstruct).
#include <sys/stat.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "../common/ct_files.h"
#include "../common/ct_phantom.h"
#include "../common/ct_write.h"
#include "command.h"
#include "files.h"
#include "splintcore/remesh.h"
#include "splintcore/segment.h"

namespace splintcore {
namespace tool {

namespace {

// "A,B,C" of unsigned integers.
bool parse_u32_triple(const char* text, uint32_t* out) {
  const char* p = text;
  for (int a = 0; a < 3; ++a) {
    const char* end = p;
    while (*end != '\0' && *end != ',') ++end;
    uint32_t value = 0;
    auto r = std::from_chars(p, end, value);
    if (r.ec != std::errc() || r.ptr != end) return false;
    out[a] = value;
    if (a < 2) {
      if (*end != ',') return false;
      p = end + 1;
    } else if (*end != '\0') {
      return false;
    }
  }
  return true;
}

// "PX,PY,PZ,NX,NY,NZ": a point and a normal pointing towards the maxilla.
bool parse_split_plane(const char* value, SplitPlane* plane) {
  const std::string text = value;
  size_t cut = std::string::npos, commas = 0;
  for (size_t n = 0; n < text.size(); ++n) {
    if (text[n] == ',' && ++commas == 3) cut = n;
  }
  if (cut == std::string::npos || !parse_point(text.substr(0, cut).c_str(), &plane->point) ||
      !parse_point(text.substr(cut + 1).c_str(), &plane->normal)) {
    return false;
  }
  plane->label_positive = 1;  // the normal points towards the maxilla
  plane->label_negative = 2;
  return true;
}

// ---- ct-phantom -------------------------------------------------------------------------------

struct CtPhantomArgs {
  CommonArgs common;
  const char* output = nullptr;
  int format = -1;  // kCtFormats
  uint32_t size[3] = {160, 160, 100};
  Vec3 spacing{0.5, 0.5, 0.5};
  double noise = 20.0;
  bool streak = true;
  uint64_t seed = 1;
};

// `ct-phantom`'s options, in the order its --help lists them.
std::vector<OptionSpec> ct_phantom_options(CtPhantomArgs* a) {
  return {
      output_option("PATH", &a->output, "the file (nrrd, mha) or folder (dicom) to write"),
      choice("--format", "dicom|nrrd|mha", &a->format, "the file format",
             "--format takes dicom, nrrd or mha"),
      custom<uint32_t, parse_u32_triple>("--size", "NX,NY,NZ", a->size,
                                         "voxels per axis (default 160,160,100)",
                                         "--size needs NX,NY,NZ"),
      point("--spacing", "SX,SY,SZ", &a->spacing, "voxel spacing, mm (default 0.5,0.5,0.5)",
            "--spacing needs SX,SY,SZ (mm)"),
      real("--noise", "HU", &a->noise, "the noise's standard deviation (default 20)",
           "--noise needs HU"),
      clear_flag("--no-streak", &a->streak, "no metal-artefact streak"),
      count("--seed", "N", &a->seed, 0, UINT64_MAX, "the noise's seed (default 1)",
            "--seed needs a number"),
  };
}

constexpr const char* kCtFormats[] = {"dicom", "nrrd", "mha"};

Status write_ct_volume(const CtVolume& volume, const CtPhantomArgs& a) {
  cli::CtWriteOptions wo;
  if (a.format == 0) return cli::write_dicom_series(volume, a.output, wo);
  if (a.format == 1) return cli::write_nrrd(volume, a.output, wo);
  return cli::write_metaimage(volume, a.output, wo);
}

void print_ct_phantom_report(const CtPhantomArgs& a, const cli::CtPhantom& phantom,
                             const CtVolume& volume, const std::string& voxels_sha, double t0,
                             double t_generate) {
  const char* format = kCtFormats[a.format];
  if (a.common.json) {
    JsonObject j;
    j.add("command", "ct-phantom");
    j.add_status(Status::ok());
    j.add("format", format);
    j.add("path", a.output);
    j.add_raw("size", "[" + std::to_string(volume.nx) + "," + std::to_string(volume.ny) + "," +
                          std::to_string(volume.nz) + "]");
    j.add("spacing", volume.spacing);
    j.add("origin", volume.origin);
    j.add("noise_hu", a.noise);
    j.add("streak", a.streak);
    j.add("seed", a.seed);
    j.add("seed_maxilla", phantom.seed_maxilla());
    j.add("seed_mandible", phantom.seed_mandible());
    j.add("voxels_sha256", voxels_sha);
    j.add("generate_s", t_generate);
    j.add("time_s", monotonic_seconds() - t0);
    print_json(j);
    return;
  }
  const Vec3 p = phantom.seed_maxilla(), q = phantom.seed_mandible();
  std::printf(
      "%s: %u x %u x %u voxels (%s), voxels sha256 %s\n"
      "seeds: --seed-maxilla %s,%s,%s --seed-mandible %s,%s,%s\n",
      a.output, volume.nx, volume.ny, volume.nz, format, voxels_sha.c_str(),
      cli::json_number(p.x).c_str(), cli::json_number(p.y).c_str(), cli::json_number(p.z).c_str(),
      cli::json_number(q.x).c_str(), cli::json_number(q.y).c_str(), cli::json_number(q.z).c_str());
}

// ---- reconstruct ------------------------------------------------------------------------------

struct ReconstructArgs {
  CommonArgs common;
  const char* output = nullptr;
  Vec3 seeds[2];
  bool has_seed[2] = {false, false};
  int32_t hu_min = 300, hu_max = 4000;
  int connectivity = 0;  // 6|26
  SplitPlane plane;
  bool has_plane = false;
  bool keep_double = false;
  uint64_t smooth = 0;    // Taubin iterations (0: none)
  uint64_t decimate = 0;  // target triangles per jaw (0: none)
};

// `reconstruct`'s options, in the order its --help lists them.
std::vector<OptionSpec> reconstruct_options(ReconstructArgs* a) {
  const char* hu_error = "--hu-min and --hu-max need an integer HU (-32768..32767)";
  const char* seed_error = "a seed needs X,Y,Z (mm)";
  return {
      output_option("OUTDIR", &a->output, "the folder to write into"),
      point("--seed-maxilla", "X,Y,Z", &a->seeds[0], "a point in the maxilla, patient mm",
            seed_error)
          .marks(&a->has_seed[0]),
      point("--seed-mandible", "X,Y,Z", &a->seeds[1], "a point in the mandible, patient mm",
            seed_error)
          .marks(&a->has_seed[1]),
      int16("--hu-min", "HU", &a->hu_min, "the window's lower bound (default 300)", hu_error),
      int16("--hu-max", "HU", &a->hu_max, "the window's upper bound (default 4000)", hu_error),
      choice("--connectivity", "6|26", &a->connectivity, "voxel neighbours (default 6)",
             "--connectivity takes 6 or 26"),
      custom<SplitPlane, parse_split_plane>(
          "--split-plane", "PX,PY,PZ,NX,NY,NZ", &a->plane,
          "the maxilla on the normal's side, the mandible on the other",
          "--split-plane needs PX,PY,PZ,NX,NY,NZ (a point and a normal, mm)")
          .marks(&a->has_plane),
      flag("--keep-double", &a->keep_double, "do not round the vertices to float32"),
      count("--smooth", "N", &a->smooth, 0, 1000, "Taubin iterations (default 0: none)",
            "--smooth needs a number of Taubin iterations (0..1000)"),
      count("--decimate", "T", &a->decimate, 4, UINT64_MAX,
            "at most T triangles per jaw (default: no decimation)",
            "--decimate needs a target triangle count per jaw (at least 4)"),
  };
}

std::string reconstruct_usage_problem(const ReconstructArgs& a) {
  if (a.common.positional.size() != 1) {
    return "reconstruct takes one volume (file or DICOM folder)";
  }
  if (a.output == nullptr) return "reconstruct needs -o OUTDIR";
  if (!a.has_seed[0] || !a.has_seed[1]) {
    return "reconstruct needs --seed-maxilla and --seed-mandible";
  }
  if (a.hu_min > a.hu_max) return "--hu-min is above --hu-max";
  return "";
}

// One run of `reconstruct`: the volume segmented once, then each jaw meshed and written.
class Reconstruct {
 public:
  Reconstruct(Run& run, const ReconstructArgs& args) : run_(run), a_(args) {}
  int run();

 private:
  static constexpr const char* kNames[2] = {"maxilla", "mandible"};

  void stage(const char* name);
  Status segment();
  Status mesh_jaw(int jaw);
  Status remesh(int jaw, Mesh* mesh, TaubinStats* smoothed, DecimateStats* decimated);
  void add_jaw_row(int jaw, const std::string& path, const Mesh& mesh, double volume_mm3,
                   const ReconstructStats& st, const TaubinStats& smoothed,
                   const DecimateStats& decimated);
  void print_report() const;

  Run& run_;
  const ReconstructArgs& a_;
  std::vector<std::pair<std::string, double>> stages_;
  double since_ = monotonic_seconds();
  CtVolume volume_;
  CtInfo info_;
  LabelVolume labels_;
  ThresholdStats ts_;
  RegionStats rs_;
  std::string rows_, warnings_;
  std::function<void()> jaw_lines_[2];  // the summary's lines, printed once the files are placed
  cli::OutputSet outputs_;              // both jaws placed together
};

void Reconstruct::stage(const char* name) {
  const double now = monotonic_seconds();
  stages_.emplace_back(name, now - since_);
  since_ = now;
}

int Reconstruct::run() {
  Status s = segment();
  if (!s.is_ok()) return run_.reject(s);
  ::mkdir(a_.output, 0777);  // an existing folder is fine; a failure shows when writing
  for (int jaw = 0; jaw < 2; ++jaw) {
    ArenaScope scope(run_.arena);  // one jaw's mesh at a time
    s = mesh_jaw(jaw);
    if (!s.is_ok()) return run_.reject(s);
  }
  s = outputs_.commit();
  if (!s.is_ok()) return run_.reject(s);
  print_report();
  return kExitOk;
}

// The volume read, the HU window marked, both jaws grown from their seeds in competition.
Status Reconstruct::segment() {
  const Context& ctx = run_.ctx;
  SPLINTCORE_RETURN_IF_ERROR(
      cli::read_ct_path(ctx, a_.common.positional[0], CtReadOptions{}, &volume_, &info_));
  stage("read");
  SPLINTCORE_RETURN_IF_ERROR(
      threshold_window(ctx, volume_, HuWindow{a_.hu_min, a_.hu_max}, &labels_, &ts_));
  stage("threshold");
  RegionSeed seeds[2];
  for (int jaw = 0; jaw < 2; ++jaw) {
    seeds[jaw].label = static_cast<uint8_t>(jaw + 1);
    seeds[jaw].patient_mm = a_.seeds[jaw];
  }
  RegionGrowOptions go;
  go.connectivity = a_.connectivity == 1 ? Connectivity::k26 : Connectivity::k6;
  go.plane = a_.has_plane ? &a_.plane : nullptr;
  SPLINTCORE_RETURN_IF_ERROR(
      grow_regions(ctx, volume_, Span<const RegionSeed>(seeds, 2), go, &labels_, &rs_));
  stage("region growing");
  return Status::ok();
}

// Smoothing (Taubin) then decimation (quadric error), as asked: both keep the mesh closed and
// outward; the check after them still says so of what is written.
Status Reconstruct::remesh(int jaw, Mesh* mesh, TaubinStats* smoothed, DecimateStats* decimated) {
  const Context& ctx = run_.ctx;
  if (a_.smooth > 0) {
    TaubinOptions to;
    to.iterations = static_cast<uint32_t>(a_.smooth);
    const Vec3& h = volume_.spacing;
    to.max_displacement = 0.5 * std::fmin(h.x, std::fmin(h.y, h.z));
    SPLINTCORE_RETURN_IF_ERROR(taubin_smooth(ctx, mesh, to, smoothed));
    stage(jaw == 0 ? "smooth maxilla" : "smooth mandible");
  }
  if (a_.decimate > 0 && mesh->triangles.size() > a_.decimate) {
    Mesh fewer(&run_.arena);
    DecimateOptions dopt;
    dopt.target_triangles = a_.decimate;
    SPLINTCORE_RETURN_IF_ERROR(decimate_qem(ctx, *mesh, dopt, &fewer, decimated));
    *mesh = fewer;
    stage(jaw == 0 ? "decimate maxilla" : "decimate mandible");
  }
  if ((a_.smooth > 0 || a_.decimate > 0) && !a_.keep_double) {
    for (Vec3& p : mesh->vertices) {
      if (!round_to_float32(&p)) {
        return make_error(StatusCode::kLimitExceeded, "a vertex is beyond float32");
      }
    }
  }
  return Status::ok();
}

// One jaw: its region meshed, remeshed as asked, checked and written.
Status Reconstruct::mesh_jaw(int jaw) {
  const Context& ctx = run_.ctx;
  Mesh mesh(&run_.arena);
  ReconstructOptions ro;
  ro.label = static_cast<uint8_t>(jaw + 1);
  ro.hu_lo = a_.hu_min;
  ro.round_to_float32 = !a_.keep_double;
  ReconstructStats st;
  SPLINTCORE_RETURN_IF_ERROR(reconstruct_region(ctx, volume_, labels_, ro, &mesh, &st));
  stage(jaw == 0 ? "reconstruct maxilla" : "reconstruct mandible");
  TaubinStats smoothed;
  DecimateStats decimated;
  SPLINTCORE_RETURN_IF_ERROR(remesh(jaw, &mesh, &smoothed, &decimated));
  double volume_mm3 = 0;
  SPLINTCORE_RETURN_IF_ERROR(check_closed_oriented(ctx, mesh, &volume_mm3));
  const std::string path = std::string(a_.output) + "/" + kNames[jaw] + ".stl";
  Status s = write_mesh_atomically(ctx, mesh, path.c_str(), false, &outputs_);
  if (!s.is_ok()) return s.in_file(path.c_str());
  stage(jaw == 0 ? "write maxilla" : "write mandible");
  if (rs_.touches_border[ro.label]) {
    warnings_ += std::string(warnings_.empty() ? "" : ",") + "\"" + kNames[jaw] +
                 " touches the volume's border: it may continue beyond the scan\"";
    std::fprintf(stderr, "splintcore: warning: the %s touches the volume's border\n", kNames[jaw]);
  }
  add_jaw_row(jaw, path, mesh, volume_mm3, st, smoothed, decimated);
  const uint64_t voxels = rs_.voxels[ro.label];
  const size_t triangles = mesh.triangles.size();
  jaw_lines_[jaw] = [=] {
    std::printf("%s: %s, %llu voxels, %zu triangles, %.1f mm^3\n", kNames[jaw], path.c_str(),
                static_cast<unsigned long long>(voxels), triangles, volume_mm3);
  };
  return Status::ok();
}

void Reconstruct::add_jaw_row(int jaw, const std::string& path, const Mesh& mesh, double volume_mm3,
                              const ReconstructStats& st, const TaubinStats& smoothed,
                              const DecimateStats& decimated) {
  const uint8_t l = static_cast<uint8_t>(jaw + 1);
  JsonObject r;
  r.add("jaw", kNames[jaw]);
  r.add("file", path);
  r.add("voxels", rs_.voxels[l]);
  r.add("meets_other_region", rs_.meets_other_region[l]);
  r.add("touches_border", rs_.touches_border[l]);
  r.add_raw("box_voxels", "[" + std::to_string(st.box_lo[0]) + "," + std::to_string(st.box_lo[1]) +
                              "," + std::to_string(st.box_lo[2]) + "," +
                              std::to_string(st.box_hi[0]) + "," + std::to_string(st.box_hi[1]) +
                              "," + std::to_string(st.box_hi[2]) + "]");
  r.add("vertices", static_cast<uint64_t>(mesh.vertices.size()));
  r.add("triangles", static_cast<uint64_t>(mesh.triangles.size()));
  r.add("volume_mm3", volume_mm3);
  r.add("layers_per_tile", st.marching.layers_per_tile);
  if (a_.smooth > 0) {
    r.add("smooth_iterations", a_.smooth);
    r.add("smooth_volume_change_mm3", smoothed.volume_after - smoothed.volume_before);
  }
  if (a_.decimate > 0) {
    r.add("decimated_from_triangles", decimated.input_triangles);
    r.add("decimate_max_error_mm", decimated.max_error);
  }
  rows_ += (jaw > 0 ? "," : "") + r.str();
}

void Reconstruct::print_report() const {
  if (!a_.common.json) {
    for (const std::function<void()>& print : jaw_lines_) print();
    if (info_.resampled) {
      std::printf(
          "resampled onto a regular grid: %u slices -> %u, gantry tilt %.2f deg, largest "
          "in-plane correction %.3f mm, largest slice correction %.3f mm\n",
          info_.slice_count, volume_.nz, info_.tilt_degrees, info_.max_shift_mm,
          info_.max_slice_offset_mm);
    }
    std::printf("window voxels %llu, unclaimed %llu; %.3f s, peak arena %llu bytes\n",
                static_cast<unsigned long long>(ts_.in_window),
                static_cast<unsigned long long>(rs_.unclaimed), monotonic_seconds() - run_.start,
                static_cast<unsigned long long>(run_.peak_arena()));
    return;
  }
  JsonObject j;
  j.add("command", "reconstruct");
  j.add_status(Status::ok());
  j.add("input", a_.common.positional[0]);
  j.add("format", ct_format_name(info_.format));
  j.add_raw("size", "[" + std::to_string(volume_.nx) + "," + std::to_string(volume_.ny) + "," +
                        std::to_string(volume_.nz) + "]");
  j.add("spacing", volume_.spacing);
  // Geometry as scanners write it: a DICOM stack put on a regular grid, and by how much.
  JsonObject g;
  g.add("resampled", info_.resampled);
  g.add("input_slices", static_cast<uint64_t>(info_.slice_count));
  g.add("tilt_deg", info_.tilt_degrees);
  g.add("max_inplane_correction_mm", info_.max_shift_mm);
  g.add("max_slice_correction_mm", info_.max_slice_offset_mm);
  j.add_raw("geometry", g.str());
  j.add("hu_min", static_cast<int64_t>(a_.hu_min));
  j.add("hu_max", static_cast<int64_t>(a_.hu_max));
  j.add("connectivity", static_cast<uint64_t>(a_.connectivity == 1 ? 26 : 6));
  j.add("split_plane", a_.has_plane);
  j.add("window_voxels", ts_.in_window);
  j.add("unclaimed_voxels", rs_.unclaimed);
  j.add("growth_layers", static_cast<uint64_t>(rs_.layers));
  j.add_raw("jaws", "[" + rows_ + "]");
  j.add_raw("warnings", "[" + warnings_ + "]");
  std::string times;
  for (const auto& st : stages_) {
    times += (times.empty() ? "" : ",") + std::string("\"") + st.first +
             "\":" + cli::json_number(st.second);
  }
  j.add_raw("stage_s", "{" + times + "}");
  j.add("time_s", monotonic_seconds() - run_.start);
  j.add("peak_arena_bytes", run_.peak_arena());
  j.add("memory_cap_bytes", a_.common.memory_cap);
  print_json(j);
}

}  // namespace

int run_ct_phantom(const Command& command, int argc, char** argv) {
  CtPhantomArgs a;
  CommandLine line(command, &a.common, ct_phantom_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (!a.common.positional.empty()) return line.usage_error("ct-phantom takes no input");
  if (a.output == nullptr) return line.usage_error("ct-phantom needs -o PATH");
  if (a.format < 0) return line.usage_error("ct-phantom needs --format");
  const double t0 = monotonic_seconds();
  cli::CtPhantomOptions po;
  po.nx = a.size[0];
  po.ny = a.size[1];
  po.nz = a.size[2];
  po.spacing = a.spacing;
  po.noise_hu = a.noise;
  po.streak = a.streak;
  po.seed = a.seed;
  cli::CtPhantom phantom;
  Status s = phantom.init(po);
  if (!s.is_ok()) return rejected(a.common, command.name, s, nullptr);
  std::vector<int16_t> hu;
  CtVolume volume;
  phantom.generate(&hu, &volume);
  const double t_generate = monotonic_seconds() - t0;
  s = write_ct_volume(volume, a);
  if (!s.is_ok()) return rejected(a.common, command.name, s, nullptr);
  const std::string voxels_sha = hex_sha256(hu.data(), hu.size() * sizeof(int16_t));
  print_ct_phantom_report(a, phantom, volume, voxels_sha, t0, t_generate);
  return kExitOk;
}

int run_reconstruct(const Command& command, int argc, char** argv) {
  ReconstructArgs a;
  CommandLine line(command, &a.common, reconstruct_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  const std::string problem = reconstruct_usage_problem(a);
  if (!problem.empty()) return line.usage_error(problem);
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();
  Reconstruct reconstruct(run, a);
  return reconstruct.run();
}

}  // namespace tool
}  // namespace splintcore
