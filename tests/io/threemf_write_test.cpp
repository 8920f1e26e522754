// The 3MF writer (io.h, write_3mf): the package read back by a ZIP reader written here from
// APPNOTE 6.3 (end record, central directory, local headers) with the entries inflated by the
// compress module's decoder (a separate implementation from the encoder) and their CRC-32
// checked; the model's vertices parsed back to the same float32 values, its triangles to the
// same ids; the same bytes every time; every error named; the arena in exactly its bound.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "splintcore/compress.h"
#include "splintcore/io.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

uint32_t get16(const std::vector<uint8_t>& b, size_t at) { return b[at] | (b[at + 1] << 8); }
uint32_t get32(const std::vector<uint8_t>& b, size_t at) {
  return get16(b, at) | (static_cast<uint32_t>(get16(b, at + 2)) << 16);
}

struct ZipEntry {
  std::string name;
  std::string text;
  uint32_t method = 0;
};

// Reads the package through its central directory; every check that fails is a test failure.
std::vector<ZipEntry> read_zip(const std::vector<uint8_t>& zip) {
  std::vector<ZipEntry> out;
  EXPECT_GE(zip.size(), 22u);
  if (zip.size() < 22) return out;
  const size_t end = zip.size() - 22;
  EXPECT_EQ(get32(zip, end), 0x06054b50u);
  const uint32_t count = get16(zip, end + 10);
  const uint32_t dir_size = get32(zip, end + 12), dir = get32(zip, end + 16);
  EXPECT_EQ(size_t{dir} + dir_size, end);
  test::TestArena t(size_t{1} << 20);
  size_t at = dir;
  for (uint32_t i = 0; i < count; ++i) {
    EXPECT_EQ(get32(zip, at), 0x02014b50u);
    ZipEntry e;
    e.method = get16(zip, at + 10);
    const uint32_t crc = get32(zip, at + 16), csize = get32(zip, at + 20);
    const uint32_t usize = get32(zip, at + 24), name_len = get16(zip, at + 28);
    const uint32_t local = get32(zip, at + 42);
    e.name.assign(reinterpret_cast<const char*>(&zip[at + 46]), name_len);
    at += 46 + name_len + get16(zip, at + 30) + get16(zip, at + 32);
    EXPECT_EQ(get32(zip, local), 0x04034b50u);
    EXPECT_EQ(get32(zip, local + 14), crc) << e.name;  // the local header agrees
    EXPECT_EQ(get32(zip, local + 18), csize) << e.name;
    const size_t data = local + 30 + get16(zip, local + 26) + get16(zip, local + 28);
    std::vector<uint8_t> plain(usize);
    if (e.method == 0) {
      EXPECT_EQ(csize, usize);
      std::memcpy(plain.data(), &zip[data], usize);
    } else {
      EXPECT_EQ(e.method, 8u);
      size_t produced = 0;
      SPLINTCORE_EXPECT_OK(inflate_buffer(t.arena, ZFormat::kRaw, &zip[data], csize, plain.data(),
                                          plain.size(), &produced));
      EXPECT_EQ(produced, usize);
    }
    EXPECT_EQ(crc32(0, plain.data(), plain.size()), crc) << e.name;
    e.text.assign(plain.begin(), plain.end());
    out.push_back(e);
  }
  return out;
}

std::vector<uint8_t> write(const std::vector<ThreeMfObject>& objects, const ThreeMfOptions& o,
                           Status* status = nullptr, size_t arena_bytes = size_t{64} << 20,
                           size_t* high_water = nullptr) {
  test::TestArena t(arena_bytes);
  std::vector<uint8_t> bytes;
  ByteSink sink;
  sink.user = &bytes;
  sink.write = [](void* user, const uint8_t* data, size_t n) {
    auto* v = static_cast<std::vector<uint8_t>*>(user);
    v->insert(v->end(), data, data + n);
    return true;
  };
  const Status s = write_3mf(Context(&t.arena),
                             Span<const ThreeMfObject>(objects.data(), objects.size()), o, sink);
  if (status != nullptr) *status = s;
  if (high_water != nullptr) *high_water = t.arena.high_water();
  if (!s.is_ok()) bytes.clear();
  return bytes;
}

// Vertices and triangles of the n-th <object> of the model, parsed back.
void parse_object(const std::string& model, int n, std::vector<float>* xyz,
                  std::vector<uint32_t>* ids) {
  size_t at = 0;
  for (int k = 0; k <= n; ++k) at = model.find("<object ", at + 1);
  const size_t end = model.find("</object>", at);
  for (size_t p = model.find("<vertex ", at); p < end; p = model.find("<vertex ", p + 1)) {
    for (const char* a : {" x=\"", " y=\"", " z=\""}) {
      xyz->push_back(std::strtof(model.c_str() + model.find(a, p) + 4, nullptr));
    }
  }
  for (size_t p = model.find("<triangle ", at); p < end; p = model.find("<triangle ", p + 1)) {
    for (const char* a : {" v1=\"", " v2=\"", " v3=\""}) {
      ids->push_back(
          static_cast<uint32_t>(std::strtoul(model.c_str() + model.find(a, p) + 5, nullptr, 10)));
    }
  }
}

Mesh tetra(Arena& arena, double shift) {
  Mesh m(&arena);
  const Vec3 v[4] = {{0.1 + shift, 0, 0}, {10.25, 0, 1e-7}, {0, 10, -3.5}, {0, 0, 1.0 / 3}};
  for (const Vec3& p : v) {
    Vec3 q = p;
    round_to_float32(&q);
    (void)m.vertices.push_back(q);
  }
  const Triangle t[4] = {{{0, 2, 1}}, {{0, 1, 3}}, {{1, 2, 3}}, {{2, 0, 3}}};
  for (const Triangle& x : t) (void)m.triangles.push_back(x);
  return m;
}

TEST(ThreeMf, PackageReadsBackWithTheSameGeometry) {
  test::TestArena t;
  const Mesh a = tetra(t.arena, 0), b = tetra(t.arena, 30);
  const std::vector<ThreeMfObject> objects = {{&a, "INT <case & \"7\">", "ab12"}, {&b, "FIN", ""}};
  ThreeMfOptions o;
  o.case_id = "case-7";
  o.title = "two splints";
  for (const bool deflate : {true, false}) {
    o.deflate = deflate;
    const std::vector<uint8_t> zip = write(objects, o);
    const std::vector<ZipEntry> entries = read_zip(zip);
    ASSERT_EQ(entries.size(), 3u);
    EXPECT_EQ(entries[0].name, "[Content_Types].xml");
    EXPECT_EQ(entries[1].name, "_rels/.rels");
    EXPECT_EQ(entries[2].name, "3D/3dmodel.model");
    EXPECT_EQ(entries[2].method, deflate ? 8u : 0u);
    EXPECT_NE(entries[1].text.find("Target=\"/3D/3dmodel.model\""), std::string::npos);
    const std::string& model = entries[2].text;
    EXPECT_NE(model.find("unit=\"millimeter\""), std::string::npos);
    EXPECT_NE(model.find("name=\"INT &lt;case &amp; &quot;7&quot;&gt;\""), std::string::npos);
    EXPECT_NE(model.find("<metadata name=\"sc:sha256\">ab12</metadata>"), std::string::npos);
    EXPECT_NE(model.find("<metadata name=\"sc:case_id\">case-7</metadata>"), std::string::npos);
    EXPECT_NE(model.find("<item objectid=\"2\"/>"), std::string::npos);
    for (int k = 0; k < 2; ++k) {
      const Mesh& m = k == 0 ? a : b;
      std::vector<float> xyz;
      std::vector<uint32_t> ids;
      parse_object(model, k, &xyz, &ids);
      ASSERT_EQ(xyz.size(), 3 * m.vertices.size());
      for (size_t v = 0; v < m.vertices.size(); ++v) {
        EXPECT_EQ(xyz[3 * v], static_cast<float>(m.vertices[v].x));
        EXPECT_EQ(xyz[3 * v + 1], static_cast<float>(m.vertices[v].y));
        EXPECT_EQ(xyz[3 * v + 2], static_cast<float>(m.vertices[v].z));
      }
      ASSERT_EQ(ids.size(), 3 * m.triangles.size());
      for (size_t i = 0; i < m.triangles.size(); ++i) {
        for (int c = 0; c < 3; ++c) EXPECT_EQ(ids[3 * i + c], m.triangles[i].v[c]);
      }
    }
    EXPECT_EQ(write(objects, o), zip);  // the same bytes again
  }
}

TEST(ThreeMf, LargeModelIsDeflatedAndRunsInItsBound) {
  test::TestArena t;
  Mesh m(&t.arena);
  // A strip of 20000 triangles.
  for (uint32_t i = 0; i < 10001; ++i) {
    (void)m.vertices.push_back(Vec3{i * 0.25, 0, 0});
    (void)m.vertices.push_back(Vec3{i * 0.25, 1, 0.5});
  }
  for (uint32_t i = 0; i < 10000; ++i) {
    (void)m.triangles.push_back(Triangle{{2 * i, 2 * i + 2, 2 * i + 1}});
    (void)m.triangles.push_back(Triangle{{2 * i + 1, 2 * i + 2, 2 * i + 3}});
  }
  const std::vector<ThreeMfObject> objects = {{&m, "strip", ""}};
  ThreeMfOptions o;
  const uint64_t bound =
      write_3mf_bound(Span<const ThreeMfObject>(objects.data(), objects.size()), o);
  Status s;
  size_t need = 0;
  const std::vector<uint8_t> zip = write(objects, o, &s, static_cast<size_t>(bound), &need);
  SPLINTCORE_ASSERT_OK(s);
  // What it takes besides the encoder's lanes (their bound, for the text as written): the
  // model's text as written (its bound given back) and the compressed entries as they grow,
  // well under the rest of the bound (the text's bound and 9/8 of it deflated).
  const uint64_t lanes = deflate_lanes_bound(SIZE_MAX);  // all lanes: the text is 1.5 MB
  ASSERT_GT(lanes, deflate_lanes_bound(0));
  EXPECT_LT(need - lanes, (bound - lanes) / 2);
  EXPECT_EQ(write(objects, o, &s, need), zip);
  const std::vector<ZipEntry> entries = read_zip(zip);
  ASSERT_EQ(entries.size(), 3u);
  EXPECT_EQ(entries[2].method, 8u);
  EXPECT_LT(zip.size(), entries[2].text.size() / 2);  // the XML compresses well
  std::printf("3MF of 20000 triangles: model %zu bytes, package %zu bytes, bound %llu, need %zu\n",
              entries[2].text.size(), zip.size(), static_cast<unsigned long long>(bound), need);
  // Room for the model's text alone, not its compressed copy: a clean status, nothing written.
  const std::vector<uint8_t> none = write(objects, o, &s, entries[2].text.size() + 4096);
  EXPECT_EQ(s.code(), StatusCode::kArenaExhausted);
  EXPECT_TRUE(none.empty());
}

TEST(ThreeMf, BuildItemsCarryTheTranslation) {
  test::TestArena t;
  const Mesh a = tetra(t.arena, 0);
  std::vector<ThreeMfObject> objects = {{&a, "a", ""}, {&a, "b", ""}};
  objects[1].translation = Vec3{127.5, -0.25, 3};
  const std::vector<ZipEntry> entries = read_zip(write(objects, ThreeMfOptions{}));
  ASSERT_EQ(entries.size(), 3u);
  EXPECT_NE(entries[2].text.find("<item objectid=\"1\"/>"), std::string::npos);
  EXPECT_NE(
      entries[2].text.find("<item objectid=\"2\" transform=\"1 0 0 0 1 0 0 0 1 127.5 -0.25 3\"/>"),
      std::string::npos)
      << entries[2].text.substr(entries[2].text.find("<build>"));
  objects[1].translation.y = NAN;
  Status s;
  write(objects, ThreeMfOptions{}, &s);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
}

TEST(ThreeMf, ErrorsNameTheCause) {
  test::TestArena t;
  Status s;
  ThreeMfOptions o;
  write({}, o, &s);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  Mesh empty(&t.arena);
  write({{&empty, "", ""}}, o, &s);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(test::format(s).find("object 0 has no triangles"), std::string::npos);
  Mesh bad = tetra(t.arena, 0);
  bad.vertices[2].y = NAN;
  const Mesh good = tetra(t.arena, 0);
  write({{&good, "", ""}, {&bad, "", ""}}, o, &s);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_NE(test::format(s).find("object 1 vertex 2"), std::string::npos) << test::format(s);
  bad.vertices[2].y = 1e39;
  write({{&bad, "", ""}}, o, &s);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded);
  Mesh ids = tetra(t.arena, 0);
  ids.triangles[3].v[1] = 9;
  write({{&ids, "", ""}}, o, &s);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(test::format(s).find("triangle 3 refers to vertex 9"), std::string::npos);
  // A sink that refuses.
  ByteSink refuse;
  refuse.write = [](void*, const uint8_t*, size_t) { return false; };
  const ThreeMfObject one{&good, "", ""};
  EXPECT_EQ(write_3mf(Context(&t.arena), Span<const ThreeMfObject>(&one, 1), o, refuse).code(),
            StatusCode::kIoError);
}

}  // namespace
}  // namespace splintcore
