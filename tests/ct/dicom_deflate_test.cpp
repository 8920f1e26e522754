// DICOM Deflated Explicit VR Little Endian, 1.2.840.10008.1.2.1.99 (issue 31): the data set
// after the file meta is a raw deflate stream. A slice deflated by zlib
// (fixtures/compress/ct_deflated.dcm, make_compress_fixtures.py) and series deflated by our
// encoder read to the same voxels as their uncompressed twins; the stream's errors name the
// file and the byte offset in it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "splintcore/compress.h"
#include "splintcore/ct.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

const char* kPlainSyntax = "1.2.840.10008.1.2.1";
const char* kDeflatedSyntax = "1.2.840.10008.1.2.1.99";

struct Writer {
  std::vector<uint8_t> b;
  void u16(uint32_t v) {
    b.push_back(static_cast<uint8_t>(v));
    b.push_back(static_cast<uint8_t>(v >> 8));
  }
  void element(uint32_t g, uint32_t e, const char* vr, std::vector<uint8_t> v) {
    if (v.size() % 2 == 1) v.push_back(std::string(vr) == "UI" ? 0 : ' ');
    u16(g);
    u16(e);
    b.push_back(static_cast<uint8_t>(vr[0]));
    b.push_back(static_cast<uint8_t>(vr[1]));
    if (std::string(vr) == "OB" || std::string(vr) == "OW") {
      u16(0);
      u16(static_cast<uint32_t>(v.size()) & 0xFFFF);
      u16(static_cast<uint32_t>(v.size()) >> 16);
    } else {
      u16(static_cast<uint32_t>(v.size()));
    }
    b.insert(b.end(), v.begin(), v.end());
  }
  void str(uint32_t g, uint32_t e, const char* vr, const std::string& s) {
    element(g, e, vr, std::vector<uint8_t>(s.begin(), s.end()));
  }
  void us(uint32_t g, uint32_t e, uint32_t v) {
    element(g, e, "US", {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)});
  }
};

std::vector<uint8_t> meta(const char* syntax) {
  Writer w;
  w.b.assign(128, 0);
  w.b.insert(w.b.end(), {'D', 'I', 'C', 'M'});
  w.element(0x0002, 0x0001, "OB", {0, 1});
  w.str(0x0002, 0x0002, "UI", "1.2.840.10008.5.1.4.1.1.2");
  w.str(0x0002, 0x0010, "UI", syntax);
  return w.b;
}

// Slice k: 16 x 12 pixels, z = 2.5 k, values from k and the pixel index.
std::vector<uint8_t> data_set(int k) {
  Writer w;
  w.str(0x0008, 0x0060, "CS", "CT");
  w.str(0x0020, 0x0032, "DS", "-4\\-3\\" + std::to_string(2.5 * k));
  w.str(0x0020, 0x0037, "DS", "1\\0\\0\\0\\1\\0");
  w.us(0x0028, 0x0002, 1);
  w.str(0x0028, 0x0004, "CS", "MONOCHROME2");
  w.us(0x0028, 0x0010, 12);
  w.us(0x0028, 0x0011, 16);
  w.str(0x0028, 0x0030, "DS", "0.5\\0.5");
  w.us(0x0028, 0x0100, 16);
  w.us(0x0028, 0x0101, 12);
  w.us(0x0028, 0x0103, 0);
  w.str(0x0028, 0x1052, "DS", "-1024");
  w.str(0x0028, 0x1053, "DS", "1");
  std::vector<uint8_t> px;
  for (int i = 0; i < 16 * 12; ++i) {
    const int v = (i % 16 < 8 ? 1000 : 24) + 7 * k + (i % 5);
    px.push_back(static_cast<uint8_t>(v));
    px.push_back(static_cast<uint8_t>(v >> 8));
  }
  w.element(0x7FE0, 0x0010, "OW", px);
  return w.b;
}

std::vector<uint8_t> deflate_raw(const std::vector<uint8_t>& plain) {
  TestArena t(deflate_workspace_bound(512));
  DeflateWorkspace ws;
  EXPECT_TRUE(deflate_workspace(t.arena, 512, &ws).is_ok());
  std::vector<uint8_t> out;
  CompressSink sink;
  sink.user = &out;
  sink.write = [](void* user, const uint8_t* d, size_t n) {
    auto* v = static_cast<std::vector<uint8_t>*>(user);
    v->insert(v->end(), d, d + n);
    return true;
  };
  EXPECT_TRUE(deflate_fixed(ws, ZFormat::kRaw, plain.data(), plain.size(), sink).is_ok());
  return out;
}

std::vector<uint8_t> file(int k, bool deflated) {
  std::vector<uint8_t> f = meta(deflated ? kDeflatedSyntax : kPlainSyntax);
  const std::vector<uint8_t> ds = deflated ? deflate_raw(data_set(k)) : data_set(k);
  f.insert(f.end(), ds.begin(), ds.end());
  return f;
}

struct Series {
  Status status;
  CtInfo info;
  std::vector<int16_t> hu;
  size_t high_water = 0;
};

Series read(const std::vector<std::vector<uint8_t>>& files, size_t max_chunk = 0,
            size_t arena_bytes = 16 << 20, size_t chunk_bytes = 64 * 1024) {
  TestArena t(arena_bytes);
  std::vector<std::string> names;
  for (size_t i = 0; i < files.size(); ++i) names.push_back("s" + std::to_string(i) + ".dcm");
  std::vector<CtMemoryFile> mem;
  for (size_t i = 0; i < files.size(); ++i) {
    mem.push_back({names[i].c_str(), files[i].data(), files[i].size()});
  }
  CtMemoryFiles m{mem.data(), static_cast<uint32_t>(mem.size()), max_chunk, {}};
  Context ctx(&t.arena);
  CtReadOptions options;
  options.chunk_bytes = chunk_bytes;
  CtVolume volume;
  Series r;
  r.status = read_dicom_series(ctx, ct_memory_series(&m), options, &volume, &r.info);
  if (r.status.is_ok()) r.hu.assign(volume.hu, volume.hu + volume.voxel_count());
  r.high_water = t.arena.high_water();
  return r;
}

std::vector<uint8_t> fixture(const char* name) {
  return test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/compress/" + name);
}

TEST(CtDicomDeflate, ZlibDeflatedSliceEqualsItsTwin) {
  const Series plain = read({fixture("ct_plain.dcm")});
  ASSERT_TRUE(plain.status.is_ok()) << test::format(plain.status);
  ASSERT_EQ(plain.hu.size(), 64u * 64);
  for (size_t max_chunk : {size_t{0}, size_t{1}, size_t{13}}) {
    const Series z = read({fixture("ct_deflated.dcm")}, max_chunk);
    ASSERT_TRUE(z.status.is_ok()) << test::format(z.status);
    EXPECT_TRUE(z.hu == plain.hu) << max_chunk;
    EXPECT_STREQ(z.info.transfer_syntax, kDeflatedSyntax);
  }
}

// The fuzz seeds of tests/fuzz/ct_corpus.py: a slice with sequences of undefined length
// inside the deflated data set (zlib level 6), and its uncompressed twin.
TEST(CtDicomDeflate, CorpusSeedWithSequencesEqualsItsTwin) {
  const std::string dir = std::string(SPLINTCORE_FIXTURES_DIR) + "/fuzz/ct_dicom/";
  const Series plain = read({test::read_file_bytes(dir + "explicit_one.dcm")});
  const Series z = read({test::read_file_bytes(dir + "deflated_one.dcm")}, 3);
  ASSERT_TRUE(plain.status.is_ok()) << test::format(plain.status);
  ASSERT_TRUE(z.status.is_ok()) << test::format(z.status);
  EXPECT_TRUE(z.hu == plain.hu);
  EXPECT_EQ(z.hu.size(), 20u);
}

TEST(CtDicomDeflate, SeriesEqualsItsTwin) {
  // Files out of position order: the deflated ones are re-read in the sorted order.
  const Series plain = read({file(2, false), file(0, false), file(1, false)});
  ASSERT_TRUE(plain.status.is_ok()) << test::format(plain.status);
  const Series z = read({file(2, true), file(0, true), file(1, true)}, 7, 16 << 20, 1024);
  ASSERT_TRUE(z.status.is_ok()) << test::format(z.status);
  EXPECT_TRUE(z.hu == plain.hu);
  EXPECT_EQ(z.info.nz, 3u);
  // The two-step contract: the first read's high water is enough, one byte less is not.
  const Series exact = read({file(2, true), file(0, true), file(1, true)}, 0, z.high_water, 1024);
  EXPECT_TRUE(exact.status.is_ok()) << test::format(exact.status);
  const Series less =
      read({file(2, true), file(0, true), file(1, true)}, 0, z.high_water - 1, 1024);
  EXPECT_EQ(less.status.code(), StatusCode::kArenaExhausted) << test::format(less.status);
}

TEST(CtDicomDeflate, StreamErrorsNameTheFileAndOffset) {
  const std::vector<uint8_t> good = file(0, true);
  const size_t meta_end = meta(kDeflatedSyntax).size();
  // Cut inside the header part of the stream, and inside the pixels.
  for (size_t cut : {meta_end + 20, good.size() - 30}) {
    const std::vector<uint8_t> f(good.begin(), good.begin() + cut);
    const Series r = read({file(1, true), f});
    EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << test::format(r.status);
    EXPECT_STREQ(r.status.file(), "s1.dcm");
    EXPECT_EQ(r.status.byte_offset(), cut) << test::format(r.status);
    // The stream's own error, at its offset in the file: not called an inflated-data offset.
    EXPECT_EQ(std::string(r.status.message()).find("inflated data set"), std::string::npos)
        << test::format(r.status);
  }
  // An invalid block type at the stream's first byte.
  std::vector<uint8_t> bad = good;
  bad[meta_end] = 0x07;
  Series r = read({bad});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), meta_end);
  EXPECT_NE(std::string(r.status.message()).find("invalid block type"), std::string::npos);
  // A deflated slice in an uncompressed series.
  r = read({file(0, false), file(1, true)});
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported) << test::format(r.status);
  EXPECT_NE(std::string(r.status.message()).find("transfer syntax"), std::string::npos);
  // A data set that inflates fine but lacks Pixel Data: named as an inflated-data-set offset.
  std::vector<uint8_t> no_pixels = meta(kDeflatedSyntax);
  Writer w;
  w.str(0x0008, 0x0060, "CS", "CT");
  const std::vector<uint8_t> ds = deflate_raw(w.b);
  no_pixels.insert(no_pixels.end(), ds.begin(), ds.end());
  r = read({no_pixels});
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << test::format(r.status);
  EXPECT_NE(std::string(r.status.message()).find("inflated data set"), std::string::npos);
}

}  // namespace
}  // namespace splintcore
