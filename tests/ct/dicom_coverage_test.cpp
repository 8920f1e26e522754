// Branches of the DICOM series reader (src/ct/ct_dicom.cpp) that the CT reader tests do not
// reach (issue 9: >= 95% branch coverage of the parsers, measured by tools/coverage.sh): every
// element-level error (VRs, lengths, delimiters, nesting), every header check, every way a
// slice can differ from the first, and series whose files lose their names, have no close(),
// or change between the header pass and the pixel pass. The builder below writes the files
// element by element (explicit or implicit VR little endian).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <new>
#include <string>
#include <vector>

#include "splintcore/ct.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

constexpr uint32_t tag(uint32_t g, uint32_t e) { return (g << 16) | e; }

// One element: `raw` bytes are appended as they are (hand-made headers, delimiters).
struct El {
  uint32_t tag = 0;
  std::string vr;
  std::vector<uint8_t> value;
  bool raw = false;
};

std::vector<uint8_t> text(const std::string& s) { return std::vector<uint8_t>(s.begin(), s.end()); }
std::vector<uint8_t> us(uint32_t v) {
  return {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)};
}
std::vector<uint8_t> pixels16(int count, int first) {
  std::vector<uint8_t> out;
  for (int i = 0; i < count; ++i) {
    const uint32_t v = static_cast<uint32_t>(first + i);
    out.push_back(static_cast<uint8_t>(v));
    out.push_back(static_cast<uint8_t>(v >> 8));
  }
  return out;
}

struct Bytes {
  std::vector<uint8_t> b;
  void u16(uint32_t v) {
    b.push_back(static_cast<uint8_t>(v));
    b.push_back(static_cast<uint8_t>(v >> 8));
  }
  void u32(uint32_t v) {
    u16(v & 0xFFFF);
    u16(v >> 16);
  }
  void element(const El& e, bool implicit) {
    if (e.raw) {
      b.insert(b.end(), e.value.begin(), e.value.end());
      return;
    }
    std::vector<uint8_t> v = e.value;
    if (v.size() % 2 == 1) v.push_back(e.vr == "UI" || e.vr == "OB" ? 0 : ' ');
    u16(e.tag >> 16);
    u16(e.tag & 0xFFFF);
    if (implicit) {
      u32(static_cast<uint32_t>(v.size()));
    } else {
      b.push_back(static_cast<uint8_t>(e.vr[0]));
      b.push_back(static_cast<uint8_t>(e.vr[1]));
      if (e.vr == "OB" || e.vr == "OW" || e.vr == "SQ" || e.vr == "UN" || e.vr == "UT") {
        u16(0);
        u32(static_cast<uint32_t>(v.size()));
      } else {
        u16(static_cast<uint32_t>(v.size()));
      }
    }
    b.insert(b.end(), v.begin(), v.end());
  }
};

// Raw bytes: a tag with a 32-bit length (implicit VR, or a delimiter).
std::vector<uint8_t> tag_length(uint32_t t, uint32_t length) {
  Bytes w;
  w.u16(t >> 16);
  w.u16(t & 0xFFFF);
  w.u32(length);
  return w.b;
}
// Raw bytes: an explicit long-VR header (OB, SQ, UN ...) with a 32-bit length.
std::vector<uint8_t> long_header(uint32_t t, const char* vr, uint32_t length) {
  Bytes w;
  w.u16(t >> 16);
  w.u16(t & 0xFFFF);
  w.b.push_back(static_cast<uint8_t>(vr[0]));
  w.b.push_back(static_cast<uint8_t>(vr[1]));
  w.u16(0);
  w.u32(length);
  return w.b;
}

// A valid slice at z: 2 x 3 signed 16-bit pixels, thickness 1 (elements in tag order).
std::vector<El> slice(double z, int first_pixel = 0) {
  return {{tag(0x0008, 0x0050), "SH", text("ACC1")},
          {tag(0x0018, 0x0050), "DS", text("1")},
          {tag(0x0020, 0x0032), "DS", text("0\\0\\" + std::to_string(z))},
          {tag(0x0020, 0x0037), "DS", text("1\\0\\0\\0\\1\\0")},
          {tag(0x0028, 0x0002), "US", us(1)},
          {tag(0x0028, 0x0004), "CS", text("MONOCHROME2")},
          {tag(0x0028, 0x0010), "US", us(2)},
          {tag(0x0028, 0x0011), "US", us(3)},
          {tag(0x0028, 0x0030), "DS", text("0.5\\0.25")},
          {tag(0x0028, 0x0100), "US", us(16)},
          {tag(0x0028, 0x0101), "US", us(16)},
          {tag(0x0028, 0x0103), "US", us(1)},
          {tag(0x7FE0, 0x0010), "OW", pixels16(6, first_pixel)}};
}

// Replaces the element with `e.tag` (or inserts it in tag order; raw elements go before it).
void put(std::vector<El>* els, const El& e) {
  for (El& x : *els) {
    if (!x.raw && x.tag == e.tag && !e.raw) {
      x = e;
      return;
    }
  }
  size_t at = 0;
  while (at < els->size() && ((*els)[at].raw || (*els)[at].tag < e.tag)) ++at;
  els->insert(els->begin() + static_cast<std::ptrdiff_t>(at), e);
}
void drop(std::vector<El>* els, uint32_t t) {
  for (size_t i = 0; i < els->size(); ++i) {
    if (!(*els)[i].raw && (*els)[i].tag == t) {
      els->erase(els->begin() + static_cast<std::ptrdiff_t>(i));
      return;
    }
  }
}
// Raw bytes placed just before the element `before`.
void raw_before(std::vector<El>* els, uint32_t before, const std::vector<uint8_t>& bytes) {
  for (size_t i = 0; i < els->size(); ++i) {
    if (!(*els)[i].raw && (*els)[i].tag == before) {
      El r;
      r.raw = true;
      r.value = bytes;
      els->insert(els->begin() + static_cast<std::ptrdiff_t>(i), r);
      return;
    }
  }
  ADD_FAILURE() << "no element to put raw bytes before";
}

// The file: preamble, "DICM", meta (explicit), the data set. `meta` replaces the meta group.
std::vector<uint8_t> file(const std::vector<El>& els, bool implicit = false,
                          const std::vector<uint8_t>* meta = nullptr) {
  Bytes w;
  w.b.assign(128, 0);
  w.b.insert(w.b.end(), {'D', 'I', 'C', 'M'});
  if (meta != nullptr) {
    w.b.insert(w.b.end(), meta->begin(), meta->end());
  } else {
    w.element({tag(0x0002, 0x0001), "OB", {0, 1}}, false);
    w.element(
        {tag(0x0002, 0x0010), "UI", text(implicit ? "1.2.840.10008.1.2" : "1.2.840.10008.1.2.1")},
        false);
  }
  for (const El& e : els) w.element(e, implicit);
  return w.b;
}

// A series over files in memory, with the odd behaviours of a real source: names that are
// null, no close(), sizes unknown or lying, and files that change after the header pass.
struct Series {
  std::vector<std::vector<uint8_t>> files;
  std::vector<std::vector<uint8_t>> second;  // what a second open of file i gives, when set
  bool null_names = false;
  bool unknown_size = false;
  uint64_t lying_size = 0;
  std::vector<int> opens;
  std::vector<std::string> names;
  MemorySource current{};
  static Status open(void* user, uint32_t index, ByteSource* out) {
    Series* s = static_cast<Series*>(user);
    if (index >= s->files.size()) return Status::error(StatusCode::kIoError, "no such file");
    s->opens.resize(s->files.size());
    const bool again = s->opens[index]++ > 0;
    const std::vector<uint8_t>& f = again && index < s->second.size() && !s->second[index].empty()
                                        ? s->second[index]
                                        : s->files[index];
    s->current = MemorySource{f.data(), f.size(), 0, 0};
    *out = memory_source(&s->current, s->null_names ? nullptr : s->names[index].c_str());
    out->name = s->null_names ? nullptr : s->names[index].c_str();
    if (s->unknown_size) out->size = kUnknownSize;
    if (s->lying_size != 0) out->size = s->lying_size;
    return Status::ok();
  }
  static void close(void* user, uint32_t, ByteSource*) {
    static_cast<Series*>(user)->current = MemorySource{};
  }
};

struct SeriesRead {
  Status status;
  CtVolume volume;
  CtInfo info;
};

SeriesRead read(Series& s, bool with_close = true, CtReadOptions options = CtReadOptions{},
                Arena* arena = nullptr) {
  static test::TestArena* shared = new test::TestArena(size_t{4} << 20);
  Arena& a = arena != nullptr ? *arena : shared->arena;
  if (arena == nullptr) a.reset();
  const size_t used = a.used();
  s.names.clear();
  for (size_t i = 0; i < s.files.size(); ++i) s.names.push_back("f" + std::to_string(i) + ".dcm");
  s.opens.assign(s.files.size(), 0);
  CtSeries series;
  series.count = static_cast<uint32_t>(s.files.size());
  series.open = &Series::open;
  series.close = with_close ? &Series::close : nullptr;
  series.user = &s;
  SeriesRead r;
  r.status = read_dicom_series(Context(&a), series, options, &r.volume, &r.info);
  if (!r.status.is_ok()) {
    EXPECT_EQ(a.used(), used) << "a failed read left memory in the arena";
  }
  return r;
}

SeriesRead read_one(const std::vector<uint8_t>& f, CtReadOptions options = CtReadOptions{}) {
  Series s;
  s.files = {f};
  return read(s, true, options);
}

bool has(const Status& s, const char* fragment) {
  return std::strstr(s.message(), fragment) != nullptr;
}

struct FileCase {
  const char* name;
  std::vector<uint8_t> bytes;
  StatusCode code;
  const char* fragment;
};

void expect_files(const std::vector<FileCase>& cases) {
  for (const FileCase& c : cases) {
    SCOPED_TRACE(c.name);
    SeriesRead r = read_one(c.bytes);
    EXPECT_EQ(r.status.code(), c.code) << test::format(r.status);
    EXPECT_TRUE(has(r.status, c.fragment)) << test::format(r.status);
    EXPECT_STREQ(r.status.file(), "f0.dcm");
    EXPECT_EQ(r.status.index(), 0u);
  }
}

std::vector<uint8_t> with(const std::function<void(std::vector<El>*)>& edit) {
  std::vector<El> els = slice(0);
  edit(&els);
  return file(els);
}

TEST(DicomCoverage, ElementsAndContainers) {
  const uint32_t kRows = tag(0x0028, 0x0010);
  const uint32_t kPhotometric = tag(0x0028, 0x0004);
  std::vector<uint8_t> meta_undefined = long_header(tag(0x0002, 0x0001), "OB", 0xFFFFFFFFu);
  Bytes long_syntax;
  long_syntax.element({tag(0x0002, 0x0010), "UI", text(std::string(70, '1'))}, false);
  std::vector<uint8_t> deep;
  for (int d = 0; d < 32; ++d) {
    const std::vector<uint8_t> sq = long_header(tag(0x0008, 0x1140), "SQ", 0xFFFFFFFFu);
    deep.insert(deep.end(), sq.begin(), sq.end());
  }
  std::vector<uint8_t> deep_item = deep;
  const std::vector<uint8_t> item = tag_length(tag(0xFFFE, 0xE000), 0xFFFFFFFFu);
  deep_item.insert(deep_item.end(), item.begin(), item.end());
  std::vector<uint8_t> item_in_item = long_header(tag(0x0008, 0x1140), "SQ", 0xFFFFFFFFu);
  item_in_item.insert(item_in_item.end(), item.begin(), item.end());
  item_in_item.insert(item_in_item.end(), item.begin(), item.end());
  std::vector<uint8_t> item_end_in_sequence = long_header(tag(0x0008, 0x1140), "SQ", 0xFFFFFFFFu);
  const std::vector<uint8_t> item_end = tag_length(tag(0xFFFE, 0xE00D), 0);
  item_end_in_sequence.insert(item_end_in_sequence.end(), item_end.begin(), item_end.end());
  std::vector<uint8_t> sequence_end_in_item = long_header(tag(0x0008, 0x1140), "SQ", 0xFFFFFFFFu);
  sequence_end_in_item.insert(sequence_end_in_item.end(), item.begin(), item.end());
  const std::vector<uint8_t> sequence_end = tag_length(tag(0xFFFE, 0xE0DD), 0);
  sequence_end_in_item.insert(sequence_end_in_item.end(), sequence_end.begin(), sequence_end.end());
  auto bad_vr = [&](const char* vr) {
    Bytes w;
    w.u16(0x0008);
    w.u16(0x0060);
    w.b.push_back(static_cast<uint8_t>(vr[0]));
    w.b.push_back(static_cast<uint8_t>(vr[1]));
    w.u16(2);
    w.b.push_back('C');
    w.b.push_back('T');
    return with([&](std::vector<El>* e) { raw_before(e, kRows, w.b); });
  };
  Bytes syntax64;  // the longest UID (PS3.5 9.1): read, then refused by name
  syntax64.element({tag(0x0002, 0x0010), "UI", text("1.2." + std::string(60, '3'))}, false);
  const std::string syntax64_message = "unsupported transfer syntax 1.2." + std::string(60, '3');
  std::vector<uint8_t> long_value = long_header(kPhotometric, "UT", 300);
  long_value.resize(long_value.size() + 300, 'M');
  std::vector<uint8_t> value256 = long_header(kPhotometric, "UT", 256);  // the most kept
  value256.resize(value256.size() + 256, 'M');
  const std::vector<FileCase> cases = {
      {"meta element of undefined length", file(slice(0), false, &meta_undefined),
       StatusCode::kParseError, "undefined length"},
      {"transfer syntax too long", file(slice(0), false, &long_syntax.b), StatusCode::kParseError,
       "Transfer Syntax UID: too long"},
      {"transfer syntax of 64 characters", file(slice(0), false, &syntax64.b),
       StatusCode::kUnsupported, syntax64_message.c_str()},
      {"item outside a sequence", with([&](std::vector<El>* e) { raw_before(e, kRows, item); }),
       StatusCode::kParseError, "Item: outside a sequence"},
      {"item in an item", with([&](std::vector<El>* e) { raw_before(e, kRows, item_in_item); }),
       StatusCode::kParseError, "Item: outside a sequence"},
      {"items nested too deeply",
       with([&](std::vector<El>* e) { raw_before(e, kRows, deep_item); }),
       StatusCode::kLimitExceeded, "Item: nested too deeply"},
      {"sequences nested too deeply", with([&](std::vector<El>* e) {
         std::vector<uint8_t> more = deep;
         const std::vector<uint8_t> sq = long_header(tag(0x0008, 0x1140), "SQ", 0xFFFFFFFFu);
         more.insert(more.end(), sq.begin(), sq.end());
         raw_before(e, kRows, more);
       }),
       StatusCode::kLimitExceeded, "Sequence: nested too deeply"},
      {"item end at the top", with([&](std::vector<El>* e) { raw_before(e, kRows, item_end); }),
       StatusCode::kParseError, "Item Delimitation: outside an item of undefined length"},
      {"item end in a sequence",
       with([&](std::vector<El>* e) { raw_before(e, kRows, item_end_in_sequence); }),
       StatusCode::kParseError, "Item Delimitation: outside an item"},
      {"sequence end at the top",
       with([&](std::vector<El>* e) { raw_before(e, kRows, sequence_end); }),
       StatusCode::kParseError, "Sequence Delimitation: outside a sequence of undefined length"},
      {"sequence end in an item",
       with([&](std::vector<El>* e) { raw_before(e, kRows, sequence_end_in_item); }),
       StatusCode::kParseError, "Sequence Delimitation: outside a sequence"},
      {"unknown delimiter",
       with([&](std::vector<El>* e) { raw_before(e, kRows, tag_length(tag(0xFFFE, 0xE0AA), 0)); }),
       StatusCode::kParseError, "unknown delimiter tag"},
      {"VR first byte low", bad_vr("\x01S"), StatusCode::kParseError, "invalid VR"},
      {"VR first byte high", bad_vr("aS"), StatusCode::kParseError, "invalid VR"},
      {"VR second byte low", bad_vr("S\x01"), StatusCode::kParseError, "invalid VR"},
      {"VR second byte high", bad_vr("Sh"), StatusCode::kParseError, "invalid VR"},
      {"VR first byte just below A", bad_vr("@S"), StatusCode::kParseError, "invalid VR"},
      {"VR first byte just above Z", bad_vr("[S"), StatusCode::kParseError, "invalid VR"},
      {"VR second byte just below A", bad_vr("S@"), StatusCode::kParseError, "invalid VR"},
      {"VR second byte just above Z", bad_vr("S["), StatusCode::kParseError, "invalid VR"},
      {"undefined length OB", with([&](std::vector<El>* e) {
         raw_before(e, kRows, long_header(tag(0x0009, 0x0010), "OB", 0xFFFFFFFFu));
       }),
       StatusCode::kParseError, "undefined length on a VR other than SQ or UN"},
      // UT and SV share a letter with UN and SQ.
      {"undefined length UT", with([&](std::vector<El>* e) {
         raw_before(e, kRows, long_header(tag(0x0009, 0x0010), "UT", 0xFFFFFFFFu));
       }),
       StatusCode::kParseError, "undefined length on a VR other than SQ or UN"},
      {"undefined length SV", with([&](std::vector<El>* e) {
         raw_before(e, kRows, long_header(tag(0x0009, 0x0010), "SV", 0xFFFFFFFFu));
       }),
       StatusCode::kParseError, "undefined length on a VR other than SQ or UN"},
      // The data set is one 8-byte element (empty) at the end of the file.
      {"one empty element", file({{tag(0x0008, 0x0050), "SH", {}}}), StatusCode::kParseError,
       "no (7FE0,0010) Pixel Data in the file"},
      {"kept value too long", with([&](std::vector<El>* e) {
         drop(e, kPhotometric);
         raw_before(e, kRows, long_value);
       }),
       StatusCode::kParseError, "value of 300 bytes is too long"},
      {"kept value of 256 bytes", with([&](std::vector<El>* e) {
         drop(e, kPhotometric);
         raw_before(e, kRows, value256);
       }),
       StatusCode::kUnsupported, "Photometric Interpretation MMMMMMMMMMMMMMMM: only"},
      {"Rows of 4 bytes", with([&](std::vector<El>* e) {
         put(e, {kRows, "UL", {2, 0, 0, 0}});
       }),
       StatusCode::kParseError, "(0028,0010) Rows: expected 2 bytes (US)"},
      {"position not numbers", with([&](std::vector<El>* e) {
         put(e, {tag(0x0020, 0x0032), "DS", text("a\\b\\c")});
       }),
       StatusCode::kParseError, "expected 3 decimal number(s), got \"a\\b\\c"},
      {"position long and short", with([&](std::vector<El>* e) {
         put(e, {tag(0x0020, 0x0032), "DS", text("1\\2\\3\\" + std::string(70, '4'))});
       }),
       StatusCode::kParseError, "expected 3 decimal number(s)"},
      {"frames not a number", with([&](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0008), "IS", text("x")});
       }),
       StatusCode::kParseError, "Number of Frames: not an integer"},
  };
  expect_files(cases);
  // The long value is cut to 64 characters in the message.
  SeriesRead r = read_one(with([&](std::vector<El>* e) {
    put(e, {tag(0x0020, 0x0032), "DS", text("1\\2\\3\\" + std::string(70, '4'))});
  }));
  EXPECT_FALSE(has(r.status, std::string(61, '4').c_str())) << r.status.message();
  EXPECT_TRUE(has(r.status, std::string(58, '4').c_str())) << r.status.message();
}

TEST(DicomCoverage, HeaderChecks) {
  const uint32_t kRows = tag(0x0028, 0x0010), kColumns = tag(0x0028, 0x0011);
  const std::vector<FileCase> cases = {
      {"long photometric", with([](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0004), "CS", text("MONOCHROME2_AND_MORE_TEXT")});
       }),
       StatusCode::kUnsupported, "Photometric Interpretation MONOCHROME2_AND_: only"},
      {"photometric one over", with([](std::vector<El>* e) {  // 17 characters: 16 kept
         put(e, {tag(0x0028, 0x0004), "CS", text("MONOCHROME2_AND_M")});
       }),
       StatusCode::kUnsupported, "Photometric Interpretation MONOCHROME2_AND_: only"},
      {"no rows", with([&](std::vector<El>* e) {
         put(e, {kRows, "US", us(0)});
         put(e, {tag(0x7FE0, 0x0010), "OW", {}});
       }),
       StatusCode::kParseError, "image of 0 rows and 3 columns is empty"},
      {"no columns", with([&](std::vector<El>* e) {
         put(e, {kColumns, "US", us(0)});
         put(e, {tag(0x7FE0, 0x0010), "OW", {}});
       }),
       StatusCode::kParseError, "image of 2 rows and 0 columns is empty"},
      {"two samples", with([](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0002), "US", us(2)});
       }),
       StatusCode::kUnsupported, "Samples per Pixel is 2"},
      {"bits stored 0", with([](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0101), "US", us(0)});
       }),
       StatusCode::kParseError, "Bits Stored is 0 with Bits Allocated 16"},
      {"bits stored 17", with([](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0101), "US", us(17)});
       }),
       StatusCode::kParseError, "Bits Stored is 17 with Bits Allocated 16"},
      {"high bit", with([](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0102), "US", us(11)});
       }),
       StatusCode::kUnsupported, "High Bit is 11: only Bits Stored - 1"},
      {"pixel representation 2", with([](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0103), "US", us(2)});
       }),
       StatusCode::kParseError, "Pixel Representation is 2"},
      {"slope 0", with([](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x1053), "DS", text("0")});
       }),
       StatusCode::kParseError, "Rescale Slope is 0: must be finite and non-zero"},
      // A scout (localizer) says what it is, whatever else it has or lacks.
      {"scout", with([](std::vector<El>* e) {
         put(e, {tag(0x0008, 0x0008), "CS", text("ORIGINAL\\PRIMARY\\LOCALIZER ")});
         drop(e, tag(0x0020, 0x0032));
       }),
       StatusCode::kUnsupported,
       "a localizer (scout) image (Image Type ORIGINAL\\PRIMARY\\LOCALIZER), not a slice"},
      // A multi-frame file without the per-frame functional groups of an enhanced image (its
      // frame positions): named as such, not as a file missing its Image Position.
      {"multi-frame", with([](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0008), "IS", text("120")});
         drop(e, tag(0x0020, 0x0032));
       }),
       StatusCode::kUnsupported,
       "Number of Frames is 120 but there is no (5200,9230) Per-frame Functional Groups "
       "Sequence"},
  };
  expect_files(cases);
  // A truncated Pixel Data; a source that does not know its size (the same file is fine).
  std::vector<uint8_t> cut = file(slice(0));
  cut.resize(cut.size() - 3);
  SeriesRead r = read_one(cut);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated);
  EXPECT_TRUE(has(r.status, "file ends inside Pixel Data (12 bytes from byte"))
      << r.status.message();
  Series unknown;
  unknown.files = {file(slice(0))};
  unknown.unknown_size = true;
  r = read(unknown);
  SPLINTCORE_EXPECT_OK(r.status);
  Series lying;
  lying.files = {file(slice(0))};
  lying.lying_size = 20;  // less than the header already read
  r = read(lying);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated);
  EXPECT_EQ(r.status.byte_offset(), 20u);
}

TEST(DicomCoverage, AcceptedVariants) {
  // 8-bit pixels with an odd count (padded Pixel Data), no Bits Stored, an SQ-encoded kept tag
  // skipped, empty and bad Slice Thickness and Spacing Between Slices (ignored), then a valid
  // Spacing Between Slices for the single slice's z spacing, High Bit matching.
  std::vector<El> els = slice(0);
  put(&els, {tag(0x0028, 0x0010), "US", us(1)});
  put(&els, {tag(0x0028, 0x0100), "US", us(8)});
  drop(&els, tag(0x0028, 0x0101));
  put(&els, {tag(0x0028, 0x0102), "US", us(7)});
  put(&els, {tag(0x0028, 0x0103), "US", us(0)});
  put(&els, {tag(0x7FE0, 0x0010), "OB", {5, 6, 7}});
  put(&els, {tag(0x0018, 0x0050), "DS", text("x")});
  put(&els, {tag(0x0018, 0x0088), "DS", text("2.5")});
  raw_before(&els, tag(0x0020, 0x0032), long_header(tag(0x0028, 0x0008), "SQ", 0));
  SeriesRead r = read_one(file(els));
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(r.volume.nx, 3u);
  EXPECT_EQ(r.volume.ny, 1u);
  EXPECT_EQ(r.volume.spacing.z, 2.5);
  EXPECT_EQ(r.volume.hu[2], 7);
  // Empty thickness and spacing values: the single slice has no z spacing.
  els = slice(0);
  put(&els, {tag(0x0018, 0x0050), "DS", {}});
  put(&els, {tag(0x0018, 0x0088), "DS", {}});
  r = read_one(file(els));
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_TRUE(has(r.status, "a single slice needs")) << r.status.message();
  put(&els, {tag(0x0018, 0x0088), "DS", text("y")});
  r = read_one(file(els));
  EXPECT_TRUE(has(r.status, "a single slice needs")) << r.status.message();
  // Image types of axial slices (LOCALIZER only as a whole value marks a scout; an empty
  // value and NUL padding are fine).
  const std::string types[] = {"ORIGINAL\\PRIMARY\\AXIAL", "DERIVED\\SECONDARY\\LOCALIZERX", "",
                               std::string("ORIGINAL\\PRIMARY\\AXIAL\0", 24)};
  for (const std::string& type : types) {
    els = slice(0);
    put(&els, {tag(0x0018, 0x0088), "DS", text("2.5")});
    put(&els, {tag(0x0008, 0x0008), "CS", text(type)});
    r = read_one(file(els));
    EXPECT_TRUE(r.status.is_ok()) << type << ": " << r.status.message();
  }
  // One frame (Number of Frames 1) with an Extended Offset Table of two entries: not read (a
  // single frame is all of Pixel Data), so its length is not checked either.
  els = slice(0);
  put(&els, {tag(0x0028, 0x0008), "IS", text("1")});
  std::vector<uint8_t> table = long_header(tag(0x7FE0, 0x0001), "OV", 16);
  table.resize(table.size() + 16, 0);
  raw_before(&els, tag(0x7FE0, 0x0010), table);
  r = read_one(file(els));
  SPLINTCORE_EXPECT_OK(r.status);
  // VRs at the ends of A-Z: AE and DA, and ZZ (not in PS3.5, read as a short VR), skipped.
  els = slice(0);
  put(&els, {tag(0x0008, 0x0020), "DA", text("20261207")});
  put(&els, {tag(0x0008, 0x0054), "AE", text("SCANNER")});
  put(&els, {tag(0x0009, 0x0010), "ZZ", text("AB")});
  r = read_one(file(els));
  SPLINTCORE_EXPECT_OK(r.status);
  // The header limit: Pixel Data starting at exactly max_header_bytes is read, one byte later
  // is not.
  const std::vector<uint8_t> bytes = file(slice(0));
  const uint8_t pixel_tag[4] = {0xE0, 0x7F, 0x10, 0x00};
  const uint64_t pixel_at = static_cast<uint64_t>(
      std::search(bytes.begin(), bytes.end(), pixel_tag, pixel_tag + 4) - bytes.begin());
  CtReadOptions small;
  small.max_header_bytes = pixel_at;
  r = read_one(bytes, small);
  SPLINTCORE_EXPECT_OK(r.status);
  small.max_header_bytes = pixel_at - 1;
  r = read_one(bytes, small);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded);
  EXPECT_TRUE(
      has(r.status,
          ("no Pixel Data within the first " + std::to_string(pixel_at - 1) + " bytes").c_str()))
      << r.status.message();
  EXPECT_EQ(r.status.byte_offset(), pixel_at);
}

TEST(DicomCoverage, SeriesArguments) {
  CtSeries none;
  none.count = 2;
  test::TestArena t(1 << 20);
  CtVolume v;
  Status s = read_dicom_series(Context(&t.arena), none, CtReadOptions{}, &v, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_STREQ(s.message(), "the DICOM series has no files");
  Series two;
  two.files = {file(slice(0)), file(slice(1))};
  CtReadOptions one;
  one.max_dimension = 1;
  SeriesRead r = read(two, true, one);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded);
  EXPECT_TRUE(has(r.status, "the series has 2 files, more than the limit 1")) << r.status.message();
}

TEST(DicomCoverage, SlicesThatDiffer) {
  struct Differ {
    const char* name;
    std::function<void(std::vector<El>*)> edit;
    const char* what;
  };
  const std::vector<Differ> cases = {
      {"rows",
       [](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0010), "US", us(1)});
         put(e, {tag(0x7FE0, 0x0010), "OW", pixels16(3, 0)});
       },
       "image size"},
      {"columns",
       [](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0011), "US", us(1)});
         put(e, {tag(0x7FE0, 0x0010), "OW", pixels16(2, 0)});
       },
       "image size"},
      {"bits allocated",
       [](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0100), "US", us(8)});
         put(e, {tag(0x0028, 0x0101), "US", us(8)});
         put(e, {tag(0x7FE0, 0x0010), "OB", std::vector<uint8_t>(6, 1)});
       },
       "pixel format"},
      {"bits stored",
       [](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0101), "US", us(12)});
       },
       "pixel format"},
      {"bits stored absent",
       [](std::vector<El>* e) {
         drop(e, tag(0x0028, 0x0101));
         put(e, {tag(0x0028, 0x0100), "US", us(16)});
       },
       ""},  // absent means Bits Allocated: the same format
      {"representation",
       [](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0103), "US", us(0)});
       },
       "pixel format"},
      {"row spacing",
       [](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x0030), "DS", text("0.6\\0.25")});
       },
       "Pixel Spacing"},
      {"orientation",
       [](std::vector<El>* e) {
         put(e, {tag(0x0020, 0x0037), "DS", text("0\\1\\0\\1\\0\\0")});
       },
       "Image Orientation (Patient)"},
      {"slope",
       [](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x1053), "DS", text("2")});
       },
       ""},
      {"intercept",
       [](std::vector<El>* e) {
         put(e, {tag(0x0028, 0x1052), "DS", text("-1000")});
       },
       ""},
  };
  for (const Differ& c : cases) {
    SCOPED_TRACE(c.name);
    std::vector<El> second = slice(1, 100);
    c.edit(&second);
    Series s;
    s.files = {file(slice(0)), file(second)};
    SeriesRead r = read(s);
    if (c.what[0] == '\0') {
      SPLINTCORE_EXPECT_OK(r.status);
      continue;
    }
    EXPECT_EQ(r.status.code(), StatusCode::kUnsupported) << test::format(r.status);
    EXPECT_TRUE(has(r.status, "slice differs from the series' file 0 (f0.dcm) in its "))
        << r.status.message();
    EXPECT_TRUE(has(r.status, c.what)) << r.status.message();
    EXPECT_STREQ(r.status.file(), "f1.dcm");
    EXPECT_EQ(r.status.index(), 1u);
  }
  // A wide absolute tolerance for the in-plane drift of positions.
  CtReadOptions loose;
  loose.slice_spacing_tolerance_mm = 5;
  Series three;
  three.files = {file(slice(0)), file(slice(1)), file(slice(2))};
  SeriesRead r = read(three, true, loose);
  SPLINTCORE_EXPECT_OK(r.status);
  EXPECT_EQ(r.volume.nz, 3u);
}

TEST(DicomCoverage, SourcesWithoutNamesOrClose) {
  // The same errors from a series whose sources have no names, and without close().
  std::vector<El> skew = slice(0);
  put(&skew, {tag(0x0020, 0x0037), "DS", text("1\\0\\0\\0.6\\0.8\\0")});
  std::vector<El> other = slice(1);
  put(&other, {tag(0x0028, 0x0030), "DS", text("0.5\\0.3")});
  std::vector<El> thin = slice(0);
  drop(&thin, tag(0x0018, 0x0050));
  std::vector<El> wide = slice(0);
  put(&wide, {tag(0x0028, 0x0030), "DS", text("500\\500")});
  const std::vector<std::vector<std::vector<uint8_t>>> series = {{file(skew)},
                                                                 {file(slice(0)), file(other)},
                                                                 {file(thin)},
                                                                 {file(wide)},
                                                                 {file(slice(0), true)}};
  const char* fragments[] = {"orthogonal", "in its Pixel Spacing", "a single slice needs",
                             "wrong units?", "orthogonal"};
  for (size_t i = 0; i < series.size(); ++i) {
    SCOPED_TRACE(i);
    Series s;
    s.files = series[i];
    s.null_names = true;
    if (i == 4) {  // an implicit-VR file that is fine: the read succeeds without close()
      SeriesRead r = read(s, false);
      SPLINTCORE_EXPECT_OK(r.status);
      continue;
    }
    SeriesRead r = read(s, false);
    EXPECT_FALSE(r.status.is_ok());
    EXPECT_TRUE(has(r.status, fragments[i])) << r.status.message();
    EXPECT_STREQ(r.status.file(), "");
    if (i == 1) {
      EXPECT_TRUE(has(r.status, "file 0 (?)")) << r.status.message();
    }
  }
  // A header error in a nameless file.
  Series bad;
  bad.files = {with([](std::vector<El>* e) { put(e, {tag(0x0028, 0x0002), "US", us(3)}); })};
  bad.null_names = true;
  SeriesRead r = read(bad, false);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_STREQ(r.status.file(), "");
}

TEST(DicomCoverage, FilesThatChangeBetweenPasses) {
  // The second open of file 1 gives a shorter file: its pixels end early (named, or not).
  for (bool names : {true, false}) {
    for (bool close : {true, false}) {
      Series s;
      s.files = {file(slice(0)), file(slice(1))};
      std::vector<uint8_t> shorter = s.files[1];
      shorter.resize(shorter.size() - 4);
      s.second = {{}, shorter};
      s.null_names = !names;
      SeriesRead r = read(s, close);
      EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << test::format(r.status);
      EXPECT_STREQ(r.status.file(), names ? "f1.dcm" : "");
      // ... or ends before its Pixel Data.
      shorter.resize(100);
      s.second = {{}, shorter};
      r = read(s, close);
      EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << test::format(r.status);
      EXPECT_TRUE(has(r.status, "the header before Pixel Data")) << r.status.message();
    }
  }
}

TEST(DicomCoverage, EachAllocationCanFail) {
  // 300 slices of one pixel: the records, keys, scratch and buffer each need a block of their
  // own (blocks are 4 KiB), so failing the Nth block request fails the Nth allocation.
  Series s;
  for (int k = 0; k < 300; ++k) {
    std::vector<El> one = slice(k);
    put(&one, {tag(0x0028, 0x0010), "US", us(1)});
    put(&one, {tag(0x0028, 0x0011), "US", us(1)});
    put(&one, {tag(0x7FE0, 0x0010), "OW", pixels16(1, k)});
    s.files.push_back(file(one));
  }
  int failures = 0;
  for (int n = 0; n < 10; ++n) {
    test::FailNthBlock state;
    state.fail_at = n;
    Arena arena(state.hooks(), size_t{1} << 20, 4096);
    SeriesRead r = read(s, true, CtReadOptions{}, &arena);
    if (r.status.is_ok()) break;
    EXPECT_EQ(r.status.code(), StatusCode::kArenaExhausted) << test::format(r.status);
    ++failures;
  }
  EXPECT_EQ(failures, 5);
}

}  // namespace
}  // namespace splintcore
