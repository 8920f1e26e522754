// NRRD with encoding gzip (issue 31): the voxels inflate as they are read, bit-identical to
// the raw-encoded twin; attached and detached, line and byte skips, every chunk size, and the
// stream's errors named with the file and the byte offset in it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "splintcore/compress.h"
#include "splintcore/ct.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

std::vector<uint8_t> fixture(const char* name) {
  return test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/compress/" + name);
}

std::vector<uint8_t> inflate_fixture(const std::vector<uint8_t>& gz) {
  TestArena t(inflate_state_bytes());
  std::vector<uint8_t> out(1 << 20);
  size_t n = 0;
  EXPECT_TRUE(
      inflate_buffer(t.arena, ZFormat::kGzip, gz.data(), gz.size(), out.data(), out.size(), &n)
          .is_ok());
  out.resize(n);
  return out;
}

std::vector<uint8_t> gzip_ours(const std::vector<uint8_t>& plain) {
  TestArena t(deflate_workspace_bound(4096));
  DeflateWorkspace ws;
  EXPECT_TRUE(deflate_workspace(t.arena, 4096, &ws).is_ok());
  std::vector<uint8_t> out;
  CompressSink sink;
  sink.user = &out;
  sink.write = [](void* user, const uint8_t* d, size_t n) {
    auto* v = static_cast<std::vector<uint8_t>*>(user);
    v->insert(v->end(), d, d + n);
    return true;
  };
  EXPECT_TRUE(deflate_fixed(ws, ZFormat::kGzip, plain.data(), plain.size(), sink).is_ok());
  return out;
}

std::string header(const char* encoding, const char* sizes, const std::string& extra = "") {
  return std::string("NRRD0005\ntype: short\ndimension: 3\nsizes: ") + sizes +
         "\nspacings: 0.5 0.5 1\nendian: little\nencoding: " + encoding + "\n" + extra + "\n";
}

std::vector<uint8_t> cat(const std::string& head, const std::vector<uint8_t>& data) {
  std::vector<uint8_t> out(head.begin(), head.end());
  out.insert(out.end(), data.begin(), data.end());
  return out;
}

struct Read {
  Status status;
  CtInfo info;
  std::vector<int16_t> hu;
  size_t high_water = 0;
};

Read read(const std::vector<uint8_t>& file, const std::vector<CtMemoryFile>& others = {},
          size_t max_chunk = 0, size_t chunk_bytes = 64 * 1024, size_t arena_bytes = 16 << 20) {
  TestArena t(arena_bytes);
  Context ctx(&t.arena);
  MemorySource ms{file.data(), file.size(), 0, max_chunk};
  CtMemoryFiles files{others.data(), static_cast<uint32_t>(others.size()), max_chunk, {}};
  CtFileOpener opener = ct_memory_opener(&files);
  CtReadOptions options;
  options.chunk_bytes = chunk_bytes;
  CtVolume volume;
  Read r;
  r.status = read_nrrd(ctx, memory_source(&ms, "ct.nrrd"), &opener, options, &volume, &r.info);
  if (r.status.is_ok()) r.hu.assign(volume.hu, volume.hu + volume.voxel_count());
  r.high_water = t.arena.high_water();
  return r;
}

TEST(CtNrrdGzip, GzipNineEqualsItsRawTwin) {
  const std::vector<uint8_t> gz = fixture("ct.gzip9.gz");  // gzip -9 of 64 x 64 x 2 int16
  const std::vector<uint8_t> plain = inflate_fixture(gz);
  ASSERT_EQ(plain.size(), 64u * 64 * 2 * 2);
  const Read raw = read(cat(header("raw", "64 64 2"), plain));
  ASSERT_TRUE(raw.status.is_ok()) << test::format(raw.status);
  for (const char* encoding : {"gzip", "gz"}) {
    for (size_t max_chunk : {size_t{0}, size_t{1}, size_t{777}}) {
      for (size_t chunk : {size_t{1024}, size_t{64 * 1024}}) {
        const Read z = read(cat(header(encoding, "64 64 2"), gz), {}, max_chunk, chunk);
        ASSERT_TRUE(z.status.is_ok()) << test::format(z.status);
        EXPECT_TRUE(z.hu == raw.hu) << encoding << " " << max_chunk << " " << chunk;
      }
    }
  }
  // Two members (gzip -1 then -9) are one stream; our own encoder's gzip too.
  const std::vector<uint8_t> two = fixture("two_members.gz");
  const std::vector<uint8_t> two_plain = inflate_fixture(two);
  const Read raw2 = read(cat(header("raw", "64 64 4"), two_plain));
  for (size_t max_chunk : {size_t{0}, size_t{1}}) {  // 1: a read ends at the members' seam
    const Read z2 = read(cat(header("gzip", "64 64 4"), two), {}, max_chunk);
    ASSERT_TRUE(z2.status.is_ok()) << test::format(z2.status);
    EXPECT_TRUE(z2.hu == raw2.hu);
  }
  const Read ours = read(cat(header("gzip", "64 64 4"), gzip_ours(two_plain)), {}, 5);
  ASSERT_TRUE(ours.status.is_ok()) << test::format(ours.status);
  EXPECT_TRUE(ours.hu == raw2.hu);
}

TEST(CtNrrdGzip, DetachedWithLineAndByteSkips) {
  const std::vector<uint8_t> gz = fixture("ct.gzip9.gz");
  const std::vector<uint8_t> plain = inflate_fixture(gz);
  const Read raw = read(cat(header("raw", "64 64 2"), plain));
  // The data file: two text lines, then the gzip stream; byte skip 6 in inflated bytes.
  std::vector<uint8_t> prefix = {0, 1, 2, 3, 4, 5};
  prefix.insert(prefix.end(), plain.begin(), plain.end());
  std::vector<uint8_t> data = cat("line one\nline two\n", gzip_ours(prefix));
  const std::vector<CtMemoryFile> files = {{"ct.raw.gz", data.data(), data.size()}};
  const std::string h =
      header("gzip", "64 64 2", "data file: ct.raw.gz\nline skip: 2\nbyte skip: 6");
  const Read z = read(std::vector<uint8_t>(h.begin(), h.end()), files, 3);
  ASSERT_TRUE(z.status.is_ok()) << test::format(z.status);
  EXPECT_TRUE(z.hu == raw.hu);
  EXPECT_TRUE(z.info.detached);

  const std::string minus =
      header("gzip", "64 64 2", "data file: ct.raw.gz\nline skip: 2\nbyte skip: -1");
  const Read m = read(std::vector<uint8_t>(minus.begin(), minus.end()), files);
  EXPECT_EQ(m.status.code(), StatusCode::kUnsupported) << test::format(m.status);
  EXPECT_STREQ(m.status.file(), "ct.raw.gz");
}

TEST(CtNrrdGzip, StreamErrorsNameTheFileAndOffset) {
  const std::vector<uint8_t> gz = fixture("ct.gzip9.gz");
  const std::string head = header("gzip", "64 64 2");
  // Cut short: truncated, at the end of the file.
  std::vector<uint8_t> cut = cat(head, std::vector<uint8_t>(gz.begin(), gz.end() - 100));
  Read r = read(cut);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), cut.size());
  EXPECT_STREQ(r.status.file(), "ct.nrrd");
  // A wrong CRC-32: the offset of the trailer in the file.
  std::vector<uint8_t> bad = cat(head, gz);
  bad[bad.size() - 6] ^= 0x40;
  r = read(bad);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), bad.size() - 8);
  EXPECT_NE(std::string(r.status.message()).find("CRC-32"), std::string::npos);
  // Not gzip at all.
  r = read(cat(head, std::vector<uint8_t>(100, 'x')));
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << test::format(r.status);
  EXPECT_EQ(r.status.byte_offset(), head.size());
  // A whole stream that holds fewer bytes than the header describes.
  r = read(cat(header("gzip", "64 64 3"), gz));
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << test::format(r.status);
  EXPECT_NE(std::string(r.status.message()).find("inflates to 16384 bytes"), std::string::npos);
  // Bytes after the member that are not another member.
  std::vector<uint8_t> trailing = cat(head, gz);
  trailing.push_back(0);
  trailing.push_back(0);
  // Stray bytes after the member end the stream (as zlib's gzread), as trailing raw data does.
  r = read(trailing);
  EXPECT_TRUE(r.status.is_ok()) << test::format(r.status);
}

TEST(CtNrrdGzip, ArenaNeedIsCheckedFirst) {
  const std::vector<uint8_t> file = cat(header("gzip", "64 64 2"), fixture("ct.gzip9.gz"));
  const Read ok = read(file, {}, 0, 1024);
  ASSERT_TRUE(ok.status.is_ok()) << test::format(ok.status);
  // The two-step contract: the high water of a first read is enough, one byte less is not.
  const Read exact = read(file, {}, 0, 1024, ok.high_water);
  EXPECT_TRUE(exact.status.is_ok()) << test::format(exact.status);
  const Read less = read(file, {}, 0, 1024, ok.high_water - 1);
  EXPECT_EQ(less.status.code(), StatusCode::kArenaExhausted) << test::format(less.status);
}

}  // namespace
}  // namespace splintcore
