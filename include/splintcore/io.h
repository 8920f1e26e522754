// splintcore io: byte sources and sinks (callbacks, so firmware can feed and drain data in
// chunks), the STL reader and the streaming STL writer. Floor 4.
#ifndef SPLINTCORE_IO_H
#define SPLINTCORE_IO_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {

constexpr uint64_t kUnknownSize = ~uint64_t{0};

// Where bytes come from. read() copies up to `capacity` bytes into `buffer` and returns how
// many (0 at the end), or -1 on an I/O error.
struct ByteSource {
  int64_t (*read)(void* user, uint8_t* buffer, size_t capacity) = nullptr;
  void* user = nullptr;
  uint64_t size = kUnknownSize;  // total bytes if known: lets readers reject lies up front
  const char* name = nullptr;    // for messages (a file name), may be null
};

// Where bytes go. write() returns false on failure. seek() (may be null: not seekable) moves
// the write position to an absolute offset; used to patch a count in a header.
struct ByteSink {
  bool (*write)(void* user, const uint8_t* data, size_t bytes) = nullptr;
  bool (*seek)(void* user, uint64_t offset) = nullptr;
  void* user = nullptr;
  const char* name = nullptr;
};

// A source over bytes in memory.
struct MemorySource {
  const uint8_t* data = nullptr;
  uint64_t size = 0;
  uint64_t position = 0;
  size_t max_chunk = 0;  // 0: no limit; tests set it to feed the reader in small pieces
};
ByteSource memory_source(MemorySource* state, const char* name = "memory");

// A sink into a caller buffer (fixed capacity: a write past it fails). Seekable.
struct MemorySink {
  uint8_t* data = nullptr;
  uint64_t capacity = 0;
  uint64_t size = 0;      // high-water of bytes written
  uint64_t position = 0;  // current write position
};
ByteSink memory_sink(MemorySink* state, const char* name = "memory");

// A sink that only hashes (SHA-256) and counts what passes through. Not seekable.
struct HashSink {
  Sha256 sha;
  uint64_t size = 0;
};
ByteSink hash_sink(HashSink* state);

// ---------------------------------------------------------------------------------------------
// STL reading.

enum class StlFormat : uint8_t { kAuto, kBinary, kAscii };

struct StlReadOptions {
  StlFormat format = StlFormat::kAuto;
  uint64_t max_triangles = 100'000'000;   // larger inputs are kLimitExceeded
  double max_abs_coordinate = 1.0e6;      // mm; beyond is kLimitExceeded ("wrong units?")
  size_t chunk_bytes = 64 * 1024;         // read buffer, from the arena
};

struct StlInfo {
  StlFormat format = StlFormat::kAuto;  // what was detected
  uint64_t triangles = 0;
  uint64_t bytes = 0;
  char header[81] = {};  // binary: the 80-byte header (NUL-terminated); ASCII: the solid name
};

// Auto-detection: ASCII when the input starts with "solid" (after optional white space) and
// its first 1024 bytes are all printable text; binary otherwise. A binary file whose header
// begins with "solid" is still binary: its count field and float data are not text.

// Reads triangles into `out` (appended). Never trusts the binary header's count: it must agree
// with the bytes that follow (and with source.size when known, checked before reading on).
// Errors (each with byte offset or line): kTruncated, kParseError, kNonFinite (names the
// triangle), kLimitExceeded, kIoError, kArenaExhausted. Arena: the read buffer
// (max(chunk_bytes, 4096)) and the triangles (36 bytes each, the array grown by half),
// both left in place on success. On an error the arena is as it was and `out` holds what it
// held before the call.
Status read_stl(const Context& ctx, const ByteSource& source, const StlReadOptions& options,
                ArenaArray<SoupTriangle>* out, StlInfo* info);

// read_stl() then weld_exact(), leaving only the mesh in the arena (the soup is reclaimed).
// `out` must be empty. Errors: read_stl()'s and weld_exact()'s. On an error the arena is as it
// was and `out` is empty.
Status read_stl_mesh(const Context& ctx, const ByteSource& source, const StlReadOptions& options,
                     Mesh* out, StlInfo* info);

// ---------------------------------------------------------------------------------------------
// STL writing: streams triangles to a sink as they are produced, without holding the mesh.
//
// Bytes are deterministic: a fixed header with no timestamp, float32 coordinates rounded to
// nearest (ties to even) from double, -0 written as +0, facet normals computed from the
// rounded corners as normalize((b - a) x (c - a)) in double then rounded (0,0,0 when
// degenerate). ASCII numbers use the shortest form that reads back to the same float32.

struct StlWriteOptions {
  StlFormat format = StlFormat::kBinary;   // kAuto means binary
  size_t buffer_bytes = 64 * 1000;         // from the arena
  const char* solid_name = "splintcore";   // ASCII only; letters, digits, '_' '-' '.'
};

constexpr char kStlBinaryHeader[] = "splintcore binary STL";  // padded with spaces to 80 bytes

class StlWriter {
 public:
  StlWriter() = default;
  StlWriter(const StlWriter&) = delete;
  StlWriter& operator=(const StlWriter&) = delete;

  // `triangle_count` may be kUnknownSize for binary output only when the sink can seek (the
  // count is patched by finish()). The buffer is taken from ctx.arena; keep the arena's top
  // until finish() (allocate nothing below it that must outlive the writer).
  Status begin(const Context& ctx, const ByteSink& sink, const StlWriteOptions& options,
               uint64_t triangle_count);
  Status add(const Vec3& a, const Vec3& b, const Vec3& c);
  // Flushes, checks the number of triangles against the declared count, patches it if needed.
  Status finish();
  uint64_t triangles_written() const { return written_; }
  uint64_t bytes_written() const { return bytes_; }

 private:
  Status flush();
  ByteSink sink_{};
  uint8_t* buffer_ = nullptr;
  size_t capacity_ = 0;
  size_t used_ = 0;
  uint64_t declared_ = 0;
  uint64_t written_ = 0;
  uint64_t bytes_ = 0;
  bool binary_ = true;
  bool count_known_ = false;
  bool open_ = false;
  const char* solid_name_ = "splintcore";
};

// Writes a whole mesh through an StlWriter.
Status write_stl(const Context& ctx, const Mesh& mesh, const ByteSink& sink,
                 const StlWriteOptions& options);

}  // namespace splintcore

#endif  // SPLINTCORE_IO_H
