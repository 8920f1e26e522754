// `splintcore design`: the whole method on a case file, with the report an auditor needs.
#include <sys/stat.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>

#include <cstring>
#include <string>
#include <vector>

#include "../common/ct_files.h"
#include "../common/preview.h"
#include "command.h"
#include "files.h"
#include "splintcore/design.h"
#include "splintcore/io.h"
#include "splintcore/platform.h"
#include "splintcore/printer.h"

namespace splintcore {
namespace tool {

namespace {

struct DesignArgs {
  CommonArgs common;
  bool outline_only = false;     // `splintcore outline`: the resolved case, no design
  const char* output = nullptr;  // OUTDIR, or the resolved case's path (outline_only)
  uint64_t max_input_bytes = 0;  // 0: cli::kMaxCaseBytes for the case, kMaxMeshBytes for jaws
};

// `design`'s options, in the order its --help lists them.
std::vector<OptionSpec> design_options(DesignArgs* a) {
  return {
      a->outline_only ? output_option("RESOLVED.json", &a->output, "the resolved case to write")
                      : output_option("OUTDIR", &a->output, "the folder to write into"),
      size("--max-input-bytes", "SIZE", &a->max_input_bytes,
           "refuse a larger case or jaw file (default 16M, 2G for a jaw)",
           "--max-input-bytes needs a size such as 16M, 2G or 1048576"),
  };
}

// Stage times and peak arena per stage from the progress callback (tools only: the clock).
struct DesignClock {
  Arena* arena = nullptr;
  bool print = false;
  std::vector<std::string> names;
  std::vector<double> seconds;
  std::vector<uint64_t> peaks;
  std::string current;
  double since = 0;
  static bool report(void* user, const char* stage, uint64_t, uint64_t) {
    DesignClock* c = static_cast<DesignClock*>(user);
    if (std::strncmp(stage, "design: ", 8) != 0 || c->current == stage) return true;
    const double now = monotonic_seconds();
    if (!c->current.empty()) {
      c->names.push_back(c->current.substr(8));
      c->seconds.push_back(now - c->since);
      c->peaks.push_back(c->arena->high_water());
      if (c->print) std::fprintf(stderr, " %.3f s\n", now - c->since);
    }
    c->current = stage;
    c->since = now;
    if (c->print && c->current != "design: done") std::fprintf(stderr, "%s...", stage + 8);
    return true;
  }
};

// The memory cap: --memory-cap, else the case's "memory_cap", else the default. The case is
// parsed once in a scratch arena to learn it (the real parse keeps its strings in the run's
// arena, whose size must be known first). Returns where the cap came from.
const char* choose_memory_cap(const std::vector<uint8_t>& case_bytes, const char* case_path,
                              CommonArgs* common) {
  if (common->memory_cap_given) return "command line";
  std::vector<unsigned char> scratch(case_bytes.size() * 8 + (size_t{1} << 20));
  Arena scratch_arena(scratch.data(), scratch.size());
  CaseFile pre;
  if (parse_case(Context(&scratch_arena), reinterpret_cast<const char*>(case_bytes.data()),
                 case_bytes.size(), case_path, &pre)
          .is_ok() &&
      pre.memory_cap != 0) {
    common->memory_cap = pre.memory_cap;
    return "case";
  }
  return "default";
}

// One run of `design`: the stages in order, sharing what they read and make.
class Design {
 public:
  Design(Run& run, const DesignArgs& args, const std::vector<uint8_t>& case_bytes,
         const char* cap_source)
      : run_(run),
        args_(args),
        case_path_(args.common.positional[0]),
        case_bytes_(case_bytes),
        cap_source_(cap_source),
        ctx_(&run.arena, &run.threads.executor(), &progress_) {
    clock_.arena = &run.arena;
    clock_.print = isatty(2) != 0 && !args.common.json;
    progress_.report = &DesignClock::report;
    progress_.user = &clock_;
  }

  int run();

 private:
  Status read_jaws();
  Status reconstruct_ct_jaws();
  Status resolve_outline();
  Status write_resolved_case(const std::string& path);
  void print_outline() const;
  Status write_splint();
  Status write_mesh_file(const Mesh& m, const std::string& path, std::string* hash);
  Status write_plan_stls();
  void write_preview();
  void preview_splint(const Mesh& splint, const DesignReport& report,
                      const std::vector<RigidTransform>& transforms, const std::string& path,
                      cli::PreviewInfo* info, Status* status, char* error, size_t error_size);
  Status write_report();
  int run_plan();
  Status write_plan_job(const std::string& path);
  Status write_splint_job(const std::string& path);
  Status write_plan_report();
  void print_summary() const;
  void print_checks() const;

  Run& run_;
  const DesignArgs& args_;
  const std::string case_path_;
  const std::vector<uint8_t>& case_bytes_;
  const char* cap_source_;
  DesignClock clock_;
  Progress progress_;
  const Context ctx_;  // the run's, with the clock as progress
  CaseFile c_;
  std::string folder_;  // of the case file: jaw paths are relative to it

  // The jaws, as read (their bytes hashed for the report); those from CT, reconstructed.
  std::vector<std::string> jaw_paths_, jaw_hashes_;
  std::vector<Mesh> jaws_;
  // The jaws' intraoral scans ("scan"), as read; an empty mesh for a jaw without one.
  std::vector<std::string> scan_paths_, scan_hashes_;
  std::vector<Mesh> scans_;
  bool any_scan_ = false;
  bool any_ct_ = false;
  CaseCtReport ct_report_;
  CtInfo ct_info_;
  std::string ct_path_, ct_hash_;

  // The automatic outline, when the case asks for it: c_ becomes the resolved case.
  bool outlined_ = false;
  Outline outline_;
  std::string resolved_path_;

  Mesh splint_;
  DesignReport report_;
  std::string splint_path_, report_path_, splint_hash_, report_text_;
  cli::PreviewInfo preview_;
  Status preview_status_;
  char preview_error_[512] = "";
  double t_read_ = 0, t_design_ = 0, t_end_ = 0;
  // The run's files, placed together once the last is written (a failure places none).
  cli::OutputSet outputs_;

  // Two-jaw surgery ("plan"): [0] the intermediate splint, [1] the final one.
  Mesh plan_splints_[2];
  PlanReport plan_report_;
  std::string plan_paths_[2], plan_hashes_[2];
  std::string job_path_, job_sha256_;  // OUTDIR/job.3mf, or the case's "output" "job"
  cli::PreviewInfo plan_previews_[2];
  Status plan_preview_status_[2];
  char plan_preview_errors_[2][512] = {};
};

int Design::run() {
  Status s = parse_case(run_.ctx, reinterpret_cast<const char*>(case_bytes_.data()),
                        case_bytes_.size(), case_path_.c_str(), &c_);
  if (!s.is_ok()) return run_.reject(s);
  const size_t slash = case_path_.find_last_of('/');
  folder_ = slash == std::string::npos ? "" : case_path_.substr(0, slash + 1);
  s = read_jaws();
  if (s.is_ok() && any_ct_) s = reconstruct_ct_jaws();
  if (!s.is_ok()) return run_.reject(s);
  t_read_ = monotonic_seconds();
  if (c_.has_plan) {
    if (args_.outline_only) {
      return run_.reject(Status::error(StatusCode::kInvalidArgument,
                                       "outline: a case with \"plan\" has an outline per splint: "
                                       "design it (report.json gives both)")
                             .in_file(case_path_.c_str()));
    }
    return run_plan();
  }
  if (c_.has_auto_outline) {
    s = resolve_outline();
    if (!s.is_ok()) return run_.reject(s.in_file(case_path_.c_str()));
    if (args_.outline_only) {
      print_outline();
      return kExitOk;
    }
  } else if (args_.outline_only) {
    return run_.reject(Status::error(StatusCode::kInvalidArgument,
                                     "outline: the case gives its picks (no \"auto\" in \"base\")")
                           .in_file(case_path_.c_str()));
  }
  s = design_splint(ctx_, c_, Span<const Mesh>(jaws_.data(), jaws_.size()),
                    Span<const Mesh>(scans_.data(), any_scan_ ? scans_.size() : 0), &splint_,
                    &report_);
  if (clock_.print && !s.is_ok()) std::fprintf(stderr, " failed\n");
  if (!s.is_ok()) return run_.reject(s.in_file(case_path_.c_str()));
  if (outlined_) {
    report_.outlined = true;
    report_.outline = outline_.report;
  }
  t_design_ = monotonic_seconds();
  s = write_splint();
  if (s.is_ok() && c_.output_job != nullptr) {
    s = write_splint_job(std::string(args_.output) + "/" + c_.output_job);
  }
  if (!s.is_ok()) return run_.reject(s);
  write_preview();
  t_end_ = monotonic_seconds();
  s = write_report();
  if (s.is_ok()) s = outputs_.commit();
  if (!s.is_ok()) return run_.reject(s);
  if (args_.common.json) {
    std::printf("%s\n", report_text_.c_str());
  } else {
    print_summary();
  }
  return kExitOk;
}

Status Design::read_jaws() {
  const uint64_t limit = args_.max_input_bytes != 0 ? args_.max_input_bytes : cli::kMaxMeshBytes;
  // Every mesh file of the case, each jaw's scan before the jaw, read in that order (the first
  // bad file is the one named) by read_mesh_files.
  std::vector<const char*> files;
  std::vector<Mesh*> into;
  std::vector<std::string*> hashes;
  for (const CaseJaw& j : c_.jaws) {
    scan_paths_.emplace_back();
    scan_hashes_.emplace_back();
    scans_.emplace_back(&run_.arena);
    jaw_paths_.emplace_back();
    jaw_hashes_.emplace_back();
    jaws_.emplace_back(&run_.arena);
    if (j.has_scan) {  // the scan's mesh, read as a jaw is (welded)
      any_scan_ = true;
      scan_paths_.back() = j.scan.path[0] == '/' ? std::string(j.scan.path) : folder_ + j.scan.path;
    }
    // A jaw with a seed is reconstructed from the case's CT (reconstruct_ct_jaws).
    if (j.has_seed) any_ct_ = true;
    if (!j.has_seed) jaw_paths_.back() = j.mesh[0] == '/' ? std::string(j.mesh) : folder_ + j.mesh;
  }
  for (size_t i = 0; i < c_.jaws.size(); ++i) {
    if (c_.jaws[i].has_scan) {
      files.push_back(scan_paths_[i].c_str());
      into.push_back(&scans_[i]);
      hashes.push_back(&scan_hashes_[i]);
    }
    if (!c_.jaws[i].has_seed) {  // STL, PLY or OBJ (by content), welded as STL is
      files.push_back(jaw_paths_[i].c_str());
      into.push_back(&jaws_[i]);
      hashes.push_back(&jaw_hashes_[i]);
    }
  }
  std::vector<Mesh> meshes;
  std::vector<MeshFileInfo> infos;
  SPLINTCORE_RETURN_IF_ERROR(read_mesh_files(ctx_, files, limit, true, &meshes, &infos));
  for (size_t k = 0; k < files.size(); ++k) {
    *into[k] = meshes[k];
    *hashes[k] = infos[k].sha256;
  }
  return Status::ok();
}

// Jaws from CT: the volume read once, every seed grown in competition, each region meshed.
Status Design::reconstruct_ct_jaws() {
  ct_path_ = c_.ct_volume[0] == '/' ? std::string(c_.ct_volume) : folder_ + c_.ct_volume;
  CtVolume volume;
  SPLINTCORE_RETURN_IF_ERROR(
      cli::read_ct_path(ctx_, ct_path_, CtReadOptions{}, &volume, &ct_info_));
  ct_hash_ = hex_sha256(volume.hu, static_cast<size_t>(volume.voxel_count() * 2));
  SPLINTCORE_RETURN_IF_ERROR(
      reconstruct_case_jaws(ctx_, c_, volume, Span<Mesh>(jaws_.data(), jaws_.size()), &ct_report_));
  for (size_t i = 0; i < c_.jaws.size(); ++i) {
    if (!c_.jaws[i].has_seed) continue;
    jaw_paths_[i] = ct_path_;
    jaw_hashes_[i] = ct_hash_;
  }
  return Status::ok();
}

// The automatic outline: the case resolved (picks, opening, direction), written as a case a
// person can edit and design again (OUTDIR/case.resolved.json, or outline's -o), and designed.
Status Design::resolve_outline() {
  CaseFile resolved;
  SPLINTCORE_RETURN_IF_ERROR(resolve_case_outline(
      ctx_, c_, Span<const Mesh>(jaws_.data(), jaws_.size()), &resolved, &outline_));
  c_ = resolved;
  outlined_ = true;
  resolved_path_ = args_.outline_only ? std::string(args_.output)
                                      : std::string(args_.output) + "/case.resolved.json";
  return write_resolved_case(resolved_path_);
}

// The file names in the resolved case: as the case gives them when it is written into the
// case's own folder, else absolute, so the written case finds the same files.
Status Design::write_resolved_case(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const std::string out_folder = slash == std::string::npos ? "." : path.substr(0, slash);
  const std::string in_folder = folder_.empty() ? "." : folder_;
  char a[PATH_MAX], b[PATH_MAX];
  const bool same = ::realpath(out_folder.c_str(), a) != nullptr &&
                    ::realpath(in_folder.c_str(), b) != nullptr && std::strcmp(a, b) == 0;
  CaseFile written = c_;
  std::vector<CaseJaw> jaws(c_.jaws.begin(), c_.jaws.end());
  std::vector<std::string> names;
  names.reserve(2 * jaws.size() + 1);  // mesh and scan paths: the pointers must stay put
  auto absolute = [&](const char* name) -> const char* {
    if (same || name == nullptr || name[0] == '/') return name;
    char full[PATH_MAX];
    names.push_back(::realpath((folder_ + name).c_str(), full) != nullptr ? full : folder_ + name);
    return names.back().c_str();
  };
  for (CaseJaw& j : jaws) {
    j.mesh = absolute(j.mesh);
    if (j.has_scan) j.scan.path = absolute(j.scan.path);
  }
  written.jaws = Span<const CaseJaw>(jaws.data(), jaws.size());
  written.ct_volume = absolute(c_.ct_volume);
  std::string text;
  SPLINTCORE_RETURN_IF_ERROR(write_case(written, cli::string_sink(&text)));
  // (Alone, --outline writes it now; else it is one of the run's files.)
  return write_bytes_atomically(path, text + "\n", args_.outline_only ? nullptr : &outputs_);
}

void Design::print_outline() const {
  const OutlineReport& o = outline_.report;
  if (args_.common.json) {
    cli::JsonObject j;
    j.add("command", "outline");
    j.add("status", "ok");
    j.add("case", case_path_.c_str());
    j.add("resolved_case", resolved_path_.c_str());
    j.add("occlusal_normal", o.occlusal_normal);
    j.add("gap_as_given_mm", o.gap_as_given);
    j.add("bite_opened", o.opened);
    j.add("mandible_translation_mm", o.mandible_translation);
    j.add("opening_mm", o.opening);
    j.add("picks_per_jaw", static_cast<uint64_t>(o.picks));
    j.add("arch_length_mm", o.arch_length_mm);
    j.add("wafer_min_mm", o.min_wafer_mm);
    j.add("wafer_max_mm", o.max_wafer_mm);
    std::printf("%s\n", j.str().c_str());
    return;
  }
  std::printf("occlusal normal (%.4f, %.4f, %.4f); jaws %.3f mm apart as given%s\n",
              o.occlusal_normal.x, o.occlusal_normal.y, o.occlusal_normal.z, o.gap_as_given,
              o.jaws_intersect ? " (they interpenetrate)" : "");
  if (o.opened) {
    std::printf("bite opened to %.6f mm: mandible moved (%.4f, %.4f, %.4f) mm\n", o.opening,
                o.mandible_translation.x, o.mandible_translation.y, o.mandible_translation.z);
  }
  std::printf("arch %.1f mm, %u picks per jaw, wafer %.2f to %.2f mm thick\n", o.arch_length_mm,
              o.picks, o.min_wafer_mm, o.max_wafer_mm);
  if (o.distal_limited) {
    std::printf("distal ends %.2f and %.2f mm from the arch: cut %.2f and %.2f mm\n",
                o.distal_offset_mm[0], o.distal_offset_mm[1], o.distal_cut_mm[0],
                o.distal_cut_mm[1]);
  }
  std::printf("wrote %s\n", resolved_path_.c_str());
}

namespace {

// A splint's binary STL (the writer's buffer from ctx's arena), streamed to the file and
// hashed as it goes.
Status write_stl_file(const Context& ctx, const Mesh& m, const std::string& path, std::string* hash,
                      cli::OutputSet* outputs) {
  return write_hashed_atomically(
      path, [&](const ByteSink& sink) { return write_stl(ctx, m, sink, StlWriteOptions{}); }, hash,
      outputs);
}

}  // namespace

Status Design::write_mesh_file(const Mesh& m, const std::string& path, std::string* hash) {
  return write_stl_file(ctx_, m, path, hash, &outputs_);
}

// OUTDIR/intermediate.stl and final.stl. With more than one thread, in two tasks, each
// writer's buffer in its own slice of the arena (given back after): the same bytes, about 20
// ms less on the real case (issue 32). A failure is the intermediate's first, as in the
// serial order; neither is placed then (outputs_).
Status Design::write_plan_stls() {
  Arena& arena = *ctx_.arena;
  ArenaScope scope(arena);
  const size_t slice = StlWriteOptions{}.buffer_bytes + 2 * Arena::kDefaultAlignment;
  auto* base =
      has_threads(ctx_.executor) ? static_cast<unsigned char*>(arena.allocate(2 * slice)) : nullptr;
  if (base == nullptr) {  // one thread, or no room: one after the other with the run's arena
    arena.forget_failure();
    for (int k = 0; k < 2; ++k) {
      SPLINTCORE_RETURN_IF_ERROR(
          write_mesh_file(plan_splints_[k], plan_paths_[k], &plan_hashes_[k]));
    }
    return Status::ok();
  }
  Arena slices[2] = {Arena(base, slice), Arena(base + slice, slice)};
  Status status[2];
  auto task = [&](uint32_t k) {
    status[k] = write_stl_file(Context(&slices[k]), plan_splints_[k], plan_paths_[k],
                               &plan_hashes_[k], &outputs_);
  };
  parallel_for_each(ctx_.executor, 2, task);
  return status[0].is_ok() ? status[1] : status[0];
}

Status Design::write_splint() {
  const std::string out_dir = args_.output;
  splint_path_ = out_dir + "/" + (c_.output_splint != nullptr ? c_.output_splint : "splint.stl");
  report_path_ = out_dir + "/" + (c_.output_report != nullptr ? c_.output_report : "report.json");
  return write_mesh_file(splint_, splint_path_, &splint_hash_);
}

// OUTDIR/preview.png: the splint on the jaws as the plan (and a tray placement) moved them;
// for an auto case, the outline's picks and arch over them (cli::PreviewMarks).
// Not fatal: the splint is written; a preview that fails (e.g. a tight --memory-cap) is a
// warning and the report says why.
void Design::write_preview() {
  std::vector<const Mesh*> preview_jaws;
  std::vector<RigidTransform> preview_moves;
  for (size_t i = 0; i < jaws_.size(); ++i) {
    if (i < DesignReport::kMaxFusedJaws && report_.fused[i]) {  // the registered scan
      preview_jaws.push_back(&scans_[i]);
      preview_moves.push_back(report_.fusion[i].applied);  // the tray's move included
      continue;
    }
    preview_jaws.push_back(&jaws_[i]);
    // On the tray the whole case moved by tray_translation before the design: the jaws
    // follow it, so the preview shows the fit where the splint is.
    preview_moves.push_back(
        report_.placed_on_tray
            ? compose(RigidTransform::translation(report_.tray_translation), c_.jaws[i].transform)
            : c_.jaws[i].transform);
  }
  // An auto case: its picks and arch drawn over the splint and the jaws.
  cli::PreviewMarks marks;
  marks.upper = outline_.upper;
  marks.lower = outline_.lower;
  marks.arch = outline_.arch;
  if (report_.placed_on_tray) marks.move = RigidTransform::translation(report_.tray_translation);
  preview_status_ = cli::write_preview(ctx_, splint_, preview_jaws, preview_moves,
                                       std::string(args_.output) + "/preview.png", 1024, 1024,
                                       &preview_, outlined_ ? &marks : nullptr, &outputs_);
  if (!preview_status_.is_ok()) {
    preview_status_.format(preview_error_, sizeof(preview_error_));
    std::fprintf(stderr, "splintcore: warning: no preview: %s\n",
                 cli::printable(preview_error_).c_str());
  }
}

// report.json: the library's report (the C API writes the same bytes), this run's part last.
Status Design::write_report() {
  std::vector<const char*> path_list, hash_list;
  for (size_t i = 0; i < jaw_paths_.size(); ++i) {
    path_list.push_back(jaw_paths_[i].c_str());
    hash_list.push_back(jaw_hashes_[i].c_str());
  }
  DesignReportFiles files;
  files.case_path = case_path_.c_str();
  files.jaw_paths = Span<const char* const>(path_list.data(), path_list.size());
  files.jaw_sha256 = Span<const char* const>(hash_list.data(), hash_list.size());
  std::vector<const char*> scan_list, scan_hash_list;
  for (size_t i = 0; i < scan_paths_.size(); ++i) {
    const bool has = c_.jaws[i].has_scan;
    scan_list.push_back(has ? scan_paths_[i].c_str() : nullptr);
    scan_hash_list.push_back(has ? scan_hashes_[i].c_str() : nullptr);
  }
  files.scan_paths = Span<const char* const>(scan_list.data(), scan_list.size());
  files.scan_sha256 = Span<const char* const>(scan_hash_list.data(), scan_hash_list.size());
  if (any_ct_) {
    files.ct_path = ct_path_.c_str();
    files.ct_size[0] = ct_info_.nx;
    files.ct_size[1] = ct_info_.ny;
    files.ct_size[2] = ct_info_.nz;
    files.ct = &ct_report_;
  }
  files.splint_path = splint_path_.c_str();
  if (outlined_) files.resolved_case_path = resolved_path_.c_str();
  files.splint_sha256 = splint_hash_.c_str();  // of the bytes just written
  if (!job_path_.empty()) {
    files.print_job_path = job_path_.c_str();
    files.print_job_sha256 = job_sha256_.c_str();
  }
  if (preview_status_.is_ok()) {
    files.preview_path = preview_.path.c_str();
    files.preview_sha256 = preview_.sha256.c_str();
  } else {
    files.preview_error = preview_error_;
  }
  std::vector<DesignStageTime> stage_times;
  for (size_t i = 0; i < clock_.names.size(); ++i) {
    stage_times.push_back(
        DesignStageTime{clock_.names[i].c_str(), clock_.seconds[i], clock_.peaks[i]});
  }
  const double t0 = run_.start;
  DesignRunInfo run_info;
  run_info.memory_cap_bytes = args_.common.memory_cap;
  run_info.memory_cap_from = cap_source_;
  run_info.threads = static_cast<uint32_t>(args_.common.threads);
  run_info.stages = Span<const DesignStageTime>(stage_times.data(), stage_times.size());
  run_info.read_seconds = t_read_ - t0;
  run_info.design_seconds = t_design_ - t_read_;
  run_info.preview_seconds =
      preview_status_.is_ok() ? preview_.render_seconds + preview_.encode_seconds : 0;
  run_info.total_seconds = t_end_ - t0;
  run_info.peak_arena_bytes = run_.peak_arena();
  SPLINTCORE_RETURN_IF_ERROR(
      write_design_report(ctx_, c_, Span<const Mesh>(jaws_.data(), jaws_.size()), splint_, report_,
                          files, &run_info, cli::string_sink(&report_text_)));
  return write_bytes_atomically(report_path_, report_text_ + "\n", &outputs_);
}

// A line for each jaw that crosses the base's side walls (none when no jaw does); `splint`
// ("intermediate: ", "final: " or "") starts it.
void print_side_walls(const char* splint, const CaseFile& c, const DesignReport& report) {
  for (uint32_t i = 0; i < report.wall_jaws; ++i) {
    const WallCrossing& w = report.walls[i];
    if (w.crossed == 0) continue;
    std::printf(
        "%sside walls (%s): crossed along %.1f of %.1f mm of the arch (%.0f%%; outer %.1f, "
        "inner %.1f mm; sideways %.1f mm, %.0f%%), first at (%.2f, %.2f, %.2f): the imprint "
        "opens through the splint's side there\n",
        splint, c.jaws[i].role, w.either_mm, w.arch_mm, 100 * w.share(), w.outer_mm, w.inner_mm,
        w.sideways_mm(), 100 * w.sideways_share(), w.first_at.x, w.first_at.y, w.first_at.z);
  }
}

// Two-jaw surgery: both splints (design_plan), OUTDIR/intermediate.stl and final.stl, a
// preview of each (intermediate.png, final.png: not fatal) and one report.json for both.
int Design::run_plan() {
  Status s = design_plan(ctx_, c_, Span<const Mesh>(jaws_.data(), jaws_.size()),
                         Span<const Mesh>(scans_.data(), any_scan_ ? scans_.size() : 0),
                         &plan_splints_[0], &plan_splints_[1], &plan_report_);
  if (clock_.print && !s.is_ok()) std::fprintf(stderr, " failed\n");
  if (!s.is_ok()) return run_.reject(s.in_file(case_path_.c_str()));
  t_design_ = monotonic_seconds();
  const std::string out_dir = args_.output;
  static const char* const kNames[2] = {"intermediate", "final"};
  const PlanSplintReport* parts[2] = {&plan_report_.intermediate, &plan_report_.final_splint};
  for (int k = 0; k < 2; ++k) plan_paths_[k] = out_dir + "/" + kNames[k] + ".stl";
  s = write_plan_stls();
  if (!s.is_ok()) return run_.reject(s);
  s = write_plan_job(out_dir + "/" + (c_.output_job != nullptr ? c_.output_job : "job.3mf"));
  if (!s.is_ok()) return run_.reject(s);
  for (int k = 0; k < 2; ++k) {
    std::vector<RigidTransform> moves;
    for (const CaseJaw& j : c_.jaws) {
      moves.push_back(std::strcmp(j.role, "maxilla") == 0 ? parts[k]->maxilla : parts[k]->mandible);
    }
    preview_splint(plan_splints_[k], parts[k]->design, moves, out_dir + "/" + kNames[k] + ".png",
                   &plan_previews_[k], &plan_preview_status_[k], plan_preview_errors_[k],
                   sizeof(plan_preview_errors_[k]));
  }
  t_end_ = monotonic_seconds();
  report_path_ = out_dir + "/" + (c_.output_report != nullptr ? c_.output_report : "report.json");
  s = write_plan_report();
  if (s.is_ok()) s = outputs_.commit();
  if (!s.is_ok()) return run_.reject(s);
  if (args_.common.json) {
    std::printf("%s\n", report_text_.c_str());
    return kExitOk;
  }
  const DesignReport& fused = parts[0]->design;  // the fusion, made once for both splints
  for (size_t i = 0; i < c_.jaws.size() && i < DesignReport::kMaxFusedJaws; ++i) {
    if (!fused.fused[i]) continue;
    const RegisterResult& f = fused.fusion[i].registration;
    std::printf("fusion (%s): scan %s registered, RMS %.4f mm, overlap %.3f, %u iterations\n",
                c_.jaws[i].role, scan_paths_[i].c_str(), f.rms_mm, f.overlap, f.iterations);
  }
  for (int k = 0; k < 2; ++k) {
    const PlanSplintReport& r = *parts[k];
    std::printf(
        "%s: mandible turned %.9f rad (%.6f deg) about the hinge axis to %.6f mm; "
        "%zu triangles, %.3f mm^3; wrote %s (sha256 %s)\n",
        kNames[k], r.autorotation.angle_rad, r.angle_deg, r.autorotation.opening,
        plan_splints_[k].triangles.size(), r.design.print.mesh.volume, plan_paths_[k].c_str(),
        plan_hashes_[k].c_str());
    const std::string prefix = std::string(kNames[k]) + ": ";
    print_side_walls(prefix.c_str(), c_, r.design);
  }
  std::printf(
      "wrote %s (both on the tray, %.0f mm apart) and %s; time: design %.3f s, total %.3f s; peak "
      "arena %llu bytes\n",
      job_path_.c_str(), kPlanJobGapMm, report_path_.c_str(), t_design_ - t_read_,
      t_end_ - run_.start, static_cast<unsigned long long>(run_.peak_arena()));
  return kExitOk;
}

// OUTDIR/job.3mf: both splints on the printer's tray, 5 mm apart (write_plan_job, design.h),
// with the SHA-256 of each splint's STL as written.
Status Design::write_plan_job(const std::string& path) {
  const char* hashes[2] = {plan_hashes_[0].c_str(), plan_hashes_[1].c_str()};
  SPLINTCORE_RETURN_IF_ERROR(write_hashed_atomically(
      path,
      [&](const ByteSink& sink) {
        return splintcore::write_plan_job(ctx_, c_, plan_splints_[0], plan_splints_[1], hashes,
                                          sink, nullptr);
      },
      &job_sha256_, &outputs_));
  job_path_ = path;
  return Status::ok();
}

// OUTDIR/NAME ("output": {"job": NAME}): the splint on the printer's tray as a 3MF
// (write_splint_job, design.h), with the SHA-256 of its STL as written.
Status Design::write_splint_job(const std::string& path) {
  SPLINTCORE_RETURN_IF_ERROR(write_hashed_atomically(
      path,
      [&](const ByteSink& sink) {
        return splintcore::write_splint_job(ctx_, c_, splint_, splint_hash_.c_str(), sink, nullptr);
      },
      &job_sha256_, &outputs_));
  job_path_ = path;
  return Status::ok();
}

// A preview of one splint on the jaws moved by `transforms` (and the tray's move); a failure is
// a warning, kept for the report.
void Design::preview_splint(const Mesh& splint, const DesignReport& report,
                            const std::vector<RigidTransform>& transforms, const std::string& path,
                            cli::PreviewInfo* info, Status* status, char* error,
                            size_t error_size) {
  std::vector<const Mesh*> preview_jaws;
  std::vector<RigidTransform> moves;
  for (size_t i = 0; i < jaws_.size(); ++i) {
    if (i < DesignReport::kMaxFusedJaws && report.fused[i]) {  // the registered scan
      preview_jaws.push_back(&scans_[i]);
      moves.push_back(report.fusion[i].applied);  // the tray's move included
      continue;
    }
    preview_jaws.push_back(&jaws_[i]);
    moves.push_back(
        report.placed_on_tray
            ? compose(RigidTransform::translation(report.tray_translation), transforms[i])
            : transforms[i]);
  }
  *status = cli::write_preview(ctx_, splint, preview_jaws, moves, path, 1024, 1024, info, nullptr,
                               &outputs_);
  if (!status->is_ok()) {
    status->format(error, error_size);
    std::fprintf(stderr, "splintcore: warning: no preview: %s\n", cli::printable(error).c_str());
  }
}

Status Design::write_plan_report() {
  std::vector<const char*> path_list, hash_list;
  for (size_t i = 0; i < jaw_paths_.size(); ++i) {
    path_list.push_back(jaw_paths_[i].c_str());
    hash_list.push_back(jaw_hashes_[i].c_str());
  }
  std::vector<const char*> scan_list, scan_hash_list;
  for (size_t i = 0; i < scan_paths_.size(); ++i) {
    const bool has = c_.jaws[i].has_scan;
    scan_list.push_back(has ? scan_paths_[i].c_str() : nullptr);
    scan_hash_list.push_back(has ? scan_hashes_[i].c_str() : nullptr);
  }
  DesignReportFiles files[2];
  for (int k = 0; k < 2; ++k) {
    files[k].case_path = case_path_.c_str();
    files[k].jaw_paths = Span<const char* const>(path_list.data(), path_list.size());
    files[k].jaw_sha256 = Span<const char* const>(hash_list.data(), hash_list.size());
    files[k].scan_paths = Span<const char* const>(scan_list.data(), scan_list.size());
    files[k].scan_sha256 = Span<const char* const>(scan_hash_list.data(), scan_hash_list.size());
    if (any_ct_) {
      files[k].ct_path = ct_path_.c_str();
      files[k].ct_size[0] = ct_info_.nx;
      files[k].ct_size[1] = ct_info_.ny;
      files[k].ct_size[2] = ct_info_.nz;
      files[k].ct = &ct_report_;
    }
    files[k].splint_path = plan_paths_[k].c_str();
    files[k].splint_sha256 = plan_hashes_[k].c_str();
    if (k == 0 && !job_path_.empty()) {
      files[k].print_job_path = job_path_.c_str();
      files[k].print_job_sha256 = job_sha256_.c_str();
    }
    if (plan_preview_status_[k].is_ok()) {
      files[k].preview_path = plan_previews_[k].path.c_str();
      files[k].preview_sha256 = plan_previews_[k].sha256.c_str();
    } else {
      files[k].preview_error = plan_preview_errors_[k];
    }
  }
  std::vector<DesignStageTime> stage_times;
  for (size_t i = 0; i < clock_.names.size(); ++i) {
    stage_times.push_back(
        DesignStageTime{clock_.names[i].c_str(), clock_.seconds[i], clock_.peaks[i]});
  }
  DesignRunInfo run_info;
  run_info.memory_cap_bytes = args_.common.memory_cap;
  run_info.memory_cap_from = cap_source_;
  run_info.threads = static_cast<uint32_t>(args_.common.threads);
  run_info.stages = Span<const DesignStageTime>(stage_times.data(), stage_times.size());
  run_info.read_seconds = t_read_ - run_.start;
  run_info.design_seconds = t_design_ - t_read_;
  for (int k = 0; k < 2; ++k) {
    if (plan_preview_status_[k].is_ok()) {
      run_info.preview_seconds +=
          plan_previews_[k].render_seconds + plan_previews_[k].encode_seconds;
    }
  }
  run_info.total_seconds = t_end_ - run_.start;
  run_info.peak_arena_bytes = run_.peak_arena();
  SPLINTCORE_RETURN_IF_ERROR(splintcore::write_plan_report(
      ctx_, c_, Span<const Mesh>(jaws_.data(), jaws_.size()), plan_splints_[0], plan_splints_[1],
      plan_report_, files, &run_info, cli::string_sink(&report_text_)));
  return write_bytes_atomically(report_path_, report_text_ + "\n", &outputs_);
}

// The summary's lines of the label and the checks (side walls, thickness, crumbs).
void Design::print_checks() const {
  const DesignReport& report = report_;
  if (report.labelled) {
    std::printf("label: \"%s\" %s, %u glyphs, %.1f mm long\n", report.label.text,
                c_.label.mode == LabelMode::kEmboss ? "embossed" : "engraved", report.label.glyphs,
                report.label.text_length_mm);
  }
  print_side_walls("", c_, report);
  if (report.thickness_checked) {
    const ThicknessReport& t = report.thickness;
    if (t.thin_triangles == 0) {
      std::printf("thickness: no wall thinner than %.3g mm\n", t.min_required);
    } else {
      std::printf(
          "thickness: %llu triangles (%.3f mm^2) thinner than %.3g mm; thinnest "
          "%.3f mm at (%.2f, %.2f, %.2f); %u spot(s) in report.json\n",
          static_cast<unsigned long long>(t.thin_triangles), t.thin_area_mm2, t.min_required,
          t.thinnest, t.spots[0].position.x, t.spots[0].position.y, t.spots[0].position.z,
          t.spot_count);
    }
  }
  if (report.crumbs.removed > 0) {
    std::printf(
        "crumbs: %llu separate shell(s) of %.3g mm^3 in all taken out (under the printer's "
        "thinnest wall cubed)\n",
        static_cast<unsigned long long>(report.crumbs.removed), report.crumbs.volume_mm3);
  }
}

void Design::print_summary() const {
  const DesignReport& report = report_;
  std::printf("case %s (%s): %zu jaw(s), %llu triangles; base %u sections, %zu + %zu picks\n",
              case_path_.c_str(), c_.case_id, jaws_.size(),
              static_cast<unsigned long long>(report.jaw_triangles), report.base.sections,
              c_.upper.size(), c_.lower.size());
  for (size_t i = 0; i < c_.jaws.size() && i < DesignReport::kMaxFusedJaws; ++i) {
    if (!report.fused[i]) continue;
    const RegisterResult& f = report.fusion[i].registration;
    std::printf("fusion (%s): scan %s registered, RMS %.4f mm, overlap %.3f, %u iterations\n",
                c_.jaws[i].role, scan_paths_[i].c_str(), f.rms_mm, f.overlap, f.iterations);
  }
  if (report.imprint_offset) {
    std::printf("imprint: a %.3g mm clearance around each jaw's swept volume\n",
                c_.blockout.offset);
  } else if (report.imprint_swept) {
    const uint32_t exact = exact_blockout_jaws(report);
    if (exact == report.blockout_jaws) {
      std::printf("imprint: each jaw's exact swept volume (its front triangles and walls)\n");
    } else {  // "auto" fell back to the height field for some jaws
      std::printf(
          "imprint: %u jaw(s) by their exact swept volume, %u by the height field of theirs\n",
          exact, report.blockout_jaws - exact);
    }
  } else if (report.imprint_heightfield) {
    std::printf("imprint: the height field of each jaw's swept volume\n");
  } else {
    std::printf("boolean: %llu crossing pairs, %llu intersection points, %u attempt(s)\n",
                static_cast<unsigned long long>(report.boolean.intersecting_pairs),
                static_cast<unsigned long long>(report.boolean.intersection_points),
                report.boolean.attempts);
  }
  if (report.blockout_fallback[0] != '\0') {
    std::printf("blockout: with the height field where the exact sweep was refused: %s\n",
                report.blockout_fallback);
  }
  for (uint32_t i = 0; i < report.blockout_jaws; ++i) {
    if (!report.blockout_exact[i]) {  // the height field lowers where the voxels inset
      const bool field = report.imprint_heightfield || report.blockout_heightfield[i];
      std::printf(
          "blockout (%s%s): %.4f mm^3 of interference removed, %llu swept triangles, %s %.3g "
          "mm\n",
          c_.jaws[i].role, field ? ", height field" : "", report.blockout_removed_mm3[i],
          static_cast<unsigned long long>(report.blockout[i].swept_triangles),
          field ? "lowered" : "inset", report.blockout[i].inset_used);
      continue;
    }
    const ExactSweepStats& e = report.blockout[i].exact;
    std::printf(
        "blockout (%s, exact): %llu of %llu front triangles kept, %llu walls, %llu fold "
        "vertices, %llu swept triangles\n",
        c_.jaws[i].role, static_cast<unsigned long long>(e.kept_triangles),
        static_cast<unsigned long long>(e.front_triangles),
        static_cast<unsigned long long>(e.walls), static_cast<unsigned long long>(e.fold_vertices),
        static_cast<unsigned long long>(report.blockout[i].swept_triangles));
  }
  print_checks();
  std::printf(
      "splint: %zu triangles, %.3f mm^3, closed, manifold, no self-intersection; "
      "printable on %s (%s%s)\n",
      splint_.triangles.size(), report.print.mesh.volume, report.printer,
      report.print.fits ? "fits the tray" : "fits turned 90 degrees",
      report.placed_on_tray ? ", placed on the tray" : "");
  std::printf("wrote %s (sha256 %s) and %s\n", splint_path_.c_str(), splint_hash_.c_str(),
              report_path_.c_str());
  if (!job_path_.empty()) {
    std::printf("wrote %s (the splint on the tray, sha256 %s)\n", job_path_.c_str(),
                job_sha256_.c_str());
  }
  if (preview_status_.is_ok()) std::printf("preview: %s\n", preview_.path.c_str());
  std::printf("time: read %.3f s, design %.3f s, total %.3f s; peak arena %llu bytes\n",
              t_read_ - run_.start, t_design_ - t_read_, t_end_ - run_.start,
              static_cast<unsigned long long>(run_.peak_arena()));
}

// `design` and `outline` (outline_only) share the reading and the resolving.
int run_design_or_outline(const Command& command, int argc, char** argv, bool outline_only) {
  DesignArgs a;
  a.outline_only = outline_only;
  CommandLine line(command, &a.common, design_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.size() != 1) return line.usage_error("takes one case file");
  if (a.output == nullptr) {
    return line.usage_error(outline_only ? "outline needs -o RESOLVED.json"
                                         : "design needs -o OUTDIR");
  }
  const char* case_path = a.common.positional[0];
  std::vector<uint8_t> case_bytes;
  const Status s = read_whole_input(
      case_path, a.max_input_bytes != 0 ? a.max_input_bytes : cli::kMaxCaseBytes, &case_bytes);
  if (!s.is_ok()) return rejected(a.common, command.name, s, nullptr);
  const char* cap_source = choose_memory_cap(case_bytes, case_path, &a.common);
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();
  if (!outline_only) ::mkdir(a.output, 0777);  // an existing folder is fine
  Design design(run, a, case_bytes, cap_source);
  return design.run();
}

}  // namespace

int run_design(const Command& command, int argc, char** argv) {
  return run_design_or_outline(command, argc, argv, false);
}

int run_outline(const Command& command, int argc, char** argv) {
  return run_design_or_outline(command, argc, argv, true);
}

}  // namespace tool
}  // namespace splintcore
