// Streaming STL writer. Triangles are encoded into a fixed buffer and handed to the sink when
// it fills, so a mesh never needs to exist whole. The bytes are a pure function of the
// triangles given (see io.h for the rounding and normal rules).
#include <cfloat>
#include <charconv>

#include "splintcore/io.h"

namespace splintcore {

namespace {

constexpr size_t kRecordBytes = 50;
constexpr double kFloatMax = static_cast<double>(FLT_MAX);
constexpr size_t kMaxAsciiFacetBytes = 512;  // 12 numbers of at most ~16 chars plus keywords

// Little-endian: one 4-byte store on a little-endian host.
inline void store_u32(uint8_t* p, uint32_t v) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  std::memcpy(p, &v, sizeof(v));
#else
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
  p[2] = static_cast<uint8_t>(v >> 16);
  p[3] = static_cast<uint8_t>(v >> 24);
#endif
}

inline void store_f32(uint8_t* p, float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof(bits));
  if (bits == 0x80000000u) bits = 0;  // -0 is written as +0
  store_u32(p, bits);
}

// Rounds to float32 (to nearest, ties to even: the IEEE default) after checking the range,
// since converting an out-of-range double to float is undefined behaviour. False when the
// value is not finite or beyond float32 range.
inline bool to_float(const Vec3& v, float out[3]) {
  // Also false for NaN; infinities fail the range test. (Without branches: each test alone.)
  const bool ok = (v.x <= kFloatMax) & (v.x >= -kFloatMax) & (v.y <= kFloatMax) &
                  (v.y >= -kFloatMax) & (v.z <= kFloatMax) & (v.z >= -kFloatMax);
  out[0] = ok ? static_cast<float>(v.x) : 0.0f;
  out[1] = ok ? static_cast<float>(v.y) : 0.0f;
  out[2] = ok ? static_cast<float>(v.z) : 0.0f;
  return ok;
}

Status unwritable(const Vec3& v, uint64_t triangle, int corner) {
  if (!is_finite(v)) {
    return make_error(StatusCode::kNonFinite, "cannot write triangle ", triangle, ": vertex ",
                      corner, " is not finite")
        .at_index(triangle);
  }
  return make_error(StatusCode::kLimitExceeded, "cannot write triangle ", triangle, ": vertex ",
                    corner, " is beyond float32 range")
      .at_index(triangle);
}

// The facet normal of the triangle as written (from the float32 corners).
inline void facet_normal(const float p[3][3], float n[3]) {
  auto corner = [&](int k) {
    return Vec3{static_cast<double>(p[k][0]), static_cast<double>(p[k][1]),
                static_cast<double>(p[k][2])};
  };
  const Vec3 a = corner(0), b = corner(1), c = corner(2);
  Vec3 m = cross(b - a, c - a);
  double len = length(m);
  if (len > 0.0 && is_finite(len)) {
    m = Vec3{m.x / len, m.y / len, m.z / len};
  } else {
    m = Vec3{};
  }
  n[0] = static_cast<float>(m.x);
  n[1] = static_cast<float>(m.y);
  n[2] = static_cast<float>(m.z);
}

// Three floats at `out` as store_f32 stores them (spelt out: GCC at -O2 keeps a loop).
inline void store_f32x3(uint8_t* out, const float f[3]) {
  store_f32(out, f[0]);
  store_f32(out + 4, f[1]);
  store_f32(out + 8, f[2]);
}

// The binary record of triangle (a, b, c) at `out` (50 bytes); false, with nothing written,
// when a corner cannot be written (not finite, beyond float32: add() names it). All three
// corners are tested before the one branch (they are writable but for a broken mesh).
inline bool encode_binary(const Vec3& a, const Vec3& b, const Vec3& c, uint8_t* out) {
  float p[3][3];
  const bool a_ok = to_float(a, p[0]), b_ok = to_float(b, p[1]), c_ok = to_float(c, p[2]);
  if (!(a_ok && b_ok && c_ok)) return false;
  float n[3];
  facet_normal(p, n);
  store_f32x3(out, n);
  store_f32x3(out + 12, p[0]);
  store_f32x3(out + 24, p[1]);
  store_f32x3(out + 36, p[2]);
  out[48] = 0;
  out[49] = 0;
  return true;
}

// A mesh's binary records are encoded in tasks (StlWriter::add_mesh) when the writer's buffer
// holds at least this many: fewer, larger batches (each is one run of the executor).
constexpr size_t kTaskBatchRecords = 8192;
constexpr uint32_t kMaxWriteTasks = 16;

size_t put_text(uint8_t* out, const char* text) {
  size_t n = std::strlen(text);
  std::memcpy(out, text, n);
  return n;
}

size_t put_float(uint8_t* out, float f) {
  if (f == 0.0f) f = 0.0f;  // no "-0"
  char* first = reinterpret_cast<char*>(out);
  auto r = std::to_chars(first, first + 32, f);
  return static_cast<size_t>(r.ptr - first);
}

size_t put_triple(uint8_t* out, const float v[3]) {
  size_t n = 0;
  for (int a = 0; a < 3; ++a) {
    out[n++] = ' ';
    n += put_float(out + n, v[a]);
  }
  out[n++] = '\n';
  return n;
}

}  // namespace

Status StlWriter::begin(const Context& ctx, const ByteSink& sink, const StlWriteOptions& options,
                        uint64_t triangle_count) {
  if (open_) return Status::error(StatusCode::kInvalidArgument, "STL writer is already open");
  if (sink.write == nullptr) {
    return Status::error(StatusCode::kInvalidArgument, "STL writer: sink has no write()");
  }
  binary_ = options.format != StlFormat::kAscii;
  count_known_ = triangle_count != kUnknownSize;
  if (binary_ && !count_known_ && sink.seek == nullptr) {
    return Status::error(StatusCode::kInvalidArgument,
                         "binary STL with an unknown triangle count needs a seekable sink "
                         "(or pass the count to begin())");
  }
  if (binary_ && count_known_ && triangle_count > UINT32_MAX) {
    return make_error(StatusCode::kLimitExceeded, "binary STL holds at most ", UINT32_MAX,
                      " triangles, asked for ", triangle_count);
  }
  if (!binary_ && !is_plain_name(options.solid_name, 64)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "ASCII STL solid name must be 1-64 letters, digits, '_', '-' or '.'");
  }
  size_t capacity = options.buffer_bytes < 4096 ? 4096 : options.buffer_bytes;
  buffer_ = ctx.arena->allocate_array<uint8_t>(capacity);
  if (buffer_ == nullptr) return ctx.arena->exhausted_status();
  capacity_ = capacity;
  sink_ = sink;
  declared_ = count_known_ ? triangle_count : 0;
  written_ = 0;
  bytes_ = 0;
  used_ = 0;
  solid_name_ = options.solid_name;
  open_ = true;
  if (binary_) {
    std::memset(buffer_, ' ', 80);
    std::memcpy(buffer_, kStlBinaryHeader, sizeof(kStlBinaryHeader) - 1);
    store_u32(buffer_ + 80, static_cast<uint32_t>(declared_));
    used_ = 84;
  } else {
    used_ += put_text(buffer_, "solid ");
    used_ += put_text(buffer_ + used_, solid_name_);
    buffer_[used_++] = '\n';
  }
  return Status::ok();
}

Status StlWriter::flush() {
  if (used_ == 0) return Status::ok();
  if (!sink_.write(sink_.user, buffer_, used_)) {
    Status s = make_error(StatusCode::kIoError, "write failed").at_byte(bytes_);
    if (sink_.name != nullptr) s.in_file(sink_.name);
    open_ = false;
    return s;
  }
  bytes_ += used_;
  used_ = 0;
  return Status::ok();
}

namespace {
Status not_open() {
  return Status::error(StatusCode::kInvalidArgument,
                       "STL writer is not open (begin() failed, or an earlier error closed it)");
}
}  // namespace

Status StlWriter::add(const Vec3& a, const Vec3& b, const Vec3& c) {
  if (!open_) return not_open();
  if (count_known_ && written_ >= declared_) {
    open_ = false;
    return make_error(StatusCode::kInvalidArgument, "STL writer: more triangles than the ",
                      declared_, " declared");
  }
  if (binary_ && written_ >= UINT32_MAX) {
    open_ = false;
    return make_error(StatusCode::kLimitExceeded, "binary STL holds at most ", UINT32_MAX,
                      " triangles");
  }
  float p[3][3];
  const Vec3* corners[3] = {&a, &b, &c};
  uint8_t record[kRecordBytes];
  if (!(binary_ ? encode_binary(a, b, c, record)
                : to_float(a, p[0]) && to_float(b, p[1]) && to_float(c, p[2]))) {
    int k = 0;  // the first corner that cannot be written (the last when the others can)
    while (k < 2 && to_float(*corners[k], p[k])) ++k;
    open_ = false;  // the output is incomplete: no finish() may seal it
    return unwritable(*corners[k], written_, k);
  }
  const size_t need = binary_ ? kRecordBytes : kMaxAsciiFacetBytes;
  if (capacity_ - used_ < need) SPLINTCORE_RETURN_IF_ERROR(flush());
  uint8_t* out = buffer_ + used_;
  if (binary_) {
    std::memcpy(out, record, kRecordBytes);
    used_ += kRecordBytes;
  } else {
    float n[3];
    facet_normal(p, n);
    size_t m = put_text(out, "  facet normal");
    m += put_triple(out + m, n);
    m += put_text(out + m, "    outer loop\n");
    for (int k = 0; k < 3; ++k) {
      m += put_text(out + m, "      vertex");
      m += put_triple(out + m, p[k]);
    }
    m += put_text(out + m, "    endloop\n  endfacet\n");
    used_ += m;
  }
  ++written_;
  return Status::ok();
}

Status StlWriter::finish() {
  if (!open_) return not_open();
  if (count_known_ && written_ != declared_) {
    open_ = false;
    return make_error(StatusCode::kInvalidArgument, "STL writer: declared ", declared_,
                      " triangles but wrote ", written_);
  }
  if (!binary_) {
    if (capacity_ - used_ < 80) SPLINTCORE_RETURN_IF_ERROR(flush());
    used_ += put_text(buffer_ + used_, "endsolid ");
    used_ += put_text(buffer_ + used_, solid_name_);
    buffer_[used_++] = '\n';
  }
  SPLINTCORE_RETURN_IF_ERROR(flush());
  if (binary_ && !count_known_) {
    uint8_t count[4];
    store_u32(count, static_cast<uint32_t>(written_));
    if (!sink_.seek(sink_.user, 80) || !sink_.write(sink_.user, count, 4) ||
        !sink_.seek(sink_.user, bytes_)) {
      open_ = false;
      Status s = make_error(StatusCode::kIoError, "could not patch the triangle count").at_byte(80);
      if (sink_.name != nullptr) s.in_file(sink_.name);
      return s;
    }
  }
  open_ = false;
  return Status::ok();
}

// Triangles [t, end) of the mesh encoded in tasks at the buffer's end, as add() would encode
// them one by one; the first that add() would refuse (or whose indices are out of range) and
// everything after it are left out. Returns how many were encoded (from t on).
size_t StlWriter::encode_in_tasks(const Executor* executor, const Mesh& mesh, size_t t,
                                  size_t end) {
  const Vec3* v = mesh.vertices.data();
  const size_t nv = mesh.vertices.size();
  uint8_t* out = buffer_ + used_;
  uint32_t tasks = !has_threads(executor)                   ? 1u
                   : executor->concurrency < kMaxWriteTasks ? executor->concurrency
                                                            : kMaxWriteTasks;
  size_t stop[kMaxWriteTasks];
  auto task = [&](uint32_t i) {
    const size_t from = t + task_start(end - t, i, tasks),
                 to = t + task_start(end - t, i + 1, tasks);
    stop[i] = to;
    for (size_t k = from; k < to; ++k) {
      const Triangle& tri = mesh.triangles[k];
      if (tri.v[0] >= nv || tri.v[1] >= nv || tri.v[2] >= nv ||
          !encode_binary(v[tri.v[0]], v[tri.v[1]], v[tri.v[2]], out + kRecordBytes * (k - t))) {
        stop[i] = k;
        return;
      }
    }
  };
  parallel_for_each(executor, tasks, task);
  size_t done = end;
  for (uint32_t i = 0; i < tasks && done == end; ++i) {
    if (stop[i] != t + task_start(end - t, i + 1, tasks)) done = stop[i];
  }
  return done - t;
}

Status StlWriter::add_mesh(const Context& ctx, const Mesh& mesh) {
  const Vec3* v = mesh.vertices.data();
  const size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  // Binary records go in batches straight into the buffer (in tasks when worth it), not
  // through add() one by one.
  const bool tasks =
      has_threads(ctx.executor) && capacity_ >= kTaskBatchRecords * kRecordBytes + 84;
  const size_t least_batch = tasks ? kTaskBatchRecords : 1;
  for (size_t t = 0; t < nt;) {
    if ((t & 0xffff) == 0) SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "write", t, nt));
    if (binary_ && open_) {
      // A batch: what the buffer holds, up to the next progress report, the declared count
      // and the format's limit (add() says what is wrong past them).
      if ((capacity_ - used_) / kRecordBytes < least_batch) {
        SPLINTCORE_RETURN_IF_ERROR(flush());
      }
      size_t end = t + (capacity_ - used_) / kRecordBytes;
      const size_t next_report = (t | 0xffff) + 1;
      end = end < next_report ? end : next_report;
      end = end < nt ? end : nt;
      const uint64_t limit = count_known_ && declared_ < UINT32_MAX ? declared_ : UINT32_MAX;
      const uint64_t room = limit > written_ ? limit - written_ : 0;
      end = end - t < room ? end : t + static_cast<size_t>(room);
      if (end > t) {
        const size_t done = encode_in_tasks(tasks ? ctx.executor : nullptr, mesh, t, end);
        used_ += kRecordBytes * done;
        written_ += done;
        t += done;
        if (t == end) continue;  // else triangle t is refused below, as add() refuses it
      }
    }
    const Triangle& tri = mesh.triangles[t];
    if (tri.v[0] >= nv || tri.v[1] >= nv || tri.v[2] >= nv) {
      return make_error(StatusCode::kInvalidMesh, "triangle ", t,
                        " refers to a vertex that does not exist")
          .at_index(t);
    }
    SPLINTCORE_RETURN_IF_ERROR(add(v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]));
    ++t;
  }
  return Status::ok();
}

Status write_stl(const Context& ctx, const Mesh& mesh, const ByteSink& sink,
                 const StlWriteOptions& options) {
  ArenaScope scope(*ctx.arena);
  StlWriter writer;
  SPLINTCORE_RETURN_IF_ERROR(writer.begin(ctx, sink, options, mesh.triangles.size()));
  SPLINTCORE_RETURN_IF_ERROR(writer.add_mesh(ctx, mesh));
  return writer.finish();
}

}  // namespace splintcore
