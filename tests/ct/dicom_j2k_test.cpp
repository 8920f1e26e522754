// JPEG 2000 in DICOM (issue 31; transfer syntaxes 1.2.840.10008.1.2.4.90 and .91,
// src/ct/jpeg2000*.cpp): the J2K twins of fixtures/ct (made by openjpeg through gdcmconv,
// make_ct_fixtures.py) read to the voxels of their uncompressed twins (lossless bit-identical;
// the 9/7 one within 1 of openjpeg's own decode); the MQ decoder and tag trees on hand cases
// and against encoders written here from T.800 C.2 and B.10.2; malformed codestreams are clear
// errors naming the cause and the byte offset.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "ct/jpeg2000.h"
#include "splintcore/ct.h"
#include "support/dicom_read.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using ct_detail::J2kBits;
using ct_detail::J2kTagNode;
using ct_detail::MqDecoder;
using test::Bytes;
using test::TestArena;

Bytes fixture(const std::string& name) { return test::ct_fixture(name); }

using Series = test::DicomRead;

Series read_names(const std::vector<std::string>& names, size_t arena_bytes = 4 << 20) {
  std::vector<Bytes> files;
  for (const std::string& n : names) files.push_back(fixture(n));
  return test::read_dicom_bytes(files, names, arena_bytes);
}

// Reads `names` and `twins`: both succeed, voxels differ by at most `tolerance`.
void expect_twins(const std::vector<std::string>& names, const std::vector<std::string>& twins,
                  const char* syntax, int tolerance = 0) {
  const Series plain = read_names(twins);
  ASSERT_TRUE(plain.status.is_ok()) << test::format(plain.status);
  const Series z = read_names(names);
  ASSERT_TRUE(z.status.is_ok()) << names[0] << ": " << test::format(z.status);
  ASSERT_EQ(z.hu.size(), plain.hu.size());
  EXPECT_STREQ(z.info.transfer_syntax, syntax) << names[0];
  int worst = 0;
  for (size_t i = 0; i < z.hu.size(); ++i) {
    const int d = std::abs(int{z.hu[i]} - int{plain.hu[i]});
    worst = d > worst ? d : worst;
  }
  EXPECT_LE(worst, tolerance) << names[0];
  if (tolerance == 0) {
    EXPECT_TRUE(z.hu == plain.hu) << names[0];
  }
}

// The one fragment of an encapsulated file (after the basic offset table).
Bytes fragment_of(const Bytes& file) {
  const uint8_t tag[] = {0xE0, 0x7F, 0x10, 0x00, 'O', 'B', 0, 0, 0xFF, 0xFF, 0xFF, 0xFF};
  size_t p = 0;
  while (p + sizeof(tag) <= file.size() && std::memcmp(&file[p], tag, sizeof(tag)) != 0) ++p;
  EXPECT_LT(p + sizeof(tag), file.size());
  p += sizeof(tag);
  auto u32 = [&](size_t q) {
    return uint32_t{file[q]} | (uint32_t{file[q + 1]} << 8) | (uint32_t{file[q + 2]} << 16) |
           (uint32_t{file[q + 3]} << 24);
  };
  p += 8 + u32(p + 4);
  const uint32_t length = u32(p + 4);
  return Bytes(file.begin() + static_cast<std::ptrdiff_t>(p + 8),
               file.begin() + static_cast<std::ptrdiff_t>(p + 8 + length));
}

// The native pixel bytes of an uncompressed fixture (its last 2 * 56 * 64 bytes).
Bytes native_pixels(const std::string& name, size_t bytes) {
  const Bytes f = fixture(name);
  return Bytes(f.end() - static_cast<std::ptrdiff_t>(bytes), f.end());
}

constexpr uint32_t kRows = 56, kColumns = 64;

Status decode(const Bytes& cs, Bytes* out, size_t arena_bytes = 0, uint32_t precision = 16) {
  if (arena_bytes == 0) {
    arena_bytes = static_cast<size_t>(ct_detail::jpeg2000_arena_bytes(kRows, kColumns, cs.size()));
  }
  TestArena t(arena_bytes);
  out->assign(2 * kRows * kColumns, 0);
  Status s = ct_detail::jpeg2000_decode(t.arena, cs.data(), cs.size(), kRows, kColumns, precision,
                                        out->data());
  EXPECT_EQ(t.arena.used(), 0u);
  return s;
}

// ---- Fixtures equal to their twins ---------------------------------------------------------

TEST(CtDicomJ2k, LosslessSeriesEqualsItsTwin) {
  expect_twins({"j2k16_2.dcm", "j2k16_0.dcm", "j2k16_1.dcm"},
               {"raw16_2.dcm", "raw16_0.dcm", "raw16_1.dcm"}, "1.2.840.10008.1.2.4.90");
  expect_twins({"j2k8.dcm"}, {"raw8.dcm"}, "1.2.840.10008.1.2.4.90");
  expect_twins({"j2ks12.dcm"}, {"raws12.dcm"}, "1.2.840.10008.1.2.4.90");
  // 4 tiles of 32 x 32 (.91 by gdcm's -Y, 5/3 with every pass: lossless values).
  expect_twins({"j2k_tiles.dcm"}, {"raw16_1.dcm"}, "1.2.840.10008.1.2.4.91");
}

// Rate-limited: 5/3 with passes cut (midpoint reconstruction, as openjpeg: equal), 9/7 on
// 6 tiles with partial ones (openjpeg computes in float, we in double: within 1).
TEST(CtDicomJ2k, LossyEqualsOpenjpegsDecode) {
  expect_twins({"j2k_r10.dcm"}, {"raw16_r10.dcm"}, "1.2.840.10008.1.2.4.91");
  expect_twins({"j2k97.dcm"}, {"raw16_97.dcm"}, "1.2.840.10008.1.2.4.91", 1);
}

// The decoder alone: the raw pixels of the twin, in exactly the documented arena.
TEST(CtDicomJ2k, DecoderInItsArenaBound) {
  const Bytes cs = fragment_of(fixture("j2k16_0.dcm"));
  Bytes out;
  Status s = decode(cs, &out);
  ASSERT_TRUE(s.is_ok()) << test::format(s);
  EXPECT_TRUE(out == native_pixels("raw16_0.dcm", out.size()));
  // 8-bit samples come out as 16-bit values with a zero high byte.
  const Bytes cs8 = fragment_of(fixture("j2k8.dcm"));
  s = decode(cs8, &out, 0, 8);
  ASSERT_TRUE(s.is_ok()) << test::format(s);
  const Bytes raw8 = native_pixels("raw8.dcm", kRows * kColumns);
  for (size_t i = 0; i < raw8.size(); ++i) {
    ASSERT_EQ(out[2 * i], raw8[i]) << i;
    ASSERT_EQ(out[2 * i + 1], 0) << i;
  }
}

// A JP2 file (signature, file type and codestream boxes) decodes as its codestream.
TEST(CtDicomJ2k, Jp2BoxesAreSkipped) {
  const Bytes cs = fragment_of(fixture("j2k16_0.dcm"));
  Bytes jp2 = {0,   0,   0,   12,  'j', 'P', ' ', ' ', 0x0D, 0x0A, 0x87, 0x0A, 0,   0,   0,   20,
               'f', 't', 'y', 'p', 'j', 'p', '2', ' ', 0,    0,    0,    0,    'j', 'p', '2', ' '};
  const uint32_t box = static_cast<uint32_t>(cs.size() + 8);
  const uint8_t head[] = {static_cast<uint8_t>(box >> 24),
                          static_cast<uint8_t>(box >> 16),
                          static_cast<uint8_t>(box >> 8),
                          static_cast<uint8_t>(box),
                          'j',
                          'p',
                          '2',
                          'c'};
  jp2.insert(jp2.end(), head, head + 8);
  jp2.insert(jp2.end(), cs.begin(), cs.end());
  Bytes out;
  Status s = decode(jp2, &out);
  ASSERT_TRUE(s.is_ok()) << test::format(s);
  EXPECT_TRUE(out == native_pixels("raw16_0.dcm", out.size()));
  // The codestream box with length 0 (to the end of the file).
  for (int i = 0; i < 4; ++i) jp2[32 + i] = 0;
  s = decode(jp2, &out);
  ASSERT_TRUE(s.is_ok()) << test::format(s);
  jp2.resize(40);  // no codestream box
  s = decode(jp2, &out);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
}

// ---- The MQ decoder --------------------------------------------------------------------------

// T.800 C.2 (the encoder: CODEMPS, CODELPS, RENORME, BYTEOUT, FLUSH with SETBITS) with Table
// C.2, written again here so the decoder meets an independent transcription.
struct MqEncoder {
  struct Row {
    uint16_t qe;
    uint8_t nmps, nlps, sw;
  };
  static const Row* table() {
    static const Row t[47] = {
        {0x5601, 1, 1, 1},   {0x3401, 2, 6, 0},   {0x1801, 3, 9, 0},   {0x0AC1, 4, 12, 0},
        {0x0521, 5, 29, 0},  {0x0221, 38, 33, 0}, {0x5601, 7, 6, 1},   {0x5401, 8, 14, 0},
        {0x4801, 9, 14, 0},  {0x3801, 10, 14, 0}, {0x3001, 11, 17, 0}, {0x2401, 12, 18, 0},
        {0x1C01, 13, 20, 0}, {0x1601, 29, 21, 0}, {0x5601, 15, 14, 1}, {0x5401, 16, 14, 0},
        {0x5101, 17, 15, 0}, {0x4801, 18, 16, 0}, {0x3801, 19, 17, 0}, {0x3401, 20, 18, 0},
        {0x3001, 21, 19, 0}, {0x2801, 22, 19, 0}, {0x2401, 23, 20, 0}, {0x2201, 24, 21, 0},
        {0x1C01, 25, 22, 0}, {0x1801, 26, 23, 0}, {0x1601, 27, 24, 0}, {0x1401, 28, 25, 0},
        {0x1201, 29, 26, 0}, {0x1101, 30, 27, 0}, {0x0AC1, 31, 28, 0}, {0x09C1, 32, 29, 0},
        {0x08A1, 33, 30, 0}, {0x0521, 34, 31, 0}, {0x0441, 35, 32, 0}, {0x02A1, 36, 33, 0},
        {0x0221, 37, 34, 0}, {0x0141, 38, 35, 0}, {0x0111, 39, 36, 0}, {0x0085, 40, 37, 0},
        {0x0049, 41, 38, 0}, {0x0025, 42, 39, 0}, {0x0015, 43, 40, 0}, {0x0009, 44, 41, 0},
        {0x0005, 45, 42, 0}, {0x0001, 45, 43, 0}, {0x5601, 46, 46, 0}};
    return t;
  }
  uint32_t a = 0x8000, c = 0, ct = 12;
  Bytes out{0};  // out[0] is the byte before the first (BP = BPST - 1)
  uint8_t index[19] = {4, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 3, 46};  // Table D.7
  uint8_t mps[19] = {};

  void byte_out() {
    if (out.back() == 0xFF) {
      out.push_back(static_cast<uint8_t>(c >> 20));
      c &= 0xFFFFF;
      ct = 7;
    } else if (c < 0x8000000) {
      out.push_back(static_cast<uint8_t>(c >> 19));
      c &= 0x7FFFF;
      ct = 8;
    } else {
      ++out.back();
      if (out.back() == 0xFF) {
        c &= 0x7FFFFFF;
        out.push_back(static_cast<uint8_t>(c >> 20));
        c &= 0xFFFFF;
        ct = 7;
      } else {
        out.push_back(static_cast<uint8_t>(c >> 19));
        c &= 0x7FFFF;
        ct = 8;
      }
    }
  }
  void renorm() {
    do {
      a <<= 1;
      c <<= 1;
      if (--ct == 0) byte_out();
    } while ((a & 0x8000) == 0);
  }
  void encode(uint32_t cx, uint32_t d) {
    const Row& r = table()[index[cx]];
    a -= r.qe;
    if (d == mps[cx]) {
      if ((a & 0x8000) == 0) {
        if (a < r.qe) {
          a = r.qe;
        } else {
          c += r.qe;
        }
        index[cx] = r.nmps;
        renorm();
      } else {
        c += r.qe;
      }
    } else {
      if (a < r.qe) {
        c += r.qe;
      } else {
        a = r.qe;
      }
      if (r.sw) mps[cx] = static_cast<uint8_t>(1 - mps[cx]);
      index[cx] = r.nlps;
      renorm();
    }
  }
  Bytes flush() {
    const uint32_t temp = c + a;
    c |= 0xFFFF;
    if (c >= temp) c -= 0x8000;
    c <<= ct;
    byte_out();
    c <<= ct;
    byte_out();
    Bytes bytes(out.begin() + 1, out.end());
    if (!bytes.empty() && bytes.back() == 0xFF) bytes.pop_back();
    return bytes;
  }
};

TEST(CtDicomJ2k, MqDecoderHandCases) {
  // A few MPSs in the uniform context flush to a short segment the decoder reads back.
  MqEncoder e;
  for (int i = 0; i < 4; ++i) e.encode(18, 0);
  const Bytes zeros = e.flush();
  MqDecoder d;
  d.init(zeros.data(), zeros.size());
  d.reset_contexts();
  for (int i = 0; i < 4; ++i) EXPECT_EQ(d.decode(18), 0u) << i;
  // One LPS in context 0 (state 4, Qe 0x0521) after MPSs.
  MqEncoder f;
  const uint32_t decisions[] = {0, 0, 1, 0, 1, 1, 0};
  for (uint32_t v : decisions) f.encode(0, v);
  const Bytes bytes = f.flush();
  d.init(bytes.data(), bytes.size());
  d.reset_contexts();
  for (uint32_t v : decisions) EXPECT_EQ(d.decode(0), v);
}

TEST(CtDicomJ2k, MqDecoderRoundTripsTheEncoder) {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 40; ++trial) {
    MqEncoder e;
    std::vector<uint32_t> cx, bits;
    const int n = 1 + static_cast<int>(rng() % 3000);
    const uint32_t skew = rng() % 16;  // how often a 1
    for (int i = 0; i < n; ++i) {
      cx.push_back(rng() % 19);
      bits.push_back(rng() % 16 < skew ? 1u : 0u);
      e.encode(cx.back(), bits.back());
    }
    const Bytes bytes = e.flush();
    MqDecoder d;
    d.init(bytes.data(), bytes.size());
    d.reset_contexts();
    for (int i = 0; i < n; ++i) ASSERT_EQ(d.decode(cx[i]), bits[i]) << trial << " " << i;
  }
}

// ---- Packet header bits (B.10.1) -------------------------------------------------------------

// The header's bit reader at its edges: after a 0xFF byte only 7 bits of the next are read
// (bit stuffing); a header ending on 0xFF owns the byte after it, which align() skips; the
// last byte is read and one bit more is "truncated" (a 0), as is a stuffed byte that is not
// there.
TEST(CtDicomJ2k, PacketHeaderBitsAtTheirEdges) {
  const uint8_t stuffed[] = {0xFF, 0x55, 0xA0};
  J2kBits b;
  b.data = stuffed;
  b.size = 3;
  EXPECT_EQ(b.bits(8), 0xFFu);
  EXPECT_EQ(b.bits(7), 0x55u);  // the stuffed byte's top bit is not read
  EXPECT_EQ(b.pos, 2u);
  EXPECT_EQ(b.bits(8), 0xA0u);
  EXPECT_FALSE(b.truncated);
  EXPECT_EQ(b.bit(), 0u);  // one past the end
  EXPECT_TRUE(b.truncated);

  const uint8_t ends_on_ff[] = {0xFF, 0x00, 0x80};
  J2kBits e;
  e.data = ends_on_ff;
  e.size = 3;
  EXPECT_EQ(e.bits(8), 0xFFu);
  e.align();  // the 0x00 belongs to the header
  EXPECT_EQ(e.pos, 2u);
  EXPECT_FALSE(e.truncated);
  EXPECT_EQ(e.bit(), 1u);  // the next header starts at 0x80

  J2kBits cut;  // the stuffed byte missing
  cut.data = ends_on_ff;
  cut.size = 1;
  EXPECT_EQ(cut.bits(8), 0xFFu);
  cut.align();
  EXPECT_TRUE(cut.truncated);
  EXPECT_EQ(cut.pos, 1u);

  J2kBits plain;  // no 0xFF: align() only drops the rest of the byte
  plain.data = stuffed + 1;
  plain.size = 2;
  EXPECT_EQ(plain.bits(3), 0x2u);
  plain.align();
  EXPECT_EQ(plain.pos, 1u);
  EXPECT_EQ(plain.bits(8), 0xA0u);
  EXPECT_FALSE(plain.truncated);
}

// ---- Tag trees (B.10.2) ----------------------------------------------------------------------

TEST(CtDicomJ2k, TagTreeHandCase) {
  // One node of value 2: thresholds 1, 2, 3 read 0, 0, 1; then it is known.
  J2kTagNode nodes[1];
  ct_detail::j2k_tag_tree_init(nodes, 1, 1);
  const uint8_t byte[] = {0x20};  // 001 then padding
  J2kBits bits;
  bits.data = byte;
  bits.size = 1;
  bool below = true;
  for (int32_t t = 1; t <= 2; ++t) {
    ct_detail::j2k_tag_tree_decode(nodes, 0, t, bits, &below);
    EXPECT_FALSE(below) << t;
  }
  ct_detail::j2k_tag_tree_decode(nodes, 0, 3, bits, &below);
  EXPECT_TRUE(below);
  EXPECT_EQ(nodes[0].value, 2);
  ct_detail::j2k_tag_tree_decode(nodes, 0, 9, bits, &below);  // no bits read
  EXPECT_EQ(bits.left, 5u);
  // 3 x 2 leaves: 6 + 2 + 1 nodes; the leaves' parents.
  EXPECT_EQ(ct_detail::j2k_tag_tree_nodes(3, 2), 9u);
  EXPECT_EQ(ct_detail::j2k_tag_tree_nodes(1, 5), 5u + 3u + 2u + 1u);
  J2kTagNode tree[9];
  ct_detail::j2k_tag_tree_init(tree, 3, 2);
  EXPECT_EQ(tree[0].parent, 6u);
  EXPECT_EQ(tree[5].parent, 7u);
  EXPECT_EQ(tree[7].parent, 8u);
  EXPECT_EQ(tree[8].parent, 8u);
  // No leaves along one side: no nodes, nothing to set up (and no endless halving).
  EXPECT_EQ(ct_detail::j2k_tag_tree_nodes(0, 4), 0u);
  EXPECT_EQ(ct_detail::j2k_tag_tree_nodes(4, 0), 0u);
  ct_detail::j2k_tag_tree_init(nullptr, 0, 4);
  ct_detail::j2k_tag_tree_init(nullptr, 4, 0);
}

// B.10.2's encoder (the same walk from the root, writing what the decoder reads) against
// the decoder on random trees, the leaves asked in raster order with rising thresholds.
TEST(CtDicomJ2k, TagTreeRoundTripsTheEncoder) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 30; ++trial) {
    const uint32_t w = 1 + rng() % 9, h = 1 + rng() % 9;
    const size_t n = ct_detail::j2k_tag_tree_nodes(w, h);
    std::vector<J2kTagNode> enc(n), dec(n);
    ct_detail::j2k_tag_tree_init(enc.data(), w, h);
    ct_detail::j2k_tag_tree_init(dec.data(), w, h);
    std::vector<int32_t> value(n, 0x7FFFFFFF);
    for (uint32_t i = 0; i < w * h; ++i) value[i] = static_cast<int32_t>(rng() % 6);
    for (size_t i = 0; i < n; ++i) {  // parents hold their children's minimum
      const size_t p = enc[i].parent;
      if (p != i && value[i] < value[p]) value[p] = value[i];
    }
    std::vector<uint8_t> stream;  // bits
    std::vector<int32_t> low(n, 0);
    std::vector<bool> known(n, false);
    std::vector<std::pair<uint32_t, int32_t>> asks;
    for (int32_t t = 1; t <= 7; ++t) {
      for (uint32_t leaf = 0; leaf < w * h; ++leaf) {
        asks.push_back({leaf, t});
        std::vector<size_t> path;
        for (size_t k = leaf;; k = enc[k].parent) {
          path.push_back(k);
          if (enc[k].parent == k) break;
        }
        int32_t l = 0;
        for (size_t i = path.size(); i-- > 0;) {
          const size_t k = path[i];
          l = l > low[k] ? l : low[k];
          while (l < t) {
            if (l >= value[k]) {
              if (!known[k]) stream.push_back(1);
              known[k] = true;
              break;
            }
            stream.push_back(0);
            ++l;
          }
          low[k] = l;
        }
      }
    }
    Bytes packed((stream.size() + 7) / 8 + 1, 0);  // no 0xFF byte: no stuffing rule hit
    for (size_t i = 0; i < stream.size(); ++i) {
      if (stream[i]) packed[i / 8] = static_cast<uint8_t>(packed[i / 8] | (0x80 >> (i % 8)));
    }
    bool has_ff = false;
    for (uint8_t b : packed) has_ff = has_ff || b == 0xFF;
    if (has_ff) continue;
    J2kBits bits;
    bits.data = packed.data();
    bits.size = packed.size();
    for (const auto& ask : asks) {
      bool below = false;
      ct_detail::j2k_tag_tree_decode(dec.data(), ask.first, ask.second, bits, &below);
      ASSERT_EQ(below, value[ask.first] < ask.second) << trial;
    }
    EXPECT_FALSE(bits.truncated);
  }
}

// ---- Errors ----------------------------------------------------------------------------------

// Every proper prefix of a codestream is an error with a byte offset, never a crash.
TEST(CtDicomJ2k, EveryTruncationIsAnError) {
  const Bytes cs = fragment_of(fixture("j2k97.dcm"));
  for (size_t n = 0; n + 2 < cs.size(); ++n) {  // the last two are the EOC marker
    const Bytes cut(cs.begin(), cs.begin() + static_cast<std::ptrdiff_t>(n));
    Bytes out;
    const Status s =
        decode(cut, &out,
               static_cast<size_t>(ct_detail::jpeg2000_arena_bytes(kRows, kColumns, cs.size())));
    ASSERT_FALSE(s.is_ok()) << n;
    EXPECT_NE(s.byte_offset(), kNoPosition) << n;
    EXPECT_LE(s.byte_offset(), n) << n << ": " << s.message();
  }
}

// Offsets in j2k16_0's codestream (gdcm's layout: SOC, SIZ at 2 (Xsiz 8, XTsiz 24, Csiz 40,
// Ssiz 42), COD at 45 (progression 50, xcb 55, style 57, transform 58), QCD at 59).
struct Mutation {
  size_t at;
  uint8_t value;
  StatusCode code;
  const char* words;
  uint64_t offset;
};

TEST(CtDicomJ2k, MalformedCodestreamsNameTheCause) {
  const Bytes cs = fragment_of(fixture("j2k16_0.dcm"));
  ASSERT_EQ(cs[45], 0xFF);
  ASSERT_EQ(cs[46], 0x52);
  ASSERT_EQ(cs[59], 0xFF);
  ASSERT_EQ(cs[60], 0x5C);
  const Mutation cases[] = {
      {0, 0x00, StatusCode::kParseError, "no SOC marker", 0},
      {3, 0x52, StatusCode::kParseError, "SIZ must follow SOC", 2},
      {41, 3, StatusCode::kUnsupported, "3 components", 40},      // Csiz
      {42, 0x10, StatusCode::kParseError, "17-bit samples", 42},  // Ssiz
      {43, 2, StatusCode::kUnsupported, "subsampled", 43},        // XRsiz
      {11, 0x41, StatusCode::kParseError, "does not match", 8},   // Xsiz 65
      {27, 0, StatusCode::kParseError, "tile grid", 24},          // XTsiz 0
      {57, 0x01, StatusCode::kUnsupported, "code-block style", 57},
      {58, 0x02, StatusCode::kUnsupported, "other than 9/7 and 5/3", 58},
      {50, 0x07, StatusCode::kParseError, "progression order", 50},
      {55, 0x0B, StatusCode::kParseError, "code-block size", 55},
      {60, 0x5E, StatusCode::kUnsupported, "RGN", 59},
      {60, 0x5F, StatusCode::kUnsupported, "POC", 59},
      {60, 0x60, StatusCode::kUnsupported, "PPM", 59},
      {62, 0x01, StatusCode::kParseError, "length under 2", 59},
      {61, 0xFF, StatusCode::kTruncated, "inside a marker segment", 0},
      {63, 0x43, StatusCode::kParseError, "style over 2", 63},
  };
  for (const Mutation& m : cases) {
    Bytes bad = cs;
    bad[m.at] = m.value;
    Bytes out;
    const Status s = decode(bad, &out);
    EXPECT_EQ(s.code(), m.code) << m.words << ": " << test::format(s);
    EXPECT_NE(std::string(s.message()).find(m.words), std::string::npos)
        << m.words << ": " << s.message();
    EXPECT_NE(std::string(s.message()).find("JPEG 2000"), std::string::npos) << s.message();
    if (m.code != StatusCode::kTruncated) {
      EXPECT_EQ(s.byte_offset(), m.offset) << m.words;
    }
  }
}

// Absurd sizes in SOT and the tile data; a tile-part whose Psot lies.
TEST(CtDicomJ2k, TilePartErrors) {
  const Bytes cs = fragment_of(fixture("j2k16_0.dcm"));
  size_t sot = 0;
  while (!(cs[sot] == 0xFF && cs[sot + 1] == 0x90)) ++sot;
  auto with = [&](size_t at, std::initializer_list<uint8_t> bytes) {
    Bytes b = cs;
    size_t i = at;
    for (uint8_t v : bytes) b[i++] = v;
    Bytes out;
    return decode(b, &out);
  };
  Status s = with(sot + 6, {0x7F, 0xFF, 0xFF, 0xFF});  // Psot past the data
  EXPECT_EQ(s.code(), StatusCode::kTruncated);
  EXPECT_NE(std::string(s.message()).find("Psot"), std::string::npos) << s.message();
  EXPECT_EQ(s.byte_offset(), sot + 6);
  s = with(sot + 4, {0x00, 0x05});  // tile 5 of 1
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_NE(std::string(s.message()).find("tile index"), std::string::npos) << s.message();
  s = with(sot + 4, {0x00, 0x01});  // tile 1 of 1: one past the last
  EXPECT_NE(std::string(s.message()).find("tile index"), std::string::npos) << s.message();
  s = with(sot + 6, {0, 0, 0, 13});
  EXPECT_NE(std::string(s.message()).find("Psot under 14"), std::string::npos) << s.message();
  s = with(sot, {0xFF, 0x91});
  EXPECT_NE(std::string(s.message()).find("unexpected marker in the main header"),
            std::string::npos);
  EXPECT_EQ(s.byte_offset(), sot);
  // The packet data cut short inside the tile-part: Psot smaller, EOC right after.
  const uint32_t psot = (uint32_t{cs[sot + 6]} << 24) | (uint32_t{cs[sot + 7]} << 16) |
                        (uint32_t{cs[sot + 8]} << 8) | cs[sot + 9];
  Bytes cut(cs.begin(), cs.begin() + static_cast<std::ptrdiff_t>(sot + 40));
  cut[sot + 6] = 0;
  cut[sot + 7] = 0;
  cut[sot + 8] = 0;
  cut[sot + 9] = 40;
  cut.push_back(0xFF);
  cut.push_back(0xD9);
  Bytes out;
  s = decode(cut, &out);
  EXPECT_EQ(s.code(), StatusCode::kTruncated) << test::format(s);
  EXPECT_GT(psot, 40u);
  EXPECT_LE(s.byte_offset(), sot + 40) << s.message();
  // A too small arena is a clean exhaustion.
  s = decode(cs, &out, 4096);
  EXPECT_EQ(s.code(), StatusCode::kArenaExhausted);
}

// COD's limits on both sides of each edge, in j2k16_0's header (levels at 54, xcb at 55, ycb
// at 56, each stored as the exponent - 2): 32 levels and code-blocks of 1024 x 4 or 4 x 1024
// pass these checks (the stream, coded otherwise, may fail later on something else), one more
// is refused by name.
TEST(CtDicomJ2k, CodingStyleLimitsAtTheirEdges) {
  const Bytes cs = fragment_of(fixture("j2k16_0.dcm"));
  ASSERT_EQ(cs[54], 4);
  auto message = [&](std::initializer_list<std::pair<size_t, uint8_t>> changes) {
    Bytes b = cs;
    for (const auto& c : changes) b[c.first] = c.second;
    Bytes out;
    return std::string(decode(b, &out).message());
  };
  const std::string kLevels = "more than 32 levels", kBlock = "code-block size";
  EXPECT_EQ(message({{54, 32}}).find(kLevels), std::string::npos);
  EXPECT_NE(message({{54, 33}}).find(kLevels), std::string::npos);
  EXPECT_EQ(message({{55, 8}, {56, 0}}).find(kBlock), std::string::npos);  // 1024 x 4
  EXPECT_NE(message({{55, 9}, {56, 0}}).find(kBlock), std::string::npos);
  EXPECT_EQ(message({{55, 0}, {56, 8}}).find(kBlock), std::string::npos);  // 4 x 1024
  EXPECT_NE(message({{55, 0}, {56, 9}}).find(kBlock), std::string::npos);
}

// Through the DICOM reader: a broken codestream's offset is an offset in the file.
TEST(CtDicomJ2k, ErrorsCarryFileOffsets) {
  Bytes file = fixture("j2k16_0.dcm");
  const Bytes cs = fragment_of(file);
  size_t at = 0;
  while (std::memcmp(&file[at], cs.data(), 8) != 0) ++at;
  file[at + 57] = 0x01;  // code-block style: bypass
  TestArena t(4 << 20);
  CtMemoryFile mem{"x.dcm", file.data(), file.size()};
  CtMemoryFiles m{&mem, 1, 0, {}};
  Context ctx(&t.arena);
  CtVolume volume;
  CtInfo info;
  const Status s = read_dicom_series(ctx, ct_memory_series(&m), CtReadOptions(), &volume, &info);
  EXPECT_EQ(s.code(), StatusCode::kUnsupported);
  EXPECT_EQ(s.byte_offset(), at + 57) << test::format(s);
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

// Headers that say the same thing another way decode to the same pixels: a COC and a QCC
// repeating COD and QCD, a tile-part COD, and (one layer, one precinct per resolution) every
// progression order, whose packets then come in the same order as LRCP's.
TEST(CtDicomJ2k, EquivalentHeadersDecodeTheSame) {
  const Bytes cs = fragment_of(fixture("j2k16_0.dcm"));
  const Bytes expected = native_pixels("raw16_0.dcm", 2 * kRows * kColumns);
  auto expect_same = [&](const Bytes& b, const char* what) {
    Bytes out;
    const Status s = decode(b, &out);
    ASSERT_TRUE(s.is_ok()) << what << ": " << test::format(s);
    EXPECT_TRUE(out == expected) << what;
  };
  for (uint8_t order = 1; order <= 4; ++order) {
    Bytes b = cs;
    b[50] = order;
    expect_same(b, "progression order");
  }
  // COC (Lcoc 9: Ccoc, Scoc, levels, xcb, ycb, style, transform) and QCC before QCD.
  const uint32_t lqcd = (uint32_t{cs[61]} << 8) | cs[62];
  Bytes b(cs.begin(), cs.begin() + 59);
  const uint8_t coc[] = {0xFF, 0x53, 0, 9, 0, 0, cs[54], cs[55], cs[56], cs[57], cs[58]};
  b.insert(b.end(), coc, coc + sizeof(coc));
  const uint8_t qcc[] = {0xFF, 0x5D, static_cast<uint8_t>((lqcd + 1) >> 8),
                         static_cast<uint8_t>(lqcd + 1), 0};
  b.insert(b.end(), qcc, qcc + sizeof(qcc));
  b.insert(b.end(), cs.begin() + 63, cs.begin() + 61 + lqcd);
  b.insert(b.end(), cs.begin() + 59, cs.end());
  expect_same(b, "COC and QCC");
  // COD and QCD again in the tile-part header (Psot grows by their lengths).
  size_t sot = 0;
  while (!(cs[sot] == 0xFF && cs[sot + 1] == 0x90)) ++sot;
  Bytes t(cs.begin(), cs.begin() + static_cast<std::ptrdiff_t>(sot + 12));
  t.insert(t.end(), cs.begin() + 45, cs.begin() + 61 + lqcd);
  t.insert(t.end(), cs.begin() + static_cast<std::ptrdiff_t>(sot + 12), cs.end());
  const uint32_t grown = ((uint32_t{cs[sot + 6]} << 24) | (uint32_t{cs[sot + 7]} << 16) |
                          (uint32_t{cs[sot + 8]} << 8) | cs[sot + 9]) +
                         16 + lqcd;
  for (int i = 0; i < 4; ++i) t[sot + 6 + i] = static_cast<uint8_t>(grown >> (24 - 8 * i));
  expect_same(t, "tile-part COD and QCD");
  // SOP markers allowed (none present); predictable termination (nothing for a decoder).
  Bytes sop = cs;
  sop[49] = 0x02;
  expect_same(sop, "SOP allowed");
  Bytes predictable = cs;
  predictable[57] = 0x10;
  expect_same(predictable, "predictable termination");
  // Styles that change the decoding (reset, causal, segmentation symbols) on a stream coded
  // without them: some result, never a crash or a leak.
  for (uint8_t style : {uint8_t{0x02}, uint8_t{0x08}, uint8_t{0x20}}) {
    Bytes other = cs;
    other[57] = style;
    Bytes out;
    (void)decode(other, &out);
  }
  // EPH required but absent.
  Bytes eph = cs;
  eph[49] = 0x04;
  Bytes out;
  const Status s = decode(eph, &out);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_NE(std::string(s.message()).find("EPH marker missing"), std::string::npos);
  // Psot 0: the last tile-part runs to the EOC.
  Bytes z = cs;
  for (int i = 0; i < 4; ++i) z[sot + 6 + i] = 0;
  expect_same(z, "Psot 0");
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

// Decodes `b`: any outcome but a crash, a leak (decode() checks the arena) or an error
// without a byte offset.
void expect_clean(const Bytes& b, const std::string& what) {
  Bytes out;
  const Status s =
      decode(b, &out,
             static_cast<size_t>(ct_detail::jpeg2000_arena_bytes(kRows, kColumns, b.size() + 64)));
  if (!s.is_ok() && s.code() != StatusCode::kArenaExhausted) {
    EXPECT_NE(s.byte_offset(), kNoPosition) << what << ": " << s.message();
    EXPECT_NE(std::string(s.message()).find("JPEG 2000"), std::string::npos) << s.message();
  }
}

// Every byte of the headers set to a few values, and every 9th byte of the packet data with
// one bit flipped: clean errors or some image (SQLite's and meshoptimizer's sweeps).
TEST(CtDicomJ2k, MutationSweepIsClean) {
  for (const char* name : {"j2k16_0.dcm", "j2k97.dcm"}) {
    const Bytes cs = fragment_of(fixture(name));
    size_t sod = 0;
    while (!(cs[sod] == 0xFF && cs[sod + 1] == 0x93)) ++sod;
    for (size_t at = 0; at < sod + 2; ++at) {
      for (uint8_t v :
           {uint8_t{0}, uint8_t{1}, uint8_t{2}, uint8_t{0x10}, uint8_t{0x7F}, uint8_t{0x80},
            uint8_t{0xFF}, static_cast<uint8_t>(cs[at] + 1), static_cast<uint8_t>(cs[at] - 1)}) {
        Bytes b = cs;
        b[at] = v;
        expect_clean(b, std::string(name) + " header byte " + std::to_string(at));
      }
    }
    for (size_t at = sod + 2; at < cs.size(); at += 9) {
      for (uint8_t bit : {uint8_t{0x01}, uint8_t{0x80}}) {
        Bytes b = cs;
        b[at] = static_cast<uint8_t>(b[at] ^ bit);
        expect_clean(b, std::string(name) + " data byte " + std::to_string(at));
      }
    }
  }
}

// Headers this decoder refuses or skips, spliced into j2k16_0 before its QCD (at 59).
TEST(CtDicomJ2k, SplicedSegments) {
  const Bytes cs = fragment_of(fixture("j2k16_0.dcm"));
  auto splice = [&](std::initializer_list<uint8_t> segment) {
    Bytes b(cs.begin(), cs.begin() + 59);
    b.insert(b.end(), segment.begin(), segment.end());
    b.insert(b.end(), cs.begin() + 59, cs.end());
    Bytes out;
    return decode(b, &out);
  };
  EXPECT_TRUE(splice({0xFF, 0x64, 0, 5, 0, 1, 'x'}).is_ok());  // COM
  EXPECT_TRUE(splice({0xFF, 0x55, 0, 4, 0, 0}).is_ok());       // TLM
  auto words = [](const Status& s, const char* w) {
    return std::string(s.message()).find(w) != std::string::npos;
  };
  Status s = splice({0xFF, 0x50, 0, 4, 0, 0});
  EXPECT_TRUE(words(s, "CAP")) << s.message();
  s = splice({0xFF, 0x52, 0, 12, 0, 0, 0, 1, 0, 4, 4, 4, 0, 1});
  EXPECT_TRUE(words(s, "a second COD")) << s.message();
  s = splice({0xFF, 0x53, 0, 9, 1, 0, 4, 4, 4, 0, 1});
  EXPECT_TRUE(words(s, "COC for a component other than 0")) << s.message();
  s = splice({0xFF, 0x53, 0, 5, 0, 0, 4});
  EXPECT_TRUE(words(s, "COC segment too short")) << s.message();
  s = splice({0xFF, 0x53, 0, 10, 0, 0, 4, 4, 4, 0, 1, 0});
  EXPECT_TRUE(words(s, "COC length 10, expected 9")) << s.message();
  s = splice({0xFF, 0x53, 0, 9, 0, 0, 33, 4, 4, 0, 1});
  EXPECT_TRUE(words(s, "more than 32 levels")) << s.message();
  s = splice({0xFF, 0x53, 0, 14, 0, 1, 4, 4, 4, 0, 1, 0x77, 0x77, 0x70, 0x77, 0x77});
  EXPECT_TRUE(words(s, "precinct size 1")) << s.message();
  s = splice({0xFF, 0x5D, 0, 5, 1, 0x40, 0x80});
  EXPECT_TRUE(words(s, "QCC for a component other than 0")) << s.message();
  s = splice({0xFF, 0x5D, 0, 4, 0, 0x40});
  EXPECT_TRUE(words(s, "too short")) << s.message();
  s = splice({0xFF, 0x5D, 0, 8, 0, 0x41, 0x80, 0, 0x80});
  EXPECT_TRUE(words(s, "does not fit its style")) << s.message();
  s = splice({0xFF, 0x5D, 0, 6, 0, 0x40, 0x80, 0x80});
  EXPECT_TRUE(words(s, "fewer values than subbands")) << s.message();
  s = splice({0xFF, 0x5D, 0, 5, 0, 0xE0, 0xF8});  // 7 guard bits + exponent 31
  EXPECT_TRUE(words(s, "more than 30 bit planes")) << s.message();
  // Precincts of 2^1 above resolution 0 and 2^1 at 0: more precincts; still the same image.
  s = splice({0xFF, 0x53, 0, 14, 0, 1, 4, 4, 4, 0, 1, 0x11, 0x11, 0x11, 0x11, 0x11});
  EXPECT_FALSE(s.is_ok());  // the packets were coded for one precinct per resolution
  // Derived quantisation on the 9/7 stream: decodes (to other values).
  const Bytes i97 = fragment_of(fixture("j2k97.dcm"));
  size_t qcd = 0;
  while (!(i97[qcd] == 0xFF && i97[qcd + 1] == 0x5C)) ++qcd;
  Bytes derived(i97.begin(), i97.begin() + static_cast<std::ptrdiff_t>(qcd));
  const uint8_t q[] = {
      0xFF,         0x5C,        0, 5, static_cast<uint8_t>((i97[qcd + 4] & 0xE0) | 1),
      i97[qcd + 5], i97[qcd + 6]};
  derived.insert(derived.end(), q, q + sizeof(q));
  const size_t lqcd = (size_t{i97[qcd + 2]} << 8) | i97[qcd + 3];
  derived.insert(derived.end(), i97.begin() + static_cast<std::ptrdiff_t>(qcd + 2 + lqcd),
                 i97.end());
  Bytes out;
  s = decode(derived, &out);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

bool has(const Status& s, const char* words) {
  return std::string(s.message()).find(words) != std::string::npos;
}

// Every arena size from the tier-1 state up to the bound: exhaustion is clean, and the bound
// is enough.
TEST(CtDicomJ2k, ArenaSweep) {
  const Bytes cs = fragment_of(fixture("j2k97.dcm"));
  const size_t bound =
      static_cast<size_t>(ct_detail::jpeg2000_arena_bytes(kRows, kColumns, cs.size()));
  for (size_t bytes = 1024; bytes < bound; bytes += bytes < 60000 ? 8192 : 256) {
    Bytes out;
    const Status s = decode(cs, &out, bytes);
    if (!s.is_ok()) {
      EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << bytes;
    }
  }
}

TEST(CtDicomJ2k, TilePartLayouts) {
  const Bytes cs = fragment_of(fixture("j2k16_0.dcm"));
  const Bytes expected = native_pixels("raw16_0.dcm", 2 * kRows * kColumns);
  size_t sot = 0;
  while (!(cs[sot] == 0xFF && cs[sot + 1] == 0x90)) ++sot;
  const Bytes empty_part = {0xFF, 0x90, 0, 10, 0, 0, 0, 0, 0, 14, 0, 2, 0xFF, 0x93};
  auto with_parts = [&](size_t count) {
    Bytes b(cs.begin(), cs.begin() + static_cast<std::ptrdiff_t>(sot));
    for (size_t i = 0; i < count; ++i) b.insert(b.end(), empty_part.begin(), empty_part.end());
    b.insert(b.end(), cs.begin() + static_cast<std::ptrdiff_t>(sot), cs.end());
    Bytes out;
    const Status s = decode(b, &out);
    return std::make_pair(s, out == expected);
  };
  auto one = with_parts(1);  // an empty tile-part first: the packets are in the second
  EXPECT_TRUE(one.first.is_ok()) << test::format(one.first);
  EXPECT_TRUE(one.second);
  EXPECT_TRUE(has(with_parts(256).first, "more than 256 tile-parts"));
  // A tile-part header longer than its Psot.
  Bytes b(cs.begin(), cs.begin() + static_cast<std::ptrdiff_t>(sot));
  const uint8_t part[] = {0xFF, 0x90, 0,    10,   0, 0, 0, 0,    0,   14,
                          0,    2,    0xFF, 0x64, 0, 3, 0, 0xFF, 0x93};
  b.insert(b.end(), part, part + sizeof(part));
  b.insert(b.end(), cs.begin() + static_cast<std::ptrdiff_t>(sot), cs.end());
  Bytes out;
  EXPECT_TRUE(has(decode(b, &out), "runs past its Psot"));
  // Psot 0 with a pad byte after the EOC, and without an EOC; a cut tile-part header.
  Bytes z = cs;
  for (int i = 0; i < 4; ++i) z[sot + 6 + i] = 0;
  z.push_back(0);
  Status s = decode(z, &out);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  z.resize(z.size() - 3);
  EXPECT_TRUE(has(decode(z, &out), "data ends before EOC"));
  z.resize(sot + 13);
  EXPECT_TRUE(has(decode(z, &out), "data ends in a tile-part header"));
  // Cut inside the first packets (Psot and EOC moved up).
  for (size_t n = sot + 15; n < sot + 60; ++n) {
    Bytes cut(cs.begin(), cs.begin() + static_cast<std::ptrdiff_t>(n));
    const size_t psot = n - sot;
    cut[sot + 8] = static_cast<uint8_t>(psot >> 8);
    cut[sot + 9] = static_cast<uint8_t>(psot);
    cut.push_back(0xFF);
    cut.push_back(0xD9);
    EXPECT_FALSE(decode(cut, &out).is_ok()) << n;
  }
  // SOP markers before the first packet (Scod says they may be there).
  Bytes sop(cs.begin(), cs.begin() + static_cast<std::ptrdiff_t>(sot + 14));
  const uint8_t marker[] = {0xFF, 0x91, 0, 4, 0, 0};
  sop.insert(sop.end(), marker, marker + 6);
  sop.insert(sop.end(), cs.begin() + static_cast<std::ptrdiff_t>(sot + 14), cs.end());
  sop[49] = 0x02;
  const uint32_t psot = ((uint32_t{cs[sot + 8]} << 8) | cs[sot + 9]) + 6;
  sop[sot + 8] = static_cast<uint8_t>(psot >> 8);
  sop[sot + 9] = static_cast<uint8_t>(psot);
  s = decode(sop, &out);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  EXPECT_TRUE(out == expected);
}

TEST(CtDicomJ2k, MoreRefusals) {
  const Bytes cs = fragment_of(fixture("j2k16_0.dcm"));
  Bytes out;
  auto splice = [&](std::initializer_list<uint8_t> segment, uint8_t progression) {
    Bytes b(cs.begin(), cs.begin() + 59);
    b.insert(b.end(), segment.begin(), segment.end());
    b.insert(b.end(), cs.begin() + 59, cs.end());
    b[50] = progression;
    return decode(b, &out);
  };
  EXPECT_TRUE(has(splice({0xFF, 0x53, 0, 14, 0, 1, 4, 4, 4, 0, 1, 0x77, 0x77, 0x70, 0x07, 0x77}, 0),
                  "precinct size 1"));
  EXPECT_TRUE(has(splice({0xFF, 0x53, 0, 14, 0, 1, 4, 4, 4, 0, 1, 0x22, 0x22, 0x22, 0x22, 0x22}, 0),
                  "too small"));
  EXPECT_TRUE(has(splice({0xFF, 0x53, 0, 14, 0, 1, 4, 4, 4, 0, 1, 0x55, 0x55, 0x55, 0x55, 0x55}, 3),
                  "several precincts"));
  {  // derived quantisation with exponent 0 on a 9/7 header: negative band exponents
    Bytes b(cs.begin(), cs.begin() + 59);
    const uint8_t qcc[] = {0xFF, 0x5D, 0, 6, 0, 0x21, 0, 0};
    b.insert(b.end(), qcc, qcc + sizeof(qcc));
    b.insert(b.end(), cs.begin() + 59, cs.end());
    b[58] = 0;
    EXPECT_TRUE(has(decode(b, &out), "negative exponent"));
  }
  EXPECT_TRUE(has(splice({0xFF, 0x61, 0, 3, 0}, 0), "PPT"));
  EXPECT_TRUE(has(splice({0xFF, 0x63, 0, 6, 0, 1, 0, 1}, 0), "unexpected") ||
              splice({0xFF, 0x63, 0, 6, 0, 1, 0, 1}, 0).is_ok());  // CRG: skipped
  // No COD.
  Bytes b(cs.begin(), cs.begin() + 45);
  b.insert(b.end(), cs.begin() + 59, cs.end());
  EXPECT_TRUE(has(decode(b, &out), "lacks COD or QCD"));
  // 16-bit samples where 8 are allocated.
  EXPECT_TRUE(has(decode(cs, &out, 0, 8), "16-bit samples, more than the 8 bits"));
  // 512 x 512 in tiles of 1 x 1: too many tiles.
  Bytes big = cs;
  big[10] = 2;  // Xsiz 0x200 + 0x40
  big[11] = 0;
  big[14] = 2;
  big[15] = 0;
  big[27] = 1;
  big[31] = 1;
  TestArena t(8 << 20);
  Bytes frame(2 * 512 * 512);
  const Status s =
      ct_detail::jpeg2000_decode(t.arena, big.data(), big.size(), 512, 512, 16, frame.data());
  EXPECT_TRUE(has(s, "more than 65535 tiles")) << s.message();
  // Rsiz with Part 2 bits; an image offset of 2^31.
  Bytes r = cs;
  r[6] = 0x80;
  EXPECT_TRUE(has(decode(r, &out), "Part 2"));
  r = cs;
  r[8] = 0x80;
  EXPECT_TRUE(has(decode(r, &out), "2^31"));
}

TEST(CtDicomJ2k, Jp2BoxVariants) {
  const Bytes cs = fragment_of(fixture("j2k16_0.dcm"));
  const Bytes sig = {0, 0, 0, 12, 'j', 'P', ' ', ' ', 0x0D, 0x0A, 0x87, 0x0A};
  Bytes xl = sig;  // an XLBox (length 1, then 64 bits)
  const uint64_t box = cs.size() + 16;
  const uint8_t head[] = {0, 0, 0, 1, 'j', 'p', '2', 'c'};
  xl.insert(xl.end(), head, head + 8);
  for (int i = 0; i < 8; ++i) xl.push_back(static_cast<uint8_t>(box >> (56 - 8 * i)));
  xl.insert(xl.end(), cs.begin(), cs.end());
  Bytes out;
  Status s = decode(xl, &out);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  Bytes cut = sig;  // an XLBox cut short
  cut.insert(cut.end(), head, head + 8);
  cut.push_back(0);
  EXPECT_TRUE(has(decode(cut, &out), "without a codestream box"));
  Bytes past = sig;  // a box longer than the file
  const uint8_t long_box[] = {0, 0, 1, 0, 'j', 'p', '2', 'h'};
  past.insert(past.end(), long_box, long_box + 8);
  EXPECT_TRUE(has(decode(past, &out), "runs past the data"));
  Bytes small = sig;  // a length under its header
  const uint8_t small_box[] = {0, 0, 0, 4, 'j', 'p', '2', 'h'};
  small.insert(small.end(), small_box, small_box + 8);
  EXPECT_TRUE(has(decode(small, &out), "runs past the data"));
}

// The first packet headers byte by byte: long Lblock runs, many passes, cut headers.
TEST(CtDicomJ2k, PacketHeaderSweep) {
  const Bytes cs = fragment_of(fixture("j2k97.dcm"));
  size_t sod = 0;
  while (!(cs[sod] == 0xFF && cs[sod + 1] == 0x93)) ++sod;
  for (size_t at = sod + 2; at < sod + 40; ++at) {
    for (uint8_t v : {uint8_t{0x00}, uint8_t{0xFF}, uint8_t{0x7F}, uint8_t{0xFE}, uint8_t{0xC0}}) {
      Bytes b = cs;
      b[at] = v;
      if (v == 0xFF) b[at + 1] = 0x7F;  // a run of 1 bits (stuffing keeps it a header)
      expect_clean(b, "packet header byte " + std::to_string(at));
    }
  }
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

// The image of fixtures/ct/j2k_style*.j2k (make_j2k_styles.py's samples(), the same values):
// a constant band, a ramp, 8 x 8 squares with sharp edges and xorshift32 noise, 12 bits.
std::vector<uint16_t> j2k_style_samples() {
  std::vector<uint16_t> out;
  uint32_t state = 2463534242u;
  for (uint32_t y = 0; y < kRows; ++y) {
    for (uint32_t x = 0; x < kColumns; ++x) {
      state ^= state << 13;
      state ^= state >> 17;
      state ^= state << 5;
      uint32_t v = state % 4096;
      if (x < 16) {
        v = 2048;
      } else if (x < 32) {
        v = 64 * x + 8 * y;
      } else if (((x >> 3) + (y >> 3)) % 2 == 0) {
        v = y < 28 ? 3900 : 100;
      }
      out.push_back(static_cast<uint16_t>(v));
    }
  }
  return out;
}

// fixtures/ct/`name` (make_j2k_styles.py) decodes, lossless, to j2k_style_samples().
void expect_style_image(const std::string& name) {
  static const std::vector<uint16_t> image = j2k_style_samples();
  const Bytes cs = fixture(name);
  Bytes out;
  const Status s = decode(cs, &out, 0, 12);
  ASSERT_TRUE(s.is_ok()) << name << ": " << test::format(s);
  size_t wrong = 0, first = image.size();
  for (size_t i = 0; i < image.size(); ++i) {
    const uint16_t v = static_cast<uint16_t>(out[2 * i] | (out[2 * i + 1] << 8));
    if (v != image[i] && wrong++ == 0) first = i;
  }
  EXPECT_EQ(wrong, 0u) << name << ": first wrong sample " << first;
}

// The code-block styles the decoder reads (T.800 Table A.19), each on the same image coded by
// openjpeg (opj_compress -M; 16 x 16 code-blocks, 3 levels): context reset after each pass,
// vertically causal contexts, predictable termination, segmentation symbols, and all four.
// Each decodes to the image itself, lossless. (Before these, the styles were only set on a
// stream coded without them, which checks that nothing crashes, not that they decode.)
TEST(CtDicomJ2k, CodeBlockStylesDecodeLossless) {
  for (int style : {0, 2, 8, 16, 32, 58}) {
    expect_style_image("j2k_style" + std::to_string(style) + ".j2k");
  }
}

// Tiles that leave one-sample signals to the inverse wavelet (F.3.7): 63 x 55 tiles, whose
// last column and row of tiles are one sample wide at odd indices (a high-pass sample,
// halved), and the image at offset (1, 1) in 64 x 56 tiles, whose first tile starts at odd
// indices and whose last column and row are one sample at even indices (low-pass, kept).
TEST(CtDicomJ2k, OneSampleTilesDecodeLossless) {
  expect_style_image("j2k_tiles63x55.j2k");
  expect_style_image("j2k_offset_tiles.j2k");
}

// The same image in the codestream's other layouts: three quality layers (the last one
// lossless) in each of the five progression orders; and in the three orders that allow
// several precincts a resolution, precincts (16 x 16 at the top resolution, smaller below)
// that cap the 32 x 32 code-blocks, with SOP and EPH markers. (The other fixtures have one
// layer and one precinct a resolution, where the orders read the packets alike.) And 4 tiles
// in 3 tile-parts each, one after the other.
TEST(CtDicomJ2k, LayoutsDecodeLossless) {
  for (const char* order : {"lrcp", "rlcp", "rpcl", "pcrl", "cprl"}) {
    expect_style_image(std::string("j2k_layers_") + order + ".j2k");
  }
  for (const char* order : {"lrcp", "rlcp", "rpcl"}) {
    expect_style_image(std::string("j2k_precincts_") + order + ".j2k");
  }
  expect_style_image("j2k_tileparts.j2k");
}

// The 9/7 wavelet at rate 6 overshoots at the image's sharp edges and in its noise: each
// sample is clamped to the precision's range (12 bits unsigned, then signed), and equals
// openjpeg's decoding within 1 (it computes in float, we in double). openjpeg's has samples at
// both ends of the range, so the clamp decides there.
TEST(CtDicomJ2k, IrreversibleIsClampedToThePrecision) {
  for (const char* stem : {"j2k_u97", "j2k_s97"}) {
    const bool is_signed = stem[4] == 's';
    const int lo = is_signed ? -2048 : 0, hi = is_signed ? 2047 : 4095;
    const Bytes oracle = fixture(std::string(stem) + ".opj");
    ASSERT_EQ(oracle.size(), 2 * kRows * kColumns) << stem;
    Bytes out;
    const Status s = decode(fixture(std::string(stem) + ".j2k"), &out, 0, 12);
    ASSERT_TRUE(s.is_ok()) << stem << ": " << test::format(s);
    size_t at_lo = 0, at_hi = 0, outside = 0, apart = 0;
    for (size_t i = 0; i < kRows * kColumns; ++i) {
      const int v = static_cast<int16_t>(out[2 * i] | (out[2 * i + 1] << 8));
      const int o = static_cast<int16_t>(oracle[2 * i] | (oracle[2 * i + 1] << 8));
      at_lo += o == lo ? 1 : 0;
      at_hi += o == hi ? 1 : 0;
      outside += v < lo || v > hi ? 1 : 0;
      apart += std::abs(v - o) > 1 ? 1 : 0;
    }
    EXPECT_GT(at_lo, 10u) << stem;
    EXPECT_GT(at_hi, 10u) << stem;
    EXPECT_EQ(outside, 0u) << stem;
    EXPECT_EQ(apart, 0u) << stem;
  }
}

}  // namespace
}  // namespace splintcore
