// Branches of the NRRD and MetaImage header parsers and of the readers' shared helpers
// (src/ct/ct_nrrd.cpp, src/ct/ct_metaimage.cpp, src/ct/ct_common.cpp) that the CT reader tests
// do not reach (issue 9: >= 95% branch coverage of the parsers, measured by
// tools/coverage.sh): every field's error, named with the file and the line, the accepted
// spellings, and the helpers' limits (numbers, sizes, budgets, axes, voxel conversion, data
// files that fail or lie about their size).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "ct/ct_common.h"
#include "splintcore/ct.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

struct CtRead {
  Status status;
  CtVolume volume;
  CtInfo info;
};

enum class Kind { kNrrd, kMeta };

// Reads `text` (header and attached data) as NRRD or MetaImage; `files` are detached files.
CtRead read_ct(Kind kind, const std::string& text, const std::vector<CtMemoryFile>& files = {},
               CtReadOptions options = CtReadOptions{}, bool with_info = true) {
  static test::TestArena* arena = new test::TestArena(size_t{4} << 20);
  arena->arena.reset();
  MemorySource ms{reinterpret_cast<const uint8_t*>(text.data()), text.size(), 0, 0};
  ByteSource source = memory_source(&ms, "head.hdr");
  CtMemoryFiles memory{files.data(), static_cast<uint32_t>(files.size()), 0, {}};
  CtFileOpener opener = ct_memory_opener(&memory);
  CtRead r;
  CtInfo* info = with_info ? &r.info : nullptr;
  r.status =
      kind == Kind::kNrrd
          ? read_nrrd(Context(&arena->arena), source, &opener, options, &r.volume, info)
          : read_metaimage(Context(&arena->arena), source, &opener, options, &r.volume, info);
  if (!r.status.is_ok()) {
    EXPECT_EQ(arena->arena.used(), 0u) << "a failed read left memory";
  }
  return r;
}

struct HeaderCase {
  const char* name;
  std::string text;
  StatusCode code;
  const char* fragment;
  uint64_t line;
};

void expect_cases(Kind kind, const std::vector<HeaderCase>& cases) {
  for (const HeaderCase& c : cases) {
    SCOPED_TRACE(c.name);
    CtRead r = read_ct(kind, c.text);
    EXPECT_EQ(r.status.code(), c.code) << test::format(r.status);
    EXPECT_NE(std::strstr(r.status.message(), c.fragment), nullptr) << test::format(r.status);
    EXPECT_STREQ(r.status.file(), "head.hdr");
    if (c.line != 0) {
      EXPECT_EQ(r.status.line(), c.line) << test::format(r.status);
    }
  }
}

// ---- NRRD -----------------------------------------------------------------------------------

const char kNrrdFields[] =
    "type: short\ndimension: 3\nsizes: 2 1 1\nencoding: raw\nendian: little\n";
std::string nrrd(const std::string& extra, const std::string& fields = kNrrdFields) {
  return "NRRD0004\n" + fields + extra + "\n" + std::string(4, '\0');
}

TEST(CtNrrdCoverage, FirstLine) {
  expect_cases(
      Kind::kNrrd,
      {
          {"empty", "", StatusCode::kParseError, "the first line must be NRRD0001 to NRRD0005", 1},
          {"long", "NRRD00041\n", StatusCode::kParseError, "must be NRRD0001", 1},
          {"other magic", "NRRX0004\n", StatusCode::kParseError, "must be NRRD0001", 1},
          {"version 0", "NRRD0000\n", StatusCode::kParseError, "must be NRRD0001", 1},
          {"version 6", "NRRD0006\n", StatusCode::kParseError, "must be NRRD0001", 1},
      });
}

TEST(CtNrrdCoverage, FieldErrors) {
  const std::string long_line = "content: " + std::string(600, 'c');
  std::vector<HeaderCase> cases = {
      {"long field line", "NRRD0004\n" + long_line + "\n", StatusCode::kParseError,
       "line longer than 511 characters", 2},
      {"sizes count", nrrd("", "type: short\nsizes: 2 2\n"), StatusCode::kParseError,
       "sizes: expected 3 integers, got \"2 2\"", 3},
      {"sizes text", nrrd("", "type: short\nsizes: a b c\n"), StatusCode::kParseError,
       "sizes: expected 3 integers", 3},
      {"sizes huge", nrrd("", "type: short\nsizes: 2 5e9 1\n"), StatusCode::kParseError,
       "bad sizes \"2 5e9 1\"", 3},
      {"sizes fraction", nrrd("", "type: short\nsizes: 2 1.5 1\n"), StatusCode::kParseError,
       "bad sizes", 3},
      {"spacings count", nrrd("spacings: 1 1\n"), StatusCode::kParseError,
       "bad spacings (three numbers) \"1 1\"", 7},
      {"spacings text", nrrd("spacings: 1 x 1\n"), StatusCode::kParseError, "bad spacings", 7},
      {"space dimension text", nrrd("space dimension: three\n"), StatusCode::kParseError,
       "bad space dimension \"three\"", 7},
      {"space dimension 2", nrrd("space dimension: 2\n"), StatusCode::kUnsupported,
       "space dimension 2: only 3 is supported", 7},
      {"data file list", nrrd("data file: LIST\n"), StatusCode::kUnsupported,
       "LIST and pattern forms are not supported", 7},
      {"data file pattern", nrrd("datafile: slice%03d.raw 1 10 1\n"), StatusCode::kUnsupported,
       "LIST and pattern forms", 7},
      {"data file empty", nrrd("data file:\n"), StatusCode::kParseError, "bad data file \"\"", 7},
      {"byte skip text", nrrd("byte skip: x\n"), StatusCode::kParseError, "bad byte skip \"x\"", 7},
      {"byte skip -2", nrrd("byteskip: -2\n"), StatusCode::kParseError, "bad byte skip \"-2\"", 7},
      {"line skip text", nrrd("line skip: x\n"), StatusCode::kParseError, "bad line skip", 7},
      {"line skip -1", nrrd("lineskip: -1\n"), StatusCode::kParseError, "bad line skip \"-1\"", 7},
      {"space origin not a vector", nrrd("space origin: 1,2,3\n"), StatusCode::kParseError,
       "bad space origin (x,y,z) \"1,2,3\"", 7},
      {"space origin two numbers", nrrd("space origin: (1,2)\n"), StatusCode::kParseError,
       "bad space origin", 7},
      {"space origin unclosed", nrrd("space origin: (1,2,3\n"), StatusCode::kParseError,
       "bad space origin", 7},
      {"space origin two vectors", nrrd("space origin: (1,2,3) (4,5,6)\n"), StatusCode::kParseError,
       "bad space origin", 7},
      {"directions two", nrrd("space directions: (1,0,0)\t(0,1,0)\n"), StatusCode::kParseError,
       "space directions: expected three vectors", 7},
      {"directions overflow", nrrd("space directions: (1e300,1e300,0) (0,1,0) (0,0,1)\n"),
       StatusCode::kParseError, "spacing along x is inf: must be a positive number of mm", 7},
      {"missing dimension", nrrd("", "type: short\nsizes: 2 1 1\nencoding: raw\nendian: little\n"),
       StatusCode::kParseError, "missing field \"dimension\"", 0},
      {"missing sizes", nrrd("", "type: short\ndimension: 3\nencoding: raw\nendian: little\n"),
       StatusCode::kParseError, "missing field \"sizes\"", 0},
      {"missing encoding", nrrd("", "type: short\ndimension: 3\nsizes: 2 1 1\nendian: little\n"),
       StatusCode::kParseError, "missing field \"encoding\"", 0},
  };
  for (const char* encoding : {"bzip2", "bz2", "ascii", "txt", "text", "hex", "zstd"}) {
    cases.push_back({encoding,
                     nrrd("", std::string("type: short\ndimension: 3\nsizes: 2 1 1\nencoding: ") +
                                  encoding + "\n"),
                     StatusCode::kUnsupported, "is not supported (only raw and gzip)", 5});
  }
  expect_cases(Kind::kNrrd, cases);
}

TEST(CtNrrdCoverage, AcceptedSpellings) {
  // Spacings after space directions (the directions' lengths win), space dimension 3, a long
  // "space" (kept to 63 characters), a detached data file with line and byte skips.
  const std::string space(100, 's');
  const std::string header = std::string("NRRD0004\n") + kNrrdFields +
                             "space dimension: 3\nspace: " + space +
                             "\nspace directions: (0.5,0,0) (0,0.5,0) (0,0,2)\nspacings: 9 9 9\n"
                             "data file: d.raw\nline skip: 1\nbyte skip: 2\n";
  const std::string data = "skip me\nxx" + std::string("\x10\x00\x20\x00", 4);
  const CtMemoryFile file{"d.raw", reinterpret_cast<const uint8_t*>(data.data()), data.size()};
  CtRead r = read_ct(Kind::kNrrd, header, {file});
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(r.volume.nx, 2u);
  EXPECT_EQ(r.volume.hu[0], 16);
  EXPECT_EQ(r.volume.hu[1], 32);
  EXPECT_EQ(r.volume.spacing.z, 2.0);
  EXPECT_EQ(std::string(r.info.space), space.substr(0, 63));
  EXPECT_TRUE(r.info.detached);
  // Key/value pairs ("key:=value") are not fields, even when the key names one; one with
  // nothing after ":=" too.
  r = read_ct(Kind::kNrrd, nrrd("sizes:=9 9 9\ntype:=\nx:=\n"));
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(r.volume.nx, 2u);
  // Without an info to fill.
  r = read_ct(Kind::kNrrd, nrrd(""), {}, CtReadOptions{}, false);
  SPLINTCORE_EXPECT_OK(r.status);
  EXPECT_EQ(r.volume.ny, 1u);
  // A header over the byte budget.
  CtReadOptions small;
  small.max_header_bytes = 25;
  r = read_ct(Kind::kNrrd, nrrd(""), {}, small);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << test::format(r.status);
  EXPECT_EQ(r.status.line(), 3u);
}

// ---- MetaImage ----------------------------------------------------------------------------

const char kMetaKeys[] =
    "ObjectType = Image\nNDims = 3\nDimSize = 2 1 1\nElementType = MET_SHORT\n";
std::string meta(const std::string& extra, const std::string& keys = kMetaKeys,
                 const std::string& last = "BinaryData = True\nElementDataFile = LOCAL\n") {
  return keys + extra + last + std::string(4, '\0');
}

TEST(CtMetaImageCoverage, KeyErrors) {
  const std::string long_line = "Comment = " + std::string(600, 'c');
  const std::vector<HeaderCase> cases = {
      {"line too long", long_line + "\n", StatusCode::kParseError,
       "line longer than 511 characters", 1},
      {"bad bool", meta("BinaryData = yes\n"), StatusCode::kParseError,
       "bad BinaryData (True or False) \"yes\"", 5},
      {"dims huge", meta("", "ObjectType = Image\nNDims = 3\nDimSize = 2 5e9 1\n"),
       StatusCode::kParseError, "bad DimSize (three positive integers)", 3},
      {"dims zero", meta("", "ObjectType = Image\nNDims = 3\nDimSize = 2 0 1\n"),
       StatusCode::kParseError, "bad DimSize (three positive integers)", 3},
      {"dims fraction", meta("", "ObjectType = Image\nNDims = 3\nDimSize = 2 1.5 1\n"),
       StatusCode::kParseError, "bad DimSize (three positive integers)", 3},
      // 2^32 - 1 is a DimSize (refused later by the dimension limit), 2^32 is not.
      {"dims 2^32 - 1",
       meta("",
            "ObjectType = Image\nNDims = 3\nDimSize = 2 4294967295 1\n"
            "ElementType = MET_SHORT\n"),
       StatusCode::kLimitExceeded, "size along y is 4294967295, more than the limit 4096", 0},
      {"dims 2^32", meta("", "ObjectType = Image\nNDims = 3\nDimSize = 2 4294967296 1\n"),
       StatusCode::kParseError, "bad DimSize (three positive integers)", 3},
      // A direction matrix with no spacing key: its axes' error names the matrix's line.
      {"matrix line", meta("TransformMatrix = 1 0 0 1 0 0 0 0 1\n"), StatusCode::kParseError,
       "directions of axes x and y are not orthogonal (dot product 1", 5},
      {"element size", meta("ElementSize = 1 1\n"), StatusCode::kParseError,
       "bad element spacing (three numbers)", 5},
      {"origin", meta("Origin = 1 2\n"), StatusCode::kParseError, "bad origin (three numbers)", 5},
      {"position", meta("Position = a b c\n"), StatusCode::kParseError, "bad origin", 5},
      {"rotation", meta("Rotation = 1 0 0\n"), StatusCode::kParseError,
       "bad direction matrix (nine numbers)", 5},
      {"orientation", meta("Orientation = 1 0 0 0 1 0 0 0 1 0\n"), StatusCode::kParseError,
       "bad direction matrix", 5},
      {"channels text", meta("ElementNumberOfChannels = x\n"), StatusCode::kParseError,
       "bad ElementNumberOfChannels \"x\"", 5},
      {"channels 3", meta("ElementNumberOfChannels = 3\n"), StatusCode::kUnsupported,
       "ElementNumberOfChannels 3: only scalar volumes", 5},
      {"header size text", meta("HeaderSize = x\n"), StatusCode::kParseError,
       "bad HeaderSize \"x\"", 5},
      {"header size -2", meta("HeaderSize = -2\n"), StatusCode::kParseError,
       "bad HeaderSize \"-2\"", 5},
      {"header size local", meta("HeaderSize = 4\n"), StatusCode::kUnsupported,
       "HeaderSize is only supported with a separate data file", 0},
      {"missing object", meta("", "NDims = 3\nDimSize = 2 1 1\nElementType = MET_SHORT\n"),
       StatusCode::kParseError, "missing key ObjectType before ElementDataFile", 0},
      {"missing ndims", meta("", "ObjectType = Image\nDimSize = 2 1 1\nElementType = MET_SHORT\n"),
       StatusCode::kParseError, "missing key NDims", 0},
      {"missing type", meta("", "ObjectType = Image\nNDims = 3\nDimSize = 2 1 1\n"),
       StatusCode::kParseError, "missing key ElementType", 0},
      {"missing binary", meta("", kMetaKeys, "ElementDataFile = LOCAL\n"), StatusCode::kUnsupported,
       "only binary MetaImage data is supported", 0},
      {"binary false", meta("", kMetaKeys, "BinaryData = 0\nElementDataFile = LOCAL\n"),
       StatusCode::kUnsupported, "only binary MetaImage data is supported", 0},
  };
  expect_cases(Kind::kMeta, cases);
}

TEST(CtMetaImageCoverage, AcceptedSpellings) {
  // Blank lines, "1"/"true" booleans, ElementSize then ElementSpacing (which wins), Offset,
  // TransformMatrix after the spacing, ElementSize after ElementSpacing (ignored), a long
  // AnatomicalOrientation (kept to 63 characters), channels 1, CompressedData False.
  const std::string orientation(80, 'R');
  const std::string text = meta(
      "\n   \n = 5\nElementSize = 3 3 3\nElementSpacing = 0.5 0.5 2\nElementSize = 7 7 7\n"
      "Offset = 1 2 3\nTransformMatrix = 1 0 0 0 1 0 0 0 1\nAnatomicalOrientation = " +
          orientation +
          "\nElementNumberOfChannels = 1\nCompressedData = false\n"
          "ElementByteOrderMSB = 0\n",
      kMetaKeys, "BinaryData = 1\nElementDataFile = LOCAL\n");
  CtRead r = read_ct(Kind::kMeta, text);
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(r.volume.spacing.x, 0.5);
  EXPECT_EQ(r.volume.spacing.z, 2.0);
  EXPECT_EQ(r.volume.origin.z, 3.0);
  EXPECT_EQ(std::string(r.info.space), orientation.substr(0, 63));
  // Without an info to fill; "true" spelled out.
  r = read_ct(Kind::kMeta, meta("", kMetaKeys, "BinaryData = true\nElementDataFile = LOCAL\n"), {},
              CtReadOptions{}, false);
  SPLINTCORE_EXPECT_OK(r.status);
  // A header over the byte budget.
  CtReadOptions small;
  small.max_header_bytes = 25;
  r = read_ct(Kind::kMeta, meta(""), {}, small);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << test::format(r.status);
  EXPECT_EQ(r.status.line(), 2u);
}

// ---- the shared helpers (ct_common) ---------------------------------------------------------

using namespace ct_detail;  // NOLINT(google-build-using-namespace): the helpers under test

// A source that fails (-1) or returns more than asked (capacity + 1), with any size.
struct OddSource {
  int64_t extra = -1;
  static int64_t read(void* user, uint8_t* buffer, size_t capacity) {
    (void)buffer;
    const int64_t e = static_cast<OddSource*>(user)->extra;
    return e < 0 ? -1 : static_cast<int64_t>(capacity) + e;
  }
};

TEST(CtCommonCoverage, NamesOpenersAndSources) {
  EXPECT_STREQ(ct_format_name(CtFormat::kDicom), "dicom");
  EXPECT_STREQ(ct_format_name(CtFormat::kNrrd), "nrrd");
  EXPECT_STREQ(ct_format_name(CtFormat::kMetaImage), "metaimage");
  EXPECT_STREQ(ct_format_name(static_cast<CtFormat>(200)), "unknown");
  const uint8_t bytes[2] = {1, 2};
  const CtMemoryFile files[3] = {{nullptr, bytes, 2}, {"a", bytes, 1}, {"b", bytes, 2}};
  CtMemoryFiles memory{files, 3, 0, {}};
  CtFileOpener opener = ct_memory_opener(&memory);
  ByteSource source;
  SPLINTCORE_ASSERT_OK(opener.open(opener.user, "b", &source));
  EXPECT_EQ(source.size, 2u);
  opener.close(opener.user, &source);
  Status s = opener.open(opener.user, "c", &source);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_STREQ(s.message(), "cannot open \"c\": no such file");
  EXPECT_STREQ(s.file(), "c");
  CtSeries series = ct_memory_series(&memory);
  SPLINTCORE_ASSERT_OK(series.open(series.user, 0, &source));
  EXPECT_STREQ(source.name, "memory");  // a file without a name
  series.close(series.user, 0, &source);
  s = series.open(series.user, 3, &source);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_STREQ(s.message(), "no file 3 in the series");
  // in_source names the file only when the status has none and the source has a name.
  ByteSource unnamed;
  EXPECT_STREQ(in_source(make_error(StatusCode::kParseError, "x"), unnamed).file(), "");
  ByteSource named;
  named.name = "n";
  EXPECT_STREQ(in_source(make_error(StatusCode::kParseError, "x").in_file("f"), named).file(), "f");
  EXPECT_STREQ(in_source(make_error(StatusCode::kParseError, "x"), named).file(), "n");
}

TEST(CtCommonCoverage, ReaderAndLines) {
  for (int64_t extra : {int64_t{-1}, int64_t{1}}) {
    OddSource odd{extra};
    ByteSource source;
    source.read = &OddSource::read;
    source.user = &odd;
    uint8_t window[16];
    Reader reader;
    reader.init(&source, window, sizeof(window));
    Status s = reader.fill(1);
    EXPECT_EQ(s.code(), StatusCode::kIoError);
    EXPECT_NE(std::strstr(s.message(), extra < 0 ? "read failed" : "more than asked"), nullptr);
  }
  // CRLF lines, a long line whose kept part ends in '\r' (kept), a spent budget.
  std::string text = "ab\r\n" + std::string(510, 'x') + "\r" + "yz\n" + "last";
  MemorySource ms{reinterpret_cast<const uint8_t*>(text.data()), text.size(), 0, 0};
  ByteSource source = memory_source(&ms, "t");
  uint8_t window[kHeaderWindow];
  Reader reader;
  reader.init(&source, window, sizeof(window));
  char line[kLineCapacity];
  size_t length = 0;
  bool too_long = false, got = false;
  uint64_t budget = text.size() - 2;
  SPLINTCORE_ASSERT_OK(reader.read_line(line, &length, &too_long, &got, &budget));
  EXPECT_STREQ(line, "ab");
  SPLINTCORE_ASSERT_OK(reader.read_line(line, &length, &too_long, &got, &budget));
  EXPECT_TRUE(too_long);
  EXPECT_EQ(length, kLineCapacity - 1);
  EXPECT_EQ(line[length - 1], '\r');
  Status s = reader.read_line(line, &length, &too_long, &got, &budget);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded);
  EXPECT_EQ(s.byte_offset(), text.size() - 2);
}

TEST(CtCommonCoverage, TextAndNumbers) {
  auto trimmed = [](const std::string& in) {
    const char* t = in.data();
    size_t n = in.size();
    trim(&t, &n);
    return std::string(t, n);
  };
  EXPECT_EQ(trimmed(std::string("\0 \t a b\r\t\0", 10)), "a b");
  // Letters match in either case, on both sides, A and Z included; the characters just outside
  // A-Z ('@', '[') are not letters ('`', '{' are their lower-case neighbours).
  EXPECT_TRUE(equal_nocase("AZaz", 4, "azAZ"));
  EXPECT_FALSE(equal_nocase("@", 1, "`"));
  EXPECT_FALSE(equal_nocase("[", 1, "{"));
  EXPECT_FALSE(equal_nocase("`", 1, "@"));
  EXPECT_FALSE(equal_nocase("{", 1, "["));
  EXPECT_FALSE(equal_nocase("ab", 2, "abc"));
  auto real = [](const std::string& in, double* out) {
    return parse_double(in.data(), in.size(), out);
  };
  double d = 0;
  EXPECT_FALSE(real("", &d));
  EXPECT_FALSE(real(std::string(65, '1'), &d));
  EXPECT_TRUE(real(std::string(64, '1'), &d));  // the longest taken
  EXPECT_EQ(d, 1.1111111111111111e63);
  EXPECT_TRUE(real("1e+5", &d));  // a sign inside: the exponent's
  EXPECT_EQ(d, 1e5);
  EXPECT_TRUE(real("-.25E+1", &d));
  EXPECT_EQ(d, -2.5);
  EXPECT_FALSE(real("+", &d));
  EXPECT_FALSE(real("+-1", &d));
  EXPECT_FALSE(real("++1", &d));
  EXPECT_TRUE(real("+1.5e1", &d));
  EXPECT_EQ(d, 15.0);
  EXPECT_TRUE(real("2E-1", &d));
  EXPECT_EQ(d, 0.2);
  EXPECT_FALSE(real("1+2", &d));    // stops early
  EXPECT_FALSE(real("1e999", &d));  // out of range
  EXPECT_FALSE(real("e", &d));      // no digits
  EXPECT_FALSE(real("inf", &d));
  auto integer = [](const std::string& in, int64_t* out) {
    return parse_i64(in.data(), in.size(), out);
  };
  int64_t i = 0;
  EXPECT_TRUE(integer(" +42 ", &i));
  EXPECT_EQ(i, 42);
  EXPECT_FALSE(integer("+", &i));
  EXPECT_FALSE(integer(std::string(25, '1'), &i));
  EXPECT_TRUE(integer(std::string(22, '0') + "42", &i));  // 24 characters: the longest taken
  EXPECT_EQ(i, 42);
  EXPECT_FALSE(integer("4x", &i));
  EXPECT_FALSE(integer("99999999999999999999", &i));
  double v[3];
  size_t count = 9;
  EXPECT_TRUE(parse_doubles("  ", 2, ',', v, 3, &count));
  EXPECT_EQ(count, 0u);
  EXPECT_FALSE(parse_doubles("1,2,3,4", 7, ',', v, 3, &count));
  EXPECT_FALSE(parse_doubles("1,x", 3, ',', v, 3, &count));
  EXPECT_TRUE(parse_doubles("1\t2 3", 5, '\0', v, 3, &count));
  EXPECT_EQ(count, 3u);
  EXPECT_EQ(v[2], 3.0);
  EXPECT_FALSE(parse_doubles("1 2 3 4", 7, '\0', v, 3, &count));
}

TEST(CtCommonCoverage, SizesBudgetsSpacingAxes) {
  CtReadOptions o;
  uint64_t bytes = 0;
  Status s = check_size(2, 0, 2, o, &bytes);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_STREQ(s.message(), "size along y is 0");
  s = check_size(2, 2, 5000, o, &bytes);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded);
  EXPECT_NE(std::strstr(s.message(), "size along z is 5000, more than the limit 4096"), nullptr);
  s = check_size(4096, 4096, 4096, o, &bytes);
  EXPECT_NE(std::strstr(s.message(), "is more than the limit 2147483648"), nullptr);
  CtReadOptions wide;
  wide.max_dimension = ~uint32_t{0};
  wide.max_voxels = ~uint64_t{0};
  s = check_size(~uint32_t{0}, ~uint32_t{0}, ~uint32_t{0}, wide, &bytes);  // 2^96 voxels
  EXPECT_NE(std::strstr(s.message(), "voxels is more than the limit"), nullptr);
  s = check_size(uint64_t{1} << 21, uint64_t{1} << 21, uint64_t{1} << 21, wide, &bytes);
  EXPECT_NE(std::strstr(s.message(), "does not fit in memory"), nullptr) << s.message();
  SPLINTCORE_EXPECT_OK(check_size(2, 3, 4, o, &bytes));
  EXPECT_EQ(bytes, 48u);
  CtReadOptions tight;  // each limit met exactly is taken, one over is refused
  tight.max_dimension = 4;
  tight.max_voxels = 24;
  SPLINTCORE_EXPECT_OK(check_size(2, 3, 4, tight, &bytes));
  EXPECT_EQ(check_size(2, 3, 5, tight, &bytes).code(), StatusCode::kLimitExceeded);
  tight.max_voxels = 23;
  EXPECT_EQ(check_size(2, 3, 4, tight, &bytes).code(), StatusCode::kLimitExceeded);

  test::TestArena t(4096);
  s = check_budget(t.arena, ~uint64_t{0}, 10, 2);  // the need overflows
  EXPECT_EQ(s.code(), StatusCode::kArenaExhausted);
  s = check_budget(t.arena, ~uint64_t{0} - 20, 10, 2);
  EXPECT_EQ(s.code(), StatusCode::kArenaExhausted);
  s = check_budget(t.arena, 1000, 3100, 2);
  EXPECT_NE(std::strstr(s.message(), "needs 4132 bytes (1000 for the voxels), 4096 are free"),
            nullptr)
      << s.message();
  ASSERT_NE(t.arena.allocate(16), nullptr);
  s = check_budget(t.arena, ~uint64_t{0} - 7, 0, 0);  // used + need overflows
  EXPECT_NE(std::strstr(s.message(), "to at least 18446744073709551615 bytes"), nullptr)
      << s.message();
  ASSERT_NE(t.arena.allocate(4096 - 16), nullptr);
  s = check_budget(t.arena, 1, 0, 0);
  EXPECT_NE(std::strstr(s.message(), "0 are free (cap 4096)"), nullptr) << s.message();

  s = check_spacing(std::nan(""), "y", o);
  EXPECT_NE(std::strstr(s.message(), "spacing along y is nan: must be a positive number"), nullptr)
      << s.message();
  EXPECT_NE(std::strstr(check_spacing(0, "x", o).message(), "must be a positive number"), nullptr);
  SPLINTCORE_EXPECT_OK(check_spacing(o.min_spacing, "x", o));  // both ends are inside
  SPLINTCORE_EXPECT_OK(check_spacing(o.max_spacing, "x", o));
  EXPECT_NE(std::strstr(check_spacing(1e-4, "x", o).message(), "wrong units?"), nullptr);
  EXPECT_NE(std::strstr(check_spacing(101, "z", o).message(), "outside [0.001, 100] mm"), nullptr);

  Vec3 x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
  Vec3 bad{std::nan(""), 0, 0};
  s = check_axes(&x, &bad, &z, o);
  EXPECT_STREQ(s.message(), "direction of axis y is not finite");
  Vec3 longer{0, 2, 0};
  s = check_axes(&x, &longer, &z, o);
  EXPECT_NE(std::strstr(s.message(), "direction of axis y has length 2, not 1"), nullptr);
  Vec3 slanted{0, 0.6, 0.8};
  s = check_axes(&x, &y, &slanted, o);
  EXPECT_NE(std::strstr(s.message(), "directions of axes y and z are not orthogonal"), nullptr);
  SPLINTCORE_EXPECT_OK(check_axes(&x, &y, &z, o));
}

TEST(CtCommonCoverage, TypesAndHu) {
  struct Named {
    uint8_t bytes;
    bool is_signed, is_float;
    const char* name;
  };
  const Named named[] = {{4, true, true, "float32"}, {8, true, true, "float64"},
                         {1, true, false, "int8"},   {1, false, false, "uint8"},
                         {2, true, false, "int16"},  {2, false, false, "uint16"},
                         {4, true, false, "int32"},  {4, false, false, "uint32"}};
  for (const Named& n : named) {
    VoxelFormat f;
    f.bytes = n.bytes;
    f.is_signed = n.is_signed;
    f.is_float = n.is_float;
    f.big_endian = true;
    CtInfo info;
    describe_type(f, &info);
    EXPECT_STREQ(info.stored_type, n.name);
    EXPECT_TRUE(info.big_endian);
  }
  bool clamped = false;
  EXPECT_EQ(to_hu(40000, 1, 0, &clamped), 32767);
  EXPECT_TRUE(clamped);
  clamped = false;
  EXPECT_EQ(to_hu(-40000, 1, 0, &clamped), -32768);
  EXPECT_TRUE(clamped);
  clamped = false;
  EXPECT_EQ(to_hu(-2.5, 1, 0, &clamped), -3);  // half away from zero
  EXPECT_FALSE(clamped);
}

// convert_voxels over `bytes` with a reader window of `window` bytes.
Status convert(const std::string& bytes, const VoxelFormat& f, uint64_t count, double slope,
               double intercept, std::vector<int16_t>* out, uint64_t* saturated,
               size_t window = 64) {
  MemorySource ms{reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), 0, 0};
  ByteSource source = memory_source(&ms, "v");
  std::vector<uint8_t> buffer(window);
  Reader reader;
  reader.init(&source, buffer.data(), buffer.size());
  out->assign(static_cast<size_t>(count), 0);
  *saturated = 0;
  return convert_voxels(reader, f, count, slope, intercept, out->data(), 100, saturated);
}
std::string le_bytes(uint64_t v, int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += static_cast<char>((v >> (8 * i)) & 0xff);
  return s;
}

TEST(CtCommonCoverage, VoxelConversion) {
  std::vector<int16_t> hu;
  uint64_t saturated = 0;
  VoxelFormat f64;  // 64-bit signed integers: through the double path
  f64.bytes = 8;
  SPLINTCORE_ASSERT_OK(
      convert(le_bytes(~uint64_t{0}, 8) + le_bytes(40000, 8), f64, 2, 1, 0, &hu, &saturated));
  EXPECT_EQ(hu, (std::vector<int16_t>{-1, 32767}));
  EXPECT_EQ(saturated, 1u);
  VoxelFormat d;  // doubles, one infinite
  d.bytes = 8;
  d.is_float = true;
  const double values[2] = {1.5, HUGE_VAL};
  std::string raw(reinterpret_cast<const char*>(values), 16);
  Status s = convert(raw, d, 2, 1, 0, &hu, &saturated);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_EQ(s.index(), 101u);
  EXPECT_EQ(s.byte_offset(), 8u);
  VoxelFormat fl;  // float32 NaN
  fl.bytes = 4;
  fl.is_float = true;
  const float nan_value = std::nanf("");
  s = convert(std::string(reinterpret_cast<const char*>(&nan_value), 4), fl, 1, 1, 0, &hu,
              &saturated);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_STREQ(s.message(), "voxel 100 is NaN or infinite");
  // 16-bit little endian, the fast path: clamped both ways by the intercept.
  VoxelFormat u16;
  u16.is_signed = false;
  SPLINTCORE_ASSERT_OK(
      convert(le_bytes(65535, 2) + le_bytes(0, 2), u16, 2, 1, -40000, &hu, &saturated));
  EXPECT_EQ(hu, (std::vector<int16_t>{25535, -32768}));
  EXPECT_EQ(saturated, 1u);
  SPLINTCORE_ASSERT_OK(convert(le_bytes(65535, 2), u16, 1, 1, 0, &hu, &saturated));
  EXPECT_EQ(hu[0], 32767);
  // 32-bit integers, integer path: clamps both ways; a 12-bit signed value sign-extended.
  VoxelFormat i32;
  i32.bytes = 4;
  SPLINTCORE_ASSERT_OK(convert(le_bytes(100000, 4) + le_bytes(static_cast<uint32_t>(-100000), 4),
                               i32, 2, 1, 0, &hu, &saturated));
  EXPECT_EQ(hu, (std::vector<int16_t>{32767, -32768}));
  EXPECT_EQ(saturated, 2u);
  VoxelFormat b12;
  b12.bits_stored = 12;
  b12.big_endian = true;
  SPLINTCORE_ASSERT_OK(convert(std::string("\x0f\xff\x07\xff", 4), b12, 2, 1, 0, &hu, &saturated));
  EXPECT_EQ(hu, (std::vector<int16_t>{-1, 2047}));
  // 32 bits allocated, 16 stored, little endian: the integer path but not the 16-bit fast one
  // (each value 4 bytes, its high half masked off).
  VoxelFormat i32b16;
  i32b16.bytes = 4;
  i32b16.bits_stored = 16;
  SPLINTCORE_ASSERT_OK(convert(le_bytes(0xABCD0064u, 4) + le_bytes(0x1234FFFFu, 4), i32b16, 2, 1, 0,
                               &hu, &saturated));
  EXPECT_EQ(hu, (std::vector<int16_t>{100, -1}));
  // Not the integer path: a slope, a fractional intercept, a huge intercept.
  SPLINTCORE_ASSERT_OK(convert(le_bytes(10, 4), i32, 1, 2, 0, &hu, &saturated));
  EXPECT_EQ(hu[0], 20);
  SPLINTCORE_ASSERT_OK(convert(le_bytes(10, 4), i32, 1, 1, 0.5, &hu, &saturated));
  EXPECT_EQ(hu[0], 11);
  SPLINTCORE_ASSERT_OK(convert(le_bytes(10, 4), i32, 1, 1, -3e9, &hu, &saturated));
  EXPECT_EQ(hu[0], -32768);
  // More values than one window holds; and fewer bytes than values.
  std::string many;
  for (int k = 0; k < 100; ++k) many += le_bytes(static_cast<uint64_t>(k), 4);
  SPLINTCORE_ASSERT_OK(convert(many, i32, 100, 1, 0, &hu, &saturated, 64));
  EXPECT_EQ(hu[99], 99);
  s = convert(many, i32, 101, 1, 0, &hu, &saturated, 64);
  EXPECT_EQ(s.code(), StatusCode::kTruncated);
  EXPECT_STREQ(s.message(), "voxel data ends early: 1 of 101 values missing");
  EXPECT_EQ(s.byte_offset(), 400u);
}

// read_raw_volume with detached data from `opener` (or attached after an empty header).
struct RawRun {
  Status status;
  std::vector<int16_t> hu;
};
RawRun raw_volume(const RawData& data, const CtFileOpener* opener, Arena* arena = nullptr,
                  CtReadOptions options = CtReadOptions{}) {
  static test::TestArena* shared = new test::TestArena(size_t{1} << 20);
  Arena& a = arena != nullptr ? *arena : shared->arena;
  if (arena == nullptr) a.reset();
  const size_t used = a.used();
  MemorySource empty{nullptr, 0, 0, 0};
  ByteSource header_source = memory_source(&empty, "head.nhdr");
  uint8_t window[kHeaderWindow];
  Reader header;
  header.init(&header_source, window, sizeof(window));
  int16_t* hu = nullptr;
  uint64_t saturated = 0;
  RawRun r;
  r.status =
      read_raw_volume(Context(&a), header, header_source, opener, data, options, &hu, &saturated);
  if (r.status.is_ok()) {
    r.hu.assign(hu, hu + uint64_t{data.nx} * data.ny * data.nz);
  } else {
    EXPECT_EQ(a.used(), used) << "a failed read left memory";
  }
  return r;
}

// An opener serving one source as it is set (name, size and read behaviour).
struct OneFile {
  MemorySource memory{};
  OddSource odd{};
  bool failing = false;
  const char* name = nullptr;
  uint64_t size = 0;
  bool unknown_size = false;
  bool error_without_file = false;
  static Status open(void* user, const char* wanted, ByteSource* out) {
    (void)wanted;
    OneFile* f = static_cast<OneFile*>(user);
    if (f->error_without_file) return Status::error(StatusCode::kIoError, "refused");
    if (f->failing) {
      out->read = &OddSource::read;
      out->user = &f->odd;
      out->size = kUnknownSize;
      out->name = f->name;
      return Status::ok();
    }
    f->memory.position = 0;
    *out = memory_source(&f->memory, f->name);
    out->name = f->name;
    if (f->unknown_size) out->size = kUnknownSize;
    if (f->size != 0) out->size = f->size;
    return Status::ok();
  }
};

TEST(CtCommonCoverage, RawVolumeDataFiles) {
  const std::string two = "line one\n" + le_bytes(7, 2) + le_bytes(9, 2);
  OneFile file;
  file.memory = MemorySource{reinterpret_cast<const uint8_t*>(two.data()), two.size(), 0, 0};
  CtFileOpener opener;
  opener.open = &OneFile::open;
  opener.user = &file;
  RawData data;
  data.nx = 2;
  data.ny = data.nz = 1;
  data.data_file = "d.raw";
  data.line_skip = 1;
  // A file without a name is named by the header's "data file"; no close() is fine.
  RawRun r = raw_volume(data, &opener);
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(r.hu, (std::vector<int16_t>{7, 9}));
  // The data is the file's end (byte skip -1), size known.
  data.byte_skip = -1;
  r = raw_volume(data, &opener);
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(r.hu, (std::vector<int16_t>{7, 9}));
  // ... but unknown: unsupported; or too small: truncated (named by the data file).
  file.unknown_size = true;
  r = raw_volume(data, &opener);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_STREQ(r.status.file(), "d.raw");
  file.unknown_size = false;
  file.size = 5;  // less than what the line skip read
  r = raw_volume(data, &opener);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated);
  EXPECT_NE(std::strstr(r.status.message(), "the voxel data needs 4 bytes, the file has 5"),
            nullptr);
  file.size = 11;
  r = raw_volume(data, &opener);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated);
  // A size smaller than the bytes already read, without byte skip -1.
  data.byte_skip = 0;
  file.size = 5;
  r = raw_volume(data, &opener);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated);
  EXPECT_NE(std::strstr(r.status.message(), "from byte 9, the file has only 5"), nullptr);
  // Unknown size, byte skip 0: read as far as the data goes.
  file.size = 0;
  file.unknown_size = true;
  r = raw_volume(data, &opener);
  SPLINTCORE_ASSERT_OK(r.status);
  file.unknown_size = false;
  // Two lines to skip, one present.
  data.line_skip = 3;
  r = raw_volume(data, &opener);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated);
  EXPECT_STREQ(r.status.message(), "file ends while skipping line 2 of 3 (line skip)");
  // A data file that fails while its lines are skipped.
  file.failing = true;
  file.name = "bad.raw";
  r = raw_volume(data, &opener);
  EXPECT_EQ(r.status.code(), StatusCode::kIoError);
  EXPECT_STREQ(r.status.file(), "bad.raw");
  file.failing = false;
  // An opener's error without a file: named by the data file.
  file.error_without_file = true;
  r = raw_volume(data, &opener);
  EXPECT_STREQ(r.status.message(), "refused");
  EXPECT_STREQ(r.status.file(), "d.raw");
  // No opener, or one without open().
  r = raw_volume(data, nullptr);
  EXPECT_EQ(r.status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::strstr(r.status.message(), "no file opener was given"), nullptr);
  CtFileOpener empty;
  r = raw_volume(data, &empty);
  EXPECT_EQ(r.status.code(), StatusCode::kInvalidArgument);
  EXPECT_STREQ(r.status.file(), "head.nhdr");
}

TEST(CtCommonCoverage, RawVolumeLimitsAndAllocations) {
  RawData data;
  data.format.bytes = 8;
  data.nx = data.ny = uint32_t{1} << 21;
  data.nz = uint32_t{1} << 20;  // 2^62 voxels: 2^63 bytes of HU, 2^65 of data
  CtReadOptions wide;
  wide.max_dimension = ~uint32_t{0};
  wide.max_voxels = ~uint64_t{0};
  RawRun r = raw_volume(data, nullptr, nullptr, wide);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded);
  EXPECT_STREQ(r.status.message(), "voxel data too large");
  // The voxels' or the chunk's block refused by the hooks (the budget check passed).
  data = RawData{};
  data.nx = 2;
  data.ny = data.nz = 1;
  data.data_file = "d.raw";
  for (int fail_at : {0, 1}) {
    test::FailNthBlock hooks_state;
    hooks_state.fail_at = fail_at;
    Arena arena(hooks_state.hooks(), size_t{1} << 20, 256);
    r = raw_volume(data, nullptr, &arena);
    EXPECT_EQ(r.status.code(), StatusCode::kArenaExhausted) << test::format(r.status);
  }
}

}  // namespace
}  // namespace splintcore
