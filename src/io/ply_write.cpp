// Binary PLY writer (Turk 1994; the format as read by ply_read.cpp): little-endian float32
// x, y, z per vertex, optionally uchar red, green, blue, then a uchar-counted int list of
// vertex_indices per face. Records go through a fixed buffer on the stack to the sink, so
// nothing is allocated; the bytes are a pure function of the mesh and the colours.
#include <cfloat>
#include <cstring>

#include "splintcore/io.h"

namespace splintcore {

namespace {

constexpr size_t kBufferBytes = 4096;

struct Out {
  explicit Out(const ByteSink& s) : sink(s) {}
  const ByteSink& sink;
  uint8_t buffer[kBufferBytes] = {};
  size_t used = 0;
  bool failed = false;

  void flush() {
    if (used > 0 && !failed && !sink.write(sink.user, buffer, used)) failed = true;
    used = 0;
  }
  void put(const void* data, size_t n) {
    if (used + n > kBufferBytes) flush();
    std::memcpy(buffer + used, data, n);
    used += n;
  }
  void put_text(const char* text) { put(text, std::strlen(text)); }
  void put_decimal(uint64_t v) {  // no printf in the core
    char digits[20];
    size_t n = 0;
    do {
      digits[n++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v > 0);
    for (size_t i = 0; i < n / 2; ++i) {
      const char c = digits[i];
      digits[i] = digits[n - 1 - i];
      digits[n - 1 - i] = c;
    }
    put(digits, n);
  }
  void put_u32(uint32_t v) {
    const uint8_t b[4] = {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8),
                          static_cast<uint8_t>(v >> 16), static_cast<uint8_t>(v >> 24)};
    put(b, 4);
  }
  void put_f32(float f) {
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    if (bits == 0x80000000u) bits = 0;  // -0 is written as +0
    put_u32(bits);
  }
};

}  // namespace

Status write_ply(const Mesh& mesh, Span<const uint8_t> rgb, const ByteSink& sink) {
  const uint64_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  if (!rgb.empty() && rgb.size() != 3 * nv) {
    return make_error(StatusCode::kInvalidArgument, "write_ply: ", rgb.size(), " colour bytes for ",
                      nv, " vertices (3 per vertex, or none)");
  }
  if (nv > INT32_MAX) {
    return make_error(StatusCode::kLimitExceeded, "write_ply: ", nv,
                      " vertices; PLY int indices hold at most 2^31 - 1");
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3& p = mesh.vertices[i];
    if (!is_finite(p)) {
      return make_error(StatusCode::kNonFinite, "write_ply: vertex ", i, " is not finite")
          .at_index(i);
    }
    constexpr double kMax = static_cast<double>(FLT_MAX);
    if (!(p.x <= kMax && p.x >= -kMax && p.y <= kMax && p.y >= -kMax && p.z <= kMax &&
          p.z >= -kMax)) {
      return make_error(StatusCode::kLimitExceeded, "write_ply: vertex ", i,
                        " is beyond float32 range")
          .at_index(i);
    }
  }
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (uint32_t k : mesh.triangles[i].v) {
      if (k >= nv) {
        return make_error(StatusCode::kInvalidMesh, "write_ply: triangle ", i, " refers to vertex ",
                          k, " but the mesh has ", nv, " vertices")
            .at_index(i);
      }
    }
  }
  Out out(sink);
  out.put_text("ply\nformat binary_little_endian 1.0\ncomment splintcore\nelement vertex ");
  out.put_decimal(nv);
  out.put_text("\nproperty float x\nproperty float y\nproperty float z\n");
  if (!rgb.empty()) {
    out.put_text("property uchar red\nproperty uchar green\nproperty uchar blue\n");
  }
  out.put_text("element face ");
  out.put_decimal(nt);
  out.put_text("\nproperty list uchar int vertex_indices\nend_header\n");
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3& p = mesh.vertices[i];
    out.put_f32(static_cast<float>(p.x));
    out.put_f32(static_cast<float>(p.y));
    out.put_f32(static_cast<float>(p.z));
    if (!rgb.empty()) out.put(rgb.data() + 3 * i, 3);
  }
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    const uint8_t three = 3;
    out.put(&three, 1);
    for (uint32_t k : mesh.triangles[i].v) out.put_u32(k);
  }
  out.flush();
  if (out.failed) {
    Status e = make_error(StatusCode::kIoError, "write failed");
    if (sink.name != nullptr) e.in_file(sink.name);
    return e;
  }
  return Status::ok();
}

}  // namespace splintcore
