// The preview renderer and PNG encoder (include/splintcore/render.h): PNGs decoded by an
// independent inflate written here (after M. Adler's puff.c, the RFC 1951 reference decoder),
// CRC-32 and Adler-32 against published check values, a cube's silhouette against its
// analytic projections, determinism (twice, and with threads), errors, and the arena
// exhaustion sweep.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "common/shapes.h"
#include "splintcore/render.h"
#include "support/test_util.h"
#if defined(SPLINTCORE_WITH_PLATFORM)
#include "splintcore/platform.h"
#endif

namespace splintcore {
namespace {

// ---- an independent inflate (stored, fixed and dynamic blocks) ------------------------------

struct Bits {
  const uint8_t* data;
  size_t size;
  size_t pos = 0;
  uint32_t buffer = 0;
  int count = 0;
  bool error = false;
  uint32_t take(int need) {
    uint64_t value = buffer;
    while (count < need) {
      if (pos >= size) {
        error = true;
        return 0;
      }
      value |= static_cast<uint64_t>(data[pos++]) << count;
      count += 8;
    }
    buffer = static_cast<uint32_t>(value >> need);
    count -= need;
    return static_cast<uint32_t>(value & ((uint64_t{1} << need) - 1));
  }
};

struct Huffman {
  std::vector<int> count = std::vector<int>(16, 0);
  std::vector<int> symbol;
};

bool build(Huffman* h, const int* lengths, int n) {
  h->count.assign(16, 0);
  h->symbol.assign(static_cast<size_t>(n), 0);
  for (int s = 0; s < n; ++s) h->count[static_cast<size_t>(lengths[s])]++;
  std::vector<int> offset(16, 0);
  for (int len = 1; len < 15; ++len) {
    const size_t l = static_cast<size_t>(len);
    offset[l + 1] = offset[l] + h->count[l];
  }
  for (int s = 0; s < n; ++s) {
    if (lengths[s] == 0) continue;
    h->symbol[static_cast<size_t>(offset[static_cast<size_t>(lengths[s])]++)] = s;
  }
  return true;
}

int decode(Bits& in, const Huffman& h) {
  int code = 0, first = 0, index = 0;
  for (int len = 1; len < 16; ++len) {
    code |= static_cast<int>(in.take(1));
    const int count = h.count[static_cast<size_t>(len)];
    if (code - count < first) return h.symbol[static_cast<size_t>(index + (code - first))];
    index += count;
    first += count;
    first <<= 1;
    code <<= 1;
    if (in.error) return -1;
  }
  return -1;
}

const int kLBase[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                        31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
const int kLExtra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                         2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
const int kDBase[30] = {1,    2,    3,    4,    5,    7,    9,    13,    17,    25,
                        33,   49,   65,   97,   129,  193,  257,  385,   513,   769,
                        1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
const int kDExtra[30] = {0, 0, 0, 0, 1, 1, 2, 2,  3,  3,  4,  4,  5,  5,  6,
                         6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

bool codes(Bits& in, const Huffman& lit, const Huffman& dist, std::vector<uint8_t>* out) {
  for (;;) {
    const int s = decode(in, lit);
    if (s < 0 || in.error) return false;
    if (s < 256) {
      out->push_back(static_cast<uint8_t>(s));
    } else if (s == 256) {
      return true;
    } else {
      const int li = s - 257;
      if (li >= 29) return false;
      const int len = kLBase[li] + static_cast<int>(in.take(kLExtra[li]));
      const int di = decode(in, dist);
      if (di < 0 || di >= 30) return false;
      const size_t d = static_cast<size_t>(kDBase[di]) + in.take(kDExtra[di]);
      if (d > out->size() || in.error) return false;
      for (int k = 0; k < len; ++k) out->push_back((*out)[out->size() - d]);
    }
  }
}

// Inflates a zlib stream (header, deflate blocks, Adler-32 checked).
bool zlib_inflate(const std::vector<uint8_t>& z, std::vector<uint8_t>* out) {
  if (z.size() < 6 || (z[0] & 0x0F) != 8 || ((z[0] << 8) | z[1]) % 31 != 0) return false;
  Bits in{z.data() + 2, z.size() - 2};
  int last = 0;
  do {
    last = static_cast<int>(in.take(1));
    const uint32_t type = in.take(2);
    if (type == 0) {
      in.buffer = 0;
      in.count = 0;
      if (in.pos + 4 > in.size) return false;
      const size_t len = in.data[in.pos] | (in.data[in.pos + 1] << 8);
      in.pos += 4;
      if (in.pos + len > in.size) return false;
      out->insert(out->end(), in.data + in.pos, in.data + in.pos + len);
      in.pos += len;
    } else if (type == 1) {
      int lengths[288 + 30];
      for (int s = 0; s < 288; ++s) lengths[s] = s < 144 ? 8 : s < 256 ? 9 : s < 280 ? 7 : 8;
      for (int s = 0; s < 30; ++s) lengths[288 + s] = 5;
      Huffman lit, dist;
      build(&lit, lengths, 288);
      build(&dist, lengths + 288, 30);
      if (!codes(in, lit, dist, out)) return false;
    } else if (type == 2) {
      const int nlen = static_cast<int>(in.take(5)) + 257, ndist = static_cast<int>(in.take(5)) + 1,
                ncode = static_cast<int>(in.take(4)) + 4;
      static const int kOrder[19] = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                     11, 4,  12, 3, 13, 2, 14, 1, 15};
      int lengths[320] = {};
      for (int i = 0; i < ncode; ++i) lengths[kOrder[i]] = static_cast<int>(in.take(3));
      Huffman lencode;
      build(&lencode, lengths, 19);
      int index = 0;
      while (index < nlen + ndist) {
        int symbol = decode(in, lencode);
        if (symbol < 0) return false;
        if (symbol < 16) {
          lengths[index++] = symbol;
        } else {
          int len = 0, repeat = 0;
          if (symbol == 16) {
            if (index == 0) return false;
            len = lengths[index - 1];
            repeat = 3 + static_cast<int>(in.take(2));
          } else if (symbol == 17) {
            repeat = 3 + static_cast<int>(in.take(3));
          } else {
            repeat = 11 + static_cast<int>(in.take(7));
          }
          if (index + repeat > nlen + ndist) return false;
          while (repeat-- > 0) lengths[index++] = len;
        }
      }
      Huffman lit, dist;
      build(&lit, lengths, nlen);
      build(&dist, lengths + nlen, ndist);
      if (!codes(in, lit, dist, out)) return false;
    } else {
      return false;
    }
    if (in.error) return false;
  } while (!last);
  // Adler-32, big-endian, after the last block (byte aligned).
  if (in.pos + 4 > in.size) return false;
  const uint32_t stored = (static_cast<uint32_t>(in.data[in.pos]) << 24) |
                          (static_cast<uint32_t>(in.data[in.pos + 1]) << 16) |
                          (static_cast<uint32_t>(in.data[in.pos + 2]) << 8) | in.data[in.pos + 3];
  uint32_t a = 1, b = 0;  // Adler-32 the slow way (not the library's)
  for (uint8_t c : *out) {
    a = (a + c) % 65521;
    b = (b + a) % 65521;
  }
  return stored == ((b << 16) | a) && in.pos + 4 == in.size;
}

uint32_t be32(const uint8_t* p) {
  return (static_cast<uint32_t>(p[0]) << 24) | (static_cast<uint32_t>(p[1]) << 16) |
         (static_cast<uint32_t>(p[2]) << 8) | p[3];
}

uint32_t slow_crc32(const uint8_t* p, size_t n) {  // bitwise, not the library's table
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

// Decodes an 8-bit RGB PNG: chunks (CRC checked), IDAT inflated, rows unfiltered.
::testing::AssertionResult decode_png(const std::vector<uint8_t>& png, uint32_t* w, uint32_t* h,
                                      std::vector<uint8_t>* rgb) {
  static const uint8_t kSig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (png.size() < 8 || std::memcmp(png.data(), kSig, 8) != 0) {
    return ::testing::AssertionFailure() << "no PNG signature";
  }
  size_t p = 8;
  std::vector<uint8_t> idat;
  std::vector<std::string> order;
  while (p + 12 <= png.size()) {
    const uint32_t n = be32(&png[p]);
    if (p + 12 + n > png.size()) return ::testing::AssertionFailure() << "chunk past the end";
    const std::string type(reinterpret_cast<const char*>(&png[p + 4]), 4);
    if (slow_crc32(&png[p + 4], n + 4) != be32(&png[p + 8 + n])) {
      return ::testing::AssertionFailure() << "bad CRC in " << type;
    }
    if (type == "IHDR") {
      if (n != 13) return ::testing::AssertionFailure() << "IHDR size";
      *w = be32(&png[p + 8]);
      *h = be32(&png[p + 12]);
      if (png[p + 16] != 8 || png[p + 17] != 2 || png[p + 18] != 0 || png[p + 19] != 0 ||
          png[p + 20] != 0) {
        return ::testing::AssertionFailure() << "not 8-bit RGB, deflate, no interlace";
      }
    }
    if (type == "IDAT")
      idat.insert(idat.end(), png.begin() + static_cast<long>(p + 8),
                  png.begin() + static_cast<long>(p + 8 + n));
    order.push_back(type);
    p += 12 + n;
  }
  if (p != png.size()) return ::testing::AssertionFailure() << "bytes after the last chunk";
  if (order.empty() || order.front() != "IHDR" || order.back() != "IEND") {
    return ::testing::AssertionFailure() << "IHDR first and IEND last";
  }
  std::vector<uint8_t> raw;
  if (!zlib_inflate(idat, &raw)) return ::testing::AssertionFailure() << "IDAT does not inflate";
  const size_t stride = static_cast<size_t>(*w) * 3 + 1;
  if (raw.size() != stride * *h) {
    return ::testing::AssertionFailure()
           << "inflated " << raw.size() << " bytes, expected " << stride * *h;
  }
  rgb->assign(static_cast<size_t>(*w) * *h * 3, 0);
  const size_t row = stride - 1;
  for (size_t y = 0; y < *h; ++y) {
    const uint8_t type = raw[y * stride];
    const uint8_t* in = &raw[y * stride + 1];
    uint8_t* out = &(*rgb)[y * row];
    const uint8_t* up = y > 0 ? out - row : nullptr;
    for (size_t i = 0; i < row; ++i) {
      const int a = i >= 3 ? out[i - 3] : 0, b = up ? up[i] : 0, c = (i >= 3 && up) ? up[i - 3] : 0;
      int pred = 0;
      if (type == 1) pred = a;
      if (type == 2) pred = b;
      if (type == 3) pred = (a + b) / 2;
      if (type == 4) {
        const int pp = a + b - c;
        const int pa = std::abs(pp - a), pb = std::abs(pp - b), pc = std::abs(pp - c);
        pred = (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
      }
      if (type > 4) return ::testing::AssertionFailure() << "filter type " << int(type);
      out[i] = static_cast<uint8_t>(in[i] + pred);
    }
  }
  return ::testing::AssertionSuccess();
}

bool vector_write(void* user, const uint8_t* data, size_t bytes) {
  auto* out = static_cast<std::vector<uint8_t>*>(user);
  out->insert(out->end(), data, data + bytes);
  return true;
}

Status encode(Arena& arena, const RenderImage& image, std::vector<uint8_t>* png) {
  png->clear();
  ByteSink sink;
  sink.write = &vector_write;
  sink.user = png;
  sink.name = "memory";
  return write_png(Context(&arena), image, sink);
}

Status draw(Arena& arena, const RenderMesh* items, size_t count, const RenderOptions& o,
            RenderImage* image) {
  return render_meshes(Context(&arena), Span<const RenderMesh>(items, count), o, image);
}

// draw() on `threads` worker threads (one: no executor; without the platform layer, always one).
Status draw_on_threads(Arena& arena, uint32_t threads, const RenderMesh* items, size_t count,
                       const RenderOptions& o, RenderImage* image) {
#if defined(SPLINTCORE_WITH_PLATFORM)
  if (threads > 1) {
    ThreadExecutor executor(threads);
    Context ctx(&arena, &executor.executor(), nullptr);
    return render_meshes(ctx, Span<const RenderMesh>(items, count), o, image);
  }
#endif
  (void)threads;
  return draw(arena, items, count, o, image);
}

Mesh cube_mesh(Arena& arena, float lo, float hi) {
  const float l[3] = {lo, lo, lo}, u[3] = {hi, hi, hi};
  Mesh m;
  Status s = test::mesh_from_soup(arena, shapes::box(l, u), &m);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return m;
}

// Pixels of the tile that differ from the background.
uint64_t covered(const RenderImage& image, const uint8_t background[3]) {
  uint64_t n = 0;
  for (size_t i = 0; i < static_cast<size_t>(image.width) * image.height; ++i) {
    if (std::memcmp(image.rgb + i * 3, background, 3) != 0) ++n;
  }
  return n;
}

// ---- checksums -----------------------------------------------------------------------------

TEST(RenderPng, Crc32AndAdler32MatchPublishedCheckValues) {
  const uint8_t* digits = reinterpret_cast<const uint8_t*>("123456789");
  EXPECT_EQ(png_crc32(0, digits, 9), 0xCBF43926u);  // the CRC-32 catalogue's check value
  EXPECT_EQ(png_crc32(png_crc32(0, digits, 4), digits + 4, 5), 0xCBF43926u);  // chained
  EXPECT_EQ(png_crc32(0, nullptr, 0), 0u);
  const uint8_t iend[4] = {'I', 'E', 'N', 'D'};
  EXPECT_EQ(png_crc32(0, iend, 4), 0xAE426082u);  // every PNG's last four bytes
  const uint8_t* wiki = reinterpret_cast<const uint8_t*>("Wikipedia");
  EXPECT_EQ(png_adler32(1, wiki, 9), 0x11E60398u);
  EXPECT_EQ(png_adler32(png_adler32(1, wiki, 3), wiki + 3, 6), 0x11E60398u);
  EXPECT_EQ(png_adler32(1, nullptr, 0), 1u);
  // Long input: the modulo is taken in time (5552-byte blocks).
  std::vector<uint8_t> ff(100000, 0xFF);
  uint32_t a = 1, b = 0;
  for (uint8_t c : ff) {
    a = (a + c) % 65521;
    b = (b + a) % 65521;
  }
  EXPECT_EQ(png_adler32(1, ff.data(), ff.size()), (b << 16) | a);
  EXPECT_EQ(png_crc32(0, ff.data(), ff.size()), slow_crc32(ff.data(), ff.size()));
}

// ---- PNG round trips -------------------------------------------------------------------------

TEST(RenderPng, RoundTripsNoiseGradientsAndFlatAreas) {
  test::TestArena t(8 << 20);
  const uint32_t sizes[][2] = {{1, 1}, {7, 3}, {64, 64}, {300, 17}, {5, 200}};
  uint64_t state = 12345;
  for (const auto& wh : sizes) {
    const uint32_t w = wh[0], h = wh[1];
    std::vector<uint8_t> pixels(static_cast<size_t>(w) * h * 3);
    for (size_t y = 0; y < h; ++y) {
      for (size_t x = 0; x < w; ++x) {
        uint8_t* p = &pixels[(y * w + x) * 3];
        if (x < w / 3) {  // noise: literals
          for (int k = 0; k < 3; ++k) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            p[k] = static_cast<uint8_t>(state >> 56);
          }
        } else if (x < 2 * w / 3) {  // gradients: Sub/Up/Paeth
          p[0] = static_cast<uint8_t>(x * 3);
          p[1] = static_cast<uint8_t>(y * 5);
          p[2] = static_cast<uint8_t>(x + y);
        } else {  // flat: long matches
          p[0] = 250;
          p[1] = 250;
          p[2] = 250;
        }
      }
    }
    RenderImage image;
    image.width = w;
    image.height = h;
    image.rgb = pixels.data();
    std::vector<uint8_t> png;
    SPLINTCORE_ASSERT_OK(encode(t.arena, image, &png));
    uint32_t dw = 0, dh = 0;
    std::vector<uint8_t> back;
    ASSERT_TRUE(decode_png(png, &dw, &dh, &back)) << w << "x" << h;
    EXPECT_EQ(dw, w);
    EXPECT_EQ(dh, h);
    EXPECT_EQ(back, pixels) << w << "x" << h;
    EXPECT_EQ(t.arena.used(), 0u);  // temporaries returned
    EXPECT_LE(t.arena.high_water(), png_bound(w, h));
    t.arena.reset_high_water();
  }
}

TEST(RenderPng, FlatImageCompressesWell) {
  test::TestArena t(16 << 20);
  std::vector<uint8_t> pixels(512 * 512 * 3, 200);
  RenderImage image;
  image.width = image.height = 512;
  image.rgb = pixels.data();
  std::vector<uint8_t> png;
  SPLINTCORE_ASSERT_OK(encode(t.arena, image, &png));
  EXPECT_LT(png.size(), 8000u);  // 786 KB of one colour: LZ77, not stored blocks
  uint32_t w = 0, h = 0;
  std::vector<uint8_t> back;
  ASSERT_TRUE(decode_png(png, &w, &h, &back));
  EXPECT_EQ(back, pixels);
}

TEST(RenderPng, RejectsBadSizesAndReportsSinkFailures) {
  test::TestArena t(8 << 20);
  uint8_t px[3] = {1, 2, 3};
  RenderImage image;
  image.width = 1;
  image.height = 1;
  image.rgb = px;
  std::vector<uint8_t> png;
  RenderImage zero = image;
  zero.width = 0;
  EXPECT_EQ(encode(t.arena, zero, &png).code(), StatusCode::kInvalidArgument);
  RenderImage huge = image;
  huge.height = kRenderMaxSide + 1;
  EXPECT_EQ(encode(t.arena, huge, &png).code(), StatusCode::kInvalidArgument);
  ByteSink failing;
  failing.write = [](void*, const uint8_t*, size_t) { return false; };
  failing.name = "full.png";
  Status s = write_png(Context(&t.arena), image, failing);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_STREQ(s.file(), "full.png");
}

// ---- the rasteriser --------------------------------------------------------------------------

TEST(Render, CubeSilhouettesMatchTheAnalyticProjections) {
  test::TestArena t(64 << 20);
  Mesh cube = cube_mesh(t.arena, 0, 10);
  RenderMesh item;
  item.mesh = &cube;
  item.rgb[0] = 200;
  item.rgb[1] = 40;
  item.rgb[2] = 40;
  // Top and front: a 10 x 10 square; iso (along a diagonal): a regular hexagon of area
  // 100 sqrt(3) (the sum over faces of |n . d| times the face area, 3 x 100 / sqrt(3)).
  // Pixel centres inside: the area in pixels, give or take a quarter of the perimeter's pixels
  // (a sub-pixel error of the scale or framing would be far more: 1% of scale is 2% of area).
  struct Case {
    RenderView view;
    double area_mm2;
    double perimeter_mm;
  } cases[] = {{RenderView::kTop, 100, 40},
               {RenderView::kFront, 100, 40},
               {RenderView::kRight, 100, 40},
               {RenderView::kIso, 100 * std::sqrt(3.0), 60 * std::sqrt(2.0 / 3.0)}};
  for (const Case& c : cases) {
    for (RenderShading shading : {RenderShading::kFlat, RenderShading::kGouraud}) {
      ArenaScope scope(t.arena);  // the cube stays
      RenderOptions o;
      o.width = 301;
      o.height = 257;
      o.views[0] = c.view;
      o.view_count = 1;
      o.shading = shading;
      RenderImage image;
      SPLINTCORE_ASSERT_OK(draw(t.arena, &item, 1, o, &image));
      ASSERT_GT(image.pixels_per_mm, 0);
      const double s = image.pixels_per_mm;
      const double expected = c.area_mm2 * s * s;
      const double perimeter = c.perimeter_mm * s;
      const double got = static_cast<double>(covered(image, o.background));
      EXPECT_NEAR(got, expected, 0.25 * perimeter + 4)
          << render_view_name(c.view) << " scale " << s;
    }
  }
}

TEST(Render, SharedEdgesAreDrawnOnceAndTilesShareOneScale) {
  test::TestArena t(64 << 20);
  // A square of two triangles in the plane z = 0 seen from the top: the diagonal's pixels
  // belong to exactly one triangle, so a translucent square blends each pixel once: every
  // covered pixel has the same colour.
  Mesh square(&t.arena);
  ASSERT_TRUE(square.vertices.push_back({0, 0, 0}) && square.vertices.push_back({7, 0, 0}) &&
              square.vertices.push_back({7, 7, 0}) && square.vertices.push_back({0, 7, 0}));
  ASSERT_TRUE(square.triangles.push_back({{0, 1, 2}}) && square.triangles.push_back({{0, 2, 3}}));
  RenderMesh item;
  item.mesh = &square;
  item.alpha = 128;
  RenderOptions o;
  o.width = 200;
  o.height = 100;
  o.views[0] = RenderView::kTop;
  o.views[1] = RenderView::kIso;
  o.view_count = 2;
  RenderImage image;
  SPLINTCORE_ASSERT_OK(draw(t.arena, &item, 1, o, &image));
  EXPECT_EQ(image.columns, 2u);
  EXPECT_EQ(image.tile_width, 100u);
  EXPECT_EQ(image.tile_height, 100u);
  const uint8_t* first = nullptr;
  uint64_t n = 0;
  for (uint32_t y = 0; y < 100; ++y) {
    for (uint32_t x = 0; x < 99; ++x) {  // the top view's tile, without the separator
      const uint8_t* p = image.rgb + (static_cast<size_t>(y) * 200 + x) * 3;
      if (std::memcmp(p, o.background, 3) == 0) continue;
      if (first == nullptr) first = p;
      EXPECT_EQ(std::memcmp(p, first, 3), 0) << x << "," << y;
      ++n;
    }
  }
  const double side = 7 * image.pixels_per_mm;
  EXPECT_NEAR(static_cast<double>(n), side * side, 2 * side + 4);
}

// A mesh that exercises every case of the rasteriser's coverage decisions: a jittered grid of
// cells (shared edges, both orientations) and a soup of sub-pixel triangles, one-pixel
// triangles and long slivers, their corners on a 1/4 mm lattice (pixel centres and pixel edges
// at 1 pixel a mm, so many edges pass exactly through pixel centres) or 1/512 mm off it, at
// depths on a 1/64 mm lattice (depth ties). Deterministic (a fixed linear congruential
// sequence).
Mesh coverage_stress_mesh(Arena& arena) {
  uint64_t state = 0x2545F4914F6CDD1Dull;
  auto next = [&state](uint32_t n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<uint32_t>((state >> 33) % n);
  };
  auto coordinate = [&next](double lo, uint32_t quarters) {
    const double jitter = next(4) == 0 ? (static_cast<double>(next(5)) - 2.0) / 512.0 : 0.0;
    return lo + 0.25 * next(quarters) + jitter;
  };
  Mesh m(&arena);
  bool ok = true;
  const uint32_t side = 24;  // grid vertices a side, 3.5 mm apart from -40 mm
  for (uint32_t j = 0; j < side; ++j) {
    for (uint32_t i = 0; i < side; ++i) {
      const double x = -40 + 3.5 * i + (next(3) == 0 ? 0.25 * next(3) : 0.0);
      const double y = -40 + 3.5 * j + (next(3) == 0 ? 0.25 * next(3) : 0.0);
      ok = ok && m.vertices.push_back({x, y, 0.015625 * next(64)});
    }
  }
  for (uint32_t j = 0; j + 1 < side; ++j) {
    for (uint32_t i = 0; i + 1 < side; ++i) {
      const uint32_t a = j * side + i, b = a + 1, c = a + side, d = c + 1;
      if ((i + j) % 2 == 0) {
        ok = ok && m.triangles.push_back({{a, b, d}}) && m.triangles.push_back({{a, d, c}});
      } else {
        ok = ok && m.triangles.push_back({{a, b, c}}) && m.triangles.push_back({{b, d, c}});
      }
    }
  }
  for (int k = 0; k < 6000; ++k) {
    const double size = k % 3 == 0 ? 0.75 : (k % 3 == 1 ? 2.0 : 12.0);  // quarters of a mm
    const double x0 = coordinate(-44, 352), y0 = coordinate(-44, 352), z0 = coordinate(-44, 352);
    const uint32_t base = static_cast<uint32_t>(m.vertices.size());
    for (int v = 0; v < 3; ++v) {
      const uint32_t q = static_cast<uint32_t>(size * 4) + 1;
      const bool sliver = k % 5 == 0 && v == 2;
      ok = ok && m.vertices.push_back(
                     {coordinate(x0, sliver ? 8 * q : q), coordinate(y0, q), coordinate(z0, q)});
    }
    ok = ok && m.triangles.push_back({{base, base + 1 + (k & 1), base + 2 - (k & 1)}});
  }
  EXPECT_TRUE(ok);
  return m;
}

// The stress mesh drawn flat, with Gouraud shading, with a per-vertex scalar and translucent,
// in four views at 1 pixel a mm: pinned bytes, recorded with the per-pixel rasteriser the
// faster one replaced (the same coverage, depth and shading decisions bit for bit).
TEST(Render, PinnedCoverageOfTiedAndSubpixelTriangles) {
  test::TestArena t(64 << 20);
  Mesh m = coverage_stress_mesh(t.arena);
  std::vector<double> scalars(m.vertices.size());
  for (size_t i = 0; i < scalars.size(); ++i) scalars[i] = static_cast<double>(i % 97);
  RenderFraming framing;
  framing.pixels_per_mm = 1;
  RenderOptions o;
  o.width = 192;
  o.height = 192;
  o.framing = &framing;
  const RigidTransform shift = RigidTransform::translation({0.25, 0.5, 0.375});
  const char* expected[3] = {"7c23d44765254e80a206dd83e45413acafc2748533891732376a2bae90c1cd56",
                             "b8d83428ad5c7b1e9b2918e5109285b7af6a2c1c22c3383acf1b8bb61c29b2b0",
                             "e0c7fb8c7864ba3396a1f40d727f2ee5fbbcd33497ccf6b277a4e6578be12353"};
  for (int variant = 0; variant < 3; ++variant) {
    RenderMesh items[2];
    items[0].mesh = &m;
    items[1].mesh = &m;
    items[1].transform = &shift;  // in front of the opaque copy in places, behind in others
    items[1].alpha = 100;
    items[1].rgb[0] = 40;
    if (variant == 2) items[0].scalars = scalars.data();
    items[0].scalar_max = 96;
    o.shading = variant == 1 ? RenderShading::kGouraud : RenderShading::kFlat;
    ArenaScope scope(t.arena);
    RenderImage image;
    SPLINTCORE_ASSERT_OK(
        render_meshes(Context(&t.arena), Span<const RenderMesh>(items, 2), o, &image));
    EXPECT_EQ(test::sha256_hex(image.rgb, size_t{192} * 192 * 3), expected[variant])
        << "variant " << variant;
  }
}

TEST(Render, NearerSurfaceWinsAndTranslucentBlends) {
  test::TestArena t(64 << 20);
  Mesh back = cube_mesh(t.arena, 0, 10);
  Mesh front = cube_mesh(t.arena, 3, 7);  // inside the big one: hidden when both are opaque
  RenderMesh items[2];
  items[0].mesh = &back;
  items[0].rgb[0] = 0;
  items[0].rgb[1] = 0;
  items[0].rgb[2] = 255;
  items[1].mesh = &front;
  items[1].rgb[0] = 255;
  items[1].rgb[1] = 0;
  items[1].rgb[2] = 0;
  RenderOptions o;
  o.width = o.height = 100;
  o.views[0] = RenderView::kTop;
  o.view_count = 1;
  RenderImage image;
  {
    ArenaScope scope(t.arena);
    SPLINTCORE_ASSERT_OK(draw(t.arena, items, 2, o, &image));
    const uint8_t* centre = image.rgb + (50 * 100 + 50) * 3;
    EXPECT_EQ(centre[0], 0);  // the big cube's top hides the small one
    EXPECT_GT(centre[2], 0);
  }
  // The big cube translucent: the small red one shows through at the centre.
  items[0].alpha = 100;
  SPLINTCORE_ASSERT_OK(draw(t.arena, items, 2, o, &image));
  const uint8_t* centre = image.rgb + (50 * 100 + 50) * 3;
  EXPECT_GT(centre[0], 0);
  EXPECT_GT(centre[2], 0);
}

TEST(Render, ScalarsFollowTheRampAndTheLegendIsDrawn) {
  uint8_t rgb[3];
  render_ramp_colour(0, 2, rgb);
  EXPECT_EQ(rgb[0], 0);
  EXPECT_EQ(rgb[1], 0);
  EXPECT_EQ(rgb[2], 255);
  render_ramp_colour(1, 2, rgb);
  EXPECT_EQ(rgb[1], 255);
  render_ramp_colour(5, 2, rgb);
  EXPECT_EQ(rgb[0], 255);
  EXPECT_EQ(rgb[2], 0);
  render_ramp_colour(std::nan(""), 2, rgb);
  EXPECT_EQ(rgb[2], 255);

  test::TestArena t(64 << 20);
  Mesh cube = cube_mesh(t.arena, 0, 10);
  std::vector<double> height(cube.vertices.size());
  for (size_t i = 0; i < height.size(); ++i) height[i] = cube.vertices[i].z;
  RenderMesh item;
  item.mesh = &cube;
  item.scalars = height.data();
  item.scalar_max = 10;
  RenderOptions o;
  o.width = 120;
  o.height = 100;
  o.views[0] = RenderView::kTop;  // the top face: z = 10 everywhere, red (times the shading)
  o.view_count = 1;
  o.legend = true;
  RenderImage image;
  SPLINTCORE_ASSERT_OK(draw(t.arena, &item, 1, o, &image));
  EXPECT_EQ(image.tile_width, 120u - 8u);
  const uint8_t* centre = image.rgb + (50 * 120 + 56) * 3;
  EXPECT_GT(centre[0], 150);
  EXPECT_EQ(centre[1], 0);
  EXPECT_EQ(centre[2], 0);
  const uint8_t* bar_top = image.rgb + (6 * 120 + 116) * 3;
  const uint8_t* bar_bottom = image.rgb + (93 * 120 + 116) * 3;
  EXPECT_GT(bar_top[0], 240);     // red at the top
  EXPECT_GT(bar_bottom[2], 240);  // blue at the bottom
}

TEST(Render, SameBytesTwiceAndWithThreads) {
  test::TestArena t(256 << 20);
  Mesh torus;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, shapes::torus(48, 24, 10, 3), &torus));
  Mesh cube = cube_mesh(t.arena, -4, 4);
  RenderMesh items[2];
  items[0].mesh = &cube;
  items[0].alpha = 150;
  items[1].mesh = &torus;
  RenderOptions o;
  o.width = 320;
  o.height = 240;
  o.shading = RenderShading::kGouraud;
  std::vector<std::vector<uint8_t>> pngs;
  for (int run = 0; run < 3; ++run) {
    ArenaScope scope(t.arena);
    RenderImage image;
    SPLINTCORE_ASSERT_OK(draw_on_threads(t.arena, run == 2 ? 3 : 1, items, 2, o, &image));
    std::vector<uint8_t> png;
    SPLINTCORE_ASSERT_OK(encode(t.arena, image, &png));
    pngs.push_back(png);
  }
  EXPECT_EQ(pngs[0], pngs[1]);
  EXPECT_EQ(pngs[0], pngs[2]);
  uint32_t w = 0, h = 0;
  std::vector<uint8_t> back;
  ASSERT_TRUE(decode_png(pngs[0], &w, &h, &back));
  EXPECT_EQ(w, 320u);
  EXPECT_EQ(h, 240u);
}

// The framing of a mesh of several chunks of vertices (validate's pass in chunks on the
// executor) is the box of its vertices taken one by one, strict comparisons keeping the first of
// equal values (-0 before +0), at 1 and 3 threads.
TEST(Render, FramingInChunksIsTheBoxOfTheVerticesInOrder) {
  test::TestArena t(64 << 20);
  Mesh m(&t.arena);
  const size_t n = 40000;  // 3 chunks of 16384 vertices
  ASSERT_TRUE(m.vertices.resize(n));
  for (size_t i = 0; i < n; ++i) {
    // The top view's u = x*1 + y*0 + z*0 keeps x's sign of zero (y, z < 0): -0 at vertex 0 and
    // every third, +0 elsewhere (the second chunk starts with +0). v = y: least in the second
    // chunk, most in the third.
    const double x = i % 3 == 0 ? -0.0 : 0.0;
    const double y = i == 20000 ? -200.0 : (i == 39000 ? -0.5 : -1.0 - static_cast<double>(i % 7));
    m.vertices[i] = Vec3(x, y, -1);
  }
  RenderMesh item;
  item.mesh = &m;
  RenderOptions o;
  o.width = 64;
  o.height = 64;
  RenderFraming framing[2];
  for (int run = 0; run < 2; ++run) {
    ArenaScope scope(t.arena);
    RenderImage image;
    SPLINTCORE_ASSERT_OK(draw_on_threads(t.arena, run == 1 ? 3 : 1, &item, 1, o, &image));
    framing[run] = image.framing;
  }
  EXPECT_TRUE(std::signbit(framing[0].centre_u[1]));  // -0: lo and hi both vertex 0's
  EXPECT_EQ(framing[0].centre_u[1], 0.0);
  EXPECT_EQ(framing[0].centre_v[1], 0.5 * -200.0 + 0.5 * -0.5);
  EXPECT_EQ(0, std::memcmp(&framing[0], &framing[1], sizeof(RenderFraming)));
}

// A mesh drawn with a transform gives the bytes of its moved copy (flat and Gouraud), and a
// second pass given the first's framing draws into the same places as a pass that frames the
// same vertices itself.
TEST(Render, TransformIsTheMovedCopyAndFramingIsReused) {
  test::TestArena t(256 << 20);
  Mesh torus;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, shapes::torus(40, 20, 10, 3), &torus));
  Mesh cube = cube_mesh(t.arena, -4, 4);
  const Vec3 axis = Vec3(1, 2, 3) * (1 / length(Vec3(1, 2, 3)));
  const RigidTransform move =
      compose(RigidTransform::translation({3, -2, 5}), rotation_about_axis({1, 2, 0}, axis, 0.7));
  Mesh moved;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, shapes::torus(40, 20, 10, 3), &moved));
  for (size_t i = 0; i < moved.vertices.size(); ++i) {
    moved.vertices[i] = move.apply_point(torus.vertices[i]);
  }
  for (RenderShading shading : {RenderShading::kFlat, RenderShading::kGouraud}) {
    RenderOptions o;
    o.width = 200;
    o.height = 160;
    o.shading = shading;
    RenderMesh a[2], b[2];
    a[0].mesh = b[0].mesh = &cube;
    a[1].mesh = &torus;
    a[1].transform = &move;
    a[1].alpha = b[1].alpha = 120;
    b[1].mesh = &moved;
    ArenaScope scope(t.arena);
    RenderImage ia, ib;
    SPLINTCORE_ASSERT_OK(render_meshes(Context(&t.arena), Span<const RenderMesh>(a, 2), o, &ia));
    SPLINTCORE_ASSERT_OK(render_meshes(Context(&t.arena), Span<const RenderMesh>(b, 2), o, &ib));
    ASSERT_EQ(0, std::memcmp(ia.rgb, ib.rgb, size_t{200} * 160 * 3));
    EXPECT_EQ(ia.framing.pixels_per_mm, ia.pixels_per_mm);

    // The cube alone in the framing of (cube + moved torus) = the cube with the torus's
    // vertices but no triangles, framed by itself.
    Mesh vertices_only;
    SPLINTCORE_ASSERT_OK(
        test::mesh_from_soup(t.arena, shapes::torus(40, 20, 10, 3), &vertices_only));
    for (size_t i = 0; i < vertices_only.vertices.size(); ++i) {
      vertices_only.vertices[i] = moved.vertices[i];
    }
    vertices_only.triangles.clear();
    RenderMesh c[2];
    c[0].mesh = &cube;
    c[1].mesh = &vertices_only;
    RenderImage ic, id;
    SPLINTCORE_ASSERT_OK(render_meshes(Context(&t.arena), Span<const RenderMesh>(c, 2), o, &ic));
    RenderOptions given = o;
    given.framing = &ia.framing;
    SPLINTCORE_ASSERT_OK(
        render_meshes(Context(&t.arena), Span<const RenderMesh>(c, 1), given, &id));
    EXPECT_EQ(0, std::memcmp(ic.rgb, id.rgb, size_t{200} * 160 * 3));
    EXPECT_EQ(id.framing.pixels_per_mm, ia.framing.pixels_per_mm);

    RenderFraming bad = ia.framing;
    bad.pixels_per_mm = 0;
    given.framing = &bad;
    const Status s = render_meshes(Context(&t.arena), Span<const RenderMesh>(c, 1), given, &id);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    bad.pixels_per_mm = ia.framing.pixels_per_mm;
    bad.centre_v[3] = std::nan("");
    EXPECT_EQ(render_meshes(Context(&t.arena), Span<const RenderMesh>(c, 1), given, &id).code(),
              StatusCode::kInvalidArgument);
  }
}

TEST(Render, RejectsBadArgumentsAndMeshes) {
  test::TestArena t(16 << 20);
  Context ctx(&t.arena);
  Mesh cube = cube_mesh(t.arena, 0, 1);
  RenderMesh item;
  item.mesh = &cube;
  RenderImage image;
  RenderOptions o;
  o.width = 0;
  EXPECT_EQ(render_meshes(ctx, Span<const RenderMesh>(&item, 1), o, &image).code(),
            StatusCode::kInvalidArgument);
  o.width = kRenderMaxSide + 1;
  EXPECT_EQ(render_meshes(ctx, Span<const RenderMesh>(&item, 1), o, &image).code(),
            StatusCode::kInvalidArgument);
  o = RenderOptions{};
  o.view_count = 0;
  EXPECT_EQ(render_meshes(ctx, Span<const RenderMesh>(&item, 1), o, &image).code(),
            StatusCode::kInvalidArgument);
  o = RenderOptions{};
  o.width = 1;  // two columns of tiles cannot fit
  EXPECT_EQ(render_meshes(ctx, Span<const RenderMesh>(&item, 1), o, &image).code(),
            StatusCode::kInvalidArgument);
  o = RenderOptions{};
  RenderMesh null_item;
  EXPECT_EQ(render_meshes(ctx, Span<const RenderMesh>(&null_item, 1), o, &image).code(),
            StatusCode::kInvalidArgument);
  Mesh broken(&t.arena);
  ASSERT_TRUE(broken.vertices.push_back({0, 0, 0}) && broken.triangles.push_back({{0, 0, 5}}));
  RenderMesh bad;
  bad.mesh = &broken;
  Status s = render_meshes(ctx, Span<const RenderMesh>(&bad, 1), o, &image);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.index(), 0u);
  Mesh nan_mesh(&t.arena);
  ASSERT_TRUE(nan_mesh.vertices.push_back({0, std::nan(""), 0}));
  bad.mesh = &nan_mesh;
  EXPECT_EQ(render_meshes(ctx, Span<const RenderMesh>(&bad, 1), o, &image).code(),
            StatusCode::kNonFinite);
  std::vector<double> scalars(cube.vertices.size(), 1.0);
  item.scalars = scalars.data();
  item.scalar_max = 0;
  EXPECT_EQ(render_meshes(ctx, Span<const RenderMesh>(&item, 1), o, &image).code(),
            StatusCode::kInvalidArgument);
  item.scalar_max = 1;
  scalars[3] = std::nan("");
  s = render_meshes(ctx, Span<const RenderMesh>(&item, 1), o, &image);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_EQ(s.index(), 3u);
  // Absurd but finite coordinates (a scene 1e300 mm wide): drawn without overflow.
  Mesh far(&t.arena);
  ASSERT_TRUE(far.vertices.push_back({-1e300, 0, 0}) && far.vertices.push_back({1e300, 0, 0}) &&
              far.vertices.push_back({0, 1e300, 1e300}) && far.triangles.push_back({{0, 1, 2}}));
  RenderMesh far_item;
  far_item.mesh = &far;
  SPLINTCORE_EXPECT_OK(render_meshes(ctx, Span<const RenderMesh>(&far_item, 1), o, &image));
  // No mesh at all: the background and the separators.
  SPLINTCORE_EXPECT_OK(render_meshes(ctx, Span<const RenderMesh>(), o, &image));
  EXPECT_EQ(image.rgb[0], 255);
}

TEST(Render, Cancelled) {
  test::TestArena t(16 << 20);
  Progress stop;
  stop.report = [](void*, const char*, uint64_t, uint64_t) { return false; };
  Context ctx(&t.arena, nullptr, &stop);
  Mesh cube = cube_mesh(t.arena, 0, 1);
  RenderMesh item;
  item.mesh = &cube;
  RenderImage image;
  EXPECT_EQ(render_meshes(ctx, Span<const RenderMesh>(&item, 1), RenderOptions{}, &image).code(),
            StatusCode::kCancelled);
}

// Every cap from 0 up: a clean kArenaExhausted naming the need until the cap suffices, within
// the documented bounds; then the same bytes as with plenty of memory.
TEST(Render, ArenaExhaustionSweep) {
  test::TestArena meshes(1 << 20);
  Mesh cube = cube_mesh(meshes.arena, 0, 10);
  Mesh torus;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(meshes.arena, shapes::torus(12, 8, 10, 3), &torus));
  RenderMesh items[2];
  items[0].mesh = &cube;
  items[0].alpha = 120;
  items[1].mesh = &torus;
  RenderOptions o;
  o.width = 48;
  o.height = 40;
  o.shading = RenderShading::kGouraud;
  const uint64_t render_need =
      render_bound(48, 40, std::max(cube.vertices.size(), torus.vertices.size()), 1);
  const uint64_t need = render_need + png_bound(48, 40);

  std::vector<uint8_t> reference;
  {
    test::TestArena t(static_cast<size_t>(need));
    RenderImage image;
    SPLINTCORE_ASSERT_OK(draw(t.arena, items, 2, o, &image));
    EXPECT_LE(t.arena.high_water(), render_need);
    SPLINTCORE_ASSERT_OK(encode(t.arena, image, &reference));
    EXPECT_LE(t.arena.high_water(), need);
  }
  // The needs reported by each failure, followed until success, and a coarse sweep of caps.
  std::vector<size_t> caps;
  for (size_t cap = 0; cap <= need; cap += need / 211 + 1) caps.push_back(cap);
  size_t cap = 0;
  int steps = 0;
  for (;;) {
    test::TestArena t(cap);
    RenderImage image;
    std::vector<uint8_t> png;
    Status s = draw(t.arena, items, 2, o, &image);
    if (s.is_ok()) s = encode(t.arena, image, &png);
    if (s.is_ok()) {
      EXPECT_EQ(png, reference);
      break;
    }
    ASSERT_EQ(s.code(), StatusCode::kArenaExhausted) << test::format(s);
    EXPECT_NE(std::strstr(s.message(), "need"), nullptr) << s.message();
    ASSERT_GT(t.arena.last_need(), cap);
    ASSERT_LE(t.arena.last_need(), need);
    cap = t.arena.last_need();
    ASSERT_LT(++steps, 64);
  }
  EXPECT_GE(steps, 5);  // image, depth, overlay x3, normals..., and the encoder's
  for (size_t c : caps) {
    test::TestArena t(c);
    RenderImage image;
    std::vector<uint8_t> png;
    Status s = draw(t.arena, items, 2, o, &image);
    if (s.is_ok()) s = encode(t.arena, image, &png);
    if (s.is_ok()) {
      EXPECT_EQ(png, reference) << "cap " << c;
    } else {
      EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << "cap " << c << ": " << test::format(s);
    }
  }
}

}  // namespace
}  // namespace splintcore
