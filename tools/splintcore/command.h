// What every command of the splintcore program shares: its entry in the command table, the
// options every command takes, its command line (parsed by the one option parser, options.h),
// the arena and threads it runs with, and how it reports a rejected input.
#ifndef SPLINTCORE_TOOLS_SPLINTCORE_COMMAND_H
#define SPLINTCORE_TOOLS_SPLINTCORE_COMMAND_H

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "../common/cli.h"
#include "options.h"
#include "splintcore/core.h"
#include "splintcore/mesh.h"
#include "splintcore/platform.h"

namespace splintcore {
namespace tool {

using cli::JsonObject;
using cli::kExitOk;
using cli::kExitRejected;
using cli::kExitUsage;

// One entry of the command table (kCommands, main.cpp).
struct Command {
  const char* name;
  int (*run)(const Command& command, int argc, char** argv);
  const char* usage;    // its --help text, starting "usage: splintcore NAME"; the options follow
  const char* summary;  // one line for `splintcore --help`
};

// The commands (each in the file of its stage of the method).
int run_check(const Command& command, int argc, char** argv);
int run_convert(const Command& command, int argc, char** argv);
int run_prepare(const Command& command, int argc, char** argv);
int run_distance(const Command& command, int argc, char** argv);
int run_autorotate(const Command& command, int argc, char** argv);
int run_register(const Command& command, int argc, char** argv);
int run_compare(const Command& command, int argc, char** argv);
int run_render(const Command& command, int argc, char** argv);
int run_base(const Command& command, int argc, char** argv);
int run_boolean(const Command& command, int argc, char** argv);
int run_phantom(const Command& command, int argc, char** argv);
int run_design(const Command& command, int argc, char** argv);
int run_outline(const Command& command, int argc, char** argv);
int run_sweep(const Command& command, int argc, char** argv);
int run_blockout(const Command& command, int argc, char** argv);
int run_ct_phantom(const Command& command, int argc, char** argv);
int run_reconstruct(const Command& command, int argc, char** argv);

constexpr uint64_t kDefaultMemoryCap = uint64_t{1} << 30;

// The options every command takes (common_options), and the arguments that are not options.
struct CommonArgs {
  bool help = false;
  bool json = false;
  uint64_t memory_cap = kDefaultMemoryCap;
  bool memory_cap_given = false;  // --memory-cap on the command line (it overrides a case's)
  uint64_t threads = 1;
  std::vector<const char*> positional;
};

std::vector<OptionSpec> common_options(CommonArgs* args);

// -o FILE (also --output FILE): where a command writes; `value_name` says what ("OUT.stl").
OptionSpec output_option(const char* value_name, const char** target, const char* help);

// A command's command line: its own option table, then the common options.
class CommandLine {
 public:
  CommandLine(const Command& command, CommonArgs* common, std::vector<OptionSpec> own);

  // Returns -1 to go on, else the exit code: 0 after printing --help, 2 after a usage error.
  int parse(int argc, char** argv);
  // Prints "splintcore: MESSAGE" and the command's help to stderr; returns 2.
  int usage_error(const std::string& message) const;
  // The command's usage text, then its options.
  void print_help(std::FILE* out) const;

 private:
  const Command& command_;
  CommonArgs* common_;
  std::vector<OptionSpec> specs_;
};

// The arena for a run: one block of the cap (acquire_arena_memory, platform.h), committed by
// the OS only as it is touched; Run's arena prefaults it a few MiB ahead of its high water
// (arena_prefault_hook), so what a run commits is its peak arena and at most a step more. Its 2 MiB
// alignment covers Arena::kDefaultAlignment (malloc gives only 8 on 32-bit ARM, which would shift
// the arena's padding and its reported figures).
struct RunMemory {
  void* buffer = nullptr;
  uint64_t bytes = 0;
  explicit RunMemory(uint64_t cap);
  ~RunMemory();
  RunMemory(const RunMemory&) = delete;
  RunMemory& operator=(const RunMemory&) = delete;
};

// Reports a failed run (JSON on stdout when asked, the message on stderr) and returns 1.
int rejected(const CommonArgs& args, const char* command, const Status& s, const Arena* arena);

// What a command runs with: the arena, the thread pool, the context, the start time.
struct Run {
  const char* command;
  const CommonArgs& args;
  RunMemory memory;
  ArenaToucher toucher;  // where the machine has a second core (see touched_bytes)
  Arena arena;
  ThreadExecutor threads;
  Context ctx;
  double start;

  Run(const Command& command, const CommonArgs& args);
  bool has_memory() const { return memory.buffer != nullptr; }
  // The memory cap could not be reserved: rejected, exit 1.
  int no_memory() const;
  // rejected() with this run's command and arena.
  int reject(const Status& s) const { return rejected(args, command, s, &arena); }
  uint64_t peak_arena() const { return arena.high_water(); }
  // The summary's last line: "time: <seconds> s, peak arena: <bytes> bytes".
  void print_time(double seconds) const;
};

// A mesh check's figures, as JSON fields and as the human summary's lines.
void add_mesh_report(JsonObject* j, const MeshReport& r);
void print_mesh_report(const MeshReport& r);

std::string hex_sha256(const void* data, size_t size);

// Prints the JSON object and a newline on stdout.
void print_json(const JsonObject& j);

}  // namespace tool
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_SPLINTCORE_COMMAND_H
