// Helpers shared by the command-line programs: sizes, JSON output, status printing.
#ifndef SPLINTCORE_TOOLS_CLI_H
#define SPLINTCORE_TOOLS_CLI_H

#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/io.h"
#include "splintcore/platform.h"

namespace splintcore {
namespace cli {

// Exit codes of every subcommand.
constexpr int kExitOk = 0;
constexpr int kExitRejected = 1;  // input rejected, check failed, or resources exhausted
constexpr int kExitUsage = 2;

// "64M", "1G", "512K", "1048576" -> bytes (binary multiples). False when malformed.
bool parse_size(const char* text, uint64_t* out);
bool parse_unsigned(const char* text, uint64_t* out);

// A flat JSON object written in insertion order; numbers in shortest round-trip form.
class JsonObject {
 public:
  void add(const char* key, const char* value);
  void add(const char* key, const std::string& value) { add(key, value.c_str()); }
  void add(const char* key, bool value);
  void add(const char* key, uint64_t value);
  void add(const char* key, int64_t value);
  void add(const char* key, int value) { add(key, static_cast<int64_t>(value)); }
  void add(const char* key, unsigned value) { add(key, static_cast<uint64_t>(value)); }
  void add(const char* key, double value);
  void add(const char* key, const Vec3& value);
  void add_raw(const char* key, const std::string& json);
  void add_status(const Status& status);  // "status", "message" and the location fields
  std::string str() const { return "{" + body_ + "}"; }

 private:
  void key(const char* k);
  std::string body_;
};

std::string json_escape(const char* text);
std::string json_number(double value);

// A sink that appends to `out` (tools only: it grows a std::string). Not seekable.
ByteSink string_sink(std::string* out);

// Caps on input files (SECURITY.md, "Input limits"). A case file is read whole and parsed
// (parse_case takes at most 16 MiB anyway); design's jaws stream through the reader, hashed on
// the way, and are refused before reading when over kMaxMeshBytes (splintcore-bench reads whole
// files under the same cap). `--max-input-bytes SIZE` (base, design) replaces both caps.
constexpr uint64_t kMaxCaseBytes = uint64_t{16} << 20;  // 16 MiB
constexpr uint64_t kMaxMeshBytes = uint64_t{2} << 30;   // 2 GiB

// Reads a whole file into `out` (replaced), refusing one over `max_bytes`: the size is checked
// before anything is read (a regular file's size from stat), and again while reading (a pipe or
// a file that grows). Errors, naming the file: kIoError (cannot open or read it), kUnsupported
// (a directory), kLimitExceeded ("file is N bytes, over the limit of M bytes"). On an error
// `out` is empty.
Status read_whole_file(const std::string& path, uint64_t max_bytes, std::vector<uint8_t>* out);

// The same with the mesh cap (kMaxMeshBytes); false on any error.
bool read_whole_file(const std::string& path, std::vector<uint8_t>* out);

// `text` with every byte a terminal would act on written out as \xNN: the C0 controls
// (newline and tab too: a message is one line), DEL, and the C1 controls as UTF-8 writes them
// (C2 80 to C2 9F); everything else as it is. For messages that quote what an input holds (a
// token of an ASCII STL, a key of a case file): such bytes could move the cursor, recolour or
// retitle the terminal, or fake a line of output.
std::string printable(const char* text);

// Prints "splintcore: error: <formatted status>" to stderr (printable()).
void print_error(const Status& status);

// The output files of one run, placed together: each is written whole, synced and closed as a
// temporary file (AtomicFile::finish) when it is kept, and none is renamed into place before
// commit(), which renames them all in the order kept. So a run that fails at any of its files
// (a full disk at the report, after the splint) leaves none of this run's files in place, and
// the files of an earlier run as they were, not new and old mixed. commit() first refuses a
// destination that is a folder (the likely way left for a rename to fail once the temporary
// files exist beside their destinations), so the renames do not stop half way for it; a rename
// that still fails (a busy or read-only mount) leaves the ones before it placed. Destroyed
// without commit(), it removes every temporary file. keep() may be called from several threads.
// commit() holds an exclusive flock() on each destination's folder while it renames, so two runs
// writing the same files at once place theirs one set after the other (the later set whole),
// not interleaved; another program that takes the same lock waits for the renames to end. A
// lock held elsewhere longer than the wait (set_lock_wait) is an error: nothing is placed.
class OutputSet {
 public:
  // Keeps `file` (open, written) for commit(): finished now; on an error it is removed.
  Status keep(std::unique_ptr<AtomicFile> file);
  Status commit();
  // A file written whole: kept in `set`, or committed now when `set` is null.
  static Status place(std::unique_ptr<AtomicFile> file, OutputSet* set);
  // How long commit() waits for a folder's lock held elsewhere before it gives up, placing
  // nothing (default 60 s; the renames themselves take milliseconds).
  void set_lock_wait(double seconds) { lock_wait_seconds_ = seconds; }

 private:
  double lock_wait_seconds_ = 60;
  std::mutex mutex_;
  std::vector<std::unique_ptr<AtomicFile>> files_;
};

// A stretch of bytes to write.
struct ByteSpan {
  const void* data;
  size_t size;
};

// Writes `parts` one after the other into a temporary file beside `path`, placed as
// OutputSet::place does: kept in `set`, or renamed over `path` now when `set` is null. A write
// that fails leaves no file and says why ("cannot write: No space left on device", in `path`).
Status write_bytes_atomically(const std::string& path, std::initializer_list<ByteSpan> parts,
                              OutputSet* set = nullptr);
Status write_bytes_atomically(const std::string& path, const void* data, size_t size,
                              OutputSet* set = nullptr);
Status write_bytes_atomically(const std::string& path, const std::string& bytes,
                              OutputSet* set = nullptr);

}  // namespace cli
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_CLI_H
