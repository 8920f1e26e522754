// PNG encoder (include/splintcore/render.h).
//
// Sources: ISO/IEC 15948:2003 (PNG, also W3C "Portable Network Graphics Specification, Second
// Edition"): chunk layout, IHDR, the five row filters and Paeth's predictor (A. W. Paeth,
// "Image file compression made easy", Graphics Gems II, 1991), the minimum-sum-of-absolute-
// differences filter heuristic (section 12.8); the zlib stream (RFC 1950/1951) and CRC-32
// come from src/compress (deflate.cpp names its sources).
//
// Deterministic: integer arithmetic only; the matcher's choices depend only on the bytes.
#include <cstring>

#include "splintcore/compress.h"
#include "splintcore/render.h"

namespace splintcore {
namespace {

constexpr size_t kOutCapacity = 65536;  // bytes of one IDAT chunk's data
constexpr uint32_t kPngBands = 16;      // filtering's tasks (the bytes do not depend on it)

void put_be32(uint8_t* p, uint32_t v) {
  p[0] = static_cast<uint8_t>(v >> 24);
  p[1] = static_cast<uint8_t>(v >> 16);
  p[2] = static_cast<uint8_t>(v >> 8);
  p[3] = static_cast<uint8_t>(v);
}

Status write_sink(const ByteSink& sink, const uint8_t* data, size_t bytes) {
  if (bytes == 0) return Status::ok();
  if (!sink.write(sink.user, data, bytes)) {
    return make_error(StatusCode::kIoError, "cannot write the PNG")
        .in_file(sink.name != nullptr ? sink.name : "output");
  }
  return Status::ok();
}

Status write_chunk(const ByteSink& sink, const char type[4], const uint8_t* data, size_t bytes) {
  uint8_t head[8];
  put_be32(head, static_cast<uint32_t>(bytes));
  std::memcpy(head + 4, type, 4);
  uint32_t crc = crc32(0, head + 4, 4);
  crc = crc32(crc, data, bytes);
  uint8_t tail[4];
  put_be32(tail, crc);
  SPLINTCORE_RETURN_IF_ERROR(write_sink(sink, head, 8));
  SPLINTCORE_RETURN_IF_ERROR(write_sink(sink, data, bytes));
  return write_sink(sink, tail, 4);
}

// The zlib stream's pieces (each full kOutCapacity but the last) become IDAT chunks; the
// first failure's Status is kept so the caller reports the PNG's sink, not the encoder's.
struct IdatWriter {
  const ByteSink* sink;
  Status failure;
  static bool write(void* user, const uint8_t* data, size_t bytes) {
    IdatWriter& w = *static_cast<IdatWriter*>(user);
    w.failure = write_chunk(*w.sink, "IDAT", data, bytes);
    return w.failure.is_ok();
  }
};

inline uint8_t paeth(uint8_t a, uint8_t b, uint8_t c) {
  const int p = static_cast<int>(a) + b - c;
  const int pa = p > a ? p - a : a - p;
  const int pb = p > b ? p - b : b - p;
  const int pc = p > c ? p - c : c - p;
  const uint8_t bc = pb <= pc ? b : c;
  return (pa <= pb && pa <= pc) ? a : bc;
}

// The predictions at byte i of a row: a (left), b (above), c (above left) are 0 outside the
// image (the first pixel's 3 bytes, the first row). The loops below handle those edges first
// so that the inner loops have no branches (the same bytes as the spec's definition).
struct Neighbours {
  uint8_t a, b, c;
};
inline Neighbours neighbours(const uint8_t* row, const uint8_t* above, size_t i) {
  return {i >= 3 ? row[i - 3] : uint8_t{0}, above != nullptr ? above[i] : uint8_t{0},
          (i >= 3 && above != nullptr) ? above[i - 3] : uint8_t{0}};
}

// Bytes i..i+7 of a row (i >= 3, with a row above) are flat: each equals its left, above and
// above-left neighbours (a uniform region, three quarters of a preview): Sub, Up and Paeth all
// predict them exactly. The filters below take such runs whole (the same bytes as byte by byte).
inline uint64_t load8(const uint8_t* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}
inline bool flat8(const uint8_t* row, const uint8_t* above, size_t i) {
  const uint64_t x = load8(row + i);
  return x == load8(row + i - 3) && x == load8(above + i) && x == load8(above + i - 3);
}

// Row `y` filtered with `type` (0 None, 1 Sub, 2 Up, 4 Paeth) into out (3w bytes).
void filter_row(const uint8_t* row, const uint8_t* above, size_t bytes, int type, uint8_t* out) {
  const size_t edge = bytes < 3 ? bytes : 3;
  for (size_t i = 0; i < edge; ++i) {
    const Neighbours n = neighbours(row, above, i);
    uint8_t predicted = 0;
    if (type == 1) predicted = n.a;
    if (type == 2) predicted = n.b;
    if (type == 4) predicted = paeth(n.a, n.b, n.c);
    out[i] = static_cast<uint8_t>(row[i] - predicted);
  }
  if (type == 0) {
    for (size_t i = edge; i < bytes; ++i) out[i] = row[i];
  } else if (type == 1 || (type == 4 && above == nullptr)) {  // Paeth of (a, 0, 0) is a
    for (size_t i = edge; i < bytes; ++i) out[i] = static_cast<uint8_t>(row[i] - row[i - 3]);
  } else if (above == nullptr) {  // Up with b = 0
    for (size_t i = edge; i < bytes; ++i) out[i] = row[i];
  } else if (type == 2) {
    for (size_t i = edge; i < bytes; ++i) out[i] = static_cast<uint8_t>(row[i] - above[i]);
  } else {
    auto one = [&](size_t i) {
      out[i] = static_cast<uint8_t>(row[i] - paeth(row[i - 3], above[i], above[i - 3]));
    };
    size_t i = edge;
    for (; i + 8 <= bytes; i += 8) {
      if (flat8(row, above, i)) {
        std::memset(out + i, 0, 8);  // Paeth predicts a flat byte exactly
      } else {
        for (size_t k = i; k < i + 8; ++k) one(k);
      }
    }
    for (; i < bytes; ++i) one(i);
  }
}

uint32_t abs_signed(uint8_t v) { return v < 128 ? v : 256u - v; }

// Sums of |filtered byte as int8| for None, Sub, Up and Paeth, in one pass.
void filter_costs(const uint8_t* row, const uint8_t* above, size_t bytes, uint64_t costs[4]) {
  uint64_t none = 0, sub = 0, up = 0, pae = 0;
  const size_t edge = bytes < 3 ? bytes : 3;
  for (size_t i = 0; i < edge; ++i) {
    const uint8_t x = row[i];
    const Neighbours n = neighbours(row, above, i);
    none += abs_signed(x);
    sub += abs_signed(static_cast<uint8_t>(x - n.a));
    up += abs_signed(static_cast<uint8_t>(x - n.b));
    pae += abs_signed(static_cast<uint8_t>(x - paeth(n.a, n.b, n.c)));
  }
  if (above == nullptr) {  // b = c = 0: Up is None, and Paeth of (a, 0, 0) is a (Sub)
    for (size_t i = edge; i < bytes; ++i) {
      const uint8_t x = row[i];
      const uint32_t s = abs_signed(static_cast<uint8_t>(x - row[i - 3]));
      none += abs_signed(x);
      up += abs_signed(x);
      sub += s;
      pae += s;
    }
  } else {
    auto one = [&](size_t i) {
      const uint8_t x = row[i];
      none += abs_signed(x);
      sub += abs_signed(static_cast<uint8_t>(x - row[i - 3]));
      up += abs_signed(static_cast<uint8_t>(x - above[i]));
      pae += abs_signed(static_cast<uint8_t>(x - paeth(row[i - 3], above[i], above[i - 3])));
    };
    size_t i = edge;
    for (; i + 8 <= bytes; i += 8) {
      if (flat8(row, above, i)) {  // Sub, Up and Paeth residuals 0
        for (size_t k = i; k < i + 8; ++k) none += abs_signed(row[k]);
      } else {
        for (size_t k = i; k < i + 8; ++k) one(k);
      }
    }
    for (; i < bytes; ++i) one(i);
  }
  costs[0] = none;
  costs[1] = sub;
  costs[2] = up;
  costs[3] = pae;
}

// A row's filter byte (the type of smallest absolute sum; ties: the lowest type) and its
// filtered bytes into dest[0..bytes].
void filter_best(const uint8_t* row, const uint8_t* above, size_t bytes, uint8_t* dest) {
  const int types[4] = {0, 1, 2, 4};
  uint64_t costs[4];
  filter_costs(row, above, bytes, costs);
  int best_type = 0;
  uint64_t best_cost = UINT64_MAX;
  for (int k = 0; k < 4; ++k) {
    if (costs[k] < best_cost) {
      best_cost = costs[k];
      best_type = types[k];
    }
  }
  dest[0] = static_cast<uint8_t>(best_type);
  filter_row(row, above, bytes, best_type, dest + 1);
}

}  // namespace

uint32_t png_crc32(uint32_t crc, const uint8_t* data, size_t bytes) {
  return crc32(crc, data, bytes);
}

uint32_t png_adler32(uint32_t adler, const uint8_t* data, size_t bytes) {
  return adler32(adler, data, bytes);
}

uint64_t png_bound(uint32_t width, uint32_t height) {
  uint64_t row = 0, rows = 0;
  if (!checked_mul(width, 3, &row) || !checked_add(row, 1, &row) ||
      !checked_mul(row, height, &rows)) {
    return UINT64_MAX;
  }
  uint64_t total = 0;
  static_assert(kOutCapacity == 65536, "deflate_parallel writes IDAT chunks of 64 KiB");
  if (!checked_add(rows, 16 + deflate_lanes_bound(static_cast<size_t>(rows)), &total)) {
    return UINT64_MAX;
  }
  return total;
}

Status write_png(const Context& ctx, const RenderImage& image, const ByteSink& sink) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && sink.write != nullptr);
  const uint32_t w = image.width, h = image.height;
  if (w == 0 || h == 0 || w > kRenderMaxSide || h > kRenderMaxSide || image.rgb == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "PNG size ", w, " x ", h,
                      " is out of range (each side 1..", kRenderMaxSide,
                      " pixels, with pixel data)");
  }
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  const size_t row_bytes = static_cast<size_t>(w) * 3;
  const size_t stride = row_bytes + 1;
  const size_t size = stride * h;  // <= 8192 * 24577: no overflow
  uint8_t* filtered = arena.allocate_array<uint8_t>(size);
  if (filtered == nullptr) return arena.exhausted_status();
  DeflateLanes lanes;
  SPLINTCORE_RETURN_IF_ERROR(deflate_lanes(arena, size, DeflateEffort{}, &lanes));

  // Each row filtered with the type of smallest absolute sum (ties: the lowest type), in
  // bands of rows on the executor (a row depends only on itself and the row above).
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "png", 0, h));
  const uint32_t bands = h < kPngBands ? h : kPngBands;
  auto band = [&](uint32_t b) {
    const uint64_t rows = h;
    const uint32_t y0 = static_cast<uint32_t>(rows * b / bands);
    const uint32_t y1 = static_cast<uint32_t>(rows * (b + 1) / bands);
    for (uint32_t y = y0; y < y1; ++y) {
      const uint8_t* row = image.rgb + static_cast<size_t>(y) * row_bytes;
      filter_best(row, y > 0 ? row - row_bytes : nullptr, row_bytes,
                  filtered + static_cast<size_t>(y) * stride);
    }
  };
  parallel_for_each(ctx.executor, bands, band);
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "png", h, h));

  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  SPLINTCORE_RETURN_IF_ERROR(write_sink(sink, kSignature, 8));
  uint8_t ihdr[13];
  put_be32(ihdr, w);
  put_be32(ihdr + 4, h);
  ihdr[8] = 8;   // bit depth
  ihdr[9] = 2;   // colour type: RGB
  ihdr[10] = 0;  // deflate
  ihdr[11] = 0;  // adaptive filtering
  ihdr[12] = 0;  // no interlace
  SPLINTCORE_RETURN_IF_ERROR(write_chunk(sink, "IHDR", ihdr, sizeof(ihdr)));
  static const char kText[] = "Software\0splintcore";
  SPLINTCORE_RETURN_IF_ERROR(
      write_chunk(sink, "tEXt", reinterpret_cast<const uint8_t*>(kText), sizeof(kText) - 1));

  IdatWriter idat{&sink, Status::ok()};
  CompressSink idat_sink;
  idat_sink.write = &IdatWriter::write;
  idat_sink.user = &idat;
  const Status deflated =
      deflate_parallel(ctx.executor, lanes, ZFormat::kZlib, filtered, size, idat_sink);
  if (!idat.failure.is_ok()) return idat.failure;
  SPLINTCORE_RETURN_IF_ERROR(deflated);
  return write_chunk(sink, "IEND", nullptr, 0);
}

}  // namespace splintcore
