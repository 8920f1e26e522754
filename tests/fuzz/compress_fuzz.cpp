// libFuzzer target: arbitrary bytes through inflate (include/splintcore/compress.h). The first
// byte picks the wrapper (raw, zlib, gzip) and the chunk sizes; the rest is the stream. The
// stream is inflated in one shot and again in small input and output chunks: the two must
// agree (status code, byte offset, output), the output never passes the limit, and a stream
// that inflates is deflated again by our encoder and must inflate back to the same bytes. Any
// crash, sanitizer report or broken invariant is a bug.
//   cmake -B build/fuzz -DCMAKE_CXX_COMPILER=clang++ -DSPLINTCORE_FUZZ=ON
//   build/fuzz/tests/splintcore_fuzz_compress -max_total_time=60 fixtures/fuzz/compress
#include <cstdlib>
#include <cstring>

#include "splintcore/compress.h"

namespace {

using namespace splintcore;

constexpr size_t kMaxOutput = 1 << 20;

void require(bool condition) {
  if (!condition) std::abort();
}

struct Buffer {
  uint8_t* data;
  size_t size;
  size_t capacity;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static unsigned char memory[1 << 20];
  static uint8_t whole[kMaxOutput], streamed[kMaxOutput], again[kMaxOutput + 64 * 1024];
  const ZFormat format = static_cast<ZFormat>(data[0] % 3);
  const size_t in_chunk = 1 + (data[0] >> 2) % 13;
  const size_t out_chunk = 1 + (data[0] >> 4) * 97;
  ++data;
  --size;
  Arena arena(memory, sizeof(memory));

  size_t produced = 0;
  const Status one = inflate_buffer(arena, format, data, size, whole, kMaxOutput, &produced);
  require(produced <= kMaxOutput);
  require(arena.used() == 0);

  Inflater inflater;
  require(inflater.begin(arena, format, kMaxOutput).is_ok());
  size_t at = 0, out = 0;
  Status two = Status::ok();
  for (;;) {
    const uint8_t* p = data + at;
    size_t n = size - at < in_chunk ? size - at : in_chunk;
    const size_t given = n;
    uint8_t* o = streamed + out;
    size_t room = kMaxOutput - out < out_chunk ? kMaxOutput - out : out_chunk;
    const size_t offered = room;
    two = inflater.run(&p, &n, &o, &room);
    at += given - n;
    out += offered - room;
    if (!two.is_ok() || (inflater.finished() && at == size)) break;  // gzip: members may follow
    if (n == given && room == offered) break;  // no progress: input ended, or bytes after the end
  }
  if (two.is_ok()) two = inflater.end_of_input();
  require(one.code() == two.code());
  require(one.byte_offset() == two.byte_offset());
  if (!one.is_ok()) return 0;
  require(out == produced && std::memcmp(whole, streamed, produced) == 0);
  require(inflater.total_out() == produced);

  // Our encoder's stream of the same bytes inflates back to them.
  arena.reset();
  DeflateWorkspace ws;
  require(deflate_workspace(arena, 4096, &ws).is_ok());
  Buffer compressed{again, 0, sizeof(again)};
  CompressSink sink;
  sink.user = &compressed;
  sink.write = [](void* user, const uint8_t* bytes, size_t n) {
    Buffer& b = *static_cast<Buffer*>(user);
    if (n > b.capacity - b.size) return false;
    std::memcpy(b.data + b.size, bytes, n);
    b.size += n;
    return true;
  };
  require(deflate_fixed(ws, format, whole, produced, sink).is_ok());
  size_t back = 0;
  require(
      inflate_buffer(arena, format, again, compressed.size, streamed, kMaxOutput, &back).is_ok());
  require(back == produced && std::memcmp(whole, streamed, produced) == 0);
  return 0;
}
