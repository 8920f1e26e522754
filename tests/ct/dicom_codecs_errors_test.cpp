// The error paths of encapsulated DICOM pixel data (src/ct/ct_dicom.cpp) and of the JPEG
// lossless decoder (src/ct/jpeg_lossless.cpp), each on a small hand-made input: every malformed
// item, marker segment and scan is a Status that names what is wrong and where.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "ct/jpeg_lossless.h"
#include "splintcore/ct.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;
using Bytes = std::vector<uint8_t>;

std::string message(const Status& s) { return s.message(); }

Bytes fixture(const std::string& name) {
  return test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/ct/" + name);
}

void put32(Bytes* b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b->push_back(static_cast<uint8_t>(v >> (8 * i)));
}
void item(Bytes* b, uint16_t element, uint32_t length) {
  const uint8_t tag[] = {0xFE, 0xFF, static_cast<uint8_t>(element),
                         static_cast<uint8_t>(element >> 8)};
  b->insert(b->end(), tag, tag + 4);
  put32(b, length);
}

// raw16_0.dcm as RLE Lossless (the UID has the same length) with its Pixel Data replaced by
// `pixels` (everything after the tag and VR: the reserved bytes and the length included).
Bytes with_pixel_data(const Bytes& pixels, const char* syntax = "1.2.840.10008.1.2.5\0") {
  Bytes f = fixture("raw16_0.dcm");
  const char* raw = "1.2.840.10008.1.2.1\0";
  for (size_t p = 0; p + 20 < f.size(); ++p) {
    if (std::memcmp(&f[p], raw, 20) == 0) {
      std::memcpy(&f[p], syntax, 20);
      break;
    }
  }
  const uint8_t tag[] = {0xE0, 0x7F, 0x10, 0x00, 'O', 'W'};
  size_t p = 0;
  while (std::memcmp(&f[p], tag, sizeof(tag)) != 0) ++p;
  f.resize(p + 4);
  f.push_back('O');
  f.push_back('B');
  f.insert(f.end(), pixels.begin(), pixels.end());
  return f;
}

// Encapsulated: reserved, undefined length, then the items.
Bytes undefined(const Bytes& items) {
  Bytes b = {0, 0, 0xFF, 0xFF, 0xFF, 0xFF};
  b.insert(b.end(), items.begin(), items.end());
  return b;
}

Status read(const std::vector<Bytes>& files, uint32_t max_dimension = 4096) {
  TestArena t(1 << 20);
  std::vector<std::string> names;
  std::vector<CtMemoryFile> mem;
  for (size_t i = 0; i < files.size(); ++i) names.push_back("s" + std::to_string(i) + ".dcm");
  for (size_t i = 0; i < files.size(); ++i) {
    mem.push_back({names[i].c_str(), files[i].data(), files[i].size()});
  }
  CtMemoryFiles m{mem.data(), static_cast<uint32_t>(mem.size()), 0, {}};
  Context ctx(&t.arena);
  CtReadOptions options;
  options.max_dimension = max_dimension;
  CtVolume volume;
  CtInfo info;
  return read_dicom_series(ctx, ct_memory_series(&m), options, &volume, &info);
}

void expect_error(const Status& s, StatusCode code, const char* text) {
  EXPECT_EQ(s.code(), code) << test::format(s);
  EXPECT_NE(message(s).find(text), std::string::npos) << test::format(s);
}

TEST(CtDicomEncapsulated, ItemErrors) {
  Bytes items;
  item(&items, 0xE0DD, 0);  // no basic offset table
  expect_error(read({with_pixel_data(undefined(items))}), StatusCode::kParseError,
               "basic offset table");
  items.clear();
  item(&items, 0xE000, 2);  // a table whose length is not a multiple of 4
  items.insert(items.end(), {0, 0});
  expect_error(read({with_pixel_data(undefined(items))}), StatusCode::kParseError,
               "basic offset table");
  items.clear();
  item(&items, 0xE000, 0xFFFFFFFF);  // a table of undefined length
  expect_error(read({with_pixel_data(undefined(items))}), StatusCode::kParseError,
               "basic offset table");
  items.clear();
  item(&items, 0xE000, 0);
  item(&items, 0xE00D, 0);  // not a fragment
  expect_error(read({with_pixel_data(undefined(items))}), StatusCode::kParseError,
               "expected a fragment Item");
  items.clear();
  item(&items, 0xE000, 0);
  item(&items, 0xE000, 0xFFFFFFFF);  // a fragment of undefined length
  expect_error(read({with_pixel_data(undefined(items))}), StatusCode::kParseError,
               "expected a fragment Item");
  items.clear();
  item(&items, 0xE000, 0);
  item(&items, 0xE0DD, 4);  // a delimiter with a length
  expect_error(read({with_pixel_data(undefined(items))}), StatusCode::kParseError, "length not 0");
  items.clear();
  item(&items, 0xE000, 0);
  item(&items, 0xE0DD, 0);  // no fragment at all
  expect_error(read({with_pixel_data(undefined(items))}), StatusCode::kParseError, "no fragment");
  items.clear();
  item(&items, 0xE000, 0);
  for (int i = 0; i < 3; ++i) item(&items, 0xE000, 0);
  item(&items, 0xE0DD, 0);
  expect_error(read({with_pixel_data(undefined(items))}, 2), StatusCode::kLimitExceeded,
               "fragments");
  // More compressed bytes than 8 a sample + 64 KiB.
  items.clear();
  item(&items, 0xE000, 0);
  const uint32_t big = 64 * 56 * 2 * 8 + 65536 + 2;
  item(&items, 0xE000, big);
  items.resize(items.size() + big, 0);
  item(&items, 0xE0DD, 0);
  expect_error(read({with_pixel_data(undefined(items))}), StatusCode::kLimitExceeded,
               "more than 8 x the raw");
  // Exactly 8 a sample + 64 KiB passes that check: the decoder is what refuses the zeros.
  items.clear();
  item(&items, 0xE000, 0);
  item(&items, 0xE000, big - 2);
  items.resize(items.size() + big - 2, 0);
  item(&items, 0xE0DD, 0);
  const Status at_limit = read({with_pixel_data(undefined(items))});
  EXPECT_NE(at_limit.code(), StatusCode::kOk);
  EXPECT_EQ(message(at_limit).find("more than 8 x the raw"), std::string::npos)
      << test::format(at_limit);
  // Pixel Data of defined length in an encapsulated syntax.
  Bytes defined = {0, 0};
  put32(&defined, 4);
  defined.insert(defined.end(), {1, 2, 3, 4});
  expect_error(read({with_pixel_data(defined)}), StatusCode::kParseError, "of defined length");
}

TEST(CtDicomEncapsulated, SliceInAnotherSyntaxAndErrorsInSeveralFragments) {
  // An RLE slice in a series of uncompressed ones.
  Status s = read({fixture("raw16_0.dcm"), fixture("rle16_1.dcm")});
  expect_error(s, StatusCode::kUnsupported, "transfer syntax");
  s = read({fixture("raw16_0.dcm"), fixture("big16_1.dcm")});  // another byte order
  expect_error(s, StatusCode::kUnsupported, "transfer syntax");
  // A bad Huffman table in a frame of five fragments: the offset is the byte's in the file.
  Bytes f = fixture("jpeg57_frag.dcm");
  size_t p = 0;
  while (!(f[p] == 0xFF && f[p + 1] == 0xC4)) ++p;
  f[p + 4] = 0x14;  // table class 1
  s = read({f});
  expect_error(s, StatusCode::kParseError, "DHT table class/id not 0/0..3");
  EXPECT_EQ(s.byte_offset(), p + 4) << test::format(s);
}

// A series whose file 0 changes between the two passes (a file rewritten while read).
struct ChangingFile {
  Bytes first, second;
  int opens = 0;
  MemorySource current{};
};

Status read_changed(const Bytes& first, const Bytes& second) {
  ChangingFile c;
  c.first = first;
  c.second = second;
  CtSeries series;
  series.count = 1;
  series.user = &c;
  series.open = [](void* user, uint32_t, ByteSource* out) {
    auto* cf = static_cast<ChangingFile*>(user);
    const Bytes& b = cf->opens++ == 0 ? cf->first : cf->second;
    cf->current = MemorySource{b.data(), b.size(), 0, 0};
    *out = memory_source(&cf->current, "s0.dcm");
    return Status::ok();
  };
  TestArena t(1 << 20);
  Context ctx(&t.arena);
  CtVolume volume;
  return read_dicom_series(ctx, series, CtReadOptions(), &volume, nullptr);
}

TEST(CtDicomEncapsulated, FileChangedBetweenPasses) {
  const Bytes first = fixture("rle16_0.dcm");
  const uint8_t item_tag[] = {0xFE, 0xFF, 0x00, 0xE0};
  size_t table = 0;
  while (std::memcmp(&first[table], item_tag, 4) != 0) ++table;
  size_t fragment = table + 1;
  while (std::memcmp(&first[fragment], item_tag, 4) != 0) ++fragment;
  const uint32_t length = uint32_t{first[fragment + 4]} | (uint32_t{first[fragment + 5]} << 8);
  // The fragment 2 bytes longer than the buffer pass 1 sized.
  Bytes longer = first;
  longer[fragment + 4] = static_cast<uint8_t>(length + 2);
  longer[fragment + 5] = static_cast<uint8_t>((length + 2) >> 8);
  longer.insert(longer.begin() + static_cast<std::ptrdiff_t>(fragment + 8 + length), {0x80, 0x80});
  expect_error(read_changed(first, longer), StatusCode::kParseError, "file changed?");
  // The offset table, then the fragment, no longer items; the offset table of undefined length.
  for (size_t at : {table + 2, fragment + 2}) {
    Bytes b = first;
    b[at] = 0x0D;
    expect_error(read_changed(first, b), StatusCode::kParseError, "file changed?");
  }
  Bytes undefined_table = first;
  for (size_t i = 4; i < 8; ++i) undefined_table[table + i] = 0xFF;
  expect_error(read_changed(first, undefined_table), StatusCode::kParseError, "file changed?");
  // The file cut inside its fragment.
  const Bytes cut(first.begin(), first.begin() + static_cast<std::ptrdiff_t>(fragment + 20));
  expect_error(read_changed(first, cut), StatusCode::kTruncated, "a Pixel Data fragment");
}

// ---- JPEG marker segments -------------------------------------------------------------------

Bytes segment(uint8_t marker, const Bytes& body) {
  Bytes b = {0xFF, marker, static_cast<uint8_t>((body.size() + 2) >> 8),
             static_cast<uint8_t>(body.size() + 2)};
  b.insert(b.end(), body.begin(), body.end());
  return b;
}

// 2 x 2, precision 8: category 0 -> "0", 1 -> "10", 8 -> "110".
Bytes sof(uint8_t precision = 8, uint8_t rows = 2) {
  return segment(0xC3, {precision, 0, rows, 0, 2, 1, 1, 0x11, 0});
}
Bytes dht(uint8_t class_id = 0) {
  Bytes body = {class_id, 1, 1, 1};
  body.resize(17, 0);
  for (uint8_t s : {0, 1, 8}) body.push_back(s);
  return segment(0xC4, body);
}
Bytes sos(uint8_t table = 0, uint8_t predictor = 1, uint8_t se = 0, uint8_t ahal = 0) {
  return segment(0xDA, {1, 1, static_cast<uint8_t>(table << 4), predictor, se, ahal});
}

Bytes jpeg(const std::vector<Bytes>& parts) {
  Bytes j = {0xFF, 0xD8};
  for (const Bytes& p : parts) j.insert(j.end(), p.begin(), p.end());
  return j;
}

const Bytes kEoi = {0xFF, 0xD9};
const Bytes kScan = {0x53};  // 128 129 / 128 128 with predictor 1

Status decode(const Bytes& j, Bytes* out = nullptr) {
  TestArena t(1 << 14);
  Bytes local(8);
  Bytes& o = out != nullptr ? *out : local;
  o.assign(8, 0);
  return ct_detail::jpeg_lossless_decode(t.arena, j.data(), j.size(), 2, 2, 16, o.data());
}

TEST(CtDicomJpegErrors, FrameAndTableSegments) {
  SPLINTCORE_EXPECT_OK(decode(jpeg({sof(), dht(), sos(), kScan, kEoi})));
  expect_error(decode(jpeg({sof(), sof()})), StatusCode::kParseError, "a second SOF");
  expect_error(decode(jpeg({segment(0xC3, {8, 0, 2, 0})})), StatusCode::kParseError, "too short");
  expect_error(
      decode(jpeg({segment(0xC3, {8, 0, 2, 0, 2, 3, 1, 0x11, 0, 2, 0x11, 0, 3, 0x11, 0})})),
      StatusCode::kUnsupported, "components");
  expect_error(decode(jpeg({sof(1)})), StatusCode::kParseError, "precision");
  expect_error(decode(jpeg({sof(17)})), StatusCode::kParseError, "precision");
  expect_error(decode(jpeg({sof(8, 0)})), StatusCode::kUnsupported, "DNL");
  expect_error(decode(jpeg({segment(0xC4, {0, 1, 2})})), StatusCode::kParseError, "too short");
  expect_error(decode(jpeg({dht(0x10)})), StatusCode::kParseError, "class");
  expect_error(decode(jpeg({dht(0x04)})), StatusCode::kParseError, "class");
  Bytes cut = dht();
  cut[3] = static_cast<uint8_t>(cut[3] - 1);  // the last symbol outside the segment
  expect_error(decode(jpeg({cut})), StatusCode::kParseError, "past the segment");
  expect_error(decode(jpeg({segment(0xDD, {0, 2, 0})})), StatusCode::kParseError, "DRI");
  expect_error(decode(jpeg({segment(0xC0, {8, 0, 2, 0, 2, 1, 1, 0x11, 0})})),
               StatusCode::kUnsupported, "not lossless process 14");
  expect_error(decode(jpeg({segment(0xCC, {0})})), StatusCode::kUnsupported, "DAC");
  // The last SOFn (15: lossless, differential, arithmetic) and the last RSTn.
  expect_error(decode(jpeg({segment(0xCF, {8, 0, 2, 0, 2, 1, 1, 0x11, 0})})),
               StatusCode::kUnsupported, "not lossless process 14");
  expect_error(decode(jpeg({sof(), {0xFF, 0xD7}})), StatusCode::kParseError, "unexpected marker");
  expect_error(decode(jpeg({{0xFF, 0x01}})), StatusCode::kParseError, "unexpected marker");
  expect_error(decode(jpeg({{0xFF, 0xD8}})), StatusCode::kParseError, "unexpected marker");
  // Two tables in one segment; APPn skipped.
  Bytes two = dht();
  Bytes second = dht(0x01);
  two.insert(two.end(), second.begin() + 4, second.end());
  two[3] = static_cast<uint8_t>(two.size() - 2);
  SPLINTCORE_EXPECT_OK(
      decode(jpeg({segment(0xE0, {'J', 'F', 'I', 'F', 0}), sof(), two, sos(1), kScan, kEoi})));
  // Table 3, the last there is, defined and used.
  SPLINTCORE_EXPECT_OK(decode(jpeg({sof(), dht(0x03), sos(3), kScan, kEoi})));
  // A table of no codes is a whole table (17 bytes): read, and the scan's first code is none.
  Bytes empty(17, 0);
  expect_error(decode(jpeg({sof(), segment(0xC4, empty), sos(), {0x00, 0x00}, kEoi})),
               StatusCode::kParseError, "invalid Huffman code");
  empty.pop_back();
  expect_error(decode(jpeg({sof(), segment(0xC4, empty)})), StatusCode::kParseError, "too short");
}

TEST(CtDicomJpegErrors, ScanHeader) {
  expect_error(decode(jpeg({dht(), sos()})), StatusCode::kParseError, "SOS before SOF3");
  expect_error(decode(jpeg({sof(), dht(), sos(), kScan, sos()})), StatusCode::kUnsupported,
               "more than one scan");
  expect_error(decode(jpeg({sof(), dht(), segment(0xDA, {2, 1, 0, 2, 0, 1, 0, 0})})),
               StatusCode::kParseError, "one component");
  // Two components in a segment of one's length; one in a longer segment.
  expect_error(decode(jpeg({sof(), dht(), segment(0xDA, {2, 1, 0, 1, 0, 0})})),
               StatusCode::kParseError, "one component");
  expect_error(decode(jpeg({sof(), dht(), segment(0xDA, {1, 1, 0, 1, 0, 0, 0, 0})})),
               StatusCode::kParseError, "one component");
  expect_error(decode(jpeg({sof(), dht(), sos(1)})), StatusCode::kParseError, "undefined");
  expect_error(decode(jpeg({sof(), dht(), sos(5)})), StatusCode::kParseError, "undefined");
  expect_error(decode(jpeg({sof(), dht(), sos(0, 8)})), StatusCode::kParseError, "predictor");
  expect_error(decode(jpeg({sof(), dht(), sos(0, 1, 1)})), StatusCode::kParseError, "Se");
  expect_error(decode(jpeg({sof(), dht(), sos(0, 1, 0, 0x10)})), StatusCode::kParseError, "Ah");
  expect_error(decode(jpeg({sof(), dht(), sos(0, 1, 0, 8)})), StatusCode::kParseError,
               "point transform");
  expect_error(decode(jpeg({sof(), dht(), segment(0xDD, {0, 3}), sos()})), StatusCode::kUnsupported,
               "whole number of lines");
  expect_error(decode(jpeg({sof(), dht(), kEoi})), StatusCode::kParseError, "EOI before");
}

TEST(CtDicomJpegErrors, MarkersAndLengths) {
  expect_error(decode(jpeg({sof(), dht(), sos(), kScan})), StatusCode::kTruncated, "before EOI");
  expect_error(decode(jpeg({sof(), {0x12}})), StatusCode::kParseError, "expected a marker");
  expect_error(decode(jpeg({sof(), {0xFF, 0xFF}})), StatusCode::kTruncated, "inside a marker");
  expect_error(decode(jpeg({{0xFF, 0xFE, 0}})), StatusCode::kTruncated, "segment length");
  expect_error(decode(jpeg({{0xFF, 0xFE, 0, 1}})), StatusCode::kParseError, "under 2");
  expect_error(decode(jpeg({{0xFF, 0xFE, 0, 9, 1}})), StatusCode::kTruncated, "marker segment");
  // Fill bytes before a marker are allowed.
  SPLINTCORE_EXPECT_OK(decode(jpeg({sof(), {0xFF}, dht(), sos(), kScan, {0xFF}, kEoi})));
  // The image size must be the DICOM one.
  TestArena t(1 << 14);
  Bytes out(32);
  const Bytes j = jpeg({sof(), dht(), sos(), kScan, kEoi});
  expect_error(ct_detail::jpeg_lossless_decode(t.arena, j.data(), j.size(), 2, 3, 16, out.data()),
               StatusCode::kParseError, "differs");
  expect_error(ct_detail::jpeg_lossless_decode(t.arena, j.data(), j.size(), 2, 2, 7, out.data()),
               StatusCode::kParseError, "over the DICOM Bits Allocated 7");
}

TEST(CtDicomJpegErrors, EntropyCodedData) {
  // Category 8 ("110") and only five of its eight bits before the marker.
  expect_error(decode(jpeg({sof(), dht(), sos(), {0xDF}, kEoi})), StatusCode::kTruncated,
               "inside a sample");
  // Category 16: 32768 and no extra bits; halves of negative numbers (predictors 5 and 6).
  Bytes sixteen = dht();
  sixteen.back() = 16;
  Bytes out;
  SPLINTCORE_EXPECT_OK(decode(jpeg({sof(), sixteen, sos(), {0xC3}, kEoi}), &out));
  EXPECT_EQ(out, (Bytes{0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80}));
  // 129 128 / 128 127: for the last sample Rb - Rc and Ra - Rc are -1, halved to -1 (floor).
  // "101" "100" / "100" "0", pad: 1011 0010 0011 1111.
  for (uint8_t predictor : {5, 6}) {
    SPLINTCORE_EXPECT_OK(decode(jpeg({sof(), dht(), sos(0, predictor), {0xB2, 0x3F}, kEoi}), &out));
    EXPECT_EQ(out, (Bytes{129, 0, 128, 0, 128, 0, 127, 0})) << int{predictor};
  }
}

TEST(CtDicomJpegErrors, RestartMarkers) {
  const Bytes dri = segment(0xDD, {0, 2});  // one line of 2
  Bytes out;
  // Row 0: "0", "10 1", pad: 0x5F; RST0; row 1 from the initial prediction: "0", "0": 0x3F.
  SPLINTCORE_EXPECT_OK(
      decode(jpeg({sof(), dht(), dri, sos(), {0x5F, 0xFF, 0xD0, 0x3F}, kEoi}), &out));
  EXPECT_EQ(out, (Bytes{128, 0, 129, 0, 128, 0, 128, 0}));
  expect_error(decode(jpeg({sof(), dht(), dri, sos(), {0x5F, 0xFF, 0xD1, 0x3F}, kEoi})),
               StatusCode::kParseError, "expected the next RSTn");
  expect_error(decode(jpeg({sof(), dht(), dri, sos(), {0x5F, 0x00, 0xFF, 0xD0, 0x3F}, kEoi})),
               StatusCode::kParseError, "continues past a restart interval");
  expect_error(decode(jpeg({sof(), dht(), dri, sos(), {0x5F, 0xFF}})), StatusCode::kTruncated,
               "before RSTn");
  // Category 0 as "0000": a line of two samples is one whole byte, so one byte more before
  // the RSTn (or after the last sample) is all that is left over, and still too much.
  Bytes body = {0x00, 0, 0, 0, 1};
  body.resize(17, 0);
  body.push_back(0);
  const Bytes four = segment(0xC4, body);
  SPLINTCORE_EXPECT_OK(
      decode(jpeg({sof(), four, dri, sos(), {0x00, 0xFF, 0xD0, 0x00}, kEoi}), &out));
  EXPECT_EQ(out, (Bytes{128, 0, 128, 0, 128, 0, 128, 0}));
  expect_error(decode(jpeg({sof(), four, dri, sos(), {0x00, 0x00, 0xFF, 0xD0, 0x00}, kEoi})),
               StatusCode::kParseError, "continues past a restart interval");
  SPLINTCORE_EXPECT_OK(decode(jpeg({sof(), four, sos(), {0x00, 0x00}, kEoi})));
  expect_error(decode(jpeg({sof(), four, sos(), {0x00, 0x00, 0x00}, kEoi})),
               StatusCode::kParseError, "continues past the last sample");
}

}  // namespace
}  // namespace splintcore
