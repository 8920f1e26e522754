// The frames of an enhanced multi-frame image's encapsulated Pixel Data (DICOM PS3.5 A.4;
// issue 31): which fragment items make frame i. A frame is one or more whole fragments, in
// frame order. Frame i starts at entry i of the Basic Offset Table (the first item's value,
// 32-bit offsets) or of the Extended Offset Table ((7FE0,0001), 64-bit; PS3.3 C.7.6.3.1.8), an
// offset from the first fragment item's first byte. Without a table, RLE frames are one
// fragment each (PS3.5 A.4.2), and a JPEG (lossless, JPEG-LS) or JPEG 2000 frame starts at the
// fragment whose bytes begin with the codestream's start marker (SOI 0xFFD8, T.81 B.2.1 and
// T.87 C.1; SOC 0xFF4F, T.800 A.4.1), which cannot appear at the start of another fragment of
// a valid stream (after 0xFF, entropy-coded data holds only 0x00 or RSTn, T.81 B.1.1.5,
// T.87 A.1; JPEG 2000 packet data no byte above 0x8F, T.800 A.1.1).
#ifndef SPLINTCORE_SRC_CT_DICOM_FRAMES_H
#define SPLINTCORE_SRC_CT_DICOM_FRAMES_H

#include "splintcore/core.h"

namespace splintcore {
namespace ct_detail {

// One slice of a DICOM series (a file, or a frame of a multi-frame file) between the passes.
struct SliceRecord {
  double position[3];
  double slope;
  double intercept;
  // Native: the pixels. Encapsulated multi-frame: the frame's first fragment item (its item
  // header), and until the frames are mapped its offset table entry.
  uint64_t pixel_offset;
  uint32_t file;
  uint32_t fragments;  // encapsulated multi-frame: the frame's fragment items
};

// What starts a frame when there is no offset table.
enum class FrameStart : uint8_t { kEachFragment, kJpegSoi, kJpeg2000Soc };

// An offset table: its name for messages, the file offset of its first entry and the bytes
// of an entry (4 or 8); name null: none.
struct OffsetTable {
  const char* name = nullptr;
  uint64_t at = 0;
  uint32_t entry_bytes = 4;
};

// Assigns fragment items, as they stream by, to frames 0..frames-1 of records[] (each record's
// pixel_offset and fragments, zero on entry). With a table, records[i].pixel_offset holds frame
// i's entry on entry. Errors name the frame, and the byte offset in the file of the item or
// table entry at fault. A frame's fragments may hold at most max_frame_bytes (kLimitExceeded).
class FrameMapper {
 public:
  FrameMapper(SliceRecord* records, uint32_t frames, const OffsetTable& table, FrameStart start,
              uint64_t max_frame_bytes)
      : records_(records),
        frames_(frames),
        table_(table),
        start_(start),
        max_bytes_(max_frame_bytes) {}

  // The next fragment item: its header at file offset `at`, `length` bytes of value whose first
  // head_bytes (<= 4) are head.
  Status add(uint64_t at, uint32_t length, const uint8_t* head, size_t head_bytes);
  // After the last fragment (the sequence delimiter at file offset `at`): every frame found.
  Status finish(uint64_t at) const;
  // Frames begun so far.
  uint32_t frames_found() const { return found_; }
  // The largest frame's fragment bytes.
  uint64_t largest() const { return largest_; }

 private:
  bool starts_frame(uint64_t relative, const uint8_t* head, size_t head_bytes) const;
  Status not_a_start(uint64_t at, uint64_t relative) const;
  Status entry_error(uint32_t frame, const char* what, uint64_t value) const;

  SliceRecord* records_;
  uint32_t frames_;
  OffsetTable table_;
  FrameStart start_;
  uint64_t max_bytes_;  // a frame's fragments may hold at most this many bytes
  uint32_t found_ = 0;  // frames begun
  uint64_t first_ = 0;  // file offset of the first fragment item
  uint64_t bytes_ = 0;  // the current frame's fragment bytes
  uint64_t largest_ = 0;
  uint32_t fragments_ = 0;  // items seen
};

}  // namespace ct_detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_CT_DICOM_FRAMES_H
