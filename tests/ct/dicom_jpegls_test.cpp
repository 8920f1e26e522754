// JPEG-LS in DICOM (issue 31: transfer syntaxes 1.2.840.10008.1.2.4.80 lossless and .81
// near-lossless; src/ct/jpeg_ls.cpp, T.87). The fixtures (fixtures/ct/make_ct_fixtures.py) are
// made by dcmtk's dcmcjpls and gdcm: lossless files read bit-identical to their uncompressed
// twins; near-lossless ones read to exactly what dcmdjpls (CharLS, an independent decoder)
// made of them when the fixtures were written, within NEAR of the original; malformed streams
// are clear errors at byte offsets.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "ct/jpeg_ls.h"
#include "splintcore/ct.h"
#include "support/dicom_read.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::Bytes;
using test::TestArena;

Bytes fixture(const std::string& name) { return test::ct_fixture(name); }

using Series = test::DicomRead;

Series read(const std::vector<Bytes>& files, size_t arena_bytes = 4 << 20) {
  return test::read_dicom_bytes(files, test::numbered_names(files.size(), "s"), arena_bytes);
}

Series read_names(const std::vector<std::string>& names) {
  std::vector<Bytes> files;
  for (const std::string& n : names) files.push_back(fixture(n));
  return read(files);
}

void expect_twins(const std::vector<std::string>& names, const std::vector<std::string>& twins,
                  const char* syntax) {
  const Series plain = read_names(twins);
  ASSERT_TRUE(plain.status.is_ok()) << test::format(plain.status);
  const Series z = read_names(names);
  ASSERT_TRUE(z.status.is_ok()) << names[0] << ": " << test::format(z.status);
  EXPECT_EQ(z.hu.size(), plain.hu.size());
  EXPECT_TRUE(z.hu == plain.hu) << names[0];
  EXPECT_STREQ(z.info.transfer_syntax, syntax) << names[0];
}

uint32_t le32(const Bytes& b, size_t p) {
  return uint32_t{b[p]} | (uint32_t{b[p + 1]} << 8) | (uint32_t{b[p + 2]} << 16) |
         (uint32_t{b[p + 3]} << 24);
}

// The offset of (7FE0,0010) in an explicit VR little endian file.
size_t pixel_data_tag(const Bytes& file) {
  size_t p = 132;
  while (p + 12 <= file.size() &&
         !(file[p] == 0xE0 && file[p + 1] == 0x7F && file[p + 2] == 0x10 && file[p + 3] == 0)) {
    ++p;
  }
  EXPECT_LT(p + 12, file.size());
  return p;
}

// The bytes of a file's one fragment (after the basic offset table), and its file offset.
Bytes fragment_of(const Bytes& file, size_t* at) {
  size_t p = pixel_data_tag(file) + 12;
  p += 8 + le32(file, p + 4);  // the basic offset table
  const uint32_t length = le32(file, p + 4);
  *at = p + 8;
  return Bytes(file.begin() + static_cast<std::ptrdiff_t>(p + 8),
               file.begin() + static_cast<std::ptrdiff_t>(p + 8 + length));
}

// The samples of an uncompressed file (16 bits allocated, or 8).
std::vector<uint32_t> raw_samples(const Bytes& file, uint32_t bytes_per_sample) {
  const size_t p = pixel_data_tag(file);
  const uint32_t length = le32(file, p + 8);
  std::vector<uint32_t> v;
  for (size_t i = p + 12; i + bytes_per_sample <= p + 12 + length; i += bytes_per_sample) {
    v.push_back(bytes_per_sample == 2 ? uint32_t{file[i]} | (uint32_t{file[i + 1]} << 8)
                                      : uint32_t{file[i]});
  }
  return v;
}

// Decodes a file's fragment (64 x 56) straight with the decoder.
Status decode_size(const Bytes& frame, uint32_t rows, uint32_t columns, uint32_t max_precision,
                   std::vector<uint32_t>* samples, size_t arena_bytes = 1 << 16) {
  TestArena t(arena_bytes);
  Bytes out(2 * size_t{rows} * columns, 0xEE);
  const Status s = ct_detail::jpeg_ls_decode(t.arena, frame.data(), frame.size(), rows, columns,
                                             max_precision, out.data());
  EXPECT_EQ(t.arena.used(), 0u);
  samples->clear();
  for (size_t i = 0; i < out.size(); i += 2) samples->push_back(out[i] | (out[i + 1] << 8));
  return s;
}

Status decode(const Bytes& frame, std::vector<uint32_t>* samples, uint32_t max_precision = 16,
              size_t arena_bytes = 1 << 16) {
  return decode_size(frame, 56, 64, max_precision, samples, arena_bytes);
}

std::string message(const Status& s) { return s.message(); }

const std::vector<std::string> kRaw16 = {"raw16_2.dcm", "raw16_0.dcm", "raw16_1.dcm"};

// ---- Lossless: bit-identical to the twins ---------------------------------------------------

TEST(CtDicomJpegLs, LosslessEqualsItsTwin) {
  expect_twins({"jls16_1.dcm", "jls16_2.dcm", "jls16_0.dcm"}, kRaw16, "1.2.840.10008.1.2.4.80");
  expect_twins({"jls8.dcm"}, {"raw8.dcm"}, "1.2.840.10008.1.2.4.80");
  expect_twins({"jlss12.dcm"}, {"raws12.dcm"}, "1.2.840.10008.1.2.4.80");
  // LSE with T1 5, T2 12, T3 40, RESET 32 instead of the defaults.
  expect_twins({"jls16_lse.dcm"}, {"raw16_0.dcm"}, "1.2.840.10008.1.2.4.80");
  // Restart markers every 5 lines (make_ct_fixtures.py's own encoder, checked by gdcm).
  expect_twins({"jls16_rst.dcm"}, {"raw16_0.dcm"}, "1.2.840.10008.1.2.4.80");
}

TEST(CtDicomJpegLs, LosslessSamplesAreTheRawOnes) {
  for (const char* name : {"jls16_0.dcm", "jls16_lse.dcm"}) {
    size_t at = 0;
    std::vector<uint32_t> got;
    SPLINTCORE_ASSERT_OK(decode(fragment_of(fixture(name), &at), &got));
    EXPECT_EQ(got, raw_samples(fixture("raw16_0.dcm"), 2)) << name;
  }
}

// ---- Near-lossless: CharLS's decoding exactly, within NEAR of the original -----------------

TEST(CtDicomJpegLs, NearLosslessEqualsCharLsAndIsWithinNear) {
  struct Case {
    const char* name;
    const char* oracle;  // dcmdjpls's decoding of `name`
    const char* original;
    uint32_t bytes;
  };
  for (const Case& c : {Case{"jlsn16_0.dcm", "rawn16_0.dcm", "raw16_0.dcm", 2},
                        Case{"jlsn8.dcm", "rawn8.dcm", "raw8.dcm", 1},
                        Case{"jlsns12.dcm", "rawns12.dcm", "raws12.dcm", 2},
                        Case{"jlsn16_rst.dcm", "rawn16_rst.dcm", "raw16_0.dcm", 2}}) {
    expect_twins({c.name}, {c.oracle}, "1.2.840.10008.1.2.4.81");
    size_t at = 0;
    const Bytes frame = fragment_of(fixture(c.name), &at);
    std::vector<uint32_t> got;
    SPLINTCORE_ASSERT_OK(decode(frame, &got));
    const std::vector<uint32_t> oracle = raw_samples(fixture(c.oracle), c.bytes);
    const std::vector<uint32_t> original = raw_samples(fixture(c.original), c.bytes);
    ASSERT_EQ(got.size(), original.size());
    EXPECT_EQ(got, oracle) << c.name;
    uint32_t worst = 0, differ = 0;
    for (size_t i = 0; i < got.size(); ++i) {
      const uint32_t d = got[i] > original[i] ? got[i] - original[i] : original[i] - got[i];
      worst = d > worst ? d : worst;
      differ += d != 0 ? 1 : 0;
    }
    EXPECT_LE(worst, 2u) << c.name;     // NEAR
    EXPECT_GT(differ, 100u) << c.name;  // it is lossy: not a lossless file by mistake
  }
}

// The fuzz seeds (tests/fuzz/ct_corpus.py, fixtures/ct/jpegls_encode.py: 12 bits stored,
// signed, 4 x 5) read to the voxels of their uncompressed twin.
TEST(CtDicomJpegLs, CorpusSeedEqualsItsTwin) {
  const std::string dir = std::string(SPLINTCORE_FIXTURES_DIR) + "/fuzz/ct_dicom/";
  const Series plain = read({test::read_file_bytes(dir + "explicit_4x5.dcm")});
  const Series z = read({test::read_file_bytes(dir + "jls_one.dcm")});
  ASSERT_TRUE(z.status.is_ok()) << test::format(z.status);
  ASSERT_EQ(plain.hu.size(), 20u);
  EXPECT_TRUE(z.hu == plain.hu);
}

// ---- Memory ---------------------------------------------------------------------------------

TEST(CtDicomJpegLs, ArenaBound) {
  size_t at = 0;
  const Bytes frame = fragment_of(fixture("jls16_0.dcm"), &at);
  std::vector<uint32_t> got;
  // The bound, and (the test arena being aligned, so no padding) its one allocation exactly.
  const size_t bound = static_cast<size_t>(ct_detail::jpeg_ls_arena_bytes(64));
  EXPECT_LT(bound, 10000u);
  SPLINTCORE_EXPECT_OK(decode(frame, &got, 16, bound));
  const size_t exact = bound - (Arena::kDefaultAlignment - 1);
  SPLINTCORE_EXPECT_OK(decode(frame, &got, 16, exact));
  EXPECT_EQ(decode(frame, &got, 16, exact - 1).code(), StatusCode::kArenaExhausted);
  // The series reader: its first read's high water is enough, one byte less is not.
  const std::vector<Bytes> files = {fixture("jls16_0.dcm")};
  const Series first = read(files);
  ASSERT_TRUE(first.status.is_ok()) << test::format(first.status);
  EXPECT_TRUE(read(files, first.high_water).status.is_ok());
  EXPECT_EQ(read(files, first.high_water - 1).status.code(), StatusCode::kArenaExhausted);
}

// ---- Truncation and corruption --------------------------------------------------------------

TEST(CtDicomJpegLs, TruncatedFramesAndFilesAreErrors) {
  for (const char* name : {"jls16_0.dcm", "jlsn8.dcm", "jls16_rst.dcm"}) {
    const Bytes file = fixture(name);
    size_t at = 0;
    const Bytes frame = fragment_of(file, &at);
    std::vector<uint32_t> got;
    for (size_t cut = 0; cut + 1 < frame.size(); cut += test::kSweepStep) {
      const Status s =
          decode(Bytes(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(cut)), &got);
      ASSERT_FALSE(s.is_ok()) << name << " frame cut at " << cut;
      ASSERT_LE(s.byte_offset(), cut) << test::format(s);
      ASSERT_NE(message(s).find("JPEG-LS: "), std::string::npos) << message(s);
    }
    for (size_t cut = at; cut < file.size(); cut += 7) {
      const Series r = read({Bytes(file.begin(), file.begin() + static_cast<std::ptrdiff_t>(cut))});
      ASSERT_FALSE(r.status.is_ok()) << name << " cut at " << cut;
    }
  }
  // Cut inside the coded data: named as such, at the end of the data.
  size_t at = 0;
  const Bytes frame = fragment_of(fixture("jls16_0.dcm"), &at);
  std::vector<uint32_t> got;
  const Status s = decode(Bytes(frame.begin(), frame.begin() + 1000), &got);
  EXPECT_EQ(s.code(), StatusCode::kTruncated);
  EXPECT_NE(message(s).find("coded data ends inside a line"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), 1000u);
}

// The offset of the first marker `code` in a frame.
size_t marker(const Bytes& frame, uint8_t code) {
  size_t p = 0;
  while (p + 1 < frame.size() && !(frame[p] == 0xFF && frame[p + 1] == code)) ++p;
  EXPECT_LT(p + 1, frame.size());
  return p;
}

Bytes with(Bytes b, size_t at, std::vector<uint8_t> bytes) {
  for (size_t i = 0; i < bytes.size(); ++i) b[at + i] = bytes[i];
  return b;
}

Bytes inserted(Bytes b, size_t at, std::vector<uint8_t> bytes) {
  b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), bytes.begin(), bytes.end());
  return b;
}

TEST(CtDicomJpegLs, MalformedStreamsNameCauseAndOffset) {
  size_t at = 0;
  const Bytes good = fragment_of(fixture("jls16_0.dcm"), &at);
  const size_t sof = marker(good, 0xF7), lse = marker(good, 0xF8), sos = marker(good, 0xDA);
  const size_t eoi = marker(good, 0xD9);
  struct Case {
    Bytes frame;
    StatusCode code;
    const char* text;
    size_t offset;
  };
  const std::vector<Case> cases = {
      {with(good, 0, {0x00}), StatusCode::kParseError, "no SOI", 0},
      {with(good, sof + 9, {3}), StatusCode::kUnsupported, "3 components", sof},
      {with(good, sof + 4, {17}), StatusCode::kParseError, "precision not in 2..16", sof},
      {with(good, sof + 5, {0xFF, 0xFF}), StatusCode::kParseError, "differs from the DICOM",
       sof},  // an absurd height
      {with(good, sof + 5, {0, 0}), StatusCode::kUnsupported, "image size 0", sof},
      {with(good, sof + 1, {0xC3}), StatusCode::kUnsupported, "another JPEG process", sof},
      {with(good, lse + 4, {2}), StatusCode::kUnsupported, "mapping table", lse},
      {with(good, lse + 4, {4}), StatusCode::kUnsupported, "oversize", lse},
      {with(good, lse + 4, {9}), StatusCode::kParseError, "LSE id", lse},
      {with(good, lse + 9, {0, 1}), StatusCode::kParseError, "thresholds", lse},  // T2 < T1
      {with(good, lse + 13, {0, 2}), StatusCode::kParseError, "RESET", lse},
      {with(good, lse + 5, {0, 100}), StatusCode::kParseError, "thresholds", lse},  // > MAXVAL
      {with(good, sos + 6, {2}), StatusCode::kUnsupported, "mapping table", sos},
      {with(with(good, lse + 5, {0, 255}), sos + 7, {0x80}), StatusCode::kParseError, "NEAR", sos},
      {with(good, sos + 8, {3}), StatusCode::kParseError, "ILV", sos},
      {with(good, sos + 9, {1}), StatusCode::kUnsupported, "point transform", sos},
      {with(good, sos + 5, {7}), StatusCode::kParseError, "another component", sos},
      {with(good, sos + 4, {2}), StatusCode::kParseError, "one component", sos},
      {with(good, eoi + 1, {0xD3}), StatusCode::kParseError, "unexpected marker", eoi},
      {with(good, eoi + 1, {0xDA}), StatusCode::kParseError, "more than one scan", eoi},
      {with(good, sos + 20, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0}), StatusCode::kParseError,
       "invalid code", 0},
      {inserted(good, eoi, {0x12, 0x34, 0x56}), StatusCode::kParseError,
       "continues past the last sample", eoi + 3},
      {inserted(good, sof, {0xFF, 0xDC, 0, 4, 0, 1}), StatusCode::kUnsupported, "DNL", sof},
      {inserted(good, sof, {0xFF, 0xFE, 0, 1}), StatusCode::kParseError, "length under 2", sof},
      {inserted(good, sof, {0xFF, 0xDD, 0, 3, 0}), StatusCode::kParseError, "DRI length", sof},
      {inserted(good, sof, {0xFF, 0xDA, 0, 8, 1, 1, 0, 0, 0, 0}), StatusCode::kParseError,
       "SOS before SOF55", sof},
      {inserted(good, sos, {0xFF, 0xF7, 0, 11, 16, 0, 56, 0, 64, 1, 1, 0x11, 0}),
       StatusCode::kParseError, "a second SOF", sos},
      {inserted(good, sos, {0xFF, 0xDD, 0, 4, 0, 1}), StatusCode::kParseError,
       "continues past the end of a restart interval", 0},
      {Bytes(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(sos)), StatusCode::kTruncated,
       "data ends before EOI", sos},
      {with(good, sos, {0x12}), StatusCode::kParseError, "expected a marker", sos},
  };
  for (const Case& c : cases) {
    std::vector<uint32_t> got;
    const Status s = decode(c.frame, &got);
    EXPECT_EQ(s.code(), c.code) << c.text << ": " << test::format(s);
    EXPECT_NE(message(s).find(c.text), std::string::npos) << c.text << ": " << message(s);
    if (c.offset != 0) {
      EXPECT_EQ(s.byte_offset(), c.offset) << c.text << ": " << message(s);
    }
  }
  // A precision over the DICOM Bits Allocated; EOI before any scan.
  std::vector<uint32_t> got;
  Status s = decode(good, &got, 12);
  EXPECT_NE(message(s).find("over the DICOM Bits Allocated 12"), std::string::npos) << message(s);
  const Bytes no_scan = {0xFF, 0xD8, 0xFF, 0xD9};
  s = decode(no_scan, &got);
  EXPECT_NE(message(s).find("EOI before the scan"), std::string::npos) << message(s);
}

TEST(CtDicomJpegLs, RestartMarkersInOrder) {
  size_t at = 0;
  const Bytes good = fragment_of(fixture("jls16_rst.dcm"), &at);
  std::vector<uint32_t> got;
  SPLINTCORE_ASSERT_OK(decode(good, &got));
  EXPECT_EQ(got, raw_samples(fixture("raw16_0.dcm"), 2));
  // The third RSTm (RST2) renumbered, then dropped.
  const size_t rst2 = marker(good, 0xD2);
  Status s = decode(with(good, rst2 + 1, {0xD5}), &got);
  EXPECT_EQ(s.code(), StatusCode::kParseError) << test::format(s);
  EXPECT_NE(message(s).find("expected the next RSTm marker"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), rst2);
  Bytes dropped = good;
  dropped.erase(dropped.begin() + static_cast<std::ptrdiff_t>(rst2),
                dropped.begin() + static_cast<std::ptrdiff_t>(rst2 + 2));
  s = decode(dropped, &got);
  EXPECT_FALSE(s.is_ok());
  EXPECT_NE(message(s).find("restart interval"), std::string::npos) << message(s);
  // The stream cut just before RST2.
  s = decode(Bytes(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(rst2)), &got);
  EXPECT_EQ(s.code(), StatusCode::kTruncated) << test::format(s);
  EXPECT_NE(message(s).find("before RSTm"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), rst2);
}

// In a series the offsets are the file's: one fragment's start plus the offset in it.
TEST(CtDicomJpegLs, SeriesErrorsNameTheFileAndItsOffset) {
  Bytes file = fixture("jls16_0.dcm");
  size_t at = 0;
  const Bytes frame = fragment_of(file, &at);
  const size_t lse = marker(frame, 0xF8);
  file[at + lse + 4] = 2;
  const Series r = read({file});
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported) << test::format(r.status);
  EXPECT_NE(message(r.status).find("JPEG-LS: LSE mapping table"), std::string::npos);
  EXPECT_EQ(r.status.byte_offset(), at + lse);
  EXPECT_STREQ(r.status.file(), "s0.dcm");
}

// Every byte of the coded data changed: a Status or an image, never a crash (the fuzz target
// tests/fuzz/ct_codecs_fuzz.cpp goes further).
TEST(CtDicomJpegLs, CorruptCodedDataNeverCrashes) {
  for (const char* name : {"jls16_0.dcm", "jlsn16_0.dcm"}) {
    size_t at = 0;
    const Bytes frame = fragment_of(fixture(name), &at);
    const size_t sos = marker(frame, 0xDA);
    std::vector<uint32_t> got;
    for (size_t i = sos + 10; i < frame.size(); i += 5) {
      for (uint8_t x : {0x5A, 0xFF}) {
        Bytes f = frame;
        f[i] = static_cast<uint8_t>(f[i] ^ x);
        (void)decode(f, &got);
      }
    }
  }
}

// ---- Small and unusual streams (the seeds of tests/fuzz/ct_corpus.py, made by
// fixtures/ct/jpegls_encode.py; hand-made bits) -----------------------------------------------

struct Seed {
  uint32_t precision, rows, columns;
  Bytes frame;
};

Seed seed(const std::string& name) {
  const Bytes b =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/fuzz/ct_codecs/" + name);
  EXPECT_GT(b.size(), 3u) << name;
  return Seed{2 + (uint32_t{b[0]} >> 2) % 15u, 1 + b[1] % 64u, 1 + b[2] % 64u,
              Bytes(b.begin() + 3, b.end())};
}

TEST(CtDicomJpegLs, SmallStreamsDecodeToTheirSamples) {
  const std::string dir = std::string(SPLINTCORE_FIXTURES_DIR) + "/fuzz/ct_dicom/";
  std::vector<uint32_t> twelve = raw_samples(test::read_file_bytes(dir + "explicit_4x5.dcm"), 2);
  ASSERT_EQ(twelve.size(), 20u);
  for (uint32_t& v : twelve) v &= 0xFFF;  // 12 bits stored
  auto masked = [&](uint32_t bits) {
    std::vector<uint32_t> v = twelve;
    for (uint32_t& x : v) x &= (1u << bits) - 1;
    return v;
  };
  auto product = [](bool down) {  // 170 x (19 - y) or 170 x y, 20 x 20
    std::vector<uint32_t> v;
    for (uint32_t y = 0; y < 20; ++y) {
      for (uint32_t x = 0; x < 20; ++x) v.push_back(170 * x * (down ? 19 - y : y));
    }
    return v;
  };
  struct Case {
    const char* name;
    std::vector<uint32_t> want;
  };
  for (const Case& c :
       {Case{"jls.bin", twelve}, Case{"jls_restart.bin", twelve}, Case{"jls_p2.bin", masked(2)},
        Case{"jls_p5.bin", masked(5)}, Case{"jls_p7.bin", masked(7)},
        Case{"jls_c_high.bin", product(false)}, Case{"jls_c_low.bin", product(true)}}) {
    const Seed sd = seed(c.name);
    std::vector<uint32_t> got;
    SPLINTCORE_ASSERT_OK(decode_size(sd.frame, sd.rows, sd.columns, sd.precision, &got));
    EXPECT_EQ(got, c.want) << c.name;
  }
  // 40 x 40 at precisions 2, 4, 7 and 8 with the default thresholds (computed from MAXVAL,
  // clamped at small ones): local gradients of every size around them, so every context
  // boundary is met (a 4 x 5 image meets few). Then MAXVAL 64 at precision 7 and 128 at 8,
  // given in an LSE segment with the thresholds left to their defaults: there the two
  // formulas of C.2.4.1.1 meet (128 takes the upper one; 64 divides 256 unevenly), which no
  // MAXVAL of 2^P - 1 tells apart.
  struct Grad {
    uint32_t p, top;
    std::string name;
  };
  for (const Grad& g :
       {Grad{2, 3, "jls_grad_p2.bin"}, Grad{4, 15, "jls_grad_p4.bin"},
        Grad{7, 127, "jls_grad_p7.bin"}, Grad{8, 255, "jls_grad_p8.bin"},
        Grad{7, 64, "jls_grad_maxval64.bin"}, Grad{8, 128, "jls_grad_maxval128.bin"}}) {
    const uint32_t p = g.p;
    std::vector<uint32_t> want;
    for (uint32_t y = 0; y < 40; ++y) {
      for (uint32_t x = 0; x < 40; ++x) want.push_back(((x * y) / 3 + (x * x) / 7) % (g.top + 1));
    }
    const std::string& name = g.name;
    const Seed sd = seed(name);
    ASSERT_EQ(sd.precision, p);
    ASSERT_EQ(sd.rows * sd.columns, 1600u);
    std::vector<uint32_t> got;
    SPLINTCORE_ASSERT_OK(decode_size(sd.frame, sd.rows, sd.columns, sd.precision, &got));
    EXPECT_EQ(got, want) << name;
  }
  // NEAR 2.
  const Seed near = seed("jls_near.bin");
  std::vector<uint32_t> got;
  SPLINTCORE_ASSERT_OK(decode_size(near.frame, 4, 5, 16, &got));
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_LE(got[i] > twelve[i] ? got[i] - twelve[i] : twelve[i] - got[i], 2u) << i;
  }
  // A code of a mapped error past 2 RANGE + 2, in regular and in run interruption mode.
  for (const char* name : {"jls_bad_regular.bin", "jls_bad_run.bin"}) {
    const Seed bad = seed(name);
    const Status s = decode_size(bad.frame, 4, 5, 16, &got);
    EXPECT_EQ(s.code(), StatusCode::kParseError) << name << ": " << test::format(s);
    EXPECT_NE(message(s).find("invalid code"), std::string::npos) << message(s);
  }
}

// Bits written as JPEG-LS codes them (D.1: a 0 bit stuffed after each 0xFF byte), between a
// header for rows x columns samples of `precision` bits and EOI.
struct BitWriter {
  Bytes out;
  uint32_t byte = 0, n = 0, width = 8;
  void put(uint32_t bit) {
    byte = (byte << 1) | bit;
    if (++n == width) {
      out.push_back(static_cast<uint8_t>(byte));
      width = byte == 0xFF ? 7 : 8;
      byte = n = 0;
    }
  }
  Bytes stream(uint32_t rows, uint32_t columns, uint32_t precision) {
    while (n != 0 || width == 7) put(0);
    Bytes s = {0xFF,
               0xD8,
               0xFF,
               0xF7,
               0,
               11,
               static_cast<uint8_t>(precision),
               static_cast<uint8_t>(rows >> 8),
               static_cast<uint8_t>(rows),
               static_cast<uint8_t>(columns >> 8),
               static_cast<uint8_t>(columns),
               1,
               1,
               0x11,
               0,
               0xFF,
               0xDA,
               0,
               8,
               1,
               1,
               0,
               0,
               0,
               0};
    s.insert(s.end(), out.begin(), out.end());
    s.push_back(0xFF);
    s.push_back(0xD9);
    return s;
  }
};

TEST(CtDicomJpegLs, LongRunsAndRunsPastTheLine) {
  // A zero image of 3 lines of 32768: every line one run (A.7.1: full segments of
  // 2^J[RUNindex] samples, then a 1 for the shorter rest), RUNindex climbing to its top, 31,
  // and staying there (the segments of J 15 fit in a line).
  static const uint32_t kJ[32] = {0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,  2,  3,  3,  3,  3,
                                  4, 4, 5, 5, 6, 6, 7, 7, 8, 9, 10, 11, 12, 13, 14, 15};
  BitWriter w;
  uint32_t run_index = 0;
  for (uint32_t y = 0; y < 3; ++y) {
    uint32_t left = 32768;
    while (left > 0) {
      w.put(1);
      const uint32_t segment = 1u << kJ[run_index];
      if (segment > left) break;
      left -= segment;
      if (run_index < 31) ++run_index;
    }
  }
  EXPECT_EQ(run_index, 31u);
  std::vector<uint32_t> got;
  SPLINTCORE_ASSERT_OK(decode_size(w.stream(3, 32768, 8), 3, 32768, 8, &got, 1 << 19));
  EXPECT_EQ(got, std::vector<uint32_t>(3 * 32768, 0));
  // 1 x 5 zeros: four segments of 1 (RUNindex 4, J 1), then an interruption whose 1-bit count
  // (1) puts the run's end at 5, past the last sample (4).
  BitWriter past;
  for (uint32_t bit : {1, 1, 1, 1, 0, 1}) past.put(bit);
  const Status s = decode_size(past.stream(1, 5, 8), 1, 5, 8, &got);
  EXPECT_EQ(s.code(), StatusCode::kParseError) << test::format(s);
  EXPECT_NE(message(s).find("invalid code"), std::string::npos) << message(s);
}

Bytes lse(uint32_t maxval, uint32_t t1, uint32_t t2, uint32_t t3, uint32_t reset) {
  Bytes b = {0xFF, 0xF8, 0, 13, 1};
  for (uint32_t v : {maxval, t1, t2, t3, reset}) {
    b.push_back(static_cast<uint8_t>(v >> 8));
    b.push_back(static_cast<uint8_t>(v));
  }
  return b;
}

// LSE preset parameters against the ranges of C.2.4.1.1, on 8-bit streams (MAXVAL 255).
TEST(CtDicomJpegLs, PresetParametersAreChecked) {
  size_t at = 0;
  const Bytes lossless = fragment_of(fixture("jls8.dcm"), &at);
  const Bytes near = fragment_of(fixture("jlsn8.dcm"), &at);
  const uint8_t n = near[marker(near, 0xDA) + 7];  // its NEAR
  ASSERT_GT(n, 0u);
  ASSERT_LT(n, 100u);
  // refused: with the text; else accepted at the edge of its range: the encoder's samples
  // (same) or, other parameters making other contexts, other samples or an error that is not
  // a refusal of the parameters (no "LSE" or "SOS" in it).
  enum Kind { kRefused, kSame, kAccepted };
  struct Case {
    const Bytes* frame;
    Bytes segment;
    Kind kind;
    const char* text;
  };
  const char* kThresholds = "LSE thresholds not NEAR + 1 <= T1 <= T2 <= T3 <= MAXVAL";
  const std::vector<Case> cases = {
      {&lossless, lse(256, 0, 0, 0, 0), kRefused, "MAXVAL over 2^P - 1"},
      {&lossless, lse(255, 0, 0, 0, 0), kSame, "MAXVAL 2^P - 1, the default"},
      {&lossless, lse(0, 256, 0, 0, 0), kRefused, kThresholds},  // T1 > MAXVAL
      {&lossless, lse(0, 0, 256, 0, 0), kRefused, kThresholds},  // T2 > MAXVAL
      {&lossless, lse(0, 0, 0, 256, 0), kRefused, kThresholds},  // T3 > MAXVAL
      {&lossless, lse(0, 255, 255, 255, 0), kAccepted, "T1 = T2 = T3 = MAXVAL"},
      {&lossless, lse(0, 0, 0, 1, 0), kRefused, kThresholds},  // T3 < T2
      {&lossless, lse(0, 1, 1, 1, 0), kAccepted, "T1 = T2 = T3 = NEAR + 1"},
      {&lossless, lse(0, 0, 0, 0, 256), kRefused, "RESET"},  // over max(255, MAXVAL)
      {&lossless, lse(0, 0, 0, 0, 255), kAccepted, "RESET 255"},
      {&lossless, lse(0, 0, 0, 0, 2), kRefused, "RESET not in 3..max(255, MAXVAL)"},
      {&lossless, lse(0, 0, 0, 0, 3), kAccepted, "RESET 3"},
      {&near, lse(0, n, 0, 0, 0), kRefused, kThresholds},  // T1 < NEAR + 1
      {&near, lse(0, n + 1u, n + 1u, n + 1u, 0), kAccepted, "near: T1 = T2 = T3 = NEAR + 1"},
      {&lossless, lse(0, 100, 0, 0, 0), kAccepted, "T2, T3 raised to T1"},
  };
  std::vector<uint32_t> lossless_samples, near_samples, got;
  SPLINTCORE_ASSERT_OK(decode(lossless, &lossless_samples, 8));
  SPLINTCORE_ASSERT_OK(decode(near, &near_samples, 8));
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    const Bytes frame = inserted(*c.frame, marker(*c.frame, 0xDA), c.segment);
    const Status s = decode(frame, &got, 8);
    if (c.kind == kRefused) {
      EXPECT_EQ(s.code(), StatusCode::kParseError) << test::format(s);
      EXPECT_NE(message(s).find(c.text), std::string::npos) << message(s);
      EXPECT_EQ(s.byte_offset(), marker(*c.frame, 0xDA)) << message(s);
      continue;
    }
    const std::vector<uint32_t>& original = c.frame == &near ? near_samples : lossless_samples;
    if (c.kind == kSame) {
      SPLINTCORE_EXPECT_OK(s);
      EXPECT_TRUE(got == original);
      continue;
    }
    EXPECT_TRUE(!s.is_ok() || got != original);
    EXPECT_EQ(message(s).find("LSE"), std::string::npos) << message(s);
    EXPECT_EQ(message(s).find("SOS"), std::string::npos) << message(s);
  }
  // In the scan header: NEAR up to MAXVAL / 2 (127 here) is taken, 128 refused; ILV 2 (the
  // most) is taken and, one component, decodes the same samples.
  const size_t sos = marker(lossless, 0xDA);
  Status s = decode(with(lossless, sos + 7, {127}), &got, 8);
  EXPECT_EQ(message(s).find("NEAR"), std::string::npos) << message(s);
  EXPECT_TRUE(!s.is_ok() || got != lossless_samples);
  s = decode(with(lossless, sos + 7, {128}), &got, 8);
  EXPECT_NE(message(s).find("SOS NEAR over MAXVAL / 2"), std::string::npos) << message(s);
  SPLINTCORE_EXPECT_OK(decode(with(lossless, sos + 8, {2}), &got, 8));
  EXPECT_TRUE(got == lossless_samples);
}

// Every marker class before SOF55: skipped, refused as another process, or unexpected.
TEST(CtDicomJpegLs, MarkerClasses) {
  size_t at = 0;
  const Bytes good = fragment_of(fixture("jls8.dcm"), &at);
  std::vector<uint32_t> original, got;
  SPLINTCORE_ASSERT_OK(decode(good, &original, 8));
  const size_t sof = marker(good, 0xF7);
  for (uint8_t code : {0xC4, 0xCC, 0xE1, 0xFE, 0xC0, 0xCF, 0xF9, 0xD8, 0xD5, 0x10}) {
    const Status s = decode(inserted(good, sof, {0xFF, code, 0, 2}), &got, 8);
    if (code == 0xC4 || code == 0xCC || code == 0xE1 || code == 0xFE) {
      EXPECT_TRUE(s.is_ok() && got == original) << int{code} << ": " << test::format(s);
    } else if (code >= 0xC0 && code != 0xD8 && code != 0xD5) {
      EXPECT_EQ(s.code(), StatusCode::kUnsupported) << int{code};
      EXPECT_NE(message(s).find("not JPEG-LS baseline"), std::string::npos) << message(s);
    } else {
      EXPECT_EQ(s.code(), StatusCode::kParseError) << int{code};
      EXPECT_NE(message(s).find("unexpected marker"), std::string::npos) << message(s);
    }
  }
}

// Coded data going on past the last sample while the bit cache still holds 57 or more unread
// bits (a 4 x 5 image at precision 7, then 47 bytes of codes): found by the ct_codecs fuzz
// target once undefined behaviour stopped its runs (fixtures/fuzz/ct_codecs/crash-jls-end-
// with-full-cache). Refilling a cache that full shifted a 64-bit word by 64, undefined (x86
// and AArch64 take the shift mod 64, ARMv7 does not); now it is an error like any other data
// past the last sample, and under the sanitizers (the asan job) any such shift stops the run.
TEST(CtDicomJpegLs, CodedDataPastAFullCacheIsAnError) {
  const Bytes frame = {0xFF, 0xD8, 0xFF, 0xF7, 0x00, 0x0B, 0x07, 0x00, 0x04, 0x00, 0x05,
                       0x01, 0x01, 0x11, 0x00, 0xFF, 0xDA, 0x00, 0x08, 0x01, 0x01, 0x00,
                       0x00, 0x00, 0x00, 0x80, 0x00, 0x01, 0xF6, 0x00, 0x00, 0x05, 0xEB,
                       0xC7, 0x40, 0x00, 0x00, 0x5A, 0x00, 0x01, 0x71, 0x00, 0x00, 0x05,
                       0xA8, 0xA0, 0x00, 0xD4, 0x00, 0x3C, 0x0A, 0x00, 0x00, 0xAD, 0x19,
                       0x30, 0x53, 0x3E, 0xB9, 0x63, 0x77, 0xCD, 0x80, 0xFF, 0xD9};
  std::vector<uint32_t> got;
  const Status s = decode_size(frame, 4, 5, 7, &got);
  EXPECT_EQ(s.code(), StatusCode::kParseError) << test::format(s);
  EXPECT_NE(message(s).find("continues past the last sample"), std::string::npos) << message(s);
}

TEST(CtDicomJpegLs, MoreMalformedSegments) {
  size_t at = 0;
  const Bytes good = fragment_of(fixture("jls16_0.dcm"), &at);
  const size_t sof = marker(good, 0xF7), sos = marker(good, 0xDA);
  struct Case {
    Bytes frame;
    StatusCode code;
    const char* text;
  };
  const std::vector<Case> cases = {
      {with(good, sof + 3, {6}), StatusCode::kParseError, "SOF55 segment too short"},
      {with(good, sof + 3, {12}), StatusCode::kUnsupported, "1 components (length must be 11)"},
      {with(good, sof + 4, {1}), StatusCode::kParseError, "precision not in 2..16"},
      {with(good, sof + 7, {0, 0}), StatusCode::kUnsupported, "image size 0"},
      {with(good, sof + 7, {0, 65}), StatusCode::kParseError, "differs from the DICOM"},
      {inserted(good, sos, {0xFF, 0xF8, 0, 2}), StatusCode::kParseError, "LSE segment too short"},
      {inserted(good, sos, {0xFF, 0xF8, 0, 3, 3}), StatusCode::kUnsupported, "mapping table"},
      {inserted(good, sos, {0xFF, 0xF8, 0, 4, 1, 0}), StatusCode::kParseError, "length not 13"},
      {inserted(good, sos, {0xFF, 0xDD, 0, 8, 0, 0, 0, 0, 0, 1}), StatusCode::kParseError,
       "DRI length"},
      {with(good, sos + 3, {10}), StatusCode::kParseError, "one component (length 8)"},
      {Bytes{0xFF}, StatusCode::kParseError, "no SOI"},
      {Bytes{0xFF, 0xD9}, StatusCode::kParseError, "no SOI"},
  };
  for (const Case& c : cases) {
    std::vector<uint32_t> got;
    const Status s = decode(c.frame, &got);
    EXPECT_EQ(s.code(), c.code) << c.text << ": " << test::format(s);
    EXPECT_NE(message(s).find(c.text), std::string::npos) << c.text << ": " << message(s);
  }
  // A restart interval of 4 bytes, longer than the image: no RSTm, the same samples.
  std::vector<uint32_t> original, got;
  SPLINTCORE_ASSERT_OK(decode(good, &original));
  SPLINTCORE_ASSERT_OK(decode(inserted(good, sos, {0xFF, 0xDD, 0, 6, 0, 1, 0, 0}), &got));
  EXPECT_EQ(got, original);
}

}  // namespace
}  // namespace splintcore
