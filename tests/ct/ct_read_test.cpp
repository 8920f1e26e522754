// CT readers (DICOM series, NRRD, MetaImage) on hand-built files in memory: every supported
// variant, and hostile inputs (truncation at every byte, lying sizes, overflowing dimensions,
// missing tags, unsupported encodings, bad slice geometry, a too-small arena).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "ct/ct_common.h"
#include "splintcore/ct.h"
#include "support/dicom_read.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

std::vector<uint8_t> cat(const std::string& header, const std::vector<uint8_t>& data) {
  std::vector<uint8_t> out(header.begin(), header.end());
  out.insert(out.end(), data.begin(), data.end());
  return out;
}

std::vector<uint8_t> le16(const std::vector<int>& values) {
  std::vector<uint8_t> out;
  for (int v : values) {
    out.push_back(static_cast<uint8_t>(v & 0xFF));
    out.push_back(static_cast<uint8_t>((v >> 8) & 0xFF));
  }
  return out;
}
std::vector<uint8_t> be16(const std::vector<int>& values) {
  std::vector<uint8_t> out;
  for (int v : values) {
    out.push_back(static_cast<uint8_t>((v >> 8) & 0xFF));
    out.push_back(static_cast<uint8_t>(v & 0xFF));
  }
  return out;
}
std::vector<uint8_t> le_f32(const std::vector<float>& values) {
  std::vector<uint8_t> out;
  for (float f : values) {
    uint32_t b;
    std::memcpy(&b, &f, 4);
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(b >> (8 * i)));
  }
  return out;
}

std::vector<int> ramp(int n, int start, int step) {
  std::vector<int> v;
  for (int i = 0; i < n; ++i) v.push_back(start + i * step);
  return v;
}

struct Result {
  Status status;
  CtVolume volume;
  CtInfo info;
  std::vector<int> hu;
};

Result read_format(CtFormat format, const std::vector<uint8_t>& bytes,
                   const std::vector<CtMemoryFile>& others = {}, size_t max_chunk = 0,
                   const CtReadOptions& options = CtReadOptions{}, Arena* arena = nullptr) {
  static TestArena* shared = new TestArena(size_t{16} << 20);
  Arena& a = arena != nullptr ? *arena : shared->arena;
  if (arena == nullptr) a.reset();
  Context ctx(&a);
  MemorySource ms{bytes.data(), bytes.size(), 0, max_chunk};
  ByteSource source = memory_source(&ms, "test.hdr");
  CtMemoryFiles files{others.data(), static_cast<uint32_t>(others.size()), max_chunk, {}};
  CtFileOpener opener = ct_memory_opener(&files);
  Result r;
  r.status = format == CtFormat::kNrrd
                 ? read_nrrd(ctx, source, &opener, options, &r.volume, &r.info)
                 : read_metaimage(ctx, source, &opener, options, &r.volume, &r.info);
  if (r.status.is_ok()) {
    for (uint64_t i = 0; i < r.volume.voxel_count(); ++i) r.hu.push_back(r.volume.hu[i]);
  }
  return r;
}

void expect_vec(const Vec3& a, const Vec3& b, double tol = 0) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

std::string message(const Status& s) { return test::format(s); }

// ---------------------------------------------------------------------------------------------
// Conversion.

TEST(CtConvert, RoundsHalvesAwayFromZeroAndSaturates) {
  bool c = false;
  EXPECT_EQ(ct_detail::to_hu(2.5, 1, 0, &c), 3);
  EXPECT_FALSE(c);
  EXPECT_EQ(ct_detail::to_hu(-2.5, 1, 0, &c), -3);
  EXPECT_EQ(ct_detail::to_hu(0.49999999999999994, 1, 0, &c), 0);
  EXPECT_EQ(ct_detail::to_hu(-0.5, 1, 0, &c), -1);
  EXPECT_EQ(ct_detail::to_hu(3, 2.5, -1024, &c), -1017);  // -1016.5: away from zero
  EXPECT_EQ(ct_detail::to_hu(32767.4, 1, 0, &c), 32767);
  EXPECT_FALSE(c);
  EXPECT_EQ(ct_detail::to_hu(32767.5, 1, 0, &c), 32767);
  EXPECT_TRUE(c);
  EXPECT_EQ(ct_detail::to_hu(-1e300, 1e10, 0, &c), -32768);
  EXPECT_TRUE(c);
}

// ---------------------------------------------------------------------------------------------
// NRRD.

const char* kNrrdHeader =
    "NRRD0004\n"
    "# a comment\n"
    "type: short\n"
    "dimension: 3\n"
    "space: left-posterior-superior\n"
    "sizes: 2 3 4\n"
    "space directions: (0.5,0,0) (0,0.75,0) (0,0,2.5)\n"
    "kinds: domain domain domain\n"
    "endian: little\n"
    "encoding: raw\n"
    "space origin: (-10,20.5,3)\n"
    "my key:=my value\n"
    "\n";

TEST(CtNrrd, ReadsAttachedLittleEndianShorts) {
  const std::vector<int> values = ramp(24, -1000, 97);
  Result r = read_format(CtFormat::kNrrd, cat(kNrrdHeader, le16(values)));
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.volume.nx, 2u);
  EXPECT_EQ(r.volume.ny, 3u);
  EXPECT_EQ(r.volume.nz, 4u);
  EXPECT_EQ(r.hu, values);
  expect_vec(r.volume.spacing, Vec3{0.5, 0.75, 2.5});
  expect_vec(r.volume.origin, Vec3{-10, 20.5, 3});
  expect_vec(r.volume.axis_x, Vec3{1, 0, 0});
  expect_vec(r.volume.axis_z, Vec3{0, 0, 1});
  EXPECT_EQ(r.info.format, CtFormat::kNrrd);
  EXPECT_STREQ(r.info.stored_type, "int16");
  EXPECT_STREQ(r.info.space, "left-posterior-superior");
  EXPECT_FALSE(r.info.detached);
  EXPECT_EQ(r.volume.saturated, 0u);
}

TEST(CtNrrd, SmallChunksGiveTheSameVoxels) {
  const std::vector<int> values = ramp(24, -3000, 251);
  CtReadOptions o;
  o.chunk_bytes = 8;  // rounded up to 1024
  Result r = read_format(CtFormat::kNrrd, cat(kNrrdHeader, le16(values)), {}, 1, o);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.hu, values);
}

TEST(CtNrrd, ReadsBigEndianUnsignedAndRotatedAxes) {
  std::string h =
      "NRRD0005\ntype: uint16\ndimension: 3\nsizes: 2 2 2\n"
      "space directions: (0,0.6,0) (-0.8,0,0) (0,0,1.5)\nendian: big\nencoding: raw\n\n";
  const std::vector<int> values = {0, 1, 65535, 40000, 32767, 32768, 7, 1000};
  Result r = read_format(CtFormat::kNrrd, cat(h, be16(values)));
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.hu, (std::vector<int>{0, 1, 32767, 32767, 32767, 32767, 7, 1000}));
  EXPECT_EQ(r.volume.saturated, 3u);
  expect_vec(r.volume.axis_x, Vec3{0, 1, 0});
  expect_vec(r.volume.axis_y, Vec3{-1, 0, 0});
  expect_vec(r.volume.spacing, Vec3{0.6, 0.8, 1.5});
  EXPECT_TRUE(r.info.big_endian);
  EXPECT_STREQ(r.info.stored_type, "uint16");
}

TEST(CtNrrd, ReadsBytesFloatsAndInts) {
  {
    std::string h = "NRRD0001\ntype: uchar\ndimension: 3\nsizes: 2 1 1\nencoding: raw\n\n";
    Result r = read_format(CtFormat::kNrrd, cat(h, {200, 3}));
    ASSERT_TRUE(r.status.is_ok()) << message(r.status);
    EXPECT_EQ(r.hu, (std::vector<int>{200, 3}));
    expect_vec(r.volume.spacing, Vec3{1, 1, 1});  // no spacing given: 1 mm
  }
  {
    std::string h =
        "NRRD0004\ntype: float\ndimension: 3\nsizes: 5 1 1\nspacings: 1 1 2\n"
        "endian: little\nencoding: raw\n\n";
    Result r = read_format(CtFormat::kNrrd, cat(h, le_f32({2.5f, -2.5f, 1e6f, -1e9f, 0.4f})));
    ASSERT_TRUE(r.status.is_ok()) << message(r.status);
    EXPECT_EQ(r.hu, (std::vector<int>{3, -3, 32767, -32768, 0}));
    EXPECT_EQ(r.volume.saturated, 2u);
    EXPECT_EQ(r.volume.spacing.z, 2.0);
  }
  {
    std::string h =
        "NRRD0004\ntype: int32\ndimension: 3\nsizes: 2 1 1\n"
        "endian: little\nencoding: raw\n\n";
    std::vector<uint8_t> d = {0x00, 0x00, 0x01, 0x00, 0xFF, 0xFF, 0xFF, 0xFF};
    Result r = read_format(CtFormat::kNrrd, cat(h, d));
    ASSERT_TRUE(r.status.is_ok()) << message(r.status);
    EXPECT_EQ(r.hu, (std::vector<int>{32767, -1}));
  }
}

TEST(CtNrrd, NonFiniteFloatNamesTheVoxel) {
  std::string h =
      "NRRD0004\ntype: float\ndimension: 3\nsizes: 3 1 1\n"
      "endian: little\nencoding: raw\n\n";
  Result r = read_format(CtFormat::kNrrd, cat(h, le_f32({1.0f, 2.0f, std::nanf("")})));
  EXPECT_EQ(r.status.code(), StatusCode::kNonFinite);
  EXPECT_EQ(r.status.index(), 2u);
}

TEST(CtNrrd, ReadsDetachedDataWithSkips) {
  std::string h =
      "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 1\nendian: little\nencoding: raw\n"
      "data file: vol.raw\nline skip: 2\nbyte skip: 3\n";
  std::vector<uint8_t> raw = test::to_bytes("first\nsecond\nXYZ");
  std::vector<uint8_t> values = le16({1, -2, 3, -4});
  raw.insert(raw.end(), values.begin(), values.end());
  raw.push_back(0x55);  // trailing bytes are allowed
  std::vector<CtMemoryFile> files = {{"vol.raw", raw.data(), raw.size()}};
  Result r = read_format(CtFormat::kNrrd, test::to_bytes(h), files);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.hu, (std::vector<int>{1, -2, 3, -4}));
  EXPECT_TRUE(r.info.detached);

  // byte skip -1: the data ends the file.
  std::string h2 =
      "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 1\nendian: little\n"
      "encoding: raw\ndata file: end.raw\nbyte skip: -1\n";
  std::vector<uint8_t> raw2 = test::to_bytes("some header of another program");
  raw2.insert(raw2.end(), values.begin(), values.end());
  std::vector<CtMemoryFile> files2 = {{"end.raw", raw2.data(), raw2.size()}};
  Result r2 = read_format(CtFormat::kNrrd, test::to_bytes(h2), files2);
  ASSERT_TRUE(r2.status.is_ok()) << message(r2.status);
  EXPECT_EQ(r2.hu, (std::vector<int>{1, -2, 3, -4}));

  // A missing data file is an I/O error naming it.
  Result r3 = read_format(CtFormat::kNrrd, test::to_bytes(h2), {});
  EXPECT_EQ(r3.status.code(), StatusCode::kIoError);
  EXPECT_NE(message(r3.status).find("end.raw"), std::string::npos);
  // Detached data shorter than the header says.
  std::vector<CtMemoryFile> short_files = {{"end.raw", raw2.data(), 5}};
  Result r4 = read_format(CtFormat::kNrrd, test::to_bytes(h2), short_files);
  EXPECT_EQ(r4.status.code(), StatusCode::kTruncated);
  EXPECT_STREQ(r4.status.file(), "end.raw");
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  size_t at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

TEST(CtNrrd, RejectsUnsupportedAndBadHeadersWithFileAndLine) {
  const std::vector<uint8_t> data = le16(ramp(24, 0, 1));
  struct Case {
    std::string from, to;
    StatusCode code;
    const char* text;
    uint64_t line;
  };
  const Case cases[] = {
      {"encoding: raw", "encoding: bzip2", StatusCode::kUnsupported, "bzip2", 10},
      {"encoding: raw", "encoding: ascii", StatusCode::kUnsupported, "ascii", 10},
      {"dimension: 3", "dimension: 4", StatusCode::kUnsupported, "dimension 4", 4},
      {"type: short", "type: int64", StatusCode::kUnsupported, "int64", 3},
      {"type: short\n", "", StatusCode::kParseError, "missing field \"type\"", 12},
      {"endian: little\n", "", StatusCode::kParseError, "endian", 12},
      {"(0,0,2.5)", "(0,0,0)", StatusCode::kParseError, "spacing along z", 7},
      {"(0,0,2.5)", "(0,0,250)", StatusCode::kParseError, "wrong units?", 7},
      {"(0,0,2.5)", "(0,0.1,2.5)", StatusCode::kParseError, "orthogonal", 7},
      {"(0,0,2.5)", "(0,0,nan)", StatusCode::kParseError, "space directions", 7},
      {"sizes: 2 3 4", "sizes: 2 3", StatusCode::kParseError, "sizes", 6},
      {"sizes: 2 3 4", "sizes: 2 0 4", StatusCode::kParseError, "sizes", 6},
      {"NRRD0004", "NRRD0009", StatusCode::kParseError, "not a NRRD file", 1},
      {"space origin: (-10,20.5,3)", "space origin (1,2,3)", StatusCode::kParseError,
       "field: value", 11},
  };
  for (const Case& c : cases) {
    Result r = read_format(CtFormat::kNrrd, cat(replace(kNrrdHeader, c.from, c.to), data));
    EXPECT_EQ(r.status.code(), c.code) << c.to << ": " << message(r.status);
    EXPECT_NE(message(r.status).find(c.text), std::string::npos) << message(r.status);
    EXPECT_EQ(r.status.line(), c.line) << c.to << ": " << message(r.status);
    EXPECT_STREQ(r.status.file(), "test.hdr");
  }
}

TEST(CtNrrd, LyingSizesAndOverflowingDimensions) {
  // More voxels than bytes: truncated before anything is allocated.
  TestArena arena(size_t{1} << 20);
  std::string lying = replace(kNrrdHeader, "sizes: 2 3 4", "sizes: 200 300 4");
  Result r = read_format(CtFormat::kNrrd, cat(lying, le16(ramp(24, 0, 1))), {}, 0, CtReadOptions{},
                         &arena.arena);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << message(r.status);
  EXPECT_EQ(arena.arena.high_water(), 0u);

  std::string huge = replace(kNrrdHeader, "sizes: 2 3 4", "sizes: 5000 2 2");
  r = read_format(CtFormat::kNrrd, cat(huge, le16(ramp(24, 0, 1))));
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << message(r.status);

  CtReadOptions unlimited;
  unlimited.max_dimension = 0xFFFFFFFFu;
  unlimited.max_voxels = ~uint64_t{0};
  std::string overflow =
      replace(kNrrdHeader, "sizes: 2 3 4", "sizes: 4294967295 4294967295 4294967295");
  r = read_format(CtFormat::kNrrd, cat(overflow, le16(ramp(24, 0, 1))), {}, 0, unlimited);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << message(r.status);
}

TEST(CtNrrd, ArenaTooSmallFailsBeforeAllocating) {
  std::string h = replace(kNrrdHeader, "sizes: 2 3 4", "sizes: 64 64 4");
  std::vector<uint8_t> bytes = cat(h, le16(std::vector<int>(64 * 64 * 4, 5)));
  TestArena small(20000);
  Result r = read_format(CtFormat::kNrrd, bytes, {}, 0, CtReadOptions{}, &small.arena);
  EXPECT_EQ(r.status.code(), StatusCode::kArenaExhausted);
  EXPECT_NE(message(r.status).find("32768 for the voxels"), std::string::npos) << message(r.status);
  EXPECT_EQ(small.arena.high_water(), 0u);
  // Enough: only the voxels stay in the arena.
  TestArena enough(32768 + 65536 + 64);
  r = read_format(CtFormat::kNrrd, bytes, {}, 0, CtReadOptions{}, &enough.arena);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(enough.arena.used(), 32768u);
}

TEST(CtNrrd, TruncationAtEveryOffsetIsAnError) {
  const std::vector<uint8_t> full = cat(kNrrdHeader, le16(ramp(24, 0, 1)));
  for (size_t n = 0; n < full.size(); ++n) {
    std::vector<uint8_t> prefix(full.begin(), full.begin() + static_cast<long>(n));
    for (size_t chunk : {size_t{0}, size_t{1}}) {
      Result r = read_format(CtFormat::kNrrd, prefix, {}, chunk);
      EXPECT_FALSE(r.status.is_ok()) << n;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// MetaImage.

const char* kMhaHeader =
    "ObjectType = Image\n"
    "NDims = 3\n"
    "BinaryData = True\n"
    "BinaryDataByteOrderMSB = False\n"
    "CompressedData = False\n"
    "TransformMatrix = 0 1 0 1 0 0 0 0 -1\n"
    "Offset = 1.5 -2 100\n"
    "CenterOfRotation = 0 0 0\n"
    "AnatomicalOrientation = RAI\n"
    "ElementSpacing = 0.3 0.4 1.25\n"
    "DimSize = 3 2 2\n"
    "ElementType = MET_SHORT\n"
    "ElementDataFile = LOCAL\n";

TEST(CtMetaImage, ReadsInlineShortsWithTransform) {
  const std::vector<int> values = ramp(12, -2048, 401);
  Result r = read_format(CtFormat::kMetaImage, cat(kMhaHeader, le16(values)));
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.hu, values);
  EXPECT_EQ(r.volume.nx, 3u);
  EXPECT_EQ(r.volume.nz, 2u);
  expect_vec(r.volume.axis_x, Vec3{0, 1, 0});
  expect_vec(r.volume.axis_y, Vec3{1, 0, 0});
  expect_vec(r.volume.axis_z, Vec3{0, 0, -1});
  expect_vec(r.volume.spacing, Vec3{0.3, 0.4, 1.25});
  expect_vec(r.volume.origin, Vec3{1.5, -2, 100});
  EXPECT_STREQ(r.info.space, "RAI");
  EXPECT_EQ(r.info.format, CtFormat::kMetaImage);
}

TEST(CtMetaImage, ReadsBigEndianFloatAndDetachedWithHeaderSize) {
  std::string h =
      replace(kMhaHeader, "BinaryDataByteOrderMSB = False", "ElementByteOrderMSB = True");
  h = replace(h, "MET_SHORT", "MET_USHORT");
  Result r = read_format(CtFormat::kMetaImage, cat(h, be16(ramp(12, 0, 1000))));
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.hu, ramp(12, 0, 1000));

  std::string d = replace(kMhaHeader, "ElementDataFile = LOCAL", "ElementDataFile = v.raw");
  d = replace(d, "MET_SHORT", "MET_FLOAT");
  d = replace(d, "ObjectType = Image\n", "ObjectType = Image\nHeaderSize = 4\n");
  std::vector<uint8_t> raw = {9, 9, 9, 9};
  std::vector<uint8_t> f = le_f32({0.5f, 1.5f, -0.5f, 10, 11, 12, 13, 14, 15, 16, 17, 18.49f});
  raw.insert(raw.end(), f.begin(), f.end());
  std::vector<CtMemoryFile> files = {{"v.raw", raw.data(), raw.size()}};
  r = read_format(CtFormat::kMetaImage, test::to_bytes(d), files);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.hu, (std::vector<int>{1, 2, -1, 10, 11, 12, 13, 14, 15, 16, 17, 18}));
  EXPECT_TRUE(r.info.detached);
}

TEST(CtMetaImage, RejectsUnsupportedAndBadHeaders) {
  const std::vector<uint8_t> data = le16(ramp(12, 0, 1));
  struct Case {
    std::string from, to;
    StatusCode code;
    const char* text;
  };
  const Case cases[] = {
      {"CompressedData = False", "CompressedData = True", StatusCode::kUnsupported, "compressed"},
      {"ElementDataFile = LOCAL", "ElementDataFile = LIST", StatusCode::kUnsupported, "LIST"},
      {"ElementDataFile = LOCAL", "ElementDataFile = s%03d.raw 1 2 1", StatusCode::kUnsupported,
       "pattern"},
      {"NDims = 3", "NDims = 2", StatusCode::kUnsupported, "NDims 2"},
      {"MET_SHORT", "MET_LONG_LONG", StatusCode::kUnsupported, "ElementType"},
      {"BinaryData = True", "BinaryData = False", StatusCode::kUnsupported, "binary"},
      {"ElementSpacing = 0.3 0.4 1.25", "ElementSpacing = 0.3 -0.4 1.25", StatusCode::kParseError,
       "spacing along y"},
      {"ElementSpacing = 0.3 0.4 1.25", "ElementSpacing = 300 0.4 1.25", StatusCode::kParseError,
       "wrong units?"},
      {"TransformMatrix = 0 1 0 1 0 0 0 0 -1", "TransformMatrix = 0 1 0 1 0 0 0 0 -2",
       StatusCode::kParseError, "length"},
      {"DimSize = 3 2 2\n", "", StatusCode::kParseError, "DimSize"},
      {"ElementDataFile = LOCAL\n", "", StatusCode::kParseError, "Key = Value"},  // data as text
      {"ObjectType = Image", "ObjectType = Mesh", StatusCode::kUnsupported, "Mesh"},
      {"Offset = 1.5 -2 100", "Offset 1.5 -2 100", StatusCode::kParseError, "Key = Value"},
  };
  Result eof = read_format(CtFormat::kMetaImage,
                           test::to_bytes(replace(kMhaHeader, "ElementDataFile = LOCAL\n", "")));
  EXPECT_EQ(eof.status.code(), StatusCode::kTruncated);
  EXPECT_NE(message(eof.status).find("ElementDataFile"), std::string::npos);
  for (const Case& c : cases) {
    Result r = read_format(CtFormat::kMetaImage, cat(replace(kMhaHeader, c.from, c.to), data));
    EXPECT_EQ(r.status.code(), c.code) << c.to << ": " << message(r.status);
    EXPECT_NE(message(r.status).find(c.text), std::string::npos) << message(r.status);
    EXPECT_NE(r.status.line(), kNoPosition) << message(r.status);
  }
}

TEST(CtMetaImage, TruncationAtEveryOffsetIsAnError) {
  const std::vector<uint8_t> full = cat(kMhaHeader, le16(ramp(12, 0, 1)));
  for (size_t n = 0; n < full.size(); ++n) {
    std::vector<uint8_t> prefix(full.begin(), full.begin() + static_cast<long>(n));
    Result r = read_format(CtFormat::kMetaImage, prefix, {}, n % 3);
    EXPECT_FALSE(r.status.is_ok()) << n;
  }
}

// ---------------------------------------------------------------------------------------------
// DICOM.

struct DicomSpec {
  bool implicit = false;
  std::string syntax;  // empty: from `implicit`
  uint32_t rows = 2, columns = 3;
  uint32_t bits_allocated = 16, bits_stored = 16;
  uint32_t pixel_representation = 1;
  std::string photometric = "MONOCHROME2";
  std::string position = "0\\0\\0";
  std::string orientation = "1\\0\\0\\0\\1\\0";
  std::string pixel_spacing = "0.5\\0.25";
  std::string slope, intercept;  // empty: absent
  std::string thickness;         // empty: absent
  std::string frames;            // empty: absent
  std::vector<uint8_t> pixels;   // raw stored bytes
  bool sequences = false;        // add skipped sequences (defined/undefined, UN)
  int nesting = 0;               // > 0: undefined-length sequences nested this deep
  bool encapsulated = false;
  std::vector<uint32_t> omit;  // tags left out
};

struct DicomWriter {
  std::vector<uint8_t> b;
  bool implicit = false;
  void u16(uint32_t v) {
    b.push_back(static_cast<uint8_t>(v));
    b.push_back(static_cast<uint8_t>(v >> 8));
  }
  void u32(uint32_t v) {
    u16(v & 0xFFFF);
    u16(v >> 16);
  }
  void header(uint32_t g, uint32_t e, const char* vr, uint32_t length, bool force_explicit) {
    u16(g);
    u16(e);
    if (implicit && !force_explicit) {
      u32(length);
      return;
    }
    b.push_back(static_cast<uint8_t>(vr[0]));
    b.push_back(static_cast<uint8_t>(vr[1]));
    const std::string v(vr);
    if (v == "OB" || v == "OW" || v == "SQ" || v == "UN" || v == "UT") {
      u16(0);
      u32(length);
    } else {
      u16(length);
    }
  }
  void bytes(uint32_t g, uint32_t e, const char* vr, std::vector<uint8_t> d,
             bool force_explicit = false) {
    if (d.size() % 2 == 1) d.push_back(std::string(vr) == "UI" ? 0 : ' ');
    header(g, e, vr, static_cast<uint32_t>(d.size()), force_explicit);
    b.insert(b.end(), d.begin(), d.end());
  }
  void str(uint32_t g, uint32_t e, const char* vr, const std::string& s, bool fe = false) {
    bytes(g, e, vr, std::vector<uint8_t>(s.begin(), s.end()), fe);
  }
  void us(uint32_t g, uint32_t e, uint32_t v) {
    bytes(g, e, "US", {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)});
  }
  void tag_only(uint32_t g, uint32_t e, uint32_t length) {
    u16(g);
    u16(e);
    u32(length);
  }
};

bool omitted(const DicomSpec& s, uint32_t tag) {
  for (uint32_t t : s.omit) {
    if (t == tag) return true;
  }
  return false;
}

std::vector<uint8_t> dicom_file(const DicomSpec& s) {
  DicomWriter w;
  w.b.assign(128, 0);
  w.b.insert(w.b.end(), {'D', 'I', 'C', 'M'});
  const std::string syntax =
      !s.syntax.empty() ? s.syntax : (s.implicit ? "1.2.840.10008.1.2" : "1.2.840.10008.1.2.1");
  w.bytes(0x0002, 0x0000, "UL", {0, 0, 0, 0}, true);  // group length (not trusted)
  w.bytes(0x0002, 0x0001, "OB", {0, 1}, true);
  w.str(0x0002, 0x0002, "UI", "1.2.840.10008.5.1.4.1.1.2", true);
  if (!omitted(s, 0x00020010)) w.str(0x0002, 0x0010, "UI", syntax, true);
  w.implicit = s.implicit;
  w.str(0x0008, 0x0060, "CS", "CT");
  if (s.sequences) {
    // (0008,1140) Referenced Image Sequence, undefined length, with a decoy Rows inside an
    // undefined-length item and a defined-length item.
    w.header(0x0008, 0x1140, "SQ", 0xFFFFFFFFu, false);
    w.tag_only(0xFFFE, 0xE000, 0xFFFFFFFFu);
    w.us(0x0028, 0x0010, 999);
    w.tag_only(0xFFFE, 0xE00D, 0);
    w.tag_only(0xFFFE, 0xE000, 4);
    w.u32(0xDEADBEEF);
    w.tag_only(0xFFFE, 0xE0DD, 0);
    // A defined-length sequence with garbage inside (skipped whole).
    w.header(0x0008, 0x1150, "SQ", 6, false);
    w.b.insert(w.b.end(), {0xFF, 0xFF, 0xFF, 0xFF, 0x01, 0x02});
    if (!s.implicit) {
      // UN of undefined length: its content is implicit VR.
      w.header(0x0009, 0x1001, "UN", 0xFFFFFFFFu, false);
      w.tag_only(0xFFFE, 0xE000, 0xFFFFFFFFu);
      w.tag_only(0x0028, 0x0011, 2);
      w.u16(777);
      w.tag_only(0xFFFE, 0xE00D, 0);
      w.tag_only(0xFFFE, 0xE0DD, 0);
    }
  }
  for (int d = 0; d < s.nesting; ++d) {
    w.header(0x0008, 0x1140, "SQ", 0xFFFFFFFFu, false);
    w.tag_only(0xFFFE, 0xE000, 0xFFFFFFFFu);
  }
  for (int d = 0; d < s.nesting; ++d) {
    w.tag_only(0xFFFE, 0xE00D, 0);
    w.tag_only(0xFFFE, 0xE0DD, 0);
  }
  if (!s.thickness.empty()) w.str(0x0018, 0x0050, "DS", s.thickness);
  w.str(0x0020, 0x0013, "IS", "1");
  if (!omitted(s, 0x00200032)) w.str(0x0020, 0x0032, "DS", s.position);
  if (!omitted(s, 0x00200037)) w.str(0x0020, 0x0037, "DS", s.orientation);
  w.us(0x0028, 0x0002, 1);
  if (!omitted(s, 0x00280004)) w.str(0x0028, 0x0004, "CS", s.photometric);
  if (!s.frames.empty()) w.str(0x0028, 0x0008, "IS", s.frames);
  if (!omitted(s, 0x00280010)) w.us(0x0028, 0x0010, s.rows);
  if (!omitted(s, 0x00280011)) w.us(0x0028, 0x0011, s.columns);
  if (!omitted(s, 0x00280030)) w.str(0x0028, 0x0030, "DS", s.pixel_spacing);
  if (!omitted(s, 0x00280100)) w.us(0x0028, 0x0100, s.bits_allocated);
  w.us(0x0028, 0x0101, s.bits_stored);
  if (!omitted(s, 0x00280103)) w.us(0x0028, 0x0103, s.pixel_representation);
  if (!s.intercept.empty()) w.str(0x0028, 0x1052, "DS", s.intercept);
  if (!s.slope.empty()) w.str(0x0028, 0x1053, "DS", s.slope);
  if (s.encapsulated) {
    w.header(0x7FE0, 0x0010, "OB", 0xFFFFFFFFu, false);
    w.tag_only(0xFFFE, 0xE000, 0);
    w.tag_only(0xFFFE, 0xE0DD, 0);
  } else if (!omitted(s, 0x7FE00010)) {
    std::vector<uint8_t> px = s.pixels;
    const size_t needed = size_t{s.rows} * s.columns * (s.bits_allocated / 8);
    if (px.empty()) px.assign(needed, 0);
    w.bytes(0x7FE0, 0x0010, s.bits_allocated == 8 ? "OB" : "OW", px);
  }
  return w.b;
}

struct SeriesResult {
  Status status;
  CtVolume volume;
  CtInfo info;
  std::vector<int> hu;
};

SeriesResult read_series(const std::vector<std::vector<uint8_t>>& files, size_t max_chunk = 0,
                         const CtReadOptions& options = CtReadOptions{}, Arena* arena = nullptr,
                         const Progress* progress = nullptr) {
  static TestArena* shared = new TestArena(size_t{16} << 20);
  Arena& a = arena != nullptr ? *arena : shared->arena;
  if (arena == nullptr) a.reset();
  std::vector<std::string> names;
  for (size_t i = 0; i < files.size(); ++i) names.push_back("f" + std::to_string(i) + ".dcm");
  std::vector<CtMemoryFile> mem;
  for (size_t i = 0; i < files.size(); ++i) {
    mem.push_back({names[i].c_str(), files[i].data(), files[i].size()});
  }
  CtMemoryFiles m{mem.data(), static_cast<uint32_t>(mem.size()), max_chunk, {}};
  Context ctx(&a, nullptr, progress);
  SeriesResult r;
  r.status = read_dicom_series(ctx, ct_memory_series(&m), options, &r.volume, &r.info);
  if (r.status.is_ok()) {
    for (uint64_t i = 0; i < r.volume.voxel_count(); ++i) r.hu.push_back(r.volume.hu[i]);
  }
  return r;
}

// Slice k of a 3-slice series: 2 x 3 pixels, values 100 k + i.
DicomSpec slice(int k, double z, bool implicit = false) {
  DicomSpec s;
  s.implicit = implicit;
  s.position = "10\\-20\\" + std::to_string(z);
  s.pixels = le16(ramp(6, 100 * k, 1));
  return s;
}

TEST(CtDicom, OrdersSlicesByPositionNotByFile) {
  for (bool implicit : {false, true}) {
    // Files in the order z = 5, -1, 2 (slices 2, 0, 1).
    std::vector<std::vector<uint8_t>> files = {dicom_file(slice(2, 5, implicit)),
                                               dicom_file(slice(0, -1, implicit)),
                                               dicom_file(slice(1, 2, implicit))};
    SeriesResult r = read_series(files);
    ASSERT_TRUE(r.status.is_ok()) << message(r.status);
    EXPECT_EQ(r.volume.nx, 3u);
    EXPECT_EQ(r.volume.ny, 2u);
    EXPECT_EQ(r.volume.nz, 3u);
    std::vector<int> expected;
    for (int k = 0; k < 3; ++k) {
      for (int i = 0; i < 6; ++i) expected.push_back(100 * k + i);
    }
    EXPECT_EQ(r.hu, expected);
    // Pixel Spacing is row spacing (y) then column spacing (x).
    expect_vec(r.volume.spacing, Vec3{0.25, 0.5, 3});
    expect_vec(r.volume.origin, Vec3{10, -20, -1});
    expect_vec(r.volume.axis_z, Vec3{0, 0, 1});
    EXPECT_STREQ(r.info.transfer_syntax, implicit ? "1.2.840.10008.1.2" : "1.2.840.10008.1.2.1");
    EXPECT_EQ(r.info.slice_count, 3u);
    EXPECT_STREQ(r.info.photometric, "MONOCHROME2");
  }
}

TEST(CtDicom, DecreasingPositionsAndObliqueOrientation) {
  // Rows along (0,1,0), columns along (0,0,-1): the normal is (-1,0,0); slices at x = 4, 2, 0
  // lie at increasing positions along it in file order 0, 1, 2.
  std::vector<std::vector<uint8_t>> files;
  for (int k = 0; k < 3; ++k) {
    DicomSpec s;
    s.orientation = "0\\1\\0\\0\\0\\-1";
    s.position = std::to_string(4 - 2 * k) + "\\7\\8";
    s.pixels = le16(ramp(6, 10 * k, 1));
    files.push_back(dicom_file(s));
  }
  std::swap(files[0], files[2]);
  SeriesResult r = read_series(files);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  expect_vec(r.volume.axis_x, Vec3{0, 1, 0});
  expect_vec(r.volume.axis_y, Vec3{0, 0, -1});
  expect_vec(r.volume.axis_z, Vec3{-1, 0, 0});
  expect_vec(r.volume.origin, Vec3{4, 7, 8});
  EXPECT_EQ(r.volume.spacing.z, 2.0);
  EXPECT_EQ(r.volume.at(0, 0, 0), 0);
  EXPECT_EQ(r.volume.at(0, 0, 2), 20);
}

TEST(CtDicom, PixelFormatsAndRescale) {
  {  // 8-bit unsigned, slope and intercept, rounding halves away from zero.
    DicomSpec s;
    s.bits_allocated = 8;
    s.bits_stored = 8;
    s.pixel_representation = 0;
    s.rows = 1;
    s.columns = 3;  // 3 bytes: padded to 4
    s.pixels = {0, 3, 255};
    s.slope = "2.5";
    s.intercept = "-1024";
    s.thickness = "1.5";
    s.photometric = "MONOCHROME1";
    SeriesResult r = read_series({dicom_file(s)});
    ASSERT_TRUE(r.status.is_ok()) << message(r.status);
    EXPECT_EQ(r.hu, (std::vector<int>{-1024, -1017, -387}));  // 7.5 - 1024 = -1016.5 -> -1017
    EXPECT_EQ(r.volume.spacing.z, 1.5);
    EXPECT_STREQ(r.info.stored_type, "uint8");
    EXPECT_EQ(r.info.slope, 2.5);
  }
  {  // 16-bit signed with 12 bits stored: high bits ignored, sign-extended.
    DicomSpec s;
    s.bits_stored = 12;
    s.rows = 1;
    s.columns = 3;
    s.pixels = le16({0xF800, 0x07FF, 0xA001});  // -2048, 2047, 1
    s.thickness = "1";
    SeriesResult r = read_series({dicom_file(s)});
    ASSERT_TRUE(r.status.is_ok()) << message(r.status);
    EXPECT_EQ(r.hu, (std::vector<int>{-2048, 2047, 1}));
    EXPECT_EQ(r.info.bits_stored, 12u);
  }
  {  // Unsigned 16-bit with intercept -32768 covers the int16 range; slope saturates.
    DicomSpec s;
    s.pixel_representation = 0;
    s.rows = 1;
    s.columns = 2;
    s.pixels = le16({0, 65535});
    s.intercept = "-32768";
    s.thickness = "1";
    SeriesResult r = read_series({dicom_file(s)});
    ASSERT_TRUE(r.status.is_ok()) << message(r.status);
    EXPECT_EQ(r.hu, (std::vector<int>{-32768, 32767}));
    EXPECT_EQ(r.volume.saturated, 0u);
    s.slope = "2";
    r = read_series({dicom_file(s)});
    ASSERT_TRUE(r.status.is_ok()) << message(r.status);
    EXPECT_EQ(r.volume.saturated, 1u);
  }
}

TEST(CtDicom, SkipsSequencesOfDefinedAndUndefinedLength) {
  for (bool implicit : {false, true}) {
    DicomSpec s = slice(0, 0, implicit);
    s.sequences = true;
    s.thickness = "2";
    SeriesResult r = read_series({dicom_file(s)});
    ASSERT_TRUE(r.status.is_ok()) << message(r.status);
    EXPECT_EQ(r.volume.ny, 2u);  // not the decoy 999 inside the sequence
    EXPECT_EQ(r.volume.nx, 3u);
  }
  DicomSpec deep = slice(0, 0);
  deep.thickness = "2";
  deep.nesting = 10;
  EXPECT_TRUE(read_series({dicom_file(deep)}).status.is_ok());
  deep.nesting = 40;
  SeriesResult r = read_series({dicom_file(deep)});
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << message(r.status);
  EXPECT_NE(message(r.status).find("nested"), std::string::npos);
}

TEST(CtDicom, UnsupportedTransferSyntaxes) {
  // (1.2.840.10008.1.2.1.99, deflated, is read: tests/ct/dicom_deflate_test.cpp; RLE, big
  // endian and JPEG lossless: tests/ct/dicom_codecs_test.cpp.)
  for (const char* uid : {"1.2.840.10008.1.2.4.50", "1.2.840.10008.1.2.4.51", "1.2.3.4"}) {
    DicomSpec s = slice(0, 0);
    s.syntax = uid;
    SeriesResult r = read_series({dicom_file(s)});
    EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
    EXPECT_NE(message(r.status).find(std::string("unsupported transfer syntax ") + uid),
              std::string::npos)
        << message(r.status);
    EXPECT_STREQ(r.status.file(), "f0.dcm");
  }
  DicomSpec e = slice(0, 0);
  e.encapsulated = true;
  SeriesResult r = read_series({dicom_file(e)});
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_NE(message(r.status).find("(7FE0,0010)"), std::string::npos) << message(r.status);
}

TEST(CtDicom, SeriesGeometryErrors) {
  auto three = [](double z0, double z1, double z2) {
    return std::vector<std::vector<uint8_t>>{dicom_file(slice(0, z0)), dicom_file(slice(1, z1)),
                                             dicom_file(slice(2, z2))};
  };
  // Uneven spacing is resampled (CtDicomResample); with resampling off it is refused.
  CtReadOptions strict;
  strict.resample_max_gap = 0;
  SeriesResult r = read_series(three(0, 1, 3), 0, strict);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_NE(message(r.status).find("non-uniform slice spacing"), std::string::npos)
      << message(r.status);
  // Within tolerance (1%): fine.
  EXPECT_TRUE(read_series(three(0, 1.005, 2)).status.is_ok());
  r = read_series(three(0, 1, 1));
  EXPECT_FALSE(r.status.is_ok());
  EXPECT_NE(message(r.status).find("duplicate"), std::string::npos) << message(r.status);
  // Gantry tilt: positions drift in y.
  std::vector<std::vector<uint8_t>> tilt;
  for (int k = 0; k < 3; ++k) {
    DicomSpec s = slice(k, k);
    s.position = "10\\" + std::to_string(-20 + 0.5 * k) + "\\" + std::to_string(k);
    tilt.push_back(dicom_file(s));
  }
  r = read_series(tilt, 0, strict);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_NE(message(r.status).find("gantry tilt"), std::string::npos) << message(r.status);
  // Mismatched slices.
  std::vector<std::vector<uint8_t>> mixed = three(0, 1, 2);
  DicomSpec other = slice(1, 1);
  other.pixel_spacing = "0.5\\0.3";
  mixed[1] = dicom_file(other);
  r = read_series(mixed);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_NE(message(r.status).find("Pixel Spacing"), std::string::npos) << message(r.status);
  EXPECT_STREQ(r.status.file(), "f1.dcm");
  // Non-orthogonal orientation.
  DicomSpec skew = slice(0, 0);
  skew.orientation = "1\\0\\0\\0.6\\0.8\\0";
  r = read_series({dicom_file(skew)});
  EXPECT_FALSE(r.status.is_ok());
  EXPECT_NE(message(r.status).find("orthogonal"), std::string::npos) << message(r.status);
  // One slice without a thickness.
  r = read_series({dicom_file(slice(0, 0))});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_STREQ(r.status.file(), "f0.dcm");
  // Absurd pixel spacing.
  DicomSpec units = slice(0, 0);
  units.thickness = "1";
  units.pixel_spacing = "500\\500";
  r = read_series({dicom_file(units)});
  EXPECT_NE(message(r.status).find("wrong units?"), std::string::npos) << message(r.status);
  EXPECT_STREQ(r.status.file(), "f0.dcm");
  // Resampled onto 4 slices (0, 1, 2, 3 mm): within a max_dimension of 4, not of 3.
  CtReadOptions limit;
  limit.max_dimension = 4;
  r = read_series(three(0, 1, 3), 0, limit);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.volume.nz, 4u);
  limit.max_dimension = 3;
  r = read_series(three(0, 1, 3), 0, limit);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << message(r.status);
  EXPECT_NE(message(r.status).find("the series has 4 slices, more than the limit 3"),
            std::string::npos)
      << message(r.status);
  // The messages name the pair of slices and their files; the mean spacing when uneven.
  r = read_series(three(0, 1, 1));
  EXPECT_NE(message(r.status).find("duplicate slice position: slices 1 and 2 (series files 1 "
                                   "and 2) are 0 mm apart along the normal"),
            std::string::npos)
      << message(r.status);
  EXPECT_EQ(r.status.index(), 2u);
  r = read_series(three(0, 1, 3), 0, strict);
  EXPECT_NE(message(r.status).find("slices 0 and 1 (series files 0 and 1) are 1 mm apart, the "
                                   "mean spacing is 1.5 mm"),
            std::string::npos)
      << message(r.status);
  // Slices exactly min_spacing apart are distinct; a gap exactly the tolerance off the mean
  // is uniform (0.25 mm, all exact in binary).
  CtReadOptions edge = strict;
  edge.min_spacing = 0.25;  // the column spacing too
  r = read_series(three(0, 0.25, 0.5), 0, edge);
  EXPECT_TRUE(r.status.is_ok()) << message(r.status);
  edge = strict;
  edge.slice_spacing_tolerance_mm = 0.25;
  edge.slice_spacing_tolerance_relative = 0;
  r = read_series(three(0, 1.25, 2), 0, edge);
  EXPECT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.volume.spacing.z, 1.0);
  edge.slice_spacing_tolerance_mm = 0.125;
  r = read_series(three(0, 1.25, 2), 0, edge);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported) << message(r.status);
  // A slice exactly the tolerance off the normal through slice 0 is on it (strict: no
  // resampling).
  std::vector<std::vector<uint8_t>> shifted = three(0, 1, 2);
  DicomSpec off_normal = slice(1, 1);
  off_normal.position = "10\\-19.75\\1";
  shifted[1] = dicom_file(off_normal);
  edge.slice_spacing_tolerance_mm = 0.25;
  r = read_series(shifted, 0, edge);
  EXPECT_TRUE(r.status.is_ok()) << message(r.status);
  edge.slice_spacing_tolerance_mm = 0.125;
  r = read_series(shifted, 0, edge);
  EXPECT_NE(message(r.status).find("slice 1 (series file 1) lies 0.25 mm off the normal"),
            std::string::npos)
      << message(r.status);
}

// Edges of the series read: the file an orientation error names, slices that differ by
// exactly the tolerance, rescale_varies, Pixel Data one odd byte long or twice too long, and
// the progress of the header and pixel passes (each ends at every file; a cancel stops it).
TEST(CtDicom, SeriesEdges) {
  DicomSpec skew = slice(0, 0);
  skew.orientation = "1\\0\\0\\0.6\\0.8\\0";
  SeriesResult r = read_series({dicom_file(skew)});
  EXPECT_NE(message(r.status).find("orthogonal"), std::string::npos) << message(r.status);
  EXPECT_STREQ(r.status.file(), "f0.dcm");
  EXPECT_EQ(r.status.index(), 0u);

  // Slice 1's column spacing 2^-10 off slice 0's (exact in binary, as is the difference).
  std::vector<std::vector<uint8_t>> files = {dicom_file(slice(0, 0)), {}, dicom_file(slice(2, 2))};
  DicomSpec off = slice(1, 1);
  off.pixel_spacing = "0.5\\0.2509765625";
  files[1] = dicom_file(off);
  CtReadOptions options;
  options.orientation_tolerance = 0.0009765625;
  r = read_series(files, 0, options);
  EXPECT_TRUE(r.status.is_ok()) << message(r.status);
  options.orientation_tolerance /= 2;
  r = read_series(files, 0, options);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_NE(message(r.status).find("Pixel Spacing"), std::string::npos) << message(r.status);

  // rescale_varies: not for equal slopes and intercepts; for another intercept, or slope.
  for (int which = 0; which < 3; ++which) {
    std::vector<std::vector<uint8_t>> series;
    for (int k = 0; k < 3; ++k) {
      DicomSpec s = slice(k, k);
      s.slope = k == 1 && which == 2 ? "2" : "1";
      s.intercept = k == 1 && which == 1 ? "-1023" : "-1024";
      series.push_back(dicom_file(s));
    }
    r = read_series(series);
    ASSERT_TRUE(r.status.is_ok()) << message(r.status);
    EXPECT_EQ(r.info.rescale_varies, which != 0) << which;
  }

  // 1 x 3 8-bit pixels are 3 bytes: 4 (padded, PixelFormatsAndRescale) are read, 6 are not,
  // and the message has no frames in it.
  DicomSpec odd;
  odd.bits_allocated = 8;
  odd.bits_stored = 8;
  odd.pixel_representation = 0;
  odd.rows = 1;
  odd.columns = 3;
  odd.thickness = "1";
  odd.pixels = {1, 2, 3, 0, 5, 6};
  r = read_series({dicom_file(odd)});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_NE(message(r.status).find("Pixel Data has 6 bytes; rows x columns x bytes per pixel is 3"),
            std::string::npos)
      << message(r.status);

  // Progress of the header and pixel passes; the arena holds the voxels after a read, nothing
  // after a cancel.
  struct Reports {
    std::vector<std::pair<uint64_t, uint64_t>> headers, pixels;
    bool cancel = false;
    static bool report(void* user, const char* stage, uint64_t done, uint64_t total) {
      Reports* self = static_cast<Reports*>(user);
      if (std::string(stage) == "read DICOM headers") self->headers.emplace_back(done, total);
      if (std::string(stage) == "read DICOM pixels") self->pixels.emplace_back(done, total);
      return !self->cancel;
    }
  };
  auto read_reporting = [](const std::vector<std::vector<uint8_t>>& series, bool cancel,
                           Reports* reports) {
    reports->cancel = cancel;
    Progress progress;
    progress.report = &Reports::report;
    progress.user = reports;
    TestArena t(1 << 20);
    const SeriesResult res = read_series(series, 0, CtReadOptions{}, &t.arena, &progress);
    EXPECT_EQ(t.arena.used(), res.status.is_ok() ? res.volume.voxel_count() * 2 : 0u);
    return res.status;
  };
  files = {dicom_file(slice(0, 0)), dicom_file(slice(1, 1)), dicom_file(slice(2, 2))};
  const std::vector<std::pair<uint64_t, uint64_t>> each = {{1, 3}, {2, 3}, {3, 3}};
  Reports reports;
  Status st = read_reporting(files, false, &reports);
  ASSERT_TRUE(st.is_ok()) << message(st);
  EXPECT_EQ(reports.headers, each);
  EXPECT_EQ(reports.pixels, each);
  reports = Reports{};
  st = read_reporting(files, true, &reports);
  EXPECT_EQ(st.code(), StatusCode::kCancelled) << message(st);
  EXPECT_EQ(reports.headers.size(), 1u);
  // A multi-frame file: one header pass over its file, the pixels frame by frame.
  reports = Reports{};
  st = read_reporting({test::ct_fixture("mf16.dcm")}, false, &reports);
  ASSERT_TRUE(st.is_ok()) << message(st);
  EXPECT_EQ(reports.headers, (std::vector<std::pair<uint64_t, uint64_t>>{{1, 1}}));
  EXPECT_EQ(reports.pixels, each);
}

// Geometry as scanners write it (issue 31): exact values on 2 x 3 slices (pixels 100 k + i,
// row spacing 0.5 mm, column spacing 0.25 mm).
TEST(CtDicomResample, UnevenSpacingInterpolatesBetweenNeighbours) {
  // Gaps 1 and 2 mm: median (the lower of two) 1 mm, four output slices; z = 2 is halfway
  // between slices 1 and 2.
  std::vector<std::vector<uint8_t>> files = {dicom_file(slice(2, 3)), dicom_file(slice(0, 0)),
                                             dicom_file(slice(1, 1))};
  SeriesResult r = read_series(files);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.volume.nz, 4u);
  EXPECT_EQ(r.volume.spacing.z, 1.0);
  const std::vector<int> expected = {0,   1,   2,   3,   4,   5,   100, 101, 102, 103, 104, 105,
                                     150, 151, 152, 153, 154, 155, 200, 201, 202, 203, 204, 205};
  EXPECT_EQ(r.hu, expected);
  EXPECT_TRUE(r.info.resampled);
  EXPECT_EQ(r.info.slice_count, 3u);
  EXPECT_EQ(r.info.tilt_degrees, 0.0);
  EXPECT_EQ(r.info.max_shift_mm, 0.0);
  EXPECT_EQ(r.info.max_slice_offset_mm, 1.0);
  expect_vec(r.volume.origin, Vec3{10, -20, 0});
  // Gaps 1 and 1.4 (median 1): output at 0, 1, 2 (0.6 of the way to 2.4); 2.4 is not reached.
  files = {dicom_file(slice(0, 0)), dicom_file(slice(1, 1)), dicom_file(slice(2, 2.4))};
  r = read_series(files);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  ASSERT_EQ(r.volume.nz, 3u);
  EXPECT_EQ(r.hu[12], 171);  // 100 x 0.2857 + 200 x 0.7143 (t = 1 / 1.4), rounded
  EXPECT_NEAR(r.info.max_slice_offset_mm, 0.4, 1e-12);
  // A gap of more than three medians (two slices missing) is refused, naming the slices.
  files = {dicom_file(slice(0, 0)), dicom_file(slice(1, 1)), dicom_file(slice(2, 5))};
  r = read_series(files);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_NE(message(r.status).find("slices too far apart to resample: slices 1 and 2"),
            std::string::npos)
      << message(r.status);
  EXPECT_NE(message(r.status).find("4 mm apart"), std::string::npos) << message(r.status);
  EXPECT_EQ(r.status.index(), 2u);
  // Resampled onto more slices than max_dimension.
  CtReadOptions small;
  small.max_dimension = 3;
  r = read_series({dicom_file(slice(0, 0)), dicom_file(slice(1, 1)), dicom_file(slice(2, 3))}, 0,
                  small);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded);
  EXPECT_NE(message(r.status).find("4 slices, more than the limit 3"), std::string::npos)
      << message(r.status);
}

TEST(CtDicomResample, GantryTiltShiftsEachSliceInPlane) {
  // Positions drift 0.5 mm (one row) along the column direction per 1 mm along the normal:
  // the output grid is centred on slice 1's, slices 0 and 2 move by one row.
  std::vector<std::vector<uint8_t>> files;
  for (int k : {2, 0, 1}) {
    DicomSpec s = slice(k, k);
    s.position = "10\\" + std::to_string(-20 + 0.5 * k) + "\\" + std::to_string(k);
    files.push_back(dicom_file(s));
  }
  SeriesResult r = read_series(files);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.volume.nz, 3u);
  const int air = -1000;
  const std::vector<int> expected = {3,   4,   5,   air, air, air, 100, 101, 102,
                                     103, 104, 105, air, air, air, 200, 201, 202};
  EXPECT_EQ(r.hu, expected);
  expect_vec(r.volume.origin, Vec3{10, -19.5, 0});
  EXPECT_EQ(r.volume.spacing.z, 1.0);
  EXPECT_TRUE(r.info.resampled);
  EXPECT_NEAR(r.info.tilt_degrees, 26.565051177077990, 1e-9);  // atan(0.5)
  EXPECT_EQ(r.info.max_shift_mm, 0.5);
  EXPECT_EQ(r.info.max_slice_offset_mm, 0.0);
  // Half a row per slice: slice 1 is interpolated halfway between two rows; the output is
  // centred on (0 + 0.5) / 2 = 0.25 mm, rounded to 0.5 (one row): slice 0 moves one row, slice 2
  // none.
  files.clear();
  for (int k = 0; k < 3; ++k) {
    DicomSpec s = slice(k, k);
    s.position = "10\\" + std::to_string(-20 + 0.25 * k) + "\\" + std::to_string(k);
    files.push_back(dicom_file(s));
  }
  r = read_series(files);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  const std::vector<int> half = {3,   4,   5,   air, air, air, 102, 103, 104,
                                 air, air, air, 200, 201, 202, 203, 204, 205};
  EXPECT_EQ(r.hu, half);
  // Columns too (shear along x), and a shift of more than the slice: all air.
  files.clear();
  for (int k = 0; k < 3; ++k) {
    DicomSpec s = slice(k, k);
    s.position = std::to_string(10 + 0.25 * k * (k == 2 ? 10 : 1)) + "\\-20\\" + std::to_string(k);
    files.push_back(dicom_file(s));
  }
  r = read_series(files);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(r.volume.nz, 3u);
  EXPECT_EQ(r.hu[0], air);
  for (int v = 12; v < 18; ++v) EXPECT_EQ(r.hu[static_cast<size_t>(v)], air) << v;
}

// Three tilted slices with a gap (four output slices: two reads), and four uneven slices
// resampled onto three (the voxels shrunk to them): at every cap the read succeeds leaving only
// the voxels or fails with kArenaExhausted leaving nothing.
std::vector<std::vector<uint8_t>> tilted_series(const std::vector<double>& z) {
  std::vector<std::vector<uint8_t>> files;
  for (size_t k = 0; k < z.size(); ++k) {
    DicomSpec s = slice(static_cast<int>(k), z[k]);
    s.position = "10\\" + std::to_string(-20 + 0.1 * z[k]) + "\\" + std::to_string(z[k]);
    files.push_back(dicom_file(s));
  }
  return files;
}

TEST(CtArena, ResampledSeriesEveryCapFailsCleanlyOrSucceeds) {
  CtReadOptions o;
  o.chunk_bytes = 1024;
  const std::vector<std::vector<uint8_t>> more = tilted_series({0, 1, 3});
  const std::vector<std::vector<uint8_t>> fewer = tilted_series({0, 1, 1.2, 2});
  size_t smallest[2] = {0, 0};
  for (size_t cap = 1000; cap <= 2600; ++cap) {
    for (int c = 0; c < 2; ++c) {
      TestArena a(cap);
      SeriesResult d = read_series(c == 0 ? more : fewer, 0, o, &a.arena);
      if (d.status.is_ok()) {
        EXPECT_EQ(d.volume.nz, c == 0 ? 4u : 3u);
        EXPECT_EQ(a.arena.used(), d.volume.nz * 12u);  // 2 x 3 voxels a slice
        if (smallest[c] == 0) smallest[c] = cap;
      } else {
        ASSERT_EQ(d.status.code(), StatusCode::kArenaExhausted) << message(d.status);
        EXPECT_EQ(a.arena.used(), 0u);
        EXPECT_EQ(smallest[c], 0u) << cap;  // no failure above the smallest cap that works
      }
    }
  }
  EXPECT_NE(smallest[0], 0u);
  EXPECT_NE(smallest[1], 0u);
}

// A series whose files change between the two reads of a resampled stack (the second finds
// even more output slices) is an error, not a loop.
struct ChangingSeries {
  CtMemoryFiles before, after;
  uint32_t opens = 0, switch_after = 0;
  CtMemoryFiles& now() { return opens <= switch_after ? before : after; }
  static Status open(void* user, uint32_t index, ByteSource* out) {
    ChangingSeries* c = static_cast<ChangingSeries*>(user);
    ++c->opens;
    CtSeries s = ct_memory_series(&c->now());
    return s.open(s.user, index, out);
  }
  static void close(void* user, uint32_t index, ByteSource* source) {
    ChangingSeries* c = static_cast<ChangingSeries*>(user);
    CtSeries s = ct_memory_series(&c->now());
    s.close(s.user, index, source);
  }
};

TEST(CtDicomResample, FilesChangingBetweenTheTwoReadsIsAnError) {
  const std::vector<std::vector<uint8_t>> a = tilted_series({0, 1, 3}),
                                          b = tilted_series({0, 1, 4});
  std::vector<CtMemoryFile> ma, mb;
  const char* names[3] = {"f0.dcm", "f1.dcm", "f2.dcm"};
  for (size_t i = 0; i < 3; ++i) {
    ma.push_back({names[i], a[i].data(), a[i].size()});
    mb.push_back({names[i], b[i].data(), b[i].size()});
  }
  ChangingSeries c;
  c.before = CtMemoryFiles{ma.data(), 3, 0, {}};
  c.after = CtMemoryFiles{mb.data(), 3, 0, {}};
  c.switch_after = 3;  // file 0's header, then files 1 and 2 in the first read
  CtSeries series{3, ChangingSeries::open, ChangingSeries::close, &c};
  TestArena t(size_t{1} << 20);
  Context ctx(&t.arena);
  CtVolume v;
  Status s = read_dicom_series(ctx, series, CtReadOptions{}, &v, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kParseError) << message(s);
  EXPECT_NE(message(s).find("changed between two reads"), std::string::npos) << message(s);
  EXPECT_EQ(t.arena.used(), 0u);
}

TEST(CtDicom, MissingAndBadTags) {
  struct Case {
    uint32_t tag;
    const char* text;
  };
  const Case cases[] = {{0x00280010, "(0028,0010) Rows"}, {0x00280011, "(0028,0011) Columns"},
                        {0x00280100, "Bits Allocated"},   {0x00280103, "Pixel Representation"},
                        {0x00200032, "Image Position"},   {0x00200037, "Image Orientation"},
                        {0x00280030, "Pixel Spacing"},    {0x00280004, "Photometric"},
                        {0x7FE00010, "Pixel Data"},       {0x00020010, "Transfer Syntax"}};
  for (const Case& c : cases) {
    DicomSpec s = slice(0, 0);
    s.thickness = "1";
    s.omit = {c.tag};
    SeriesResult r = read_series({dicom_file(s)});
    EXPECT_EQ(r.status.code(), StatusCode::kParseError) << c.text << ": " << message(r.status);
    EXPECT_NE(message(r.status).find(c.text), std::string::npos) << message(r.status);
    EXPECT_STREQ(r.status.file(), "f0.dcm");
  }
  DicomSpec s = slice(0, 0);
  s.thickness = "1";
  s.frames = "4";
  EXPECT_EQ(read_series({dicom_file(s)}).status.code(), StatusCode::kUnsupported);
  s = slice(0, 0);
  s.thickness = "1";
  s.bits_allocated = 32;
  s.bits_stored = 32;
  EXPECT_EQ(read_series({dicom_file(s)}).status.code(), StatusCode::kUnsupported);
  s = slice(0, 0);
  s.thickness = "1";
  s.photometric = "RGB";
  EXPECT_EQ(read_series({dicom_file(s)}).status.code(), StatusCode::kUnsupported);
  s = slice(0, 0);
  s.thickness = "1";
  s.position = "1\\2";
  SeriesResult r = read_series({dicom_file(s)});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_NE(r.status.byte_offset(), kNoPosition);
  EXPECT_NE(message(r.status).find("(0020,0032)"), std::string::npos) << message(r.status);
  // Pixel Data length that lies about the image size.
  s = slice(0, 0);
  s.thickness = "1";
  s.pixels = le16(ramp(5, 0, 1));
  r = read_series({dicom_file(s)});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_NE(message(r.status).find("Pixel Data has 10 bytes"), std::string::npos)
      << message(r.status);
  // Not DICOM at all.
  r = read_series({std::vector<uint8_t>(300, 7)});
  EXPECT_NE(message(r.status).find("DICM"), std::string::npos);
  // An empty series.
  EXPECT_EQ(read_series({}).status.code(), StatusCode::kInvalidArgument);
}

TEST(CtDicom, RowsAndColumnsOverflowAndArenaTooSmall) {
  DicomSpec s = slice(0, 0);
  s.thickness = "1";
  s.rows = 65535;
  s.columns = 65535;
  s.pixels = {0, 0};
  SeriesResult r = read_series({dicom_file(s)});
  EXPECT_FALSE(r.status.is_ok());  // lying Pixel Data length or limits: never an allocation

  std::vector<std::vector<uint8_t>> files;
  for (int k = 0; k < 3; ++k) {
    DicomSpec big = slice(k, k);
    big.rows = 64;
    big.columns = 64;
    big.pixels = le16(std::vector<int>(64 * 64, k));
    files.push_back(dicom_file(big));
  }
  TestArena small(20000);
  r = read_series(files, 0, CtReadOptions{}, &small.arena);
  EXPECT_EQ(r.status.code(), StatusCode::kArenaExhausted);
  EXPECT_NE(message(r.status).find("24576 for the voxels"), std::string::npos) << message(r.status);
  EXPECT_EQ(small.arena.high_water(), 0u);
  TestArena enough(24576 + 65536 + 1024);
  r = read_series(files, 0, CtReadOptions{}, &enough.arena);
  ASSERT_TRUE(r.status.is_ok()) << message(r.status);
  EXPECT_EQ(enough.arena.used(), 24576u);
  EXPECT_EQ(r.volume.at(5, 5, 2), 2);
}

TEST(CtDicom, TruncationAtEveryOffsetIsAnError) {
  DicomSpec s = slice(0, 0);
  s.thickness = "1";
  s.sequences = true;
  const std::vector<uint8_t> full = dicom_file(s);
  ASSERT_TRUE(read_series({full}).status.is_ok());
  for (size_t n = 0; n < full.size(); ++n) {
    std::vector<uint8_t> prefix(full.begin(), full.begin() + static_cast<long>(n));
    SeriesResult r = read_series({prefix}, n % 4);
    EXPECT_FALSE(r.status.is_ok()) << n;
  }
}

// ---------------------------------------------------------------------------------------------
// The fuzz seeds (tests/fuzz/ct_corpus.py) are valid files: the fuzzers start from reads that
// succeed. DICOM seeds may hold a series joined by the fuzz target's separator; detached NRRD
// and MetaImage seeds get their own bytes as the data file (as in the fuzz targets).

std::vector<std::vector<uint8_t>> split_series(const std::vector<uint8_t>& bytes) {
  const std::string sep = "SPLINTCORE-NEXT-FILE";
  std::vector<std::vector<uint8_t>> files;
  size_t start = 0;
  for (size_t i = 0; i + sep.size() <= bytes.size(); ++i) {
    if (std::memcmp(bytes.data() + i, sep.data(), sep.size()) == 0) {
      files.emplace_back(bytes.begin() + static_cast<long>(start),
                         bytes.begin() + static_cast<long>(i));
      start = i + sep.size();
      i = start - 1;
    }
  }
  files.emplace_back(bytes.begin() + static_cast<long>(start), bytes.end());
  return files;
}

TEST(CtCorpus, FuzzSeedsAreReadable) {
  const std::string root = std::string(SPLINTCORE_FIXTURES_DIR) + "/fuzz/";
  const char* dicom[] = {"explicit_one.dcm", "implicit_one.dcm", "uint8_one.dcm", "series3.bin",
                         "series2_implicit.bin"};
  for (const char* name : dicom) {
    const std::vector<uint8_t> bytes = test::read_file_bytes(root + "ct_dicom/" + name);
    ASSERT_FALSE(bytes.empty()) << name;
    SeriesResult r = read_series(split_series(bytes));
    EXPECT_TRUE(r.status.is_ok()) << name << ": " << message(r.status);
  }
  const char* nrrd[] = {"attached_short.nrrd", "big_ushort.nrrd", "float.nrrd", "uchar.nrrd",
                        "detached.nhdr"};
  for (const char* name : nrrd) {
    const std::vector<uint8_t> bytes = test::read_file_bytes(root + "ct_nrrd/" + name);
    ASSERT_FALSE(bytes.empty()) << name;
    std::vector<CtMemoryFile> self = {{"data.raw", bytes.data(), bytes.size()}};
    Result r = read_format(CtFormat::kNrrd, bytes, self);
    EXPECT_TRUE(r.status.is_ok()) << name << ": " << message(r.status);
  }
  const char* mha[] = {"inline_short.mha", "msb_float.mha", "uchar.mha", "detached.mhd"};
  for (const char* name : mha) {
    const std::vector<uint8_t> bytes = test::read_file_bytes(root + "ct_metaimage/" + name);
    ASSERT_FALSE(bytes.empty()) << name;
    std::vector<CtMemoryFile> self = {{"data.raw", bytes.data(), bytes.size()}};
    Result r = read_format(CtFormat::kMetaImage, bytes, self);
    EXPECT_TRUE(r.status.is_ok()) << name << ": " << message(r.status);
  }
}

// Every arena cap either succeeds (leaving exactly the voxels) or fails with kArenaExhausted
// and leaves the arena empty.
TEST(CtArena, EveryCapFailsCleanlyOrSucceeds) {
  const std::vector<uint8_t> nrrd = cat(kNrrdHeader, le16(ramp(24, 0, 1)));
  std::vector<std::vector<uint8_t>> series = {dicom_file(slice(0, 0)), dicom_file(slice(1, 1))};
  CtReadOptions o;
  o.chunk_bytes = 1024;
  bool nrrd_ok = false, dicom_ok = false;
  for (size_t cap = 0; cap <= 1300; cap += 16) {
    TestArena a(cap);
    Result r = read_format(CtFormat::kNrrd, nrrd, {}, 0, o, &a.arena);
    if (r.status.is_ok()) {
      EXPECT_EQ(a.arena.used(), 48u);
      nrrd_ok = true;
    } else {
      EXPECT_EQ(r.status.code(), StatusCode::kArenaExhausted) << message(r.status);
      EXPECT_EQ(a.arena.used(), 0u);
    }
    TestArena b(cap);
    SeriesResult d = read_series(series, 0, o, &b.arena);
    if (d.status.is_ok()) {
      EXPECT_EQ(b.arena.used(), 24u);  // 2 slices of 2 x 3 voxels
      dicom_ok = true;
    } else {
      EXPECT_EQ(d.status.code(), StatusCode::kArenaExhausted) << message(d.status);
      EXPECT_EQ(b.arena.used(), 0u);
    }
  }
  EXPECT_TRUE(nrrd_ok);
  EXPECT_TRUE(dicom_ok);
}

}  // namespace
}  // namespace splintcore
