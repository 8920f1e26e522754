// 3MF print jobs (io.h): the 3MF Core Specification 1.3 (3MF Consortium): one model part,
// 3D/3dmodel.model, with units in millimetres, an object per mesh and a build item per
// object; packaged as OPC (ECMA-376 part 2: [Content_Types].xml and _rels/.rels) in a ZIP
// container (PKWARE APPNOTE 6.3: local file headers, central directory, end of central
// directory; no ZIP64, no data descriptors, every date 1980-01-01 00:00). Entries are deflated
// with the compress module's fixed-Huffman encoder (method 8) unless that is not smaller
// (then stored, method 0). Same input, same bytes.
#include <charconv>
#include <cstring>

#include "splintcore/compress.h"
#include "splintcore/io.h"

namespace splintcore {

namespace {

constexpr double kFloatMax = 3.4028234663852886e38;
const char kSplintcoreNamespace[] = "http://schemas.splintcore.org/3mf/2026/11";

const char kContentTypes[] =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">"
    "<Default Extension=\"rels\" "
    "ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/>"
    "<Default Extension=\"model\" "
    "ContentType=\"application/vnd.ms-package.3dmanufacturing-3dmodel+xml\"/></Types>\n";

const char kRels[] =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">"
    "<Relationship Target=\"/3D/3dmodel.model\" Id=\"rel0\" "
    "Type=\"http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel\"/></Relationships>\n";

// The longest text of one vertex and of one triangle line (float32 in its shortest form: at
// most 15 characters; ids at most 10 digits).
constexpr uint64_t kVertexLine = 18 + 3 * (4 + 15 + 1) + 3;
constexpr uint64_t kTriangleLine = 15 + 3 * (5 + 10 + 1) + 3;
constexpr uint64_t kFixedText = 1024;          // the model's header, footer, and per object's tags
constexpr uint64_t kPerObject = 256 + 3 * 25;  // with a build item's transform

// A text that grows in the arena (the model part is built whole: a ZIP entry's header holds
// its size and CRC).
// The model's text, in an arena array that grows as it is written (in place: it is the top
// allocation), never past `bound` (model_bound: the text cannot be longer); `exhausted` when
// the arena had no room (the rest is dropped).
struct Text {
  Arena* arena = nullptr;
  ArenaArray<uint8_t> bytes;
  size_t bound = 0;
  bool exhausted = false;
  void put(const char* s, size_t n) {
    const size_t need = bytes.size() + n;
    if (need > bytes.capacity() && !grow(need)) return;
    const size_t at = bytes.size();
    (void)bytes.resize(need);  // within the capacity
    std::memcpy(bytes.data() + at, s, n);
  }
  bool grow(size_t need) {
    SPLINTCORE_ASSERT(need <= bound);
    if (exhausted) return false;
    const size_t doubled =
        2 * bytes.capacity() > (size_t{1} << 16) ? 2 * bytes.capacity() : size_t{1} << 16;
    const size_t wanted = doubled < bound ? doubled : bound;
    if (wanted > need) {
      if (bytes.reserve(wanted)) return true;
      arena->forget_failure();  // the exact size replaces the failed larger request
    }
    exhausted = !bytes.reserve(need);
    return !exhausted;
  }
  void put(const char* s) { put(s, std::strlen(s)); }
  void put_u64(uint64_t v) {
    char buf[24];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    put(buf, static_cast<size_t>(r.ptr - buf));
  }
  void put_f64(double d) {
    if (d == 0.0) d = 0.0;  // no "-0"
    char buf[40];
    const auto r = std::to_chars(buf, buf + sizeof buf, d);
    put(buf, static_cast<size_t>(r.ptr - buf));
  }
  // XML character data or an attribute value: & < > " ' escaped.
  void put_escaped(const char* s) {
    for (; *s != 0; ++s) {
      switch (*s) {
        case '&': put("&amp;"); break;
        case '<': put("&lt;"); break;
        case '>': put("&gt;"); break;
        case '"': put("&quot;"); break;
        case '\'': put("&apos;"); break;
        default: put(s, 1); break;
      }
    }
  }
};

// One vertex or triangle line, formatted on the stack and put whole (one bound check a line,
// not one a piece): at most kVertexLine bytes (shortest float32 and decimal integers).
struct Line {
  char text[kVertexLine > kTriangleLine ? kVertexLine : kTriangleLine];
  size_t size = 0;
  template <size_t N>
  void put(const char (&literal)[N]) {
    std::memcpy(text + size, literal, N - 1);
    size += N - 1;
  }
  void put_u64(uint64_t v) {
    const auto r = std::to_chars(text + size, text + sizeof text, v);
    size = static_cast<size_t>(r.ptr - text);
  }
  void put_float(float f) {
    if (f == 0.0f) f = 0.0f;  // no "-0"
    const auto r = std::to_chars(text + size, text + sizeof text, f);
    size = static_cast<size_t>(r.ptr - text);
  }
};

// The vertex and triangle lines are formatted in chunks of kChunkLines lines, kTextLanes chunks
// at a time on the executor, each into its lane of a scratch array, then appended in order:
// the same text as line by line, at every thread count (and the same arena use: the lanes are
// taken whatever the executor).
constexpr size_t kChunkLines = 1024;
constexpr uint32_t kTextLanes = 4;
constexpr size_t kLineBytes = sizeof(Line::text);
constexpr uint64_t kLanesBytes = uint64_t{kTextLanes} * kChunkLines * kLineBytes;

struct LineLanes {
  const Executor* executor = nullptr;
  char* scratch = nullptr;  // kTextLanes lanes of kChunkLines * kLineBytes
};

// Lines 0..count-1, format(i, &line) making line i, appended to `t` in order.
template <class Format>
void put_lines(const LineLanes& lanes, size_t count, const Format& format, Text* t) {
  const size_t chunks = (count + kChunkLines - 1) / kChunkLines;
  size_t used[kTextLanes] = {};
  for (size_t first = 0; first < chunks; first += kTextLanes) {
    const uint32_t wave =
        static_cast<uint32_t>(chunks - first < kTextLanes ? chunks - first : kTextLanes);
    auto task = [&](uint32_t k) {
      const size_t begin = (first + k) * kChunkLines;
      const size_t end = count - begin < kChunkLines ? count : begin + kChunkLines;
      char* out = lanes.scratch + k * kChunkLines * kLineBytes;
      size_t n = 0;
      for (size_t i = begin; i < end; ++i) {
        Line line;
        format(i, &line);
        std::memcpy(out + n, line.text, line.size);
        n += line.size;
      }
      used[k] = n;
    };
    parallel_for_each(lanes.executor, wave, task);
    for (uint32_t k = 0; k < wave; ++k)
      t->put(lanes.scratch + k * kChunkLines * kLineBytes, used[k]);
  }
}

uint64_t escaped_bound(const char* s) { return s == nullptr ? 0 : 6 * uint64_t{std::strlen(s)}; }

uint64_t model_bound(Span<const ThreeMfObject> objects, const ThreeMfOptions& options) {
  uint64_t n = kFixedText + escaped_bound(options.title) + escaped_bound(options.case_id);
  for (const ThreeMfObject& o : objects) {
    n += kPerObject + escaped_bound(o.name) + escaped_bound(o.sha256);
    if (o.mesh != nullptr) {
      n += kVertexLine * o.mesh->vertices.size() + kTriangleLine * o.mesh->triangles.size();
    }
  }
  return n;
}

// Fixed-Huffman deflate output of n bytes: at most 9 bits a literal, the block's 3 header bits
// and its end code (7 bits): n * 9 / 8 + 3.
uint64_t deflated_bound(uint64_t n) { return n + n / 8 + 16; }

Status check_objects(Span<const ThreeMfObject> objects) {
  if (objects.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "3MF: no objects to write");
  }
  for (size_t i = 0; i < objects.size(); ++i) {
    const Mesh* m = objects[i].mesh;
    if (m == nullptr || m->triangles.empty()) {
      return make_error(StatusCode::kInvalidArgument, "3MF: object ", i, " has no triangles")
          .at_index(i);
    }
    if (!is_finite(objects[i].translation)) {
      return make_error(StatusCode::kNonFinite, "3MF: object ", i, "'s translation is not finite")
          .at_index(i);
    }
    const size_t nv = m->vertices.size();
    for (size_t t = 0; t < m->triangles.size(); ++t) {
      for (const uint32_t v : m->triangles[t].v) {
        if (v >= nv) {
          return make_error(StatusCode::kInvalidMesh, "3MF: object ", i, " triangle ", t,
                            " refers to vertex ", v, " of ", nv)
              .at_index(t);
        }
      }
    }
    for (size_t v = 0; v < nv; ++v) {
      const Vec3& p = m->vertices[v];
      const double c[3] = {p.x, p.y, p.z};
      for (const double x : c) {
        if (!(x <= kFloatMax && x >= -kFloatMax)) {
          return make_error(is_finite(p) ? StatusCode::kLimitExceeded : StatusCode::kNonFinite,
                            "3MF: object ", i, " vertex ", v,
                            is_finite(p) ? " is beyond float32 range" : " is not finite")
              .at_index(v);
        }
      }
    }
  }
  return Status::ok();
}

void write_model(const LineLanes& lines, Span<const ThreeMfObject> objects,
                 const ThreeMfOptions& options, Text* t) {
  t->put(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<model unit=\"millimeter\" xml:lang=\"en-US\" "
      "xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\" xmlns:sc=\"");
  t->put(kSplintcoreNamespace);
  t->put("\">\n<metadata name=\"Application\">splintcore ");
  t->put(library_version());
  t->put("</metadata>\n");
  if (options.title != nullptr && options.title[0] != 0) {
    t->put("<metadata name=\"Title\">");
    t->put_escaped(options.title);
    t->put("</metadata>\n");
  }
  if (options.case_id != nullptr && options.case_id[0] != 0) {
    t->put("<metadata name=\"sc:case_id\">");
    t->put_escaped(options.case_id);
    t->put("</metadata>\n");
  }
  t->put("<resources>\n");
  for (size_t i = 0; i < objects.size(); ++i) {
    const ThreeMfObject& o = objects[i];
    t->put("<object id=\"");
    t->put_u64(i + 1);
    t->put("\" type=\"model\"");
    if (o.name != nullptr && o.name[0] != 0) {
      t->put(" name=\"");
      t->put_escaped(o.name);
      t->put("\"");
    }
    t->put(">\n");
    if (o.sha256 != nullptr && o.sha256[0] != 0) {
      t->put("<metadatagroup><metadata name=\"sc:sha256\">");
      t->put_escaped(o.sha256);
      t->put("</metadata></metadatagroup>\n");
    }
    t->put("<mesh>\n<vertices>\n");
    const Vec3* vertices = o.mesh->vertices.data();
    auto vertex = [vertices](size_t at, Line* line) {
      const Vec3& p = vertices[at];
      line->put("<vertex x=\"");
      line->put_float(static_cast<float>(p.x));
      line->put("\" y=\"");
      line->put_float(static_cast<float>(p.y));
      line->put("\" z=\"");
      line->put_float(static_cast<float>(p.z));
      line->put("\"/>\n");
    };
    put_lines(lines, o.mesh->vertices.size(), vertex, t);
    t->put("</vertices>\n<triangles>\n");
    const Triangle* triangles = o.mesh->triangles.data();
    auto triangle = [triangles](size_t at, Line* line) {
      const Triangle& tr = triangles[at];
      line->put("<triangle v1=\"");
      line->put_u64(tr.v[0]);
      line->put("\" v2=\"");
      line->put_u64(tr.v[1]);
      line->put("\" v3=\"");
      line->put_u64(tr.v[2]);
      line->put("\"/>\n");
    };
    put_lines(lines, o.mesh->triangles.size(), triangle, t);
    t->put("</triangles>\n</mesh>\n</object>\n");
  }
  t->put("</resources>\n<build>\n");
  for (size_t i = 0; i < objects.size(); ++i) {
    t->put("<item objectid=\"");
    t->put_u64(i + 1);
    const Vec3& d = objects[i].translation;
    if (!(d == Vec3{})) {
      t->put("\" transform=\"1 0 0 0 1 0 0 0 1 ");
      t->put_f64(d.x);
      t->put(" ");
      t->put_f64(d.y);
      t->put(" ");
      t->put_f64(d.z);
    }
    t->put("\"/>\n");
  }
  t->put("</build>\n</model>\n");
}

// One entry of the package: its name, its bytes as written (deflated or stored) and what the
// ZIP headers say of it.
struct Entry {
  const char* name = "";
  const uint8_t* data = nullptr;
  uint32_t size = 0;        // as written
  uint32_t plain_size = 0;  // uncompressed
  uint32_t crc = 0;         // of the uncompressed bytes
  uint16_t method = 0;      // 0 stored, 8 deflated
  uint32_t offset = 0;      // of its local header
};

// Deflated bytes into an arena array that grows as they come (in place: it is the top
// allocation), up to `limit` bytes: past that the entry is stored (deflate would not be
// smaller), so only what the compressed entry takes is held, not its bound.
struct GrowingSink {
  ArenaArray<uint8_t>* bytes = nullptr;
  size_t limit = 0;
  bool larger = false;     // the deflated bytes reached `limit`
  bool exhausted = false;  // the arena had no room
  static bool write(void* user, const uint8_t* data, size_t n) {
    GrowingSink* g = static_cast<GrowingSink*>(user);
    ArenaArray<uint8_t>& b = *g->bytes;
    if (n >= g->limit - b.size()) {
      g->larger = true;
      return false;
    }
    const size_t need = b.size() + n;
    // Exactly what is needed (in place: the array is the top allocation), so the arena's high
    // water is what the package takes, to the byte.
    if (need > b.capacity() && !b.reserve(need)) {
      g->exhausted = true;
      return false;
    }
    const size_t at = b.size();
    if (!b.resize(need)) return false;  // within the capacity: cannot fail
    std::memcpy(b.data() + at, data, n);
    return true;
  }
};

// The entry's bytes: deflated into `out` (an empty array bound to the arena) when that is
// smaller.
Status pack_entry(const Context& ctx, const DeflateLanes& lanes, bool deflate, const char* name,
                  const uint8_t* data, size_t size, ArenaArray<uint8_t>* out, Entry* e) {
  Arena& arena = *ctx.arena;
  e->name = name;
  e->plain_size = static_cast<uint32_t>(size);
  e->data = data;
  e->size = static_cast<uint32_t>(size);
  e->method = 0;
  if (!deflate) {
    e->crc = crc32(0, data, size);
    return Status::ok();
  }
  GrowingSink g;
  g.bytes = out;
  g.limit = size;
  CompressSink sink;
  sink.write = &GrowingSink::write;
  sink.user = &g;
  // The CRC comes with the deflate (piece by piece on the executor), unless it stops early.
  const Status s = deflate_parallel(ctx.executor, lanes, ZFormat::kRaw, data, size, sink, &e->crc);
  if (g.exhausted) return arena.exhausted_status();
  if (g.larger) {
    e->crc = crc32(0, data, size);
    out->clear();
    out->shrink_to_fit();
    return Status::ok();
  }
  SPLINTCORE_RETURN_IF_ERROR(s);
  out->shrink_to_fit();
  e->data = out->data();
  e->size = static_cast<uint32_t>(out->size());
  e->method = 8;
  return Status::ok();
}

void put16(uint8_t* p, uint32_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
void put32(uint8_t* p, uint32_t v) {
  for (int k = 0; k < 4; ++k) p[k] = static_cast<uint8_t>(v >> (8 * k));
}

// The fields a local header and a central directory header share, from "version needed".
void common_fields(uint8_t* p, const Entry& e) {
  put16(p, 20);     // version needed to extract: 2.0 (deflate)
  put16(p + 2, 0);  // flags
  put16(p + 4, e.method);
  put16(p + 6, 0);       // time 00:00:00
  put16(p + 8, 0x0021);  // date 1980-01-01
  put32(p + 10, e.crc);
  put32(p + 14, e.size);
  put32(p + 18, e.plain_size);
  put16(p + 22, static_cast<uint32_t>(std::strlen(e.name)));
  put16(p + 24, 0);  // extra field length
}

bool emit(const ByteSink& sink, const uint8_t* p, size_t n, uint64_t* at) {
  *at += n;
  return n == 0 || sink.write(sink.user, p, n);
}

Status write_zip(const ByteSink& sink, Entry* entries, size_t count) {
  const auto failed = [&]() {
    return Status::error(StatusCode::kIoError, "3MF: cannot write the package")
        .in_file(sink.name != nullptr ? sink.name : "");
  };
  uint64_t at = 0;
  uint8_t h[46];
  for (size_t i = 0; i < count; ++i) {
    Entry& e = entries[i];
    e.offset = static_cast<uint32_t>(at);
    put32(h, 0x04034b50);
    common_fields(h + 4, e);
    const size_t name = std::strlen(e.name);
    if (!emit(sink, h, 30, &at) ||
        !emit(sink, reinterpret_cast<const uint8_t*>(e.name), name, &at) ||
        !emit(sink, e.data, e.size, &at)) {
      return failed();
    }
  }
  const uint64_t directory = at;
  for (size_t i = 0; i < count; ++i) {
    const Entry& e = entries[i];
    put32(h, 0x02014b50);
    put16(h + 4, 20);  // version made by: MS-DOS attributes, 2.0
    common_fields(h + 6, e);
    put16(h + 32, 0);  // comment length
    put16(h + 34, 0);  // disk number start
    put16(h + 36, 0);  // internal attributes
    put32(h + 38, 0);  // external attributes
    put32(h + 42, e.offset);
    const size_t name = std::strlen(e.name);
    if (!emit(sink, h, 46, &at) ||
        !emit(sink, reinterpret_cast<const uint8_t*>(e.name), name, &at)) {
      return failed();
    }
  }
  if (at > UINT32_MAX) {
    return make_error(StatusCode::kLimitExceeded, "3MF: the package would be ", at,
                      " bytes; at most 4 GiB without ZIP64");
  }
  put32(h, 0x06054b50);
  put16(h + 4, 0);
  put16(h + 6, 0);
  put16(h + 8, static_cast<uint32_t>(count));
  put16(h + 10, static_cast<uint32_t>(count));
  put32(h + 12, static_cast<uint32_t>(at - directory));
  put32(h + 16, static_cast<uint32_t>(directory));
  put16(h + 20, 0);
  if (!emit(sink, h, 22, &at)) return failed();
  return Status::ok();
}

}  // namespace

uint64_t write_3mf_bound(Span<const ThreeMfObject> objects, const ThreeMfOptions& options) {
  const uint64_t model = model_bound(objects, options);
  uint64_t n = arena_array_bound<char>(static_cast<size_t>(kLanesBytes)) + model + 16;
  if (options.deflate) {
    n += deflate_lanes_bound(static_cast<size_t>(model)) + deflated_bound(model) + 16 +
         deflated_bound(sizeof kContentTypes) + 16 + deflated_bound(sizeof kRels) + 16;
  }
  return n;
}

Status write_3mf(const Context& ctx, Span<const ThreeMfObject> objects,
                 const ThreeMfOptions& options, const ByteSink& sink) {
  if (sink.write == nullptr) {
    return Status::error(StatusCode::kInvalidArgument, "3MF: the sink has no write()");
  }
  SPLINTCORE_RETURN_IF_ERROR(check_objects(objects));
  const uint64_t bound = model_bound(objects, options);
  if (bound > UINT32_MAX) {
    return make_error(StatusCode::kLimitExceeded, "3MF: the model would take up to ", bound,
                      " bytes; at most 4 GiB without ZIP64");
  }
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  LineLanes lines;  // below the model's text, which grows in place above them
  lines.executor = ctx.executor;
  lines.scratch = arena.allocate_array<char>(static_cast<size_t>(kLanesBytes));
  if (lines.scratch == nullptr) return arena.exhausted_status();
  Text model;
  model.arena = &arena;
  model.bytes.bind(&arena);
  model.bound = static_cast<size_t>(bound);
  write_model(lines, objects, options, &model);
  if (model.exhausted) return arena.exhausted_status();
  model.bytes.shrink_to_fit();
  DeflateLanes lanes;
  const size_t plain[3] = {sizeof kContentTypes - 1, sizeof kRels - 1, model.bytes.size()};
  if (options.deflate) {
    SPLINTCORE_RETURN_IF_ERROR(deflate_lanes(arena, plain[2], kDeflateFast, &lanes));
  }
  Entry entries[3];
  ArenaArray<uint8_t> packed[3];
  const char* names[3] = {"[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model"};
  const uint8_t* data[3] = {reinterpret_cast<const uint8_t*>(kContentTypes),
                            reinterpret_cast<const uint8_t*>(kRels), model.bytes.data()};
  for (int k = 0; k < 3; ++k) {  // each grows while it is the top allocation
    packed[k].bind(&arena);
    SPLINTCORE_RETURN_IF_ERROR(pack_entry(ctx, lanes, options.deflate, names[k], data[k], plain[k],
                                          &packed[k], &entries[k]));
  }
  return write_zip(sink, entries, 3);
}

}  // namespace splintcore
