// Compressed enhanced multi-frame DICOM (PS3.5 A.4, issue 31): encapsulated Pixel Data of
// several frames, each one or more fragments, with or without a Basic or Extended Offset
// Table; and multi-frame files with tilted or uneven frame positions, resampled. The oracle:
// fixtures/ct/mf16.dcm (three uncompressed frames: the slices raw16_0, raw16_1, raw16_2) and
// the single-frame compressed twins of those slices (rle16_k, jpeg70_k, jls16_k, j2k16_k, made
// by gdcm and dcmtk, make_ct_fixtures.py): their fragments joined into mf16's header must read
// to mf16's voxels, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "splintcore/ct.h"
#include "support/dicom_read.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::Bytes;
using Read = test::DicomRead;

Bytes fixture(const std::string& name) { return test::ct_fixture(name); }

Read read(const std::vector<Bytes>& files, size_t arena_bytes = 4 << 20, size_t max_chunk = 0) {
  return test::read_dicom_bytes(files, test::numbered_names(files.size(), "m"), arena_bytes,
                                max_chunk);
}

bool has(const Status& s, const std::string& text) {
  return std::string(s.message()).find(text) != std::string::npos;
}

uint32_t get_u32(const Bytes& b, size_t at) {
  return uint32_t{b[at]} | (uint32_t{b[at + 1]} << 8) | (uint32_t{b[at + 2]} << 16) |
         (uint32_t{b[at + 3]} << 24);
}
void append_u32(Bytes* b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b->push_back(static_cast<uint8_t>(v >> (8 * i)));
}
void append(Bytes* b, const std::string& s) { b->insert(b->end(), s.begin(), s.end()); }

// The one fragment of a single-frame encapsulated file.
Bytes fragment_of(const Bytes& file) {
  size_t p = test::find_bytes(file, test::dicom_tag(0x7FE0, 0x0010) + "OB") + 12;
  p += 8 + get_u32(file, p + 4);  // the basic offset table
  const uint32_t length = get_u32(file, p + 4);
  return Bytes(file.begin() + static_cast<std::ptrdiff_t>(p + 8),
               file.begin() + static_cast<std::ptrdiff_t>(p + 8 + length));
}

// Frame k of mf16 in codec `prefix` ("jpeg70", "rle16", "jls16", "j2k16"), cut into `pieces`
// fragments of even length.
std::vector<Bytes> frame_fragments(const std::string& prefix, int k, int pieces) {
  const Bytes whole = fragment_of(fixture(prefix + "_" + std::to_string(k) + ".dcm"));
  std::vector<Bytes> out;
  size_t from = 0;
  for (int i = 0; i < pieces; ++i) {
    size_t to = i + 1 == pieces ? whole.size() : (whole.size() * (i + 1) / pieces) & ~size_t{1};
    out.emplace_back(whole.begin() + static_cast<std::ptrdiff_t>(from),
                     whole.begin() + static_cast<std::ptrdiff_t>(to));
    from = to;
  }
  return out;
}

const char* syntax_of(const std::string& prefix) {
  if (prefix == "rle16") return "1.2.840.10008.1.2.5";
  if (prefix == "jpeg70") return "1.2.840.10008.1.2.4.70";
  if (prefix == "jls16") return "1.2.840.10008.1.2.4.80";
  return "1.2.840.10008.1.2.4.90";
}

enum class Table { kNone, kBasic, kExtended };

struct Encapsulated {
  Bytes file;
  size_t table_at = 0;             // the first offset table entry
  std::vector<size_t> item_at;     // each fragment item's header
  std::vector<size_t> frame_item;  // index of each frame's first fragment
};

// `header` (mf16 or an edit of it, native explicit VR) with transfer syntax `uid` and frames[k]
// as the fragments of frame k, with the offset table asked for.
Encapsulated encapsulate(Bytes header, const std::string& uid,
                         const std::vector<std::vector<Bytes>>& frames, Table table) {
  Encapsulated e;
  // The transfer syntax (its length and the file meta group length updated).
  const size_t at = test::find_bytes(header, test::dicom_tag(0x0002, 0x0010) + "UI");
  std::string value = uid;
  if (value.size() % 2 == 1) value.push_back('\0');
  const size_t old = header[at + 6] | (header[at + 7] << 8);
  header.erase(header.begin() + static_cast<std::ptrdiff_t>(at + 8),
               header.begin() + static_cast<std::ptrdiff_t>(at + 8 + old));
  header.insert(header.begin() + static_cast<std::ptrdiff_t>(at + 8), value.begin(), value.end());
  header[at + 6] = static_cast<uint8_t>(value.size());
  const size_t group = test::find_bytes(header, test::dicom_tag(0x0002, 0x0000) + "UL");
  test::put_le32(&header, group + 8,
                 static_cast<uint32_t>(get_u32(header, group + 8) + value.size() - old));
  header.resize(test::find_bytes(header, test::dicom_tag(0x7FE0, 0x0010) + "OW"));
  std::vector<uint64_t> offsets;
  uint64_t relative = 0;
  for (const auto& frame : frames) {
    offsets.push_back(relative);
    for (const Bytes& f : frame) relative += 8 + f.size();
  }
  e.file = header;
  if (table == Table::kExtended) {
    append(&e.file, test::dicom_tag(0x7FE0, 0x0001) + "OV" + std::string(2, '\0'));
    append_u32(&e.file, static_cast<uint32_t>(8 * frames.size()));
    e.table_at = e.file.size();
    for (uint64_t o : offsets) {
      append_u32(&e.file, static_cast<uint32_t>(o));
      append_u32(&e.file, static_cast<uint32_t>(o >> 32));
    }
  }
  append(&e.file, test::dicom_tag(0x7FE0, 0x0010) + "OB" + std::string(2, '\0'));
  append_u32(&e.file, 0xFFFFFFFFu);
  append(&e.file, test::dicom_tag(0xFFFE, 0xE000));
  append_u32(&e.file, table == Table::kBasic ? static_cast<uint32_t>(4 * frames.size()) : 0);
  if (table == Table::kBasic) {
    e.table_at = e.file.size();
    for (uint64_t o : offsets) append_u32(&e.file, static_cast<uint32_t>(o));
  }
  for (const auto& frame : frames) {
    e.frame_item.push_back(e.item_at.size());
    for (const Bytes& f : frame) {
      e.item_at.push_back(e.file.size());
      append(&e.file, test::dicom_tag(0xFFFE, 0xE000));
      append_u32(&e.file, static_cast<uint32_t>(f.size()));
      e.file.insert(e.file.end(), f.begin(), f.end());
    }
  }
  append(&e.file, test::dicom_tag(0xFFFE, 0xE0DD));
  append_u32(&e.file, 0);
  return e;
}

// mf16's three frames in `prefix`, each in `pieces` fragments.
Encapsulated mf16_as(const std::string& prefix, int pieces, Table table,
                     const Bytes& header = fixture("mf16.dcm")) {
  std::vector<std::vector<Bytes>> frames;
  for (int k = 0; k < 3; ++k) frames.push_back(frame_fragments(prefix, k, pieces));
  return encapsulate(header, syntax_of(prefix), frames, table);
}

void expect_same_volume(const Read& a, const Read& b) {
  ASSERT_TRUE(a.status.is_ok()) << test::format(a.status);
  ASSERT_TRUE(b.status.is_ok()) << test::format(b.status);
  EXPECT_EQ(a.volume.nx, b.volume.nx);
  EXPECT_EQ(a.volume.ny, b.volume.ny);
  EXPECT_EQ(a.volume.nz, b.volume.nz);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(a.volume.spacing[c], b.volume.spacing[c]) << c;
    EXPECT_EQ(a.volume.origin[c], b.volume.origin[c]) << c;
    EXPECT_EQ(a.volume.axis_z[c], b.volume.axis_z[c]) << c;
  }
  EXPECT_TRUE(a.hu == b.hu);
  EXPECT_EQ(a.info.resampled, b.info.resampled);
}

// ---- Bit-identical to the uncompressed twin --------------------------------------------------

TEST(CtDicomMultiFrameCodecs, EveryCodecAndLayoutReadsLikeTheUncompressedTwin) {
  const Read twin = read({fixture("mf16.dcm")});
  ASSERT_TRUE(twin.status.is_ok()) << test::format(twin.status);
  ASSERT_EQ(twin.volume.nz, 3u);
  for (const char* prefix : {"rle16", "jpeg70", "jls16", "j2k16"}) {
    for (int pieces : {1, 3}) {
      for (Table table : {Table::kNone, Table::kBasic, Table::kExtended}) {
        // RLE frames without a table are one fragment each (PS3.5 A.4.2).
        if (std::string(prefix) == "rle16" && pieces > 1 && table == Table::kNone) continue;
        const Encapsulated e = mf16_as(prefix, pieces, table);
        for (size_t chunk : {size_t{0}, size_t{7}}) {
          const Read r = read({e.file}, 4 << 20, chunk);
          SCOPED_TRACE(std::string(prefix) + " pieces " + std::to_string(pieces) + " table " +
                       std::to_string(static_cast<int>(table)) + " chunk " + std::to_string(chunk));
          expect_same_volume(r, twin);
          EXPECT_STREQ(r.info.transfer_syntax, syntax_of(prefix));
        }
      }
    }
  }
}

// The fuzz seeds of tests/fuzz/ct_corpus.py (its own assembly of the same fragments).
TEST(CtDicomMultiFrameCodecs, CorpusSeedsEqualTheTwin) {
  const Read twin = read({fixture("mf16.dcm")});
  const std::string dir = std::string(SPLINTCORE_FIXTURES_DIR) + "/fuzz/ct_dicom/";
  for (const char* name :
       {"mf_rle.dcm", "mf_jpeg70_bot.dcm", "mf_jls_split.dcm", "mf_j2k_eot.dcm"}) {
    SCOPED_TRACE(name);
    expect_same_volume(read({test::read_file_bytes(dir + name)}), twin);
  }
}

// Frames out of position order (mf16_rev: frames 2, 0, 1; undefined lengths) and frames of
// many fragments (more than the 32 whose file offsets an error can name).
TEST(CtDicomMultiFrameCodecs, OutOfOrderFramesAndManyFragments) {
  const Read twin = read({fixture("mf16.dcm")});
  std::vector<std::vector<Bytes>> frames;
  for (int k : {2, 0, 1}) frames.push_back(frame_fragments("jpeg70", k, 1));
  const Encapsulated rev =
      encapsulate(fixture("mf16_rev.dcm"), syntax_of("jpeg70"), frames, Table::kBasic);
  expect_same_volume(read({rev.file}), twin);
  expect_same_volume(read({mf16_as("jls16", 40, Table::kNone).file}), twin);
  expect_same_volume(read({mf16_as("rle16", 40, Table::kBasic).file}), twin);
}

// The two-step contract: the first read's high water is enough, one byte less is not.
// (Not JPEG 2000: its budget is checked against jpeg2000_arena_bytes(), a bound above what a
// decode takes, so a read in its high water is refused; a single-frame file too.)
TEST(CtDicomMultiFrameCodecs, ArenaOfTheFirstReadsHighWater) {
  for (const char* prefix : {"jpeg70", "jls16", "rle16"}) {
    const Bytes file = mf16_as(prefix, 3, Table::kBasic).file;
    const Read first = read({file});
    ASSERT_TRUE(first.status.is_ok()) << test::format(first.status);
    EXPECT_TRUE(read({file}, first.high_water).status.is_ok()) << prefix;
    const Read less = read({file}, first.high_water - 1);
    EXPECT_EQ(less.status.code(), StatusCode::kArenaExhausted) << test::format(less.status);
  }
}

// ---- Malformed: errors name the frame and the byte offset ------------------------------------

TEST(CtDicomMultiFrameCodecs, FragmentCountMismatch) {
  // Two frames' fragments for three frames (no table: JPEG frames start at SOI).
  std::vector<std::vector<Bytes>> two = {frame_fragments("jpeg70", 0, 1),
                                         frame_fragments("jpeg70", 1, 2)};
  Encapsulated e = encapsulate(fixture("mf16.dcm"), syntax_of("jpeg70"), two, Table::kNone);
  Read r = read({e.file});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status,
                  "Pixel Data has 3 fragment items, 2 of them starting a frame (beginning with "
                  "its start marker), for 3 frames"))
      << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), e.file.size() - 8);  // the sequence delimiter
  // Four frames for three.
  std::vector<std::vector<Bytes>> four;
  for (int k : {0, 1, 2, 0}) four.push_back(frame_fragments("jpeg70", k, 1));
  e = encapsulate(fixture("mf16.dcm"), syntax_of("jpeg70"), four, Table::kNone);
  r = read({e.file});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status,
                  "fragment item 3 starts a frame (its start marker) beyond Number of "
                  "Frames (3)"))
      << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), e.item_at[3]);
  // RLE: one fragment more than frames, no table.
  std::vector<std::vector<Bytes>> rle;
  for (int k : {0, 1, 2}) rle.push_back(frame_fragments("rle16", k, 1));
  rle[2].push_back(rle[2][0]);
  e = encapsulate(fixture("mf16.dcm"), syntax_of("rle16"), rle, Table::kNone);
  r = read({e.file});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status, "fragment item 3 is one more than Number of Frames (3)"))
      << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), e.item_at[3]);
  // No fragment at all.
  e = encapsulate(fixture("mf16.dcm"), syntax_of("rle16"), {}, Table::kNone);
  r = read({e.file});
  EXPECT_TRUE(has(r.status, "Pixel Data has 0 fragment items, 0 of them starting a frame, for 3"))
      << test::format(r.status);
  // The first fragment not a JPEG stream.
  e = mf16_as("jpeg70", 3, Table::kNone);
  e.file[e.item_at[0] + 9] = 0xD9;
  r = read({e.file});
  EXPECT_TRUE(has(r.status, "frame 0: its first fragment item does not begin with the SOI marker"))
      << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), e.item_at[0]);
  e = mf16_as("j2k16", 1, Table::kNone);
  e.file[e.item_at[0] + 9] = 0x51;
  r = read({e.file});
  EXPECT_TRUE(has(r.status, "does not begin with the SOC marker 0xFF4F")) << test::format(r.status);
}

TEST(CtDicomMultiFrameCodecs, LyingOffsetTables) {
  for (Table table : {Table::kBasic, Table::kExtended}) {
    const std::string name =
        table == Table::kBasic ? "Basic Offset Table" : "Extended Offset Table (7FE0,0001)";
    const size_t width = table == Table::kBasic ? 4 : 8;
    const Encapsulated good = mf16_as("jpeg70", 3, table);
    // Frame 1's entry 2 bytes into a fragment.
    Bytes b = good.file;
    test::put_le32(&b, good.table_at + width, get_u32(b, good.table_at + width) + 2);
    Read r = read({b});
    EXPECT_EQ(r.status.code(), StatusCode::kParseError);
    EXPECT_TRUE(has(r.status, "frame 1: its " + name + " entry is ")) << test::format(r.status);
    EXPECT_TRUE(has(r.status, "inside fragment item 3: a frame starts at a fragment item"))
        << test::format(r.status);
    EXPECT_EQ(r.status.byte_offset(), good.table_at + width);
    // Frame 0's entry not 0.
    b = good.file;
    test::put_le32(&b, good.table_at, 8);
    r = read({b});
    EXPECT_TRUE(has(r.status, "frame 0: its " + name + " entry is 8, not 0"))
        << test::format(r.status);
    EXPECT_EQ(r.status.byte_offset(), good.table_at);
    // Frame 2's entry past the end.
    b = good.file;
    test::put_le32(&b, good.table_at + 2 * width, 1u << 30);
    r = read({b});
    EXPECT_TRUE(has(r.status, "frame 2: its " + name +
                                  " entry is 1073741824 bytes, past the last "
                                  "fragment item (9 fragment items, 2 frames found)"))
        << test::format(r.status);
    EXPECT_EQ(r.status.byte_offset(), good.table_at + 2 * width);
  }
  // A basic offset table of two entries for three frames.
  Encapsulated e = mf16_as("jpeg70", 1, Table::kBasic);
  Bytes b = e.file;
  test::put_le32(&b, e.table_at - 4, 8);
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(e.table_at + 8),
          b.begin() + static_cast<std::ptrdiff_t>(e.table_at + 12));
  Read r = read({b});
  EXPECT_TRUE(has(r.status, "Basic Offset Table: has 2 entries for 3 frames (Number of Frames)"))
      << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), e.table_at - 8);
  // Both tables.
  e = mf16_as("jpeg70", 1, Table::kExtended);
  b = e.file;
  const size_t bot = test::find_bytes(b, test::dicom_tag(0x7FE0, 0x0010) + "OB") + 12;
  test::put_le32(&b, bot + 4, 12);
  b.insert(b.begin() + static_cast<std::ptrdiff_t>(bot + 8), 12, 0);
  r = read({b});
  EXPECT_TRUE(has(r.status, "frames and an Extended Offset Table (then it must be empty)"))
      << test::format(r.status);
  // An extended offset table of the wrong length.
  b = e.file;
  test::put_le32(&b, e.table_at - 4, 16);
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(e.table_at + 16),
          b.begin() + static_cast<std::ptrdiff_t>(e.table_at + 24));
  r = read({b});
  EXPECT_TRUE(has(r.status,
                  "(7FE0,0001) Extended Offset Table: has 16 bytes, 8 x Number of "
                  "Frames is 24"))
      << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), e.table_at - 12);
}

TEST(CtDicomMultiFrameCodecs, TruncatedAndCorruptFrames) {
  const Encapsulated e = mf16_as("jpeg70", 3, Table::kBasic);
  // Cut inside frame 2's second fragment.
  const size_t cut = e.item_at[7] + 20;
  Bytes b(e.file.begin(), e.file.begin() + static_cast<std::ptrdiff_t>(cut));
  Read r = read({b});
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated);
  EXPECT_TRUE(has(r.status, "frame 2 (fragment item 7 at byte " + std::to_string(e.item_at[7]) +
                                "): file ends inside a Pixel Data fragment"))
      << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), cut);
  // Frame 1's SOF3 precision 17: the decoder's error, at its byte in the file (known for the
  // first 32 fragments of a frame).
  for (int pieces : {3, 32, 33}) {
    const Encapsulated c = mf16_as("jpeg70", pieces, Table::kBasic);
    b = c.file;
    const size_t frame1 = c.item_at[c.frame_item[1]];
    size_t at = frame1 + 8;
    while (!(b[at] == 0xFF && b[at + 1] == 0xC3)) ++at;
    b[at + 4] = 17;
    r = read({b});
    EXPECT_NE(r.status.code(), StatusCode::kOk);
    EXPECT_TRUE(has(r.status, "frame 1 (of 3, " + std::to_string(pieces) +
                                  " fragment item(s) from byte " + std::to_string(frame1) + "): "))
        << test::format(r.status);
    EXPECT_EQ(r.status.index(), 1u);
    EXPECT_STREQ(r.status.file(), "m0.dcm");
    if (pieces <= 32) {
      EXPECT_EQ(r.status.byte_offset(), at) << test::format(r.status);
    } else {
      EXPECT_TRUE(has(r.status, "(byte offset in the concatenated fragments)"))
          << test::format(r.status);
    }
  }
  // The same error (named at the SOF3 marker) at the first byte of a fragment: frame 1 cut
  // just before the marker, which starts its second fragment.
  {
    Bytes whole = frame_fragments("jpeg70", 1, 1)[0];
    size_t p = 0;
    while (!(whole[p] == 0xFF && whole[p + 1] == 0xC3)) ++p;
    ASSERT_EQ(p % 2, 0u);
    whole[p + 4] = 17;
    const std::vector<std::vector<Bytes>> frames = {
        frame_fragments("jpeg70", 0, 1),
        {Bytes(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(p)),
         Bytes(whole.begin() + static_cast<std::ptrdiff_t>(p), whole.end())},
        frame_fragments("jpeg70", 2, 1)};
    const Encapsulated cut =
        encapsulate(fixture("mf16.dcm"), syntax_of("jpeg70"), frames, Table::kNone);
    r = read({cut.file});
    EXPECT_NE(r.status.code(), StatusCode::kOk);
    EXPECT_EQ(r.status.byte_offset(), cut.item_at[2] + 8) << test::format(r.status);
  }
  // A frame of absurdly many bytes.
  std::vector<std::vector<Bytes>> big = {
      {Bytes(130000, 0)}, frame_fragments("jpeg70", 1, 1), frame_fragments("jpeg70", 2, 1)};
  big[0][0][0] = 0xFF;
  big[0][0][1] = 0xD8;
  const Encapsulated huge =
      encapsulate(fixture("mf16.dcm"), syntax_of("jpeg70"), big, Table::kNone);
  r = read({huge.file});
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded);
  EXPECT_TRUE(has(r.status, "frame 0: its fragments hold more than 122880 bytes"))
      << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), huge.item_at[0]);
  // A fragment item of undefined length (frame 1's): refused as such, not read as a frame of
  // 2^32 - 1 bytes.
  Encapsulated undefined = mf16_as("rle16", 1, Table::kNone);
  test::put_le32(&undefined.file, undefined.item_at[1] + 4, 0xFFFFFFFFu);
  r = read({undefined.file});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status, "expected a fragment Item (FFFE,E000) of defined length"))
      << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), undefined.item_at[1]);
}

// A series of one file that is `first` when opened for its header (twice: a multi-frame file's
// frames are found, then checked) and `second` when opened for its pixels (a file changed
// between the passes), served without a name and without close() (both optional in CtSeries).
struct ChangingFile {
  ChangingFile(Bytes a, Bytes b, int from = 2)
      : first(std::move(a)), second(std::move(b)), changed_from(from) {}
  Bytes first, second;
  int changed_from;  // the first open that gives `second`
  int opens = 0;
  MemorySource state;
  static Status open(void* user, uint32_t, ByteSource* out) {
    ChangingFile& f = *static_cast<ChangingFile*>(user);
    const Bytes& b = f.opens++ < f.changed_from ? f.first : f.second;
    f.state = MemorySource{b.data(), b.size(), 0, 0};
    *out = memory_source(&f.state, nullptr);
    return Status::ok();
  }
};

Status read_changing(ChangingFile* f) {  // read_dicom_series of f
  test::TestArena t(4 << 20);
  Context ctx(&t.arena);
  CtSeries series;
  series.count = 1;
  series.open = &ChangingFile::open;
  series.user = f;
  CtReadOptions options;
  options.chunk_bytes = 1024;
  CtVolume volume;
  CtInfo info;
  return read_dicom_series(ctx, series, options, &volume, &info);
}

// What the second pass finds differs from the first: named, with the frame and the byte.
TEST(CtDicomMultiFrameCodecs, FileChangedBetweenThePasses) {
  const Encapsulated e = mf16_as("jpeg70", 1, Table::kBasic);
  ChangingFile same(e.file, e.file);
  SPLINTCORE_EXPECT_OK(read_changing(&same));
  EXPECT_EQ(same.opens, 3);  // the header twice (frames found, then checked), the pixels
  // Frame 0's fragment item is now the sequence's end.
  ChangingFile ended(e.file, e.file);
  const size_t item0 = e.item_at[0];
  const std::string delimiter = test::dicom_tag(0xFFFE, 0xE0DD);
  test::put_le32(&ended.second, item0 + 4, 0);
  std::copy(delimiter.begin(), delimiter.end(),
            ended.second.begin() + static_cast<std::ptrdiff_t>(item0));
  Status s = read_changing(&ended);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(s, "frame 0 (of 3, 1 fragment item(s) from byte " + std::to_string(item0) +
                         "): Pixel Data differs from the first read (file changed?)"))
      << test::format(s);
  EXPECT_EQ(s.byte_offset(), item0);
  // Frame 0's fragment two bytes longer (padding after its end of image): frame 1 is not where
  // the first pass found it.
  ChangingFile longer(e.file, e.file);
  const uint32_t length = get_u32(e.file, item0 + 4);
  test::put_le32(&longer.second, item0 + 4, length + 2);
  longer.second.insert(longer.second.begin() + static_cast<std::ptrdiff_t>(item0 + 8 + length), 2,
                       0);
  s = read_changing(&longer);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(s, "frame 1 (of 3, 1 fragment item(s) from byte " + std::to_string(e.item_at[1]) +
                         "): Pixel Data differs"))
      << test::format(s);
  EXPECT_EQ(s.byte_offset(), e.item_at[1] + 2);
  // The file now ends inside frame 1: the reader's error, in that frame.
  ChangingFile cut(e.file, Bytes(e.file.begin(),
                                 e.file.begin() + static_cast<std::ptrdiff_t>(e.item_at[1] + 20)));
  s = read_changing(&cut);
  EXPECT_EQ(s.code(), StatusCode::kTruncated);
  EXPECT_TRUE(has(s, "frame 1 (of 3,")) << test::format(s);
  // Other rows when the header is read the second time (the frames checked).
  ChangingFile rows(e.file, e.file, 1);
  const size_t at = test::find_bytes(e.file, test::dicom_tag(0x0028, 0x0010) + "US");
  ASSERT_NE(at, std::string::npos);
  rows.second[at + 8] = static_cast<uint8_t>(rows.second[at + 8] + 2);
  s = read_changing(&rows);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_EQ(std::string(s.message()), "the file changed between two reads");
  EXPECT_STREQ(s.file(), "?");
}

// ---- Tilted and uneven multi-frame, resampled ---------------------------------------------

// `file` with the n-th Image Position (Patient) set to `value` (lengths of undefined-length
// sequences need no update; with defined lengths, keep the length).
Bytes with_position(Bytes file, int n, std::string value) {
  EXPECT_TRUE(test::replace_short_value(&file, test::dicom_tag(0x0020, 0x0032) + "DS", n, value));
  return file;
}

// Frames stored in increasing position (mf16_rev's frames are raw16_2, raw16_0, raw16_1: given
// increasing positions, with a shear and uneven gaps): the same volume as the folder of the
// three slices placed there, read through the series' resampler.
TEST(CtDicomMultiFrameResample, AscendingFramesEqualTheirFolder) {
  Bytes mf = fixture("mf16_rev.dcm");
  mf = with_position(mf, 1, "-36.6\\-33\\-2.5");
  mf = with_position(mf, 2, "-35.7\\-33\\30");
  const Bytes s0 = with_position(fixture("raw16_0.dcm"), 0, "-36.6\\-33\\-2.5");
  const Bytes s1 = with_position(fixture("raw16_1.dcm"), 0, "-35.7\\-33\\30");
  const Read folder = read({s0, s1, fixture("raw16_2.dcm")});
  ASSERT_TRUE(folder.status.is_ok()) << test::format(folder.status);
  EXPECT_TRUE(folder.info.resampled);
  EXPECT_GT(folder.info.max_shift_mm, 0);
  EXPECT_GT(folder.info.max_slice_offset_mm, 0);
  const Read r = read({mf});
  expect_same_volume(r, folder);
  EXPECT_EQ(r.info.tilt_degrees, folder.info.tilt_degrees);
  EXPECT_EQ(r.info.max_shift_mm, folder.info.max_shift_mm);
  EXPECT_EQ(r.info.max_slice_offset_mm, folder.info.max_slice_offset_mm);
  // JPEG lossless frames in the same file.
  std::vector<std::vector<Bytes>> frames;
  for (int k : {2, 0, 1}) frames.push_back(frame_fragments("jpeg70", k, 2));
  expect_same_volume(read({encapsulate(mf, syntax_of("jpeg70"), frames, Table::kNone).file}),
                     folder);
}

// mf16 stores its frames in decreasing position: tilted (whole pixels: copies, no blend), it
// is read with the normal reversed. Its slices are the folder's in reverse order, axis_z the
// opposite, the origin at the folder's last slice.
TEST(CtDicomMultiFrameResample, DescendingFramesAreReadReversed) {
  Bytes mf = fixture("mf16.dcm");  // positions of equal length: defined lengths stay right
  mf = with_position(mf, 1, "-36.6\\-33\\-2.5");
  mf = with_position(mf, 2, "-35.4\\-33\\-27.5");
  const Bytes s1 = with_position(fixture("raw16_1.dcm"), 0, "-36.6\\-33\\-2.5");
  const Bytes s2 = with_position(fixture("raw16_2.dcm"), 0, "-35.4\\-33\\-27.5");
  const Read folder = read({fixture("raw16_0.dcm"), s1, s2});
  ASSERT_TRUE(folder.status.is_ok()) << test::format(folder.status);
  ASSERT_TRUE(folder.info.resampled);
  for (const Bytes& file : {mf, mf16_as("j2k16", 2, Table::kExtended, mf).file}) {
    const Read r = read({file});
    ASSERT_TRUE(r.status.is_ok()) << test::format(r.status);
    EXPECT_TRUE(r.info.resampled);
    ASSERT_EQ(r.volume.nz, folder.volume.nz);
    const size_t n = size_t{r.volume.nx} * r.volume.ny;
    for (uint32_t k = 0; k < r.volume.nz; ++k) {
      const size_t other = r.volume.nz - 1 - k;
      EXPECT_TRUE(std::equal(r.hu.begin() + k * n, r.hu.begin() + (k + 1) * n,
                             folder.hu.begin() + other * n))
          << "slice " << k;
    }
    const double last = (r.volume.nz - 1) * folder.volume.spacing.z;
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(r.volume.axis_z[c], -folder.volume.axis_z[c]) << c;
      EXPECT_NEAR(r.volume.origin[c], folder.volume.origin[c] + folder.volume.axis_z[c] * last,
                  1e-9)
          << c;
    }
    EXPECT_NEAR(r.volume.spacing.z, folder.volume.spacing.z, 1e-12);
    EXPECT_NEAR(r.info.tilt_degrees, folder.info.tilt_degrees, 1e-9);
  }
}

TEST(CtDicomMultiFrameResample, FramesOutOfSliceOrderAreRefused) {
  // mf16_rev (frames 2, 0, 1) tilted.
  const Bytes mf = with_position(fixture("mf16_rev.dcm"), 1, "-36.6\\-33\\22.5");
  const Read r = read({mf});
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_TRUE(has(r.status,
                  "must store its frames in slice order, ascending or descending; "
                  "frame 2 is slice 1 of 3"))
      << test::format(r.status);
  EXPECT_EQ(r.status.index(), 2u);
  EXPECT_STREQ(r.status.file(), "m0.dcm");
}

// Frames out of slice order in a file without a name: refused, naming the frame.
TEST(CtDicomMultiFrameResample, FramesOutOfOrderInAFileWithoutAName) {
  const Bytes mf = with_position(fixture("mf16_rev.dcm"), 1, "-36.6\\-33\\22.5");
  ChangingFile unnamed(mf, mf);
  const Status s = read_changing(&unnamed);
  EXPECT_EQ(s.code(), StatusCode::kUnsupported);
  EXPECT_EQ(s.index(), 2u);
  EXPECT_STREQ(s.file(), "");
}

}  // namespace
}  // namespace splintcore
