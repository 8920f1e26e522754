#include "command.h"

#include <cstdlib>
#include <cstring>
#include <thread>

namespace splintcore {
namespace tool {

std::vector<OptionSpec> common_options(CommonArgs* a) {
  return {
      flag("--help", &a->help, "this text for the command").or_as("-h"),
      flag("--json", &a->json, "one JSON object on stdout with every figure"),
      memory_cap("--memory-cap", &a->memory_cap, "arena cap, e.g. 64M or 2G (default 1G)",
                 "--memory-cap needs a size such as 64M, 2G or 1048576")
          .marks(&a->memory_cap_given),
      count("--threads", "N", &a->threads, 1, 64,
            "worker threads (default 1; results are identical for any N)",
            "--threads needs a number from 1 to 64"),
  };
}

namespace {
// An output's name: not empty, and not "-", which would name a file "-" where the standard
// output is meant (that carries the command's summary; /dev/stdout is written as a stream).
bool parse_output_name(const char* value, const char** out) {
  if (value[0] == '\0' || std::strcmp(value, "-") == 0) return false;
  *out = value;
  return true;
}
}  // namespace

OptionSpec output_option(const char* value_name, const char** target, const char* help) {
  return custom<const char*, parse_output_name>(
             "-o", value_name, target, help,
             "-o needs a file name (not \"-\": the summary goes to the standard output)")
      .or_as("--output");
}

CommandLine::CommandLine(const Command& command, CommonArgs* common, std::vector<OptionSpec> own)
    : command_(command), common_(common), specs_(std::move(own)) {
  for (const OptionSpec& s : common_options(common)) specs_.push_back(s);
}

int CommandLine::parse(int argc, char** argv) {
  std::string error;
  if (!parse_options(specs_, argc, argv, &common_->positional, &error)) return usage_error(error);
  if (common_->help) {
    print_help(stdout);
    return kExitOk;
  }
  return -1;
}

int CommandLine::usage_error(const std::string& message) const {
  std::fprintf(stderr, "splintcore: %s\n\n", message.c_str());
  print_help(stderr);
  return kExitUsage;
}

void CommandLine::print_help(std::FILE* out) const {
  std::fputs(command_.usage, out);
  std::fputs("\noptions:\n", out);
  print_options(out, specs_);
}

RunMemory::RunMemory(uint64_t cap) : buffer(acquire_arena_memory(cap)), bytes(cap) {}

RunMemory::~RunMemory() { release_arena_memory(buffer, bytes); }

int rejected(const CommonArgs& args, const char* command, const Status& s, const Arena* arena) {
  cli::print_error(s);
  if (args.json) {
    JsonObject j;
    j.add("command", command);
    j.add_status(s);
    if (arena != nullptr) j.add("peak_arena_bytes", static_cast<uint64_t>(arena->high_water()));
    print_json(j);
  }
  return kExitRejected;
}

// How far ahead of the arena's furthest point ArenaToucher keeps the memory touched. The real
// dentition's Boolean reaches 15 MiB of its 23 MiB peak while it reads its files (its first
// 40 ms). At --threads 2, 4 MiB was as fast as 8, 16 and 32 (12 and 16 rounds, alternated) and
// 2 MiB slower; what is touched beyond the peak is the thread's time lost, beside the
// self-intersection check's two threads.
constexpr size_t kTouchAhead = size_t{4} << 20;

// The toucher runs whenever there is a second core to run it, whatever --threads says: it
// computes nothing (the bytes are the same at any N) and takes the first touch of the arena's
// pages off the run's own thread. The real dentition's Boolean at --threads 1, whole process
// by its own clock (median of 16, alternated, 2026-12-05): 198.5 ms without it, 165.9 ms with
// it; pinned to one core (taskset -c 0) 198.0 and 199.3 ms: nothing lost where no second core
// is free. The paper-scale phantom's design: 408 -> 380 ms. The 543k check: within noise (its
// large arrays are touched as they are reserved, so the run waits for the toucher anyway).
namespace {
size_t touched_bytes(const CommonArgs& a) {
  const bool second_core = a.threads >= 2 || std::thread::hardware_concurrency() >= 2;
  return second_core ? static_cast<size_t>(a.memory_cap) : 0;
}
}  // namespace

Run::Run(const Command& c, const CommonArgs& a)
    : command(c.name),
      args(a),
      memory(a.memory_cap),
      toucher(memory.buffer, touched_bytes(a), kTouchAhead),
      arena(memory.buffer, memory.buffer != nullptr ? static_cast<size_t>(a.memory_cap) : 0),
      threads(static_cast<unsigned>(a.threads)),
      ctx(&arena, &threads.executor(), nullptr),
      start(monotonic_seconds()) {
  // The arena's pages prefaulted a few MiB at a time, as it first reaches them; where the
  // machine has a second core, touched ahead of it on a thread of their own (ArenaToucher).
  arena.set_touch_hook(toucher.hook());
}

int Run::no_memory() const {
  return rejected(args, command,
                  make_error(StatusCode::kArenaExhausted, "cannot reserve the memory cap of ",
                             args.memory_cap, " bytes"),
                  nullptr);
}

void Run::print_time(double seconds) const {
  std::printf("time: %.3f s, peak arena: %llu bytes\n", seconds,
              static_cast<unsigned long long>(peak_arena()));
}

void add_mesh_report(JsonObject* j, const MeshReport& r) {
  // An open mesh (a scan) has no volume, genus or outward side: those are null for it.
  const bool closed = r.closed();
  j->add("vertices", r.vertex_count);
  j->add("triangles", r.triangle_count);
  j->add("edges", r.edge_count);
  j->add("boundary_edges", r.boundary_edges);
  j->add("boundary_loops", r.boundary_loops);
  j->add("nonmanifold_edges", r.nonmanifold_edges);
  j->add("orientation_conflicts", r.orientation_conflicts);
  j->add("degenerate_triangles", r.degenerate_triangles);
  j->add("duplicate_triangles", r.duplicate_triangles);
  j->add("unreferenced_vertices", r.unreferenced_vertices);
  j->add("shells", r.shells);
  j->add("euler_characteristic", r.euler_characteristic);
  if (closed) {
    j->add("genus", r.genus);
  } else {
    j->add_raw("genus", "null");
  }
  j->add("closed", closed);
  j->add("edge_manifold", r.edge_manifold());
  j->add("oriented", r.oriented());
  if (closed) {
    j->add("outward", r.outward());
  } else {
    j->add_raw("outward", "null");
  }
  j->add("area_mm2", r.area);
  if (closed) {
    j->add("volume_mm3", r.volume);
  } else {
    j->add_raw("volume_mm3", "null");
  }
  j->add("bounds_min_mm", r.bounds.lo);
  j->add("bounds_max_mm", r.bounds.hi);
}

void print_mesh_report(const MeshReport& r) {
  const bool closed = r.closed();
  char genus[32] = "n/a (open)";
  if (closed) std::snprintf(genus, sizeof genus, "%lld", static_cast<long long>(r.genus));
  std::printf("mesh: %llu vertices, %llu triangles, %llu edges, %llu shell(s), genus %s\n",
              static_cast<unsigned long long>(r.vertex_count),
              static_cast<unsigned long long>(r.triangle_count),
              static_cast<unsigned long long>(r.edge_count),
              static_cast<unsigned long long>(r.shells), genus);
  if (closed) {
    std::printf("closed: yes (0 boundary edges)\n");
  } else {
    std::printf("closed: no (%llu boundary edges in %llu loop%s)\n",
                static_cast<unsigned long long>(r.boundary_edges),
                static_cast<unsigned long long>(r.boundary_loops),
                r.boundary_loops == 1 ? "" : "s");
  }
  std::printf("edge-manifold: %s (%llu edges with 3+ triangles)\n",
              r.edge_manifold() ? "yes" : "no",
              static_cast<unsigned long long>(r.nonmanifold_edges));
  std::printf("consistently oriented: %s (%llu conflicting edges)\n", r.oriented() ? "yes" : "no",
              static_cast<unsigned long long>(r.orientation_conflicts));
  std::printf("outward: %s\n", closed ? (r.outward() ? "yes" : "no") : "n/a (open)");
  std::printf("degenerate triangles: %llu, duplicate triangles: %llu\n",
              static_cast<unsigned long long>(r.degenerate_triangles),
              static_cast<unsigned long long>(r.duplicate_triangles));
  if (closed) {
    std::printf("area: %.6f mm^2, volume: %.6f mm^3\n", r.area, r.volume);
  } else {
    std::printf("area: %.6f mm^2, volume: n/a (open)\n", r.area);
  }
  std::printf("bounds: [%.6f, %.6f, %.6f] - [%.6f, %.6f, %.6f] mm\n", r.bounds.lo.x, r.bounds.lo.y,
              r.bounds.lo.z, r.bounds.hi.x, r.bounds.hi.y, r.bounds.hi.z);
}

std::string hex_sha256(const void* data, size_t size) {
  Sha256 sha;
  sha.update(data, size);
  uint8_t digest[32];
  sha.finish(digest);
  char hex[65];
  Sha256::to_hex(digest, hex);
  return hex;
}

void print_json(const JsonObject& j) { std::printf("%s\n", j.str().c_str()); }

}  // namespace tool
}  // namespace splintcore
