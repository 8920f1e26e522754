// FrameMapper (src/ct/dicom_frames.h) on hand-made fragment sequences: which fragment items
// make which frame, at the edges the DICOM files in fixtures/ct do not reach (a frame's first
// fragment holding only its start marker, a frame of exactly the byte limit, a record past
// the frame count), and which message names which cause.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "ct/dicom_frames.h"

namespace splintcore {
namespace ct_detail {
namespace {

bool has(const Status& s, const char* text) {
  return std::string(s.message()).find(text) != std::string::npos;
}

const uint8_t kSoi[4] = {0xFF, 0xD8, 0xFF, 0xC3};
const uint8_t kSoc[4] = {0xFF, 0x4F, 0xFF, 0x51};
const uint8_t kData[4] = {0x12, 0x34, 0x56, 0x78};

// A frame's first fragment may hold only its two-byte start marker (fragments split a
// codestream anywhere): head_bytes 2 is enough to see it, 1 is not.
TEST(DicomFrameMapper, TwoByteFragmentStartsAFrame) {
  const struct {
    FrameStart start;
    const uint8_t* marker;
  } cases[] = {{FrameStart::kJpegSoi, kSoi}, {FrameStart::kJpeg2000Soc, kSoc}};
  for (const auto& c : cases) {
    SliceRecord records[2] = {};
    FrameMapper m(records, 2, OffsetTable{}, c.start, 1000);
    ASSERT_TRUE(m.add(100, 2, c.marker, 2).is_ok());
    ASSERT_TRUE(m.add(110, 40, kData, 4).is_ok());
    ASSERT_TRUE(m.add(158, 2, c.marker, 2).is_ok());
    ASSERT_TRUE(m.add(168, 30, kData, 4).is_ok());
    ASSERT_TRUE(m.finish(206).is_ok());
    EXPECT_EQ(m.frames_found(), 2u);
    EXPECT_EQ(records[0].pixel_offset, 100u);
    EXPECT_EQ(records[0].fragments, 2u);
    EXPECT_EQ(records[1].pixel_offset, 158u);
    EXPECT_EQ(records[1].fragments, 2u);
    EXPECT_EQ(m.largest(), 42u);

    // One byte of marker is not a start: the first fragment is refused at its offset.
    SliceRecord one[1] = {};
    FrameMapper short_head(one, 1, OffsetTable{}, c.start, 1000);
    const Status s = short_head.add(100, 1, c.marker, 1);
    EXPECT_EQ(s.code(), StatusCode::kParseError);
    EXPECT_TRUE(has(s, "first fragment item does not begin with the"));
    EXPECT_EQ(s.byte_offset(), 100u);
  }
}

// A frame may hold exactly max_frame_bytes of fragments; one more byte is refused by limit.
TEST(DicomFrameMapper, FrameBytesLimitIsInclusive) {
  SliceRecord records[1] = {};
  FrameMapper at_limit(records, 1, OffsetTable{}, FrameStart::kJpegSoi, 100);
  ASSERT_TRUE(at_limit.add(0, 60, kSoi, 4).is_ok());
  ASSERT_TRUE(at_limit.add(68, 40, kData, 4).is_ok());
  EXPECT_EQ(at_limit.largest(), 100u);

  SliceRecord over_records[1] = {};
  FrameMapper over(over_records, 1, OffsetTable{}, FrameStart::kJpegSoi, 100);
  ASSERT_TRUE(over.add(0, 60, kSoi, 4).is_ok());
  const Status s = over.add(68, 41, kData, 4);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded);
  EXPECT_TRUE(has(s, "frame 0: its fragments hold more than 100 bytes"));
  EXPECT_EQ(s.byte_offset(), 68u);
}

// A frame start past Number of Frames: without a table, RLE's message says why fragments
// cannot be grouped; a JPEG stream's names its start marker, not the RLE rule.
TEST(DicomFrameMapper, ExtraFrameMessageNamesItsCause) {
  SliceRecord rle_records[1] = {};
  FrameMapper rle(rle_records, 1, OffsetTable{}, FrameStart::kEachFragment, 1000);
  ASSERT_TRUE(rle.add(0, 10, kData, 4).is_ok());
  const Status r = rle.add(18, 10, kData, 4);
  EXPECT_EQ(r.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r, "is one more than Number of Frames (1), and there is no offset table"));
  EXPECT_EQ(r.byte_offset(), 18u);

  SliceRecord jpeg_records[1] = {};
  FrameMapper jpeg(jpeg_records, 1, OffsetTable{}, FrameStart::kJpegSoi, 1000);
  ASSERT_TRUE(jpeg.add(0, 10, kSoi, 4).is_ok());
  const Status j = jpeg.add(18, 10, kSoi, 4);
  EXPECT_EQ(j.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(j, "starts a frame (its start marker) beyond Number of Frames (1)"));
  EXPECT_FALSE(has(j, "offset table"));
}

// With a table, the mapper reads entries 0..frames-1 only: a record past the last frame
// whose offset matches a later fragment does not make that fragment a frame.
TEST(DicomFrameMapper, TableEntriesPastTheFrameCountAreNotRead) {
  SliceRecord records[3] = {};
  records[0].pixel_offset = 0;
  records[1].pixel_offset = 18;
  records[2].pixel_offset = 36;  // not a frame: the mapper is told of 2
  const OffsetTable table{"Basic Offset Table", 200, 4};
  FrameMapper m(records, 2, table, FrameStart::kEachFragment, 1000);
  ASSERT_TRUE(m.add(300, 10, kData, 4).is_ok());
  ASSERT_TRUE(m.add(318, 10, kData, 4).is_ok());
  ASSERT_TRUE(m.add(336, 10, kData, 4).is_ok());
  ASSERT_TRUE(m.finish(354).is_ok());
  EXPECT_EQ(records[0].pixel_offset, 300u);
  EXPECT_EQ(records[1].pixel_offset, 318u);
  EXPECT_EQ(records[1].fragments, 2u);
  EXPECT_EQ(records[2].fragments, 0u);
}

}  // namespace
}  // namespace ct_detail
}  // namespace splintcore
