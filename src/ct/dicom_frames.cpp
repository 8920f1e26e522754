// The frames of encapsulated multi-frame Pixel Data: DICOM PS3.5 A.4 (fragments, the Basic
// Offset Table, A.4.2 RLE), PS3.3 C.7.6.3.1.8 (the Extended Offset Table); the start markers
// of ITU-T T.81 B.2.1 (SOI), T.87 C.1 and T.800 A.4.1 (SOC). See dicom_frames.h.
#include "ct/dicom_frames.h"

namespace splintcore {
namespace ct_detail {

bool FrameMapper::starts_frame(uint64_t relative, const uint8_t* head, size_t head_bytes) const {
  if (table_.name != nullptr) {
    return found_ < frames_ && records_[found_].pixel_offset == relative;
  }
  switch (start_) {
    case FrameStart::kJpegSoi: return head_bytes >= 2 && head[0] == 0xFF && head[1] == 0xD8;
    case FrameStart::kJpeg2000Soc: return head_bytes >= 2 && head[0] == 0xFF && head[1] == 0x4F;
    default: return true;
  }
}

Status FrameMapper::entry_error(uint32_t frame, const char* what, uint64_t value) const {
  return make_error(StatusCode::kParseError, "frame ", frame, ": its ", table_.name, " entry is ",
                    value, what)
      .at_byte(table_.at + uint64_t{frame} * table_.entry_bytes);
}

// The item at `at` (relative bytes after the first) does not start a frame: the first item
// must; with a table, no entry may fall inside the previous item.
Status FrameMapper::not_a_start(uint64_t at, uint64_t relative) const {
  if (table_.name != nullptr) {
    const uint64_t entry = records_[found_ < frames_ ? found_ : 0].pixel_offset;
    if (fragments_ == 0) {
      return entry_error(0, ", not 0: the first frame starts at the first fragment item", entry);
    }
    if (found_ < frames_ && entry < relative) {
      Status s = entry_error(found_, " (bytes from the first fragment item), inside fragment item ",
                             entry);
      s.append_u64(fragments_ - 1);
      s.append(": a frame starts at a fragment item (the table lies)");
      return s;
    }
    return Status::ok();
  }
  if (fragments_ == 0) {
    return make_error(
               StatusCode::kParseError, "frame 0: its first fragment item does not begin with the ",
               start_ == FrameStart::kJpegSoi ? "SOI marker 0xFFD8 of a JPEG stream"
                                              : "SOC marker 0xFF4F of a JPEG 2000 codestream")
        .at_byte(at);
  }
  return Status::ok();
}

Status FrameMapper::add(uint64_t at, uint32_t length, const uint8_t* head, size_t head_bytes) {
  if (fragments_ == 0) first_ = at;
  const uint64_t relative = at - first_;
  if (starts_frame(relative, head, head_bytes)) {
    if (found_ == frames_) {
      return make_error(StatusCode::kParseError, "fragment item ", fragments_,
                        start_ == FrameStart::kEachFragment
                            ? " is one more than Number of Frames ("
                            : " starts a frame (its start marker) beyond Number of Frames (",
                        frames_,
                        start_ == FrameStart::kEachFragment
                            ? "), and there is no offset table to group fragments into frames "
                              "(RLE: one fragment a frame, PS3.5 A.4.2)"
                            : ")")
          .at_byte(at);
    }
    records_[found_].pixel_offset = at;
    records_[found_].fragments = 0;
    ++found_;
    bytes_ = 0;
  } else {
    SPLINTCORE_RETURN_IF_ERROR(not_a_start(at, relative));
  }
  const uint32_t frame = found_ - 1;
  bytes_ += length;
  if (bytes_ > max_bytes_) {
    return make_error(StatusCode::kLimitExceeded, "frame ", frame,
                      ": its fragments hold more than ", max_bytes_,
                      " bytes (8 x its raw bytes + 64 KiB)")
        .at_byte(at);
  }
  if (bytes_ > largest_) largest_ = bytes_;
  ++records_[frame].fragments;
  ++fragments_;
  return Status::ok();
}

Status FrameMapper::finish(uint64_t at) const {
  if (found_ == frames_) return Status::ok();
  if (table_.name != nullptr) {
    Status s =
        entry_error(found_, " bytes, past the last fragment item (", records_[found_].pixel_offset);
    s.append_u64(fragments_);
    s.append(" fragment items, ");
    s.append_u64(found_);
    s.append(" frames found)");
    return s;
  }
  return make_error(StatusCode::kParseError, "Pixel Data has ", fragments_, " fragment items, ",
                    found_, " of them starting a frame",
                    start_ == FrameStart::kEachFragment ? "" : " (beginning with its start marker)",
                    ", for ", frames_, " frames (Number of Frames)")
      .at_byte(at);
}

}  // namespace ct_detail
}  // namespace splintcore
