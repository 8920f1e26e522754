// DICOM encapsulated pixel data (PS3.5 A.4) and the transfer syntaxes that use it or another
// byte order (issue 31): RLE Lossless (1.2.840.10008.1.2.5), explicit VR big endian
// (1.2.840.10008.1.2.2), JPEG lossless process 14 (1.2.840.10008.1.2.4.57 and .70). The
// compressed slices of fixtures/ct (made by gdcm and dcmtk, make_ct_fixtures.py) read to the
// same voxels as their uncompressed twins; malformed frames are clear errors at byte offsets.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "ct/dicom_rle.h"
#include "ct/jpeg_lossless.h"
#include "splintcore/ct.h"
#include "support/dicom_read.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using ct_detail::JpegBits;
using ct_detail::JpegHuffman;
using test::Bytes;
using test::TestArena;

Bytes fixture(const std::string& name) { return test::ct_fixture(name); }

using Series = test::DicomRead;

Series read(const std::vector<Bytes>& files, size_t arena_bytes = 4 << 20, size_t max_chunk = 0) {
  return test::read_dicom_bytes(files, test::numbered_names(files.size(), "s"), arena_bytes,
                                max_chunk);
}

Series read_names(const std::vector<std::string>& names, size_t max_chunk = 0) {
  std::vector<Bytes> files;
  for (const std::string& n : names) files.push_back(fixture(n));
  return read(files, 4 << 20, max_chunk);
}

// Reads `names` and their twins; expects both to succeed with the same voxels.
void expect_twins(const std::vector<std::string>& names, const std::vector<std::string>& twins,
                  const char* syntax) {
  const Series plain = read_names(twins);
  ASSERT_TRUE(plain.status.is_ok()) << test::format(plain.status);
  for (size_t max_chunk : {size_t{0}, size_t{7}}) {
    const Series z = read_names(names, max_chunk);
    ASSERT_TRUE(z.status.is_ok()) << names[0] << ": " << test::format(z.status);
    EXPECT_EQ(z.hu.size(), plain.hu.size());
    EXPECT_TRUE(z.hu == plain.hu) << names[0];
    EXPECT_STREQ(z.info.transfer_syntax, syntax) << names[0];
  }
}

const std::vector<std::string> kRaw16 = {"raw16_2.dcm", "raw16_0.dcm", "raw16_1.dcm"};

// The bytes of a file's one fragment (after the basic offset table), and its file offset.
Bytes fragment_of(const Bytes& file, size_t* at) {
  const uint8_t tag[] = {0xE0, 0x7F, 0x10, 0x00, 'O', 'B', 0, 0, 0xFF, 0xFF, 0xFF, 0xFF};
  size_t p = 0;
  while (p + sizeof(tag) <= file.size() && std::memcmp(&file[p], tag, sizeof(tag)) != 0) ++p;
  EXPECT_LT(p + sizeof(tag), file.size());
  p += sizeof(tag);
  auto u32 = [&](size_t q) {
    return uint32_t{file[q]} | (uint32_t{file[q + 1]} << 8) | (uint32_t{file[q + 2]} << 16) |
           (uint32_t{file[q + 3]} << 24);
  };
  p += 8 + u32(p + 4);  // the basic offset table
  const uint32_t length = u32(p + 4);
  *at = p + 8;
  return Bytes(file.begin() + static_cast<std::ptrdiff_t>(p + 8),
               file.begin() + static_cast<std::ptrdiff_t>(p + 8 + length));
}

std::string message(const Status& s) { return s.message(); }

// ---- Series equal to their twins ------------------------------------------------------------

TEST(CtDicomCodecs, RleSeriesEqualsItsTwin) {
  expect_twins({"rle16_2.dcm", "rle16_0.dcm", "rle16_1.dcm"}, kRaw16, "1.2.840.10008.1.2.5");
  expect_twins({"rle8.dcm"}, {"raw8.dcm"}, "1.2.840.10008.1.2.5");
  expect_twins({"rles12.dcm"}, {"raws12.dcm"}, "1.2.840.10008.1.2.5");
}

TEST(CtDicomCodecs, BigEndianSeriesEqualsItsTwin) {
  expect_twins({"big16_1.dcm", "big16_2.dcm", "big16_0.dcm"}, kRaw16, "1.2.840.10008.1.2.2");
  const Series r = read_names({"big16_0.dcm"});
  EXPECT_TRUE(r.info.big_endian);
}

TEST(CtDicomCodecs, JpegLosslessEqualsItsTwin) {
  expect_twins({"jpeg70_0.dcm", "jpeg70_1.dcm", "jpeg70_2.dcm"}, kRaw16, "1.2.840.10008.1.2.4.70");
  for (int p = 1; p <= 7; ++p) {
    expect_twins({"jpeg57_p" + std::to_string(p) + ".dcm"}, {"raw16_0.dcm"},
                 "1.2.840.10008.1.2.4.57");
  }
  expect_twins({"jpeg57_frag.dcm"}, {"raw16_0.dcm"}, "1.2.840.10008.1.2.4.57");   // 5 fragments
  expect_twins({"jpeg57_rst.dcm"}, {"raw16_0.dcm"}, "1.2.840.10008.1.2.4.57");    // RSTn
  expect_twins({"jpeg57_pt2.dcm"}, {"raw16_pt2.dcm"}, "1.2.840.10008.1.2.4.57");  // Pt 2
  expect_twins({"jpeg57s12.dcm"}, {"raws12.dcm"}, "1.2.840.10008.1.2.4.57");
  expect_twins({"jpeg57_8.dcm"}, {"raw8.dcm"}, "1.2.840.10008.1.2.4.57");  // 8 bits, predictor 7
}

// The fuzz seeds of tests/fuzz/ct_corpus.py (its own small encoders: 12 bits stored, signed,
// 4 x 5 pixels) read to the voxels of their uncompressed twin.
TEST(CtDicomCodecs, CorpusSeedsEqualTheirTwin) {
  const std::string dir = std::string(SPLINTCORE_FIXTURES_DIR) + "/fuzz/ct_dicom/";
  const Series plain = read({test::read_file_bytes(dir + "explicit_4x5.dcm")});
  ASSERT_TRUE(plain.status.is_ok()) << test::format(plain.status);
  ASSERT_EQ(plain.hu.size(), 20u);
  for (const char* name : {"rle16_one.dcm", "jpeg57_p1.dcm", "jpeg57_p4.dcm", "jpeg57_p7.dcm",
                           "jpeg70_restart.dcm", "big_one.dcm"}) {
    const Series z = read({test::read_file_bytes(dir + name)});
    ASSERT_TRUE(z.status.is_ok()) << name << ": " << test::format(z.status);
    EXPECT_TRUE(z.hu == plain.hu) << name;
  }
}

// The two-step contract: a first read's high water is enough, one byte less is not.
TEST(CtDicomCodecs, ArenaOfTheFirstReadsHighWater) {
  for (const char* name : {"rle16_0.dcm", "jpeg57_p1.dcm"}) {
    const std::vector<Bytes> files = {fixture(name)};
    const Series first = read(files);
    ASSERT_TRUE(first.status.is_ok()) << test::format(first.status);
    const Series exact = read(files, first.high_water);
    EXPECT_TRUE(exact.status.is_ok()) << test::format(exact.status);
    const Series less = read(files, first.high_water - 1);
    EXPECT_EQ(less.status.code(), StatusCode::kArenaExhausted) << test::format(less.status);
  }
}

// ---- Truncation and corruption --------------------------------------------------------------

TEST(CtDicomCodecs, TruncatedFilesAndFramesAreErrors) {
  for (const char* name : {"rle16_0.dcm", "jpeg57_rst.dcm", "rle8.dcm"}) {
    const Bytes file = fixture(name);
    for (size_t cut = 0; cut < file.size(); cut += test::kSweepStep) {
      const Series r =
          read({Bytes(file.begin(), file.begin() + static_cast<std::ptrdiff_t>(cut))}, 1 << 20);
      ASSERT_FALSE(r.status.is_ok()) << name << " cut at " << cut;
    }
    size_t at = 0;
    const Bytes frame = fragment_of(file, &at);
    const bool rle = name[0] == 'r';
    const uint32_t bytes = std::string(name) == "rle8.dcm" ? 1 : 2;
    Bytes out(2 * 64 * 56);
    TestArena t(1 << 16);
    for (size_t cut = 0; cut < frame.size(); cut += test::kSweepStep) {
      const Status s =
          rle ? ct_detail::rle_decode_frame(frame.data(), cut, 56, 64, bytes, out.data())
              : ct_detail::jpeg_lossless_decode(t.arena, frame.data(), cut, 56, 64, 16, out.data());
      // The last byte may be the fragment's pad to an even length.
      if (cut + 1 < frame.size()) {
        ASSERT_FALSE(s.is_ok()) << name << " frame cut at " << cut;
        ASSERT_LE(s.byte_offset(), cut) << test::format(s);
      }
      EXPECT_EQ(t.arena.used(), 0u);
    }
  }
}

TEST(CtDicomCodecs, CorruptRleHeaderNamesOffsetAndFile) {
  const Bytes good = fixture("rle16_0.dcm");
  size_t at = 0;
  fragment_of(good, &at);
  struct Case {
    size_t field;  // 32-bit field of the RLE header: 0 the count, 1 + i segment i's offset
    uint32_t value;
    const char* text;
  };
  for (const Case& c : {Case{0, 16, "more than the 15"}, Case{0, 3, "expected 2"},
                        Case{1, 40, "out of order"}, Case{1, 0xFFFFFF, "past the frame's end"},
                        Case{2, 63, "out of order"}, Case{2, 0xFFFFFF, "past the frame's end"}}) {
    Bytes bad = good;
    for (size_t b = 0; b < 4; ++b)
      bad[at + 4 * c.field + b] = static_cast<uint8_t>(c.value >> (8 * b));
    const Series r = read({bad});
    EXPECT_EQ(r.status.code(), StatusCode::kParseError) << test::format(r.status);
    EXPECT_NE(message(r.status).find(c.text), std::string::npos) << test::format(r.status);
    EXPECT_EQ(r.status.byte_offset(), at + 4 * c.field) << test::format(r.status);
    EXPECT_STREQ(r.status.file(), "s0.dcm");
  }
}

TEST(CtDicomCodecs, CorruptHuffmanTableIsAClearError) {
  const Bytes good = fixture("jpeg57_p1.dcm");
  size_t at = 0;
  const Bytes frame = fragment_of(good, &at);
  size_t dht = 0;
  while (!(frame[dht] == 0xFF && frame[dht + 1] == 0xC4)) ++dht;
  Bytes bad = good;
  size_t l = 1;  // three codes of a longer length moved to length 1: over-subscribed
  while (bad[at + dht + 5 + l] < 3) ++l;
  bad[at + dht + 5] = static_cast<uint8_t>(bad[at + dht + 5] + 3);
  bad[at + dht + 5 + l] = static_cast<uint8_t>(bad[at + dht + 5 + l] - 3);
  Series r = read({bad});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << test::format(r.status);
  EXPECT_NE(message(r.status).find("over-subscribed"), std::string::npos) << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), at + dht + 4);
  bad = good;
  bad[at + dht + 5 + 16] = 17;  // the first symbol: not a difference category
  r = read({bad});
  EXPECT_NE(message(r.status).find("symbol 17"), std::string::npos) << test::format(r.status);
  // Every byte of the entropy-coded data flipped: a Status or the same size of image, no crash.
  size_t sos = 0;
  while (!(frame[sos] == 0xFF && frame[sos + 1] == 0xDA)) ++sos;
  TestArena t(1 << 16);
  Bytes out(2 * 64 * 56);
  for (size_t i = sos; i < frame.size(); i += 3) {
    Bytes f = frame;
    f[i] = static_cast<uint8_t>(f[i] ^ 0x5A);
    (void)ct_detail::jpeg_lossless_decode(t.arena, f.data(), f.size(), 56, 64, 16, out.data());
  }
}

TEST(CtDicomCodecs, UnsupportedSyntaxesAreNamed) {
  Bytes file = fixture("jpeg57_p1.dcm");
  const char* uid57 = "1.2.840.10008.1.2.4.57";
  size_t p = 0;
  while (std::memcmp(&file[p], uid57, std::strlen(uid57)) != 0) ++p;
  struct Case {
    const char* uid;  // as long as uid57 (with its pad), so the group length stays right
    const char* name;
  };
  for (const Case& c : {Case{"1.2.840.10008.1.2.4.50", "JPEG Baseline"},
                        Case{"1.2.840.10008.1.2.4.51", "JPEG Extended"}}) {
    Bytes bad = file;
    std::memcpy(&bad[p], c.uid, std::strlen(c.uid));
    const Series r = read({bad});
    EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
    EXPECT_NE(
        message(r.status).find(std::string("unsupported transfer syntax ") + c.uid + " (" + c.name),
        std::string::npos)
        << message(r.status);
  }
}

// ---- PackBits and RLE frames on hand-made bytes ---------------------------------------------

TEST(CtDicomRle, PackBitsLiteralRepeatAndNoOp) {
  // Row 0: literal 3 (1 2 3), repeat 9 twice; row 1: no-op, repeat 7 five times; a pad byte.
  const Bytes in = {2, 1, 2, 3, 0xFF, 9, 0x80, 0xFC, 7, 0x00};
  Bytes out(5 * 2 * 2, 0xEE);
  SPLINTCORE_ASSERT_OK(ct_detail::packbits_decode(in.data(), in.size(), 0, 0, 2, 5, out.data(), 2));
  const Bytes want = {1, 2, 3, 9, 9, 7, 7, 7, 7, 7};
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(out[2 * i], want[i]) << i;
    EXPECT_EQ(out[2 * i + 1], 0xEE) << i;  // the other plane is untouched
  }
}

TEST(CtDicomRle, PackBitsErrors) {
  Bytes out(64);
  auto run = [&](const Bytes& in, uint32_t rows, uint32_t columns) {
    return ct_detail::packbits_decode(in.data(), in.size(), 100, 3, rows, columns, out.data(), 1);
  };
  Status s = run({0xFD, 5}, 1, 3);  // a run of 4 in a row of 3
  EXPECT_NE(message(s).find("passes the end of row 0"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), 100u);
  EXPECT_NE(message(s).find("RLE segment 3"), std::string::npos);
  s = run({1, 5, 6, 3, 1, 2, 3, 4}, 2, 2);  // a literal of 4 in row 1
  EXPECT_NE(message(s).find("passes the end of row 1"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), 103u);
  s = run({1, 5, 6}, 2, 2);  // row 1 missing
  EXPECT_NE(message(s).find("output short"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), 103u);
  s = run({3, 5, 6}, 1, 4);  // a literal cut
  EXPECT_NE(message(s).find("ends inside a run"), std::string::npos) << message(s);
  s = run({0xFF}, 1, 4);  // a repeat without its byte
  EXPECT_NE(message(s).find("ends inside a run"), std::string::npos) << message(s);
  s = run({0xFF, 1, 0xFF, 2}, 1, 2);  // one more run after the last row
  EXPECT_NE(message(s).find("output long"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), 102u);
  EXPECT_TRUE(run({0xFF, 1, 0x80, 0x80, 0x42}, 1, 2).is_ok());  // no-ops and a pad byte
}

Bytes rle_header(std::vector<uint32_t> fields) {
  Bytes h(64, 0);
  for (size_t i = 0; i < fields.size(); ++i) {
    for (int b = 0; b < 4; ++b) h[4 * i + b] = static_cast<uint8_t>(fields[i] >> (8 * b));
  }
  return h;
}

TEST(CtDicomRle, FrameOf16BitSamplesMostSignificantPlaneFirst) {
  Bytes frame = rle_header({2, 64, 67});
  for (uint8_t b : {1, 0x12, 0x34}) frame.push_back(b);  // high bytes 12 34
  for (uint8_t b : {0xFF, 0x56}) frame.push_back(b);     // low bytes 56 56
  Bytes out(4);
  SPLINTCORE_ASSERT_OK(
      ct_detail::rle_decode_frame(frame.data(), frame.size(), 1, 2, 2, out.data()));
  EXPECT_EQ(out, (Bytes{0x56, 0x12, 0x56, 0x34}));
  // 8-bit samples: the high byte is zero.
  Bytes frame8 = rle_header({1, 64});
  for (uint8_t b : {1, 0xAB, 0xCD}) frame8.push_back(b);
  Bytes out8(4, 0xEE);
  SPLINTCORE_ASSERT_OK(
      ct_detail::rle_decode_frame(frame8.data(), frame8.size(), 1, 2, 1, out8.data()));
  EXPECT_EQ(out8, (Bytes{0xAB, 0, 0xCD, 0}));
  // Errors: a short header, a first offset inside the header; segment errors at frame offsets.
  Status s = ct_detail::rle_decode_frame(frame.data(), 63, 1, 2, 2, out.data());
  EXPECT_NE(message(s).find("64-byte header"), std::string::npos) << message(s);
  Bytes early = rle_header({1, 60});
  early.resize(70);
  s = ct_detail::rle_decode_frame(early.data(), early.size(), 1, 2, 1, out.data());
  EXPECT_NE(message(s).find("starts at 64"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), 4u);
  Bytes cut = frame;
  cut[67] = 0xFE;  // segment 1 now repeats 3 times in a row of 2
  s = ct_detail::rle_decode_frame(cut.data(), cut.size(), 1, 2, 2, out.data());
  EXPECT_NE(message(s).find("RLE segment 1"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), 67u);
  // At the edges: a frame of its header alone, its one segment empty at the frame's end
  // (read: the segment is short, at 64); 15 segments, the most allowed (read: not the one per
  // byte of a sample expected), and 16.
  const Bytes bare = rle_header({1, 64});
  s = ct_detail::rle_decode_frame(bare.data(), bare.size(), 1, 2, 1, out.data());
  EXPECT_NE(message(s).find("output short"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), 64u);
  for (uint32_t segments : {15u, 16u}) {
    const Bytes many = rle_header({segments, 64});
    s = ct_detail::rle_decode_frame(many.data(), many.size(), 1, 2, 2, out.data());
    EXPECT_NE(message(s).find(segments == 15 ? "15 segments, expected 2" : "more than the 15"),
              std::string::npos)
        << message(s);
  }
}

// ---- JPEG: Huffman codes and bits on hand-made bytes ----------------------------------------

// Codes: 0 -> "00", 1 -> "01", 2 -> "10", 16 -> "110", 5 -> "1110".
constexpr uint8_t kShortCounts[16] = {0, 3, 1, 1};
constexpr uint8_t kShortSymbols[] = {0, 1, 2, 16, 5};

// A bit reader over `data` (which must outlive it).
JpegBits bits_over(const Bytes& data) {
  JpegBits bits;
  bits.data = data.data();
  bits.size = data.size();
  return bits;
}

TEST(CtDicomJpeg, HuffmanDecodeWithByteStuffing) {
  JpegHuffman table;
  SPLINTCORE_ASSERT_OK(ct_detail::jpeg_build_huffman(kShortCounts, kShortSymbols, 5, &table));
  // 110 1110 10 01 00, then 11 ones = 1101 1101 | 0010 0111 | 1111 1111 (stuffed: FF 00);
  // then a marker FF D9.
  const Bytes data = {0xDD, 0x27, 0xFF, 0x00, 0xFF, 0xD9};
  JpegBits bits = bits_over(data);
  uint32_t got = 0;
  for (uint32_t want : {16u, 5u, 2u, 1u, 0u}) {
    SPLINTCORE_ASSERT_OK(bits.decode(table, &got));
    EXPECT_EQ(got, want);
  }
  uint32_t v = 0;
  ASSERT_TRUE(bits.bits(7, &v));
  EXPECT_EQ(v, 0x7Fu);
  ASSERT_TRUE(bits.bits(4, &v));
  EXPECT_EQ(v, 0xFu);
  EXPECT_FALSE(bits.bits(1, &v));  // the marker: no more bits
  EXPECT_TRUE(bits.at_marker);
  EXPECT_EQ(bits.pos, 4u);
  Status s = bits.decode(table, &got);
  EXPECT_EQ(s.code(), StatusCode::kTruncated) << message(s);
  // "1111" matches no code of up to 16 bits.
  const Bytes ones = {0xFF, 0x00, 0xFF, 0x00, 0xFF, 0x00};
  JpegBits b2 = bits_over(ones);
  s = b2.decode(table, &got);
  EXPECT_NE(message(s).find("invalid Huffman code"), std::string::npos) << message(s);
}

// The longest codes (16 bits: one per length 1..15, then two of 16, a complete code), a code
// that ends exactly where the data does (at a marker), and tables of 256 codes (the most) and
// 257.
TEST(CtDicomJpeg, HuffmanLongestCodesAndTheLastBits) {
  uint8_t counts[16];
  for (uint8_t& c : counts) c = 1;
  counts[15] = 2;
  uint8_t symbols[17];
  for (uint8_t i = 0; i < 17; ++i) symbols[i] = i;
  JpegHuffman table;
  SPLINTCORE_ASSERT_OK(ct_detail::jpeg_build_huffman(counts, symbols, 17, &table));
  // 1111 1111 1111 1110 (symbol 15), 1111 1111 1111 1111 (16), then "0" (0) and seven more
  // zeros: FF 00 FE FF 00 FF 00 00, then a marker.
  const Bytes data = {0xFF, 0x00, 0xFE, 0xFF, 0x00, 0xFF, 0x00, 0x00, 0xFF, 0xD9};
  JpegBits bits = bits_over(data);
  uint32_t got = 0;
  for (uint32_t want : {15u, 16u, 0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u}) {
    SPLINTCORE_ASSERT_OK(bits.decode(table, &got));
    EXPECT_EQ(got, want);
  }
  EXPECT_EQ(bits.decode(table, &got).code(), StatusCode::kTruncated);
  // The short table ("00" is 0): four codes fill the byte before the marker, the last
  // ending on its last bit.
  SPLINTCORE_ASSERT_OK(ct_detail::jpeg_build_huffman(kShortCounts, kShortSymbols, 5, &table));
  const Bytes zeros = {0x00, 0xFF, 0xD9};
  JpegBits b2 = bits_over(zeros);
  for (int i = 0; i < 4; ++i) {
    SPLINTCORE_ASSERT_OK(b2.decode(table, &got));
    EXPECT_EQ(got, 0u);
  }
  EXPECT_EQ(b2.decode(table, &got).code(), StatusCode::kTruncated);
  // 255 codes of 8 bits and one of 9: 256, the most a table holds; one more of 9 is refused.
  uint8_t many[16] = {0, 0, 0, 0, 0, 0, 0, 255, 1};
  const std::vector<uint8_t> values(257, 3);
  SPLINTCORE_EXPECT_OK(ct_detail::jpeg_build_huffman(many, values.data(), 256, &table));
  many[8] = 2;
  const Status s = ct_detail::jpeg_build_huffman(many, values.data(), 257, &table);
  EXPECT_NE(message(s).find("257 codes for 257 symbols (at most 256)"), std::string::npos)
      << message(s);
}

TEST(CtDicomJpeg, HuffmanTableErrors) {
  JpegHuffman table;
  const uint8_t over[16] = {3};
  const uint8_t symbols[3] = {0, 1, 2};
  Status s = ct_detail::jpeg_build_huffman(over, symbols, 3, &table);
  EXPECT_NE(message(s).find("over-subscribed"), std::string::npos) << message(s);
  const uint8_t two[16] = {2};
  s = ct_detail::jpeg_build_huffman(two, symbols, 3, &table);
  EXPECT_NE(message(s).find("2 codes for 3 symbols"), std::string::npos) << message(s);
  const uint8_t big[3] = {0, 17, 1};
  const uint8_t one_two[16] = {1, 2};
  s = ct_detail::jpeg_build_huffman(one_two, big, 3, &table);
  EXPECT_NE(message(s).find("symbol 17"), std::string::npos) << message(s);
}

// A 2 x 2 image, precision 8, predictor 1, with the given entropy bytes.
Bytes tiny_jpeg(uint8_t sof, const Bytes& entropy, uint8_t predictor = 1) {
  Bytes j = {0xFF, 0xD8, 0xFF, 0xFE, 0x00, 0x04, 'h', 'i'};  // SOI, COM
  Bytes frame = {0xFF, sof, 0, 11, 8, 0, 2, 0, 2, 1, 1, 0x11, 0};
  j.insert(j.end(), frame.begin(), frame.end());
  // DHT: category 0 -> "0", 1 -> "10", 8 -> "110".
  Bytes dht = {0xFF, 0xC4, 0, 22, 0x00, 1, 1, 1};
  dht.resize(4 + 1 + 16, 0);
  for (uint8_t symbol : {0, 1, 8}) dht.push_back(symbol);
  j.insert(j.end(), dht.begin(), dht.end());
  Bytes sos = {0xFF, 0xDA, 0, 8, 1, 1, 0x00, predictor, 0, 0};
  j.insert(j.end(), sos.begin(), sos.end());
  j.insert(j.end(), entropy.begin(), entropy.end());
  j.push_back(0xFF);
  j.push_back(0xD9);
  return j;
}

TEST(CtDicomJpeg, TinyImagesAndMarkerErrors) {
  TestArena t(1 << 14);
  Bytes out(8);
  // Sample 0: 128 + 0; sample 1: Ra + 1 (10 1); row 1: Rb + 0, then Ra + 0:
  // 0 101 0 0 + pad 11 = 0101 0011 -> 0x53.
  Bytes j = tiny_jpeg(0xC3, {0x53});
  SPLINTCORE_ASSERT_OK(
      ct_detail::jpeg_lossless_decode(t.arena, j.data(), j.size(), 2, 2, 16, out.data()));
  EXPECT_EQ(out, (Bytes{128, 0, 129, 0, 128, 0, 128, 0}));
  EXPECT_EQ(t.arena.used(), 0u);
  // The image size must match the DICOM one.
  Status s = ct_detail::jpeg_lossless_decode(t.arena, j.data(), j.size(), 3, 2, 16, out.data());
  EXPECT_NE(message(s).find("differs from the DICOM"), std::string::npos) << message(s);
  // Lossy and arithmetic processes are refused by name.
  j = tiny_jpeg(0xC0, {0x53});
  s = ct_detail::jpeg_lossless_decode(t.arena, j.data(), j.size(), 2, 2, 16, out.data());
  EXPECT_EQ(s.code(), StatusCode::kUnsupported);
  EXPECT_NE(message(s).find("not lossless process 14"), std::string::npos) << message(s);
  EXPECT_EQ(s.byte_offset(), 8u);
  // Predictor 0 is not lossless; extra entropy data after the last sample.
  j = tiny_jpeg(0xC3, {0x53}, 0);
  s = ct_detail::jpeg_lossless_decode(t.arena, j.data(), j.size(), 2, 2, 16, out.data());
  EXPECT_NE(message(s).find("predictor"), std::string::npos) << message(s);
  j = tiny_jpeg(0xC3, {0x53, 0x00});
  s = ct_detail::jpeg_lossless_decode(t.arena, j.data(), j.size(), 2, 2, 16, out.data());
  EXPECT_NE(message(s).find("continues past the last sample"), std::string::npos) << message(s);
  // Not a JPEG stream; a restart marker where none belongs.
  const Bytes junk = {0x00, 0x01};
  s = ct_detail::jpeg_lossless_decode(t.arena, junk.data(), junk.size(), 2, 2, 16, out.data());
  EXPECT_NE(message(s).find("no SOI"), std::string::npos) << message(s);
  j = tiny_jpeg(0xC3, {0x53});
  j[2] = 0xFF;
  j[3] = 0xD0;
  s = ct_detail::jpeg_lossless_decode(t.arena, j.data(), j.size(), 2, 2, 16, out.data());
  EXPECT_NE(message(s).find("unexpected marker"), std::string::npos) << message(s);
  // No room for the decoder's state.
  TestArena small(ct_detail::jpeg_lossless_arena_bytes() - 16);
  j = tiny_jpeg(0xC3, {0x53});
  s = ct_detail::jpeg_lossless_decode(small.arena, j.data(), j.size(), 2, 2, 16, out.data());
  EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << message(s);
  TestArena exact(ct_detail::jpeg_lossless_arena_bytes());
  SPLINTCORE_EXPECT_OK(
      ct_detail::jpeg_lossless_decode(exact.arena, j.data(), j.size(), 2, 2, 16, out.data()));
}

}  // namespace
}  // namespace splintcore
