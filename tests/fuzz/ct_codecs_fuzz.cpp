// libFuzzer target: arbitrary frames straight into the DICOM pixel decoders (RLE Lossless,
// src/ct/dicom_rle.cpp; JPEG lossless, src/ct/jpeg_lossless.cpp; JPEG-LS, src/ct/jpeg_ls.cpp;
// JPEG 2000, src/ct/jpeg2000*.cpp), without the DICOM framing the ct_dicom target needs before
// it reaches them. Input: a mode byte (bits 0 and 1 set: JPEG-LS; bit 0 alone: JPEG; both with
// bits 2-7 the max precision; bit 0 clear and bit 2 set: JPEG 2000, bits 3-7 its max
// precision; else RLE, bit 1: 8-bit samples, else 16-bit),
// rows and columns (one byte each, 1..64), then the frame. tests/fuzz/ct_corpus.py writes the
// seeds. Any crash or sanitizer report, or arena left in use, is a bug.
//   build/fuzz/tests/splintcore_fuzz_ct_codecs -max_total_time=60 fixtures/fuzz/ct_codecs
#include <cstdlib>

#include "ct/dicom_rle.h"
#include "ct/jpeg2000.h"
#include "ct/jpeg_lossless.h"
#include "ct/jpeg_ls.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace splintcore;
  if (size < 3) return 0;
  static uint8_t out[2 * 64 * 64];
  alignas(16) static unsigned char memory[16384];
  const uint32_t mode = data[0];
  const uint32_t rows = 1 + data[1] % 64u, columns = 1 + data[2] % 64u;
  const uint8_t* frame = data + 3;
  const size_t n = size - 3;
  if ((mode & 3) == 3) {
    Arena arena(memory, sizeof(memory));  // jpeg_ls_arena_bytes(64): about 9.4 KB
    (void)ct_detail::jpeg_ls_decode(arena, frame, n, rows, columns, 2 + (mode >> 2) % 15u, out);
    if (arena.used() != 0) std::abort();
  } else if ((mode & 1) != 0) {
    Arena arena(memory, sizeof(memory));
    const uint32_t precision = 2 + (mode >> 2) % 15u;
    (void)ct_detail::jpeg_lossless_decode(arena, frame, n, rows, columns, precision, out);
    if (arena.used() != 0) std::abort();
  } else if ((mode & 4) != 0) {
    alignas(16) static unsigned char j2k_memory[1 << 20];
    if (ct_detail::jpeg2000_arena_bytes(rows, columns, n) > sizeof(j2k_memory)) return 0;
    Arena arena(j2k_memory, sizeof(j2k_memory));
    const uint32_t precision = 2 + (mode >> 3) % 15u;
    (void)ct_detail::jpeg2000_decode(arena, frame, n, rows, columns, precision, out);
    if (arena.used() != 0) std::abort();
  } else {
    (void)ct_detail::rle_decode_frame(frame, n, rows, columns, (mode & 2) != 0 ? 1 : 2, out);
  }
  return 0;
}
