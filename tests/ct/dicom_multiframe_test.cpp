// Enhanced multi-frame DICOM (PS3.3 C.7.6.16, A.38 Enhanced CT; issue 31): one file holding
// the volume, positions in the Per-frame Functional Groups. The oracle: fixtures/ct/mf16*.dcm
// (make_ct_fixtures.py: the three single-frame slices raw16_{0,1,2}.dcm as one file, in
// order or not, with defined or undefined lengths, re-encoded by dcmtk as implicit VR and as
// deflated) read to the same volume as the folder of the three slices, in the same arena.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "splintcore/ct.h"
#include "support/dicom_read.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::Bytes;
using test::TestArena;

Bytes fixture(const std::string& name) { return test::ct_fixture(name); }

using Read = test::DicomRead;

Read read(const std::vector<Bytes>& files, size_t arena_bytes = 1 << 20,
          uint32_t max_dimension = 4096) {
  return test::read_dicom_bytes(files, test::numbered_names(files.size(), "f"), arena_bytes, 0,
                                max_dimension);
}

Read read_folder() {
  return read({fixture("raw16_0.dcm"), fixture("raw16_1.dcm"), fixture("raw16_2.dcm")});
}

bool has(const Status& s, const char* text) {
  return std::string(s.message()).find(text) != std::string::npos;
}

// mf16.dcm (explicit VR, defined lengths) with the top-level element (group, element) of a
// short VR given `value` (its length updated).
Bytes with_value(uint16_t group, uint16_t element, const std::string& value) {
  Bytes b = fixture("mf16.dcm");
  EXPECT_TRUE(test::replace_short_value(&b, test::dicom_tag(group, element), 0, value));
  return b;
}

// mf16 cut to its first `count` frames: Number of Frames `count`, the later per-frame items
// dropped (the sequence is of defined length), `count` frames of pixels.
Bytes mf16_first_frames(int count) {
  Bytes b = with_value(0x0028, 0x0008, std::to_string(count) + (count < 10 ? " " : ""));
  const size_t sq = test::find_bytes(b, test::dicom_tag(0x5200, 0x9230) + "SQ");
  auto u32_at = [&](size_t at) {
    return uint32_t{b[at]} | (uint32_t{b[at + 1]} << 8) | (uint32_t{b[at + 2]} << 16) |
           (uint32_t{b[at + 3]} << 24);
  };
  size_t cut = sq + 12;
  for (int k = 0; k < count; ++k) cut += 8 + u32_at(cut + 4);
  size_t end = cut;
  for (int k = count; k < 3; ++k) end += 8 + u32_at(end + 4);
  test::put_le32(&b, sq + 8, static_cast<uint32_t>(u32_at(sq + 8) - (end - cut)));
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(cut),
          b.begin() + static_cast<std::ptrdiff_t>(end));
  const size_t pixels = test::find_bytes(b, test::dicom_tag(0x7FE0, 0x0010) + "OW");
  const uint32_t frame_bytes = 64 * 56 * 2;
  test::put_le32(&b, pixels + 8, static_cast<uint32_t>(count) * frame_bytes);
  b.resize(pixels + 12 + count * frame_bytes);
  return b;
}

void expect_same_volume(const Read& a, const Read& b) {
  ASSERT_TRUE(a.status.is_ok()) << a.status.message();
  ASSERT_TRUE(b.status.is_ok()) << b.status.message();
  EXPECT_EQ(a.volume.nx, b.volume.nx);
  EXPECT_EQ(a.volume.ny, b.volume.ny);
  EXPECT_EQ(a.volume.nz, b.volume.nz);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(a.volume.spacing[c], b.volume.spacing[c]) << c;
    EXPECT_EQ(a.volume.origin[c], b.volume.origin[c]) << c;
    EXPECT_EQ(a.volume.axis_z[c], b.volume.axis_z[c]) << c;
  }
  EXPECT_TRUE(a.hu == b.hu);
  EXPECT_EQ(a.info.slope, b.info.slope);
  EXPECT_EQ(a.info.intercept, b.info.intercept);
  EXPECT_EQ(a.info.rescale_varies, b.info.rescale_varies);
  EXPECT_EQ(a.info.slice_count, b.info.slice_count);
}

TEST(CtDicomMultiFrame, ReadsLikeTheFolderOfItsSlices) {
  const Read folder = read_folder();
  ASSERT_TRUE(folder.status.is_ok()) << folder.status.message();
  ASSERT_EQ(folder.volume.nz, 3u);
  // In file order, defined lengths, everything shared but the positions.
  const Read mf = read({fixture("mf16.dcm")});
  expect_same_volume(mf, folder);
  // Frames in file order 2, 0, 1; undefined lengths; orientation, measures, rescale per frame.
  expect_same_volume(read({fixture("mf16_rev.dcm")}), folder);
  // dcmtk's implicit VR (sequences known by tag) and deflated re-encodings.
  expect_same_volume(read({fixture("mf16_imp.dcm")}), folder);
  expect_same_volume(read({fixture("mf16_defl.dcm")}), folder);
  // The arena: what the folder takes, and the read fits exactly in it.
  EXPECT_EQ(mf.high_water, folder.high_water);
  expect_same_volume(read({fixture("mf16.dcm")}, mf.high_water), folder);
  const Read less = read({fixture("mf16.dcm")}, mf.high_water - 1);
  EXPECT_EQ(less.status.code(), StatusCode::kArenaExhausted) << less.status.message();
}

TEST(CtDicomMultiFrame, MissingFramePositionNamesTheFrame) {
  Bytes b = fixture("mf16.dcm");
  const std::string position = test::dicom_tag(0x0020, 0x0032) + "DS";
  const size_t second = test::find_bytes(b, position, 1);
  ASSERT_NE(second, std::string::npos);
  b[second + 2] = 0x31;  // (0020,0031): not a position
  const Read r = read({b});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status, "frame 1 (item 1 of (5200,9230)")) << r.status.message();
  EXPECT_TRUE(has(r.status, "no (0020,0032) Image Position (Patient)")) << r.status.message();
  // At frame 1's item: after frame 0's position, before its own.
  EXPECT_GT(r.status.byte_offset(), test::find_bytes(b, position, 0));
  EXPECT_LT(r.status.byte_offset(), second);
}

TEST(CtDicomMultiFrame, FrameCountMustMatchItemsAndPixels) {
  // Pixel Data of two frames for three.
  Bytes b = fixture("mf16.dcm");
  const size_t pixels = test::find_bytes(b, test::dicom_tag(0x7FE0, 0x0010) + "OW");
  ASSERT_NE(pixels, std::string::npos);
  const uint32_t frame_bytes = 64 * 56 * 2;
  test::put_le32(&b, pixels + 8, 2 * frame_bytes);
  b.resize(pixels + 12 + 2 * frame_bytes);
  Read r = read({b});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status,
                  "Pixel Data has 14336 bytes; rows x columns x bytes per pixel x "
                  "Number of Frames is 21504"))
      << r.status.message();
  // Four frames, three items; two frames, three items.
  r = read({with_value(0x0028, 0x0008, "4 ")});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status,
                  "Number of Frames is 4 but the (5200,9230) Per-frame Functional "
                  "Groups Sequence (the frame positions) has 3 items"))
      << r.status.message();
  r = read({with_value(0x0028, 0x0008, "2 ")});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status, "has more items than Number of Frames (2)")) << r.status.message();
}

// One frame in an enhanced file: its position (the per-frame item's) and z spacing (the
// shared Slice Thickness) as the single slice raw16_0.dcm gives them.
TEST(CtDicomMultiFrame, OneFrameReadsLikeItsSlice) {
  expect_same_volume(read({mf16_first_frames(1)}), read({fixture("raw16_0.dcm")}));
}

// A frame's orientation and pixel spacing may differ from frame 0's by the tolerance, not
// more: mf16_rev (per-frame values, undefined lengths) with its second item's Image
// Orientation and Pixel Spacing each 2^-10 off (exact in binary, as is the difference).
TEST(CtDicomMultiFrame, FrameValuesWithinTheTolerance) {
  Bytes orientation = fixture("mf16_rev.dcm");
  ASSERT_TRUE(test::replace_short_value(&orientation, test::dicom_tag(0x0020, 0x0037) + "DS", 1,
                                        "1\\0.0009765625\\0\\0\\1\\0"));
  Bytes spacing = fixture("mf16_rev.dcm");
  ASSERT_TRUE(test::replace_short_value(&spacing, test::dicom_tag(0x0028, 0x0030) + "DS", 1,
                                        "1.2009765625\\1.2"));
  const double tolerance = 0.0009765625;
  for (const Bytes& f : {orientation, spacing}) {
    const Read r = test::read_dicom_bytes({f}, {"f0.dcm"}, 1 << 20, 0, 4096, tolerance);
    EXPECT_TRUE(r.status.is_ok()) << r.status.message();
    EXPECT_EQ(r.volume.nz, 3u);
  }
  Read r = test::read_dicom_bytes({orientation}, {"f0.dcm"}, 1 << 20, 0, 4096, tolerance / 2);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_TRUE(has(r.status, "its Image Orientation (Patient) differs from frame 0's"))
      << r.status.message();
  r = test::read_dicom_bytes({spacing}, {"f0.dcm"}, 1 << 20, 0, 4096, tolerance / 2);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_TRUE(has(r.status, "its Pixel Spacing differs from frame 0's")) << r.status.message();
}

TEST(CtDicomMultiFrame, AbsurdNumberOfFramesIsAnError) {
  Read r = read({with_value(0x0028, 0x0008, "0 ")});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status, "(0028,0008) Number of Frames: is 0: must be 1 to 4096"))
      << r.status.message();
  r = read({with_value(0x0028, 0x0008, "-7")});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  r = read({with_value(0x0028, 0x0008, "4000000000")});
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded);
  EXPECT_TRUE(has(r.status, "is 4000000000: must be 1 to 4096 (CtReadOptions::max_dimension)"))
      << r.status.message();
  r = read({fixture("mf16.dcm")}, 1 << 20, 2);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << r.status.message();
  EXPECT_TRUE(has(r.status, "is 3: must be 1 to 2 (CtReadOptions::max_dimension)"))
      << r.status.message();
  // Number of Frames equal to the limit passes its check (mf16's slices are 64 wide): what
  // stops this file is its 3 frame items.
  r = read({with_value(0x0028, 0x0008, "64")}, 1 << 20, 64);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status, "Number of Frames is 64 but the (5200,9230)")) << r.status.message();
}

TEST(CtDicomMultiFrame, MalformedFunctionalGroupsAreErrors) {
  // The Plane Position item of frame 0 two bytes shorter than its position element.
  Bytes b = fixture("mf16.dcm");
  const size_t sq = test::find_bytes(b, test::dicom_tag(0x0020, 0x9113) + "SQ");
  ASSERT_NE(sq, std::string::npos);
  test::put_le32(&b, sq + 16, 20);  // the item's length (22)
  Read r = read({b});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(
      has(r.status, "(FFFE,E000) sequence or item: an element inside runs past its defined length"))
      << r.status.message();
  // The sequence longer than the frame's item.
  b = fixture("mf16.dcm");
  test::put_le32(&b, sq + 8, 3000);
  r = read({b});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status,
                  "(0020,9113) sequence or item: its length runs past the end of the "
                  "enclosing item"))
      << r.status.message();
  EXPECT_EQ(r.status.byte_offset(), sq);
  // A frame whose orientation is not the others'.
  b = fixture("mf16_rev.dcm");
  const size_t o = test::find_bytes(b, test::dicom_tag(0x0020, 0x0037) + "DS", 2);
  ASSERT_NE(o, std::string::npos);
  ASSERT_EQ(std::memcmp(&b[o + 8], "1\\0\\0\\0\\1\\0", 11), 0);
  std::memcpy(&b[o + 8], "0\\1\\0\\1\\0\\0", 11);
  r = read({b});
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_TRUE(has(r.status,
                  "frame 2 (item 2 of (5200,9230) Per-frame Functional Groups "
                  "Sequence): its Image Orientation (Patient) differs"))
      << r.status.message();
  // And one whose pixel spacing is not.
  b = fixture("mf16_rev.dcm");
  const size_t ps = test::find_bytes(b, test::dicom_tag(0x0028, 0x0030) + "DS", 1);
  ASSERT_NE(ps, std::string::npos);
  ASSERT_EQ(std::memcmp(&b[ps + 8], "1.2\\1.2", 7), 0);
  b[ps + 8] = '2';
  r = read({b});
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_TRUE(has(r.status, "frame 1 (item 1")) << r.status.message();
  EXPECT_TRUE(has(r.status, "Pixel Spacing differs")) << r.status.message();
}

// Frame positions go through the series' checks, messages naming frames; rescale per frame.
TEST(CtDicomMultiFrame, FramesAreCheckedAsSlices) {
  const std::string position = test::dicom_tag(0x0020, 0x0032) + "DS";
  // Frame 1 at frame 0's position.
  Bytes b = fixture("mf16.dcm");
  const size_t second = test::find_bytes(b, position, 1);
  ASSERT_EQ(std::memcmp(&b[second + 8], "-37.8\\-33\\-2.5", 14), 0);
  std::memcpy(&b[second + 8], "-37.8\\-33\\22.5", 14);
  Read r = read({b});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status, "duplicate slice position")) << r.status.message();
  EXPECT_TRUE(has(r.status, "(frames ")) << r.status.message();
  // Frame 1 off the normal through frame 0 (a shear): resampled (dicom_multiframe_codecs_test).
  b = fixture("mf16.dcm");
  b[second + 10] = '0';  // -30.8
  r = read({b});
  ASSERT_TRUE(r.status.is_ok()) << r.status.message();
  EXPECT_TRUE(r.info.resampled);
  EXPECT_GT(r.info.max_shift_mm, 0.0);
  // Frame 0 of mf16_rev (raw16_2: lowest z, slice 0) one HU up: its own intercept is used.
  b = fixture("mf16_rev.dcm");
  const size_t intercept = test::find_bytes(b, test::dicom_tag(0x0028, 0x1052) + "DS");
  ASSERT_EQ(std::memcmp(&b[intercept + 8], "-1063", 5), 0);
  b[intercept + 12] = '2';
  r = read({b});
  const Read folder = read_folder();
  ASSERT_TRUE(r.status.is_ok()) << r.status.message();
  EXPECT_TRUE(r.info.rescale_varies);
  const size_t per_slice = 64 * 56;
  for (size_t i = 0; i < r.hu.size(); ++i) {
    ASSERT_EQ(r.hu[i], folder.hu[i] + (i < per_slice ? 1 : 0)) << i;
  }
}

TEST(CtDicomMultiFrame, RefusedWhereNotSupported) {
  // A multi-frame file is read alone, not in a series, nor among single-frame slices.
  Read r = read({fixture("mf16.dcm"), fixture("raw16_0.dcm")});
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_TRUE(has(r.status, "a multi-frame image (3 frames) in a series of 2 files"))
      << r.status.message();
  r = read({fixture("raw16_0.dcm"), fixture("mf16.dcm")});
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_TRUE(has(r.status, "Number of Frames")) << r.status.message();
  // Compressed multi-frame (read: dicom_multiframe_codecs_test): mf16 as RLE (same-length UID)
  // with encapsulated Pixel Data of one fragment for three frames.
  Bytes b = fixture("mf16.dcm");
  const size_t uid = test::find_bytes(b, std::string("1.2.840.10008.1.2.1\0", 20));
  ASSERT_NE(uid, std::string::npos);
  b[uid + 18] = '5';
  const size_t pixels = test::find_bytes(b, test::dicom_tag(0x7FE0, 0x0010) + "OW");
  b.resize(pixels);
  const uint8_t tail[] = {0xE0, 0x7F, 0x10, 0x00, 'O',  'B',  0, 0, 0xFF, 0xFF,
                          0xFF, 0xFF, 0xFE, 0xFF, 0x00, 0xE0, 0, 0, 0,    0,
                          0xFE, 0xFF, 0x00, 0xE0, 4,    0,    0, 0, 1,    2,
                          3,    4,    0xFE, 0xFF, 0xDD, 0xE0, 0, 0, 0,    0};
  b.insert(b.end(), tail, tail + sizeof(tail));
  r = read({b});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status,
                  "Pixel Data has 1 fragment items, 1 of them starting a frame, for 3 "
                  "frames"))
      << r.status.message();
}

// A file that changes between the header pass and the frames' pass (the second open serves
// other bytes: two frames of the three) is an error, not a read of stale records.
struct ChangingFile {
  Bytes first, then;
  int opens = 0;
  MemorySource source;
};

TEST(CtDicomMultiFrame, FileChangedBetweenReadsIsAnError) {
  ChangingFile file;
  file.first = fixture("mf16.dcm");
  Bytes b = mf16_first_frames(2);
  ASSERT_TRUE(read({b}).status.is_ok()) << read({b}).status.message();  // valid alone
  file.then = b;
  CtSeries series;
  series.count = 1;
  series.user = &file;
  series.open = [](void* user, uint32_t, ByteSource* out) {
    ChangingFile* f = static_cast<ChangingFile*>(user);
    const Bytes& bytes = f->opens++ == 0 ? f->first : f->then;
    f->source = MemorySource{bytes.data(), bytes.size(), 0, 0};
    *out = memory_source(&f->source, "changing.dcm");
    return Status::ok();
  };
  TestArena t(1 << 20);
  Context ctx(&t.arena);
  CtReadOptions options;
  CtVolume volume;
  const Status s = read_dicom_series(ctx, series, options, &volume, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(s, "the file changed between two reads")) << s.message();
  EXPECT_EQ(file.opens, 2);
  // Grown from two frames to three: the frames' records have room for two, and the third
  // item is refused before anything is written for it.
  file.first = b;
  file.then = fixture("mf16.dcm");
  file.opens = 0;
  const Status grown = read_dicom_series(ctx, series, options, &volume, nullptr);
  EXPECT_EQ(grown.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(grown,
                  "the file changed between two reads: (5200,9230) Per-frame Functional Groups "
                  "Sequence has more than the 2 items read first"))
      << test::format(grown);
  EXPECT_STREQ(grown.file(), "changing.dcm");
  EXPECT_EQ(file.opens, 2);
}

}  // namespace
}  // namespace splintcore
