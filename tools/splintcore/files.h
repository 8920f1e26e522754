// The splintcore program's files (issue 27): one way to read an input file, one way to write an
// output file.
#ifndef SPLINTCORE_TOOLS_SPLINTCORE_FILES_H
#define SPLINTCORE_TOOLS_SPLINTCORE_FILES_H

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "../common/cli.h"
#include "splintcore/core.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "splintcore/platform.h"

namespace splintcore {
namespace tool {

constexpr uint64_t kNoInputLimit = UINT64_MAX;

// An input file, opened through the library's FileSource. Every command reads its input files
// through it (meshes stream from source() into the library's read_mesh, case files are read
// whole), so a missing, unreadable or oversized file gets the same message everywhere. A
// regular file larger than `max_bytes` is refused before anything is read; a pipe or device
// is counted as it is read. The path "-" is standard input (once per run; named
// "(standard input)" in messages).
// SHA-256 on a thread of its own: the bytes handed to add() are copied into one of a few
// slots and hashed in order while the caller goes on (reading a mesh hashes its file this way
// when the run has more than one thread: the same digest, without the hash's time in the read).
class BackgroundHasher {
 public:
  explicit BackgroundHasher(Sha256* sha);
  ~BackgroundHasher();  // finishes
  BackgroundHasher(const BackgroundHasher&) = delete;
  BackgroundHasher& operator=(const BackgroundHasher&) = delete;
  void add(const uint8_t* data, size_t bytes);  // waits while every slot is full
  void finish();                                // every byte added is hashed

 private:
  static constexpr size_t kSlots = 4;
  static constexpr size_t kSlotBytes = size_t{1} << 20;
  void publish();  // the slot being filled goes to the hashing thread
  void run();

  Sha256* sha_;
  std::vector<uint8_t> slot_[kSlots];
  size_t fill_ = 0;   // the slot being filled (owned by the caller)
  size_t ready_ = 0;  // slots published, not yet hashed
  bool finishing_ = false;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::thread thread_;
};

class InputFile {
 public:
  Status open(const char* path, uint64_t max_bytes = kNoInputLimit);
  // Every byte read through source() (or read by read_rest) also goes to `sha`.
  void hash_into(Sha256* sha) { sha_ = sha; }
  // The same through a BackgroundHasher (finished by the caller).
  void hash_into(BackgroundHasher* hasher) { hasher_ = hasher; }
  // The file as a ByteSource (its name: the path).
  ByteSource source();
  // Reads the rest of the file into `out` (replaced).
  Status read_all(std::vector<uint8_t>* out);
  // Reads what a reader left unread (bytes after a binary STL's triangles), for the hash.
  Status read_rest();
  // A read through source() that failed because the file grew past the limit: the status to
  // report instead of the reader's "read failed".
  bool went_over_limit() const { return over_limit_; }
  Status limit_status(uint64_t size) const;

 private:
  static int64_t read(void* user, uint8_t* buffer, size_t capacity);

  FileSource file_;
  ByteSource inner_;
  std::string path_;
  uint64_t max_bytes_ = kNoInputLimit;
  uint64_t count_ = 0;
  Sha256* sha_ = nullptr;
  BackgroundHasher* hasher_ = nullptr;
  bool over_limit_ = false;
};

// What reading a mesh file found.
struct MeshFileInfo {
  MeshFormat format = MeshFormat::kStlBinary;
  uint64_t triangles = 0;  // in the file
  uint64_t bytes = 0;      // read by the reader
  std::string sha256;      // of the whole file, when asked for
};

// Reads a mesh file (STL binary or ASCII, PLY, OBJ: by content, then extension) into a mesh
// welded exactly (read_mesh with weld: PLY and OBJ meshes hold the same vertices as their STL
// would). `info` may be null; with `hash`, info->sha256 is the file's SHA-256. `keep`
// (MeshReadOptions::keep): the triangles wholly beyond one side of it are left out as they
// are read (empty: none).
Status read_mesh_file(const Context& ctx, const char* path, uint64_t max_bytes, bool hash,
                      Mesh* mesh, MeshFileInfo* info, const Aabb& keep = Aabb{});

// Reads several mesh files as read_mesh_file does, one after the other, into out[i] (replaced,
// bound to ctx.arena, in the arena in order) and, when not null, infos[i]; the first error in
// order stops it. (Reading them in tasks, each into a slice of the arena, gave no measurable
// gain on the 2-core machine of issue 29's figures: the read is memory-bound. Not kept. Tried
// again on 2026-12-04 with the crop (the real dentition's 31 files, 192,564 of 887,688
// triangles kept, two tasks of alternate files in 10 MiB slices, --threads 2): the read took
// 0.035-0.042 s against 0.039-0.046 s, within the VM's noise, for 2.2 MB more arena.)
Status read_mesh_files(const Context& ctx, const std::vector<const char*>& paths,
                       uint64_t max_bytes, bool hash, std::vector<Mesh>* out,
                       std::vector<MeshFileInfo>* infos);

// Reads a whole file (a case) into `out`.
Status read_whole_input(const char* path, uint64_t max_bytes, std::vector<uint8_t>* out);

// "ascii" for the text formats (STL ASCII, PLY ASCII, OBJ), else "binary".
const char* encoding_name(MeshFormat format);

// What write_mesh_atomically writes to `path`: "binary PLY" for a name ending in .ply (any
// case), else "ascii STL" or "binary STL".
const char* mesh_output_format(const char* path, bool ascii);

// Refuses (kUnsupported, naming the path) an output name whose extension is another mesh
// format (.obj .3mf .off ...: STL bytes there would not open in the program that reads it by
// name), and --ascii with .ply; with `stl_only` (an output streamed as STL) .ply too.
// Commands call it before their work; write_mesh_atomically again.
Status check_mesh_output(const char* path, bool ascii, bool stl_only = false);

// Writes a mesh into a temporary file renamed over `path` only when everything succeeded: as
// binary PLY (write_ply) when `path` ends in .ply, else as STL through the streaming writer
// (check_mesh_output's refusals first). With `outputs`, the file is kept there (written whole and
// synced) and placed by its commit() with the run's other outputs, instead of now.
Status write_mesh_atomically(const Context& ctx, const Mesh& mesh, const char* path, bool ascii,
                             cli::OutputSet* outputs = nullptr);

// The same without the commit: `file` opened on `path` and the STL written into it; the
// caller commits it (or it is removed: on an error here, by abort() or the destructor).
Status write_mesh_uncommitted(const Context& ctx, const Mesh& mesh, const char* path, bool ascii,
                              AtomicFile* file);

// Bytes are written the same way by cli::write_bytes_atomically.
using cli::write_bytes_atomically;

// Writes what `write` puts into the sink it is given (in order: the sink cannot seek) the same
// way, streamed to the file as it comes, and the SHA-256 of those bytes (hex) into *sha256: no
// copy of the whole file in memory (for the splints' STL and 3MF files, several MB each, that
// copy cost more than the write; issue 32). A `write` that fails leaves no file. `outputs` as
// for write_mesh_atomically.
Status write_hashed_atomically(const std::string& path,
                               const std::function<Status(const ByteSink&)>& write,
                               std::string* sha256, cli::OutputSet* outputs = nullptr);

}  // namespace tool
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_SPLINTCORE_FILES_H
