// Inflate (include/splintcore/compress.h): streams made by gzip(1) and zlib
// (fixtures/compress/, their plain inputs' SHA-256 in manifest.txt), round trips through our
// own encoder, streaming in every chunk size down to one byte, every error the header names,
// and the state in exactly inflate_state_bytes().
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "splintcore/compress.h"
#include "support/test_util.h"
#if defined(SPLINTCORE_WITH_PLATFORM)
#include "splintcore/platform.h"
#endif

namespace splintcore {
namespace {

using test::format;
using test::TestArena;

struct Fixture {
  std::string name;
  ZFormat format;
  size_t plain_bytes;
  std::string sha256;
  std::vector<uint8_t> data;
};

std::vector<Fixture> fixtures() {
  std::vector<Fixture> out;
  const std::string dir = std::string(SPLINTCORE_FIXTURES_DIR) + "/compress/";
  std::ifstream in(dir + "manifest.txt");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    Fixture f;
    std::string wrapper;
    fields >> f.name >> wrapper >> f.plain_bytes >> f.sha256;
    f.format = wrapper == "gzip"   ? ZFormat::kGzip
               : wrapper == "zlib" ? ZFormat::kZlib
                                   : ZFormat::kRaw;
    f.data = test::read_file_bytes(dir + f.name);
    out.push_back(f);
  }
  return out;
}

const Fixture& fixture(const char* name) {
  static const std::vector<Fixture> all = fixtures();
  for (const Fixture& f : all) {
    if (f.name == name) return f;
  }
  ADD_FAILURE() << "no fixture " << name;
  return all.front();
}

Status inflate_all(ZFormat format, const std::vector<uint8_t>& in, std::vector<uint8_t>* out,
                   uint64_t max_output = UINT64_MAX) {
  TestArena t(inflate_state_bytes());
  out->assign(std::min<size_t>(in.size() * 1100 + 100000, size_t{1} << 22), 0);
  size_t produced = 0;
  const size_t cap = max_output < out->size() ? static_cast<size_t>(max_output) : out->size();
  Status s = inflate_buffer(t.arena, format, in.data(), in.size(), out->data(), cap, &produced);
  out->resize(produced);
  return s;
}

// Streams `in` in pieces of in_chunk bytes into output pieces of out_chunk bytes.
Status inflate_chunked(ZFormat format, const std::vector<uint8_t>& in, size_t in_chunk,
                       size_t out_chunk, std::vector<uint8_t>* out) {
  TestArena t(inflate_state_bytes());
  Inflater inflater;
  SPLINTCORE_RETURN_IF_ERROR(inflater.begin(t.arena, format));
  out->clear();
  std::vector<uint8_t> piece(out_chunk);
  size_t at = 0;
  for (;;) {
    const uint8_t* p = in.data() + at;
    size_t n = in.size() - at < in_chunk ? in.size() - at : in_chunk;
    const size_t given = n;
    uint8_t* o = piece.data();
    size_t room = piece.size();
    SPLINTCORE_RETURN_IF_ERROR(inflater.run(&p, &n, &o, &room));
    at += given - n;
    out->insert(out->end(), piece.data(), o);
    if (inflater.finished() && at == in.size()) break;
    if (n == given && room == piece.size()) break;  // no progress
  }
  EXPECT_EQ(inflater.total_out(), out->size());
  return inflater.end_of_input();
}

TEST(Checksum, KnownValues) {
  const uint8_t digits[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(crc32(0, digits, 9), 0xCBF43926u);
  EXPECT_EQ(crc32(crc32(0, digits, 4), digits + 4, 5), 0xCBF43926u);
  const uint8_t wiki[] = {'W', 'i', 'k', 'i', 'p', 'e', 'd', 'i', 'a'};
  EXPECT_EQ(adler32(1, wiki, 9), 0x11E60398u);
  EXPECT_EQ(adler32(adler32(1, wiki, 2), wiki + 2, 7), 0x11E60398u);
}

// The table-driven CRC (eight bytes a step) and Adler-32 against their definitions, bit by bit
// and byte by byte, at every length and alignment up to 40 bytes and chained at every split.
TEST(Checksum, MatchTheDefinitions) {
  uint8_t data[48];
  for (size_t i = 0; i < sizeof(data); ++i) data[i] = static_cast<uint8_t>(hash_mix(i) >> 7);
  auto slow_crc = [](const uint8_t* p, size_t n) {
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i) {
      c ^= p[i];
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return c ^ 0xFFFFFFFFu;
  };
  auto slow_adler = [](const uint8_t* p, size_t n) {
    uint32_t a = 1, b = 0;
    for (size_t i = 0; i < n; ++i) {
      a = (a + p[i]) % 65521;
      b = (b + a) % 65521;
    }
    return (b << 16) | a;
  };
  for (size_t start = 0; start < 8; ++start) {
    for (size_t n = 0; n + start <= 40; ++n) {
      const uint8_t* p = data + start;
      EXPECT_EQ(crc32(0, p, n), slow_crc(p, n)) << start << " " << n;
      EXPECT_EQ(adler32(1, p, n), slow_adler(p, n)) << start << " " << n;
      for (size_t split = 0; split <= n; ++split) {
        EXPECT_EQ(crc32(crc32(0, p, split), p + split, n - split), slow_crc(p, n));
      }
    }
  }
}

// crc32_combine against the CRC of the joined bytes: every split of short inputs (empty parts
// included), and a long second part (3 MiB + 77 bytes: a length with several bits set).
TEST(Checksum, CombineEqualsTheCrcOfTheJoinedBytes) {
  std::vector<uint8_t> data(300);
  for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>(hash_mix(i + 99) >> 11);
  for (size_t n : {size_t{0}, size_t{1}, size_t{7}, size_t{64}, size_t{300}}) {
    for (size_t split = 0; split <= n; ++split) {
      const uint32_t a = crc32(0, data.data(), split);
      const uint32_t b = crc32(0, data.data() + split, n - split);
      EXPECT_EQ(crc32_combine(a, b, n - split), crc32(0, data.data(), n)) << n << " " << split;
    }
  }
  const std::vector<uint8_t> zeros(size_t{1} << 20, 0);
  uint32_t chained = crc32(0, data.data(), 5);  // 5 bytes, then 3 MiB + 77 zero bytes
  for (int k = 0; k < 3; ++k) chained = crc32(chained, zeros.data(), zeros.size());
  chained = crc32(chained, zeros.data(), 77);
  const uint32_t zeros_crc =
      crc32(crc32(crc32(crc32(0, zeros.data(), zeros.size()), zeros.data(), zeros.size()),
                  zeros.data(), zeros.size()),
            zeros.data(), 77);
  EXPECT_EQ(crc32_combine(crc32(0, data.data(), 5), zeros_crc, 3 * zeros.size() + 77), chained);
  // A combine with an empty second part changes nothing; the CRC of no bytes is 0.
  EXPECT_EQ(crc32_combine(0x12345678u, 0, 0), 0x12345678u);
  EXPECT_EQ(crc32_combine(0, crc32(0, data.data(), 9), 9), crc32(0, data.data(), 9));
}

TEST(Inflate, FixturesFromGzipAndZlib) {
  const std::vector<Fixture> all = fixtures();
  ASSERT_GE(all.size(), 20u);
  for (const Fixture& f : all) {
    ASSERT_FALSE(f.data.empty()) << f.name;
    std::vector<uint8_t> out;
    Status s = inflate_all(f.format, f.data, &out);
    ASSERT_TRUE(s.is_ok()) << f.name << ": " << format(s);
    EXPECT_EQ(out.size(), f.plain_bytes) << f.name;
    EXPECT_EQ(test::sha256_hex(out.data(), out.size()), f.sha256) << f.name;
  }
}

TEST(Inflate, ByteAtATimeEqualsOneShot) {
  for (const Fixture& f : fixtures()) {
    std::vector<uint8_t> whole, streamed;
    SPLINTCORE_ASSERT_OK(inflate_all(f.format, f.data, &whole));
    const size_t in_chunks[] = {1, 7, 4096};
    const size_t out_chunks[] = {1, 333, 70000};
    for (size_t k = 0; k < 3; ++k) {
      if (in_chunks[k] == 1 && out_chunks[k] == 1 && f.plain_bytes > 20000) continue;  // time
      Status s = inflate_chunked(f.format, f.data, in_chunks[k], out_chunks[k], &streamed);
      ASSERT_TRUE(s.is_ok()) << f.name << " in " << in_chunks[k] << ": " << format(s);
      EXPECT_TRUE(streamed == whole)
          << f.name << " in " << in_chunks[k] << " out " << out_chunks[k];
    }
    // One byte in, everything out at once.
    SPLINTCORE_ASSERT_OK(inflate_chunked(f.format, f.data, 1, 1 << 20, &streamed));
    EXPECT_TRUE(streamed == whole) << f.name;
  }
}

TEST(Inflate, SinkOutput) {
  const Fixture& f = fixture("two_members.gz");
  TestArena t(2 * inflate_state_bytes());
  Inflater inflater;
  SPLINTCORE_ASSERT_OK(inflater.begin(t.arena, f.format));
  std::vector<uint8_t> out;
  CompressSink sink;
  sink.user = &out;
  sink.write = [](void* user, const uint8_t* data, size_t bytes) {
    auto* v = static_cast<std::vector<uint8_t>*>(user);
    v->insert(v->end(), data, data + bytes);
    return bytes <= 32768;
  };
  const uint8_t* p = f.data.data();
  size_t n = f.data.size();
  SPLINTCORE_ASSERT_OK(inflater.run(&p, &n, sink));
  EXPECT_EQ(n, 0u);
  EXPECT_TRUE(inflater.finished());
  SPLINTCORE_EXPECT_OK(inflater.end_of_input());
  EXPECT_EQ(test::sha256_hex(out.data(), out.size()), f.sha256);
  EXPECT_EQ(inflater.total_in(), f.data.size());

  // A sink that refuses: kIoError, and the inflater stays failed.
  Inflater refused;
  SPLINTCORE_ASSERT_OK(refused.begin(t.arena, f.format));
  sink.write = [](void*, const uint8_t*, size_t) { return false; };
  p = f.data.data();
  n = f.data.size();
  Status s = refused.run(&p, &n, sink);
  EXPECT_EQ(s.code(), StatusCode::kIoError) << format(s);
  EXPECT_EQ(refused.run(&p, &n, sink).code(), StatusCode::kIoError);
  EXPECT_EQ(refused.end_of_input().code(), StatusCode::kIoError);
}

// Our encoder's output in every wrapper reads back; input with runs, text and noise.
TEST(Inflate, RoundTripOwnDeflate) {
  TestArena t(deflate_workspace_bound(1000) + inflate_state_bytes());
  DeflateWorkspace ws;
  SPLINTCORE_ASSERT_OK(deflate_workspace(t.arena, 1000, &ws));
  uint64_t seed = 12345;
  for (size_t size :
       {size_t{0}, size_t{1}, size_t{2}, size_t{300}, size_t{40000}, size_t{200000}}) {
    std::vector<uint8_t> data(size);
    for (size_t i = 0; i < size; ++i) {
      seed = hash_mix(seed + i);
      const size_t region = (i / 5000) % 3;
      data[i] = region == 0   ? 0
                : region == 1 ? static_cast<uint8_t>("splint "[i % 7])
                              : static_cast<uint8_t>(seed);
    }
    for (ZFormat format : {ZFormat::kRaw, ZFormat::kZlib, ZFormat::kGzip}) {
      std::vector<uint8_t> compressed;
      CompressSink sink;
      sink.user = &compressed;
      sink.write = [](void* user, const uint8_t* d, size_t bytes) {
        auto* v = static_cast<std::vector<uint8_t>*>(user);
        v->insert(v->end(), d, d + bytes);
        return true;
      };
      SPLINTCORE_ASSERT_OK(deflate_fixed(ws, format, data.data(), data.size(), sink));
      std::vector<uint8_t> back;
      SPLINTCORE_ASSERT_OK(inflate_all(format, compressed, &back));
      EXPECT_TRUE(back == data) << size;
    }
  }
}

// The stream does not depend on the output buffer's size (the sink sees the same bytes in
// writes of out_bytes), whatever the effort; both efforts read back, and on mesh-like text the
// fast one is at most a tenth longer.
TEST(Deflate, BytesIndependentOfTheBufferAndEffortsReadBack) {
  std::string text;
  uint64_t seed = 7;
  for (int k = 0; k < 3000; ++k) {
    seed = hash_mix(seed + static_cast<uint64_t>(k));
    text += "<vertex x=\"" + std::to_string(seed % 100000 / 1000.0) + "\" y=\"" +
            std::to_string(static_cast<int>(seed >> 20) % 977) + "\"/>\n";
  }
  const std::vector<uint8_t> data(text.begin(), text.end());
  auto deflate = [&](size_t out_bytes, const DeflateEffort& effort, std::vector<uint8_t>* out) {
    TestArena t(deflate_workspace_bound(out_bytes));
    DeflateWorkspace ws;
    SPLINTCORE_ASSERT_OK(deflate_workspace(t.arena, out_bytes, &ws));
    ws.effort = effort;
    CompressSink sink;
    struct Seen {
      std::vector<uint8_t>* bytes;
      size_t cap;
      bool full;
    } seen{out, out_bytes, true};
    sink.user = &seen;
    sink.write = [](void* user, const uint8_t* d, size_t bytes) {
      auto* s = static_cast<Seen*>(user);
      if (!s->full) return false;  // only the last write may be short
      s->full = bytes == s->cap;
      s->bytes->insert(s->bytes->end(), d, d + bytes);
      return true;
    };
    SPLINTCORE_ASSERT_OK(deflate_fixed(ws, ZFormat::kZlib, data.data(), data.size(), sink));
  };
  for (const DeflateEffort& effort : {DeflateEffort{}, kDeflateFast}) {
    std::vector<uint8_t> whole;
    deflate(size_t{1} << 20, effort, &whole);
    for (size_t out_bytes : {size_t{1}, size_t{3}, size_t{4}, size_t{5}, size_t{7}, size_t{4096}}) {
      std::vector<uint8_t> chunked;
      deflate(out_bytes, effort, &chunked);
      EXPECT_TRUE(chunked == whole) << "buffer " << out_bytes << ", chain " << effort.max_chain;
    }
    std::vector<uint8_t> back;
    SPLINTCORE_ASSERT_OK(inflate_all(ZFormat::kZlib, whole, &back));
    EXPECT_TRUE(back == data) << effort.max_chain;
  }
  std::vector<uint8_t> best, fast;
  deflate(4096, DeflateEffort{}, &best);
  deflate(4096, kDeflateFast, &fast);
  EXPECT_LE(fast.size(), best.size() + best.size() / 10);
  EXPECT_LT(best.size(), data.size() / 2);
}

// The encoder's sink failure is an I/O error.
TEST(Deflate, SinkRefuses) {
  TestArena t(deflate_workspace_bound(16));
  DeflateWorkspace ws;
  SPLINTCORE_ASSERT_OK(deflate_workspace(t.arena, 16, &ws));
  CompressSink sink;
  sink.write = [](void*, const uint8_t*, size_t) { return false; };
  const uint8_t data[64] = {1, 2, 3};
  for (ZFormat format : {ZFormat::kRaw, ZFormat::kZlib, ZFormat::kGzip}) {
    EXPECT_EQ(deflate_fixed(ws, format, data, sizeof(data), sink).code(), StatusCode::kIoError);
  }
  TestArena small(kDeflateHashEntries * 4 + kDeflateWindow * 4 + 16 - 1);
  EXPECT_EQ(deflate_workspace(small.arena, 16, &ws).code(), StatusCode::kArenaExhausted);
}

// Mesh-like text with a stretch of noise: matches across the pieces' seams, literals too.
std::vector<uint8_t> piece_test_input(size_t size) {
  std::vector<uint8_t> data;
  uint64_t seed = 99;
  while (data.size() < size) {
    seed = hash_mix(seed + data.size());
    const std::string line = "<vertex x=\"" + std::to_string(seed % 100000 / 1000.0) + "\" y=\"" +
                             std::to_string(static_cast<int>(seed >> 20) % 977) + "\"/>\n";
    data.insert(data.end(), line.begin(), line.end());
    if (data.size() / 100000 % 7 == 3) data.push_back(static_cast<uint8_t>(seed >> 40));
  }
  data.resize(size);
  return data;
}

Status deflate_in_pieces(const Executor* executor, size_t arena_bytes, DeflateEffort effort,
                         ZFormat format, const std::vector<uint8_t>& data,
                         std::vector<uint8_t>* out, uint32_t* data_crc = nullptr) {
  TestArena t(arena_bytes);
  DeflateLanes lanes;
  SPLINTCORE_RETURN_IF_ERROR(deflate_lanes(t.arena, data.size(), effort, &lanes));
  CompressSink sink;
  sink.user = out;
  sink.write = [](void* user, const uint8_t* d, size_t bytes) {
    auto* v = static_cast<std::vector<uint8_t>*>(user);
    v->insert(v->end(), d, d + bytes);
    return bytes <= 65536;  // the writes of at most 64 KiB the header promises
  };
  return deflate_parallel(executor, lanes, format, data.data(), data.size(), sink, data_crc);
}

// Inputs of more than one piece: one stream that inflates back, the same bytes serially and on
// threads, in deflate_lanes_bound bytes exactly; at most one piece: deflate_fixed's bytes.
TEST(Deflate, ParallelPiecesJoinIntoOneStream) {
  const Executor* threaded = nullptr;
#if defined(SPLINTCORE_WITH_PLATFORM)
  ThreadExecutor threads(3);
  threaded = &threads.executor();
#endif
  for (size_t size : {kDeflatePiece - 1, kDeflatePiece, kDeflatePiece + 1, 5 * kDeflatePiece / 2,
                      9 * kDeflatePiece + 77}) {
    const std::vector<uint8_t> data = piece_test_input(size);
    for (ZFormat format : {ZFormat::kRaw, ZFormat::kZlib, ZFormat::kGzip}) {
      const uint64_t bound = deflate_lanes_bound(size);
      std::vector<uint8_t> serial, parallel, back;
      SPLINTCORE_ASSERT_OK(deflate_in_pieces(nullptr, bound, kDeflateFast, format, data, &serial));
      uint32_t crc = 0;  // the input's CRC-32, joined from the pieces' (threemf_write's use)
      SPLINTCORE_ASSERT_OK(
          deflate_in_pieces(threaded, bound, kDeflateFast, format, data, &parallel, &crc));
      EXPECT_TRUE(serial == parallel) << size;
      EXPECT_EQ(crc, crc32(0, data.data(), data.size())) << size;
      SPLINTCORE_ASSERT_OK(inflate_all(format, serial, &back));
      EXPECT_TRUE(back == data) << size;
      if (size <= kDeflatePiece) {
        TestArena t(deflate_workspace_bound(65536));
        DeflateWorkspace ws;
        SPLINTCORE_ASSERT_OK(deflate_workspace(t.arena, 65536, &ws));
        ws.effort = kDeflateFast;
        std::vector<uint8_t> fixed;
        CompressSink sink;
        sink.user = &fixed;
        sink.write = [](void* user, const uint8_t* d, size_t bytes) {
          auto* v = static_cast<std::vector<uint8_t>*>(user);
          v->insert(v->end(), d, d + bytes);
          return true;
        };
        SPLINTCORE_ASSERT_OK(deflate_fixed(ws, format, data.data(), data.size(), sink));
        EXPECT_TRUE(fixed == serial) << size;
      } else {
        std::vector<uint8_t> none;
        EXPECT_EQ(deflate_in_pieces(nullptr, bound / 2, kDeflateFast, format, data, &none).code(),
                  StatusCode::kArenaExhausted);
      }
    }
  }
  // The seams cost little: nine pieces are at most 1% longer than one stream of them.
  const std::vector<uint8_t> data = piece_test_input(9 * kDeflatePiece);
  TestArena t(deflate_workspace_bound(65536));
  DeflateWorkspace ws;
  SPLINTCORE_ASSERT_OK(deflate_workspace(t.arena, 65536, &ws));
  size_t whole = 0;
  CompressSink sink;
  sink.user = &whole;
  sink.write = [](void* user, const uint8_t*, size_t bytes) {
    *static_cast<size_t*>(user) += bytes;
    return true;
  };
  SPLINTCORE_ASSERT_OK(deflate_fixed(ws, ZFormat::kRaw, data.data(), data.size(), sink));
  std::vector<uint8_t> pieces;
  SPLINTCORE_ASSERT_OK(deflate_in_pieces(nullptr, deflate_lanes_bound(data.size()), DeflateEffort{},
                                         ZFormat::kRaw, data, &pieces));
  EXPECT_LE(pieces.size(), whole + whole / 100);
}

// The state in exactly inflate_state_bytes(), with the arena's top at any alignment; one byte
// less fails when the top is one byte past an alignment boundary (the worst case).
TEST(Inflate, StateInExactlyItsBytes) {
  const Fixture& f = fixture("ct.zlib6.zz");
  for (size_t skew = 0; skew < 16; ++skew) {
    TestArena t(skew + inflate_state_bytes());
    if (skew > 0) {
      ASSERT_NE(t.arena.allocate(skew, 1), nullptr);
    }
    Inflater inflater;
    SPLINTCORE_ASSERT_OK(inflater.begin(t.arena, ZFormat::kZlib));
    std::vector<uint8_t> out(f.plain_bytes);
    const uint8_t* p = f.data.data();
    size_t n = f.data.size();
    uint8_t* o = out.data();
    size_t room = out.size();
    SPLINTCORE_ASSERT_OK(inflater.run(&p, &n, &o, &room));
    EXPECT_TRUE(inflater.finished());
    EXPECT_EQ(test::sha256_hex(out.data(), out.size()), f.sha256);
  }
  TestArena t(1 + inflate_state_bytes() - 1);
  ASSERT_NE(t.arena.allocate(1, 1), nullptr);
  Inflater inflater;
  EXPECT_EQ(inflater.begin(t.arena, ZFormat::kZlib).code(), StatusCode::kArenaExhausted);
  size_t produced = 0;
  uint8_t out[4];
  EXPECT_EQ(inflate_buffer(t.arena, ZFormat::kZlib, nullptr, 0, out, 4, &produced).code(),
            StatusCode::kArenaExhausted);
}

// Every prefix of a stream is kTruncated at its own length, never anything else.
TEST(InflateErrors, TruncatedAtEveryByte) {
  for (const char* name : {"ct.fields.gz", "text.fixed.zz", "random.stored.zz", "byte.raw.deflate",
                           "two_members.gz"}) {
    const Fixture& f = fixture(name);
    const size_t step = (f.data.size() > 3000 ? 7 : 1) * test::kSweepStep;
    for (size_t cut = 0; cut < f.data.size(); cut += step) {
      std::vector<uint8_t> prefix(f.data.begin(), f.data.begin() + cut), out;
      Status s = inflate_all(f.format, prefix, &out);
      if (f.format == ZFormat::kGzip && name == std::string("two_members.gz") && s.is_ok()) {
        continue;  // the cut fell between the members: the first member is a whole stream
      }
      ASSERT_EQ(s.code(), StatusCode::kTruncated) << name << " cut " << cut << ": " << format(s);
      EXPECT_EQ(s.byte_offset(), cut) << name;
    }
  }
}

// Bits LSB first, as deflate packs them; Huffman codes MSB first.
struct Bits {
  std::vector<uint8_t> bytes;
  uint32_t count = 0;
  void put(uint32_t value, uint32_t n) {
    for (uint32_t i = 0; i < n; ++i) {
      if (count % 8 == 0) bytes.push_back(0);
      bytes.back() |= static_cast<uint8_t>(((value >> i) & 1) << (count % 8));
      ++count;
    }
  }
  void code(uint32_t value, uint32_t n) {
    for (uint32_t i = n; i > 0; --i) put((value >> (i - 1)) & 1, 1);
  }
  // Fixed code of literal/length symbol s (RFC 1951 3.2.6).
  void fixed(uint32_t s) {
    if (s < 144) {
      code(0x30 + s, 8);
    } else if (s < 256) {
      code(0x190 + s - 144, 9);
    } else if (s < 280) {
      code(s - 256, 7);
    } else {
      code(0xC0 + s - 280, 8);
    }
  }
};

Status inflate_raw(const Bits& b, std::vector<uint8_t>* out) {
  return inflate_all(ZFormat::kRaw, b.bytes, out);
}

void expect_error(const Status& s, StatusCode code, const char* words, uint64_t offset) {
  EXPECT_EQ(s.code(), code) << format(s);
  EXPECT_NE(std::string(s.message()).find(words), std::string::npos) << format(s);
  EXPECT_EQ(s.byte_offset(), offset) << format(s);
}

TEST(InflateErrors, BlockTypeAndStoredLength) {
  std::vector<uint8_t> out;
  Bits b;
  b.put(1, 1);
  b.put(3, 2);
  expect_error(inflate_raw(b, &out), StatusCode::kParseError, "invalid block type", 0);
  {  // the error stays: run() and end_of_input() repeat it
    TestArena t(inflate_state_bytes());
    Inflater z;
    SPLINTCORE_ASSERT_OK(z.begin(t.arena, ZFormat::kRaw));
    const uint8_t* p = b.bytes.data();
    size_t n = b.bytes.size();
    uint8_t sink[4];
    uint8_t* o = sink;
    size_t room = sizeof(sink);
    EXPECT_EQ(z.run(&p, &n, &o, &room).code(), StatusCode::kParseError);
    EXPECT_EQ(z.run(&p, &n, &o, &room).code(), StatusCode::kParseError);
    EXPECT_EQ(z.end_of_input().code(), StatusCode::kParseError);
    EXPECT_FALSE(z.finished());
  }
  Bits stored;
  stored.put(0, 1);  // not final
  stored.put(0, 2);
  stored.put(0, 5);  // to the boundary
  stored.put(2, 16);
  stored.put(0xFFFD, 16);
  stored.put('h', 8);
  stored.put('i', 8);
  stored.put(1, 1);  // final, stored
  stored.put(0, 7);
  stored.put(5, 16);
  stored.put(0x1234, 16);
  expect_error(inflate_raw(stored, &out), StatusCode::kParseError, "stored block length 5", 8);
  EXPECT_EQ(out.size(), 0u);
}

// A dynamic block header: HLIT, HDIST, HCLEN and the code length code's lengths in their
// order (RFC 1951 3.2.7), from lengths by symbol.
Bits dynamic_header(uint32_t hlit, uint32_t hdist, const std::vector<uint32_t>& clen_by_symbol) {
  static const uint8_t order[19] = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                    11, 4,  12, 3, 13, 2, 14, 1, 15};
  uint32_t hclen = 4;
  for (uint32_t i = 0; i < 19; ++i) {
    if (clen_by_symbol[order[i]] != 0) hclen = i + 1 > 4 ? i + 1 : 4;
  }
  Bits b;
  b.put(1, 1);
  b.put(2, 2);
  b.put(hlit - 257, 5);
  b.put(hdist - 1, 5);
  b.put(hclen - 4, 4);
  for (uint32_t i = 0; i < hclen; ++i) b.put(clen_by_symbol[order[i]], 3);
  return b;
}

std::vector<uint32_t> clens(std::initializer_list<std::pair<uint32_t, uint32_t>> set) {
  std::vector<uint32_t> v(19, 0);
  for (auto& p : set) v[p.first] = p.second;
  return v;
}

TEST(InflateErrors, CodeLengths) {
  std::vector<uint8_t> out;
  // Code length code: every symbol 1 bit long.
  std::vector<uint32_t> all_ones(19, 1);
  expect_error(inflate_raw(dynamic_header(257, 1, all_ones), &out), StatusCode::kParseError,
               "over-subscribed code length", 9);
  expect_error(inflate_raw(dynamic_header(257, 1, clens({{16, 2}})), &out), StatusCode::kParseError,
               "incomplete code length", 3);
  // Symbols 0 and 1 of one bit each: code 0 -> length 0, code 1 -> length 1.
  const auto zero_one = clens({{0, 1}, {1, 1}});
  Bits over = dynamic_header(257, 1, zero_one);
  for (int i = 0; i < 258; ++i) over.code(1, 1);  // 257 one-bit literal/length codes
  expect_error(inflate_raw(over, &out), StatusCode::kParseError, "over-subscribed literal/length",
               41);
  Bits no_end = dynamic_header(257, 1, zero_one);
  no_end.code(1, 1);
  no_end.code(1, 1);
  for (int i = 2; i < 258; ++i) no_end.code(0, 1);
  expect_error(inflate_raw(no_end, &out), StatusCode::kParseError, "end-of-block", 41);
  // Symbols 0 (1 bit), 1 and 2 (2 bits): a single 2-bit literal/length code is incomplete.
  const auto zero_one_two = clens({{0, 1}, {1, 2}, {2, 2}});
  Bits single2 = dynamic_header(257, 1, zero_one_two);
  for (int i = 0; i < 256; ++i) single2.code(0, 1);
  single2.code(3, 2);  // symbol 2: length 2 for the end of block
  single2.code(0, 1);  // no distance code
  expect_error(inflate_raw(single2, &out), StatusCode::kParseError, "incomplete literal/length",
               41);
  // Distance code of two 2-bit codes: incomplete.
  Bits dist2 = dynamic_header(257, 2, zero_one_two);
  for (int i = 0; i < 256; ++i) dist2.code(0, 1);
  dist2.code(2, 2);  // end of block: length 1, a single 1-bit code (allowed)
  dist2.code(3, 2);
  dist2.code(3, 2);
  expect_error(inflate_raw(dist2, &out), StatusCode::kParseError, "incomplete distance", 41);
  // Repeats: 16 first, then 18 past the end.
  const auto rep = clens({{16, 1}, {18, 2}, {0, 2}});
  Bits first16 = dynamic_header(257, 1, rep);
  first16.code(0, 1);
  first16.put(0, 2);
  expect_error(inflate_raw(first16, &out), StatusCode::kParseError, "no length before", 3);
  Bits past = dynamic_header(257, 1, rep);
  past.code(3, 2);  // 18: 11 + 127 zeros
  past.put(127, 7);
  past.code(3, 2);
  past.put(127, 7);
  expect_error(inflate_raw(past, &out), StatusCode::kParseError, "passes the end", 4);
  Bits many_dist = dynamic_header(257, 32, zero_one);  // HDIST 32
  expect_error(inflate_raw(many_dist, &out), StatusCode::kParseError, "at most 286 and 30", 0);
  Bits many = dynamic_header(257, 1, zero_one);
  many.bytes[0] |= 30 << 3;  // HLIT 287
  expect_error(inflate_raw(many, &out), StatusCode::kParseError, "at most 286", 0);
}

TEST(InflateErrors, InvalidCodesAndDistances) {
  std::vector<uint8_t> out;
  Bits len286;
  len286.put(1, 1);
  len286.put(1, 2);
  len286.fixed('a');
  len286.fixed(286);
  expect_error(inflate_raw(len286, &out), StatusCode::kParseError, "invalid length code 286", 1);
  Bits dist30;
  dist30.put(1, 1);
  dist30.put(1, 2);
  dist30.fixed('a');
  dist30.fixed(257);  // length 3
  dist30.code(30, 5);
  expect_error(inflate_raw(dist30, &out), StatusCode::kParseError, "invalid distance code", 1);
  Bits far;
  far.put(1, 1);
  far.put(1, 2);
  far.fixed('a');
  far.fixed(257);
  far.code(1, 5);  // distance 2: one byte so far
  expect_error(inflate_raw(far, &out), StatusCode::kParseError, "distance 2 reaches before", 1);
  // A literal/length code of one 1-bit code ("0" = end of block): "1" is no code.
  const auto zero_one = clens({{0, 1}, {1, 1}});
  Bits single = dynamic_header(257, 1, zero_one);
  for (int i = 0; i < 256; ++i) single.code(0, 1);
  single.code(1, 1);
  single.code(0, 1);
  for (int i = 0; i < 16; ++i) single.code(1, 1);  // "1...": no code starts so
  expect_error(inflate_raw(single, &out), StatusCode::kParseError, "invalid literal/length", 41);
  // No distance codes at all (allowed), then a match: its distance has no code.
  Bits nodist = dynamic_header(258, 1, zero_one);
  for (int i = 0; i < 256; ++i) nodist.code(0, 1);
  nodist.code(1, 1);  // 256: code "0"
  nodist.code(1, 1);  // 257: code "1" (length 3)
  nodist.code(0, 1);  // the one distance length: 0
  nodist.code(1, 1);  // 257
  nodist.put(0, 15);
  expect_error(inflate_raw(nodist, &out), StatusCode::kParseError, "invalid distance code", 41);
}

TEST(InflateErrors, Wrappers) {
  std::vector<uint8_t> out;
  std::vector<uint8_t> z = fixture("text.zlib9.zz").data;
  std::vector<uint8_t> bad = z;
  bad.back() ^= 1;
  expect_error(inflate_all(ZFormat::kZlib, bad, &out), StatusCode::kParseError, "Adler-32",
               z.size() - 4);
  bad = z;
  bad[0] = 0x77;
  EXPECT_EQ(inflate_all(ZFormat::kZlib, bad, &out).code(), StatusCode::kParseError);
  bad = {0x78, 0x9D};
  expect_error(inflate_all(ZFormat::kZlib, bad, &out), StatusCode::kParseError, "check bits", 0);
  bad = {0x79, 0x00};
  bad[1] = static_cast<uint8_t>(31 - (0x7900 % 31));
  expect_error(inflate_all(ZFormat::kZlib, bad, &out), StatusCode::kParseError, "method 9", 0);
  bad = {0x88, 0x00};
  bad[1] = static_cast<uint8_t>(31 - (0x8800 % 31));
  expect_error(inflate_all(ZFormat::kZlib, bad, &out), StatusCode::kParseError, "window", 0);
  bad = {0x78, 0x20};
  bad[1] = static_cast<uint8_t>(0x20 + 31 - (0x7820 % 31));
  expect_error(inflate_all(ZFormat::kZlib, bad, &out), StatusCode::kUnsupported, "FDICT", 1);

  const std::vector<uint8_t> g = fixture("ct.fields.gz").data;
  bad = g;
  bad[bad.size() - 5] ^= 1;  // CRC-32
  expect_error(inflate_all(ZFormat::kGzip, bad, &out), StatusCode::kParseError, "CRC-32",
               g.size() - 8);
  bad = g;
  bad[bad.size() - 1] ^= 1;  // ISIZE
  expect_error(inflate_all(ZFormat::kGzip, bad, &out), StatusCode::kParseError, "ISIZE",
               g.size() - 4);
  bad = g;
  bad[20] ^= 1;  // inside FEXTRA: the header CRC no longer matches
  expect_error(inflate_all(ZFormat::kGzip, bad, &out), StatusCode::kParseError, "header CRC", 69);
  bad = g;
  bad[1] = 0x8C;
  expect_error(inflate_all(ZFormat::kGzip, bad, &out), StatusCode::kParseError, "magic", 0);
  bad = g;
  bad[2] = 7;
  expect_error(inflate_all(ZFormat::kGzip, bad, &out), StatusCode::kParseError, "method 7", 2);
  bad = g;
  bad[3] |= 0x80;
  expect_error(inflate_all(ZFormat::kGzip, bad, &out), StatusCode::kParseError, "reserved", 3);
  bad = g;
  bad.push_back(0);
  bad.push_back(0);
  // Bytes after a member that are not another one end the stream (zlib's gzread does so).
  {
    TestArena t(inflate_state_bytes());
    Inflater z;
    SPLINTCORE_ASSERT_OK(z.begin(t.arena, ZFormat::kGzip));
    const uint8_t* p = bad.data();
    size_t n = bad.size();
    std::vector<uint8_t> plain(1 << 16);
    uint8_t* o = plain.data();
    size_t room = plain.size();
    SPLINTCORE_ASSERT_OK(z.run(&p, &n, &o, &room));
    EXPECT_TRUE(z.finished());
    EXPECT_EQ(z.total_in(), g.size());
    EXPECT_EQ(z.total_out(), 16384u);
    SPLINTCORE_EXPECT_OK(z.end_of_input());
  }
  // A lone 0x1f after a member could start one: the stream ends there when the input does.
  bad = g;
  bad.push_back(0x1F);
  SPLINTCORE_EXPECT_OK(inflate_all(ZFormat::kGzip, bad, &out));
  std::vector<uint8_t> none;
  expect_error(inflate_all(ZFormat::kGzip, none, &out), StatusCode::kTruncated, "header", 0);
}

// Stored blocks of 65,535 bytes: the window fills and wraps inside a block; the bomb guard
// cuts a stored copy short.
TEST(Inflate, LongStoredBlocks) {
  Bits b;
  std::vector<uint8_t> plain;
  for (int block = 0; block < 3; ++block) {
    b.put(block == 2 ? 1 : 0, 1);
    b.put(0, 2);
    b.put(0, b.count % 8 == 0 ? 0 : 8 - b.count % 8);
    b.put(65535, 16);
    b.put(0, 16);
    for (uint32_t i = 0; i < 65535; ++i) {
      const uint8_t v = static_cast<uint8_t>(hash_mix(i + 70000u * block));
      plain.push_back(v);
      b.put(v, 8);
    }
  }
  std::vector<uint8_t> out;
  SPLINTCORE_ASSERT_OK(inflate_all(ZFormat::kRaw, b.bytes, &out));
  EXPECT_TRUE(out == plain);
  std::vector<uint8_t> streamed;
  SPLINTCORE_ASSERT_OK(inflate_chunked(ZFormat::kRaw, b.bytes, 40000, 5000, &streamed));
  EXPECT_TRUE(streamed == plain);
  expect_error(inflate_all(ZFormat::kRaw, b.bytes, &out, 40000), StatusCode::kLimitExceeded,
               "limit of 40000", 40005);
}

TEST(InflateErrors, OutputLimit) {
  const Fixture& f = fixture("run.zlib9.zz");
  std::vector<uint8_t> out;
  SPLINTCORE_EXPECT_OK(inflate_all(f.format, f.data, &out, f.plain_bytes));
  expect_error(inflate_all(f.format, f.data, &out, f.plain_bytes - 1), StatusCode::kLimitExceeded,
               "limit of 69999 bytes", 84);
  const Fixture& s = fixture("random.stored.zz");
  expect_error(inflate_all(s.format, s.data, &out, 1000), StatusCode::kLimitExceeded,
               "limit of 1000", 1017);
  expect_error(inflate_all(s.format, s.data, &out, 500), StatusCode::kLimitExceeded, "limit of 500",
               507);
  const Fixture& h = fixture("ct.huffman.zz");  // literals only
  EXPECT_EQ(inflate_all(h.format, h.data, &out, 10).code(), StatusCode::kLimitExceeded);
  const Fixture& t = fixture("text.fixed.zz");
  EXPECT_EQ(inflate_all(t.format, t.data, &out, 10).code(), StatusCode::kLimitExceeded);
}

}  // namespace
}  // namespace splintcore
