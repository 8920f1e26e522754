// `register` (issue 30, scan-CT fusion): an intraoral scan placed rigidly onto a jaw
// reconstructed from CT (register_rigid, registration.h); the transform, RMS, overlap and
// iterations written as JSON, atomically; optionally the moved scan as STL.
#include <cctype>
#include <charconv>
#include <string>
#include <vector>

#include "command.h"
#include "files.h"
#include "options.h"
#include "splintcore/json.h"
#include "splintcore/registration.h"

namespace splintcore {
namespace tool {

namespace {

// "x y z x y z; x y z x y z; ...": the scan point then the CT point of each pair (spaces or
// commas between the numbers). False when a pair does not have six finite numbers.
bool parse_landmarks(const char* text, std::vector<LandmarkPair>* out) {
  out->clear();
  const std::string all(text);
  size_t from = 0;
  while (from <= all.size()) {
    size_t end = all.find(';', from);
    if (end == std::string::npos) end = all.size();
    std::vector<double> numbers;
    size_t at = from;
    while (at < end) {
      if (std::isspace(static_cast<unsigned char>(all[at])) != 0 || all[at] == ',') {
        ++at;
        continue;
      }
      double v = 0;
      const auto r = std::from_chars(all.data() + at, all.data() + end, v);
      if (r.ec != std::errc() || !is_finite(v)) return false;
      numbers.push_back(v);
      at = static_cast<size_t>(r.ptr - all.data());
    }
    if (numbers.size() == 6) {
      out->push_back(LandmarkPair{Vec3{numbers[0], numbers[1], numbers[2]},
                                  Vec3{numbers[3], numbers[4], numbers[5]}});
    } else if (!numbers.empty() || end < all.size()) {
      return false;  // a pair without six numbers (an empty one only after the last ';')
    }
    from = end + 1;
  }
  return !out->empty();
}

struct RegisterArgs {
  CommonArgs common;
  const char* output = nullptr;
  const char* moved = nullptr;
  std::vector<LandmarkPair> landmarks;
  RegisterOptions options;
};

// `register`'s options, in the order its --help lists them.
std::vector<OptionSpec> register_options(RegisterArgs* a) {
  return {
      output_option("OUT.json", &a->output, "the transform, RMS, overlap and iterations (JSON)"),
      custom<std::vector<LandmarkPair>, parse_landmarks>(
          "--landmarks", "\"X Y Z X Y Z; ...\"", &a->landmarks,
          "landmark pairs, scan point then CT point (mm), 3 or more",
          "--landmarks needs pairs of six numbers (scan X Y Z, CT X Y Z) separated by ';'"),
      positive("--overlap", "F", &a->options.overlap,
               "the fraction of scan samples fitted (default 0.6; at most 1)",
               "--overlap needs a fraction in (0, 1]"),
      positive("--max-rms", "MM", &a->options.max_rms_mm,
               "a fit with a larger RMS is rejected (default 0.3)",
               "--max-rms needs a number of mm > 0"),
      text("--moved", "MOVED.stl", &a->moved, "write the scan moved onto the CT (STL)",
           "--moved needs a file name"),
      direction("--toward", "X,Y,Z", &a->options.toward_other_jaw,
                "the direction from the CT jaw to the other jaw: the scan's occlusal side must "
                "face it (an upside-down fit is passed over or refused)",
                "--toward needs a direction X,Y,Z (three finite numbers, not all 0)"),
  };
}

std::string result_json(const RegisterArgs& a, const RegisterResult& r, const Status& status) {
  std::string out;
  JsonWriter w(cli::string_sink(&out));
  w.begin_object();
  w.add("command", "register");
  w.add("scan", a.common.positional[0]);
  w.add("ct_jaw", a.common.positional[1]);
  w.add("status", status_code_name(status.code()));
  w.begin_array("transform");  // row-major 4x4, scan -> CT
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) w.add(nullptr, r.transform.r[i][j]);
    w.add(nullptr, r.transform.t[i]);
  }
  for (double v : {0.0, 0.0, 0.0, 1.0}) w.add(nullptr, v);
  w.end_array();
  w.add("rms_mm", r.rms_mm);
  w.add("overlap", r.overlap);
  w.add("inlier_mm", a.options.inlier_mm);
  w.add("iterations", r.iterations);
  w.add("converged", r.converged);
  w.add("samples", r.samples);
  w.add("kept", r.kept);
  w.add("facing", r.facing);
  if (length(a.options.toward_other_jaw) > 0) w.add("occlusal_cos", r.occlusal_cos);
  w.add("overlap_asked", a.options.overlap);
  w.add("max_rms_mm", a.options.max_rms_mm);
  w.add("landmarks", static_cast<uint64_t>(a.landmarks.size()));
  if (!a.landmarks.empty()) {
    w.add("landmark_rms_mm", r.landmark_rms_mm);
  } else {
    static const char* const kStarts[] = {"as given", "turned -10", "turned -5", "turned 5",
                                          "turned 10"};
    w.add("start", r.start >= 0 && r.start < 5 ? kStarts[r.start] : "principal axes");
  }
  w.end_object();
  (void)w.finish();  // a string sink does not fail
  return out + "\n";
}

void print_register(const Run& run, const RegisterArgs& a, const RegisterResult& r,
                    const std::string& json) {
  const double seconds = monotonic_seconds() - run.start;
  if (a.common.json) {
    std::printf("%s", json.c_str());
    return;
  }
  std::printf("scan: %s\nct jaw: %s\n", a.common.positional[0], a.common.positional[1]);
  std::printf("RMS: %.6f mm over the best %u of %u samples; overlap %.4f within %.3g mm\n",
              r.rms_mm, r.kept, r.samples, r.overlap, a.options.inlier_mm);
  std::printf("iterations: %u (%s)\n", r.iterations, r.converged ? "converged" : "not converged");
  std::printf("facing the CT: %.4f of the matched area", r.facing);
  if (r.occlusal_cos != 0) {  // --toward, and a scan with an occlusal side to go by
    std::printf("; occlusal side towards the other jaw: cosine %.4f", r.occlusal_cos);
  }
  std::printf("\n");
  if (!a.landmarks.empty()) std::printf("landmarks: RMS %.6f mm\n", r.landmark_rms_mm);
  std::printf("transform (row-major 4x4, scan -> CT):\n");
  for (int i = 0; i < 3; ++i) {
    std::printf("  %.17g %.17g %.17g %.17g\n", r.transform.r[i][0], r.transform.r[i][1],
                r.transform.r[i][2], r.transform.t[i]);
  }
  std::printf("  0 0 0 1\noutput: %s\n", a.output);
  if (a.moved != nullptr) std::printf("moved scan: %s\n", a.moved);
  run.print_time(seconds);
}

}  // namespace

int run_register(const Command& command, int argc, char** argv) {
  RegisterArgs a;
  CommandLine line(command, &a.common, register_options(&a));
  const int early = line.parse(argc, argv);
  if (early >= 0) return early;
  if (a.common.positional.size() != 2) {
    return line.usage_error("register takes two mesh files: SCAN CT_JAW");
  }
  if (a.output == nullptr) return line.usage_error("register needs -o OUT.json");
  if (a.options.overlap > 1) return line.usage_error("--overlap needs a fraction in (0, 1]");
  Run run(command, a.common);
  if (!run.has_memory()) return run.no_memory();
  if (a.moved != nullptr) {
    if (const Status out = check_mesh_output(a.moved, false); !out.is_ok()) return run.reject(out);
  }
  Mesh meshes[2] = {Mesh(&run.arena), Mesh(&run.arena)};
  for (size_t j = 0; j < 2; ++j) {
    const Status s =
        read_mesh_file(run.ctx, a.common.positional[j], kNoInputLimit, false, &meshes[j], nullptr);
    if (!s.is_ok()) return run.reject(s);
  }
  a.options.landmarks = Span<const LandmarkPair>(a.landmarks.data(), a.landmarks.size());
  RegisterResult r;
  Status s = register_rigid(run.ctx, meshes[0], meshes[1], a.options, &r);
  if (!s.is_ok()) return run.reject(s);  // a fit over --max-rms too: nothing is written
  const std::string json = result_json(a, r, s);
  cli::OutputSet outputs;  // the result and the moved scan placed together
  s = write_bytes_atomically(a.output, json, &outputs);
  if (s.is_ok() && a.moved != nullptr) {
    for (Vec3& v : meshes[0].vertices) v = r.transform.apply_point(v);
    s = write_mesh_atomically(run.ctx, meshes[0], a.moved, false, &outputs);
  }
  if (s.is_ok()) s = outputs.commit();
  if (!s.is_ok()) return run.reject(s);
  print_register(run, a, r, json);
  return kExitOk;
}

}  // namespace tool
}  // namespace splintcore
