// JPEG lossless decoder, one component. Source: ITU-T T.81 (1992) | ISO/IEC 10918-1, "Digital
// compression and coding of continuous-tone still images": Annex B (interchange format:
// markers, SOF, DHT, SOS, DRI segments; B.1.1.5 fill bytes 0xFF), C (Huffman tables from BITS
// and HUFFVAL), F.1.2.3 (byte stuffing), F.2.2.3 (the DECODE procedure: MAXCODE, MINCODE,
// VALPTR) and Annex H (lossless processes: H.1.2.1 predictors 1-7 and the first line / first
// column / restart rules, H.1.2.2 difference categories 0-16 with category 16 meaning 32768
// and no extra bits, H.2.2 reconstruction modulo 2^16, point transform Pt). DICOM PS3.5 A.4.1
// and A.4.2 (transfer syntaxes .4.57 and .4.70 of PS3.6). Decodes straight into the slice.
#include "ct/jpeg_lossless.h"

#include <cstring>

#include "ct/ct_common.h"

namespace splintcore {
namespace ct_detail {

namespace {

Status jpeg_error(StatusCode code, const char* what, uint64_t at) {
  return make_error(code, "JPEG lossless: ", what).at_byte(at);
}

// What the marker segments before the scan said.
struct JpegFrame {
  JpegFrameHeader sof;
  uint32_t restart = 0;  // samples (MCUs) per restart interval; 0: none
  uint32_t predictor = 0, point_transform = 0, table = 0;
  bool scanned = false;
  JpegHuffman tables[4];
};

// The segments of T.81 lossless on the shared marker walk (ct_common.h).
struct JpegParser : JpegMarkers {
  // DHT (B.2.4.2): one or more tables, class 0 (lossless uses DC-style tables) ids 0..3.
  Status huffman(size_t at, JpegFrame* f) {
    uint32_t length = 0;
    size_t b = 0;
    SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
    const size_t end = b + length - 2;
    while (b < end) {
      if (end - b < 17) return jpeg_error(StatusCode::kParseError, "DHT segment too short", b);
      const uint32_t tc = u8(b) >> 4, th = u8(b) & 15;
      if (tc != 0 || th > 3) {
        return jpeg_error(StatusCode::kParseError,
                          "DHT table class/id not 0/0..3 (lossless has no AC tables)", b);
      }
      size_t total = 0;
      for (size_t i = 0; i < 16; ++i) total += data[b + 1 + i];
      if (total > end - b - 17) {
        return jpeg_error(StatusCode::kParseError, "DHT symbols run past the segment", b);
      }
      Status s = jpeg_build_huffman(data + b + 1, data + b + 17, total, &f->tables[th]);
      if (!s.is_ok()) return s.at_byte(b);
      b += 17 + total;
    }
    return Status::ok();
  }

  // DRI (B.2.4.4).
  Status restart_interval(size_t at, JpegFrame* f) {
    uint32_t length = 0;
    size_t b = 0;
    SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
    if (length != 4) return jpeg_error(StatusCode::kParseError, "DRI length not 4", at);
    f->restart = u16(b);
    return Status::ok();
  }

  // SOS (B.2.3): one component, predictor Ss 1..7, Se 0, Ah 0, point transform Al < P.
  Status scan_header(size_t at, JpegFrame* f) {
    uint32_t length = 0;
    size_t b = 0;
    SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
    if (!f->sof.read) return jpeg_error(StatusCode::kParseError, "SOS before SOF3", at);
    if (f->scanned) return jpeg_error(StatusCode::kUnsupported, "more than one scan", at);
    if (length != 8 || u8(b) != 1) {
      return jpeg_error(StatusCode::kParseError, "SOS must have one component (length 8)", at);
    }
    f->table = u8(b + 2) >> 4;
    f->predictor = u8(b + 3);
    f->point_transform = u8(b + 5) & 15;
    if (f->table > 3 || !f->tables[f->table].defined) {
      return jpeg_error(StatusCode::kParseError, "SOS names an undefined Huffman table", at);
    }
    if (f->predictor < 1 || f->predictor > 7 || u8(b + 4) != 0 || (u8(b + 5) >> 4) != 0) {
      return jpeg_error(StatusCode::kParseError,
                        "SOS predictor not 1..7, or Se / Ah not 0 (not lossless)", at);
    }
    if (f->point_transform >= f->sof.precision) {
      return jpeg_error(StatusCode::kParseError, "point transform not below the precision", at);
    }
    if (f->restart != 0 && f->restart % f->sof.columns != 0) {
      return jpeg_error(StatusCode::kUnsupported, "restart interval not a whole number of lines",
                        at);
    }
    f->scanned = true;
    return Status::ok();
  }
};

inline uint32_t load16(const uint8_t* out, uint64_t index) {
  return uint32_t{out[2 * index]} | (uint32_t{out[2 * index + 1]} << 8);
}

// floor(v / 2), also for negative v (no right shift of a negative number).
inline int32_t half(int32_t v) { return v >= 0 ? v / 2 : -((1 - v) / 2); }

// H.1.2.1 table H.1: the prediction from the left (a), upper (b) and upper-left (c) samples.
inline int32_t predict(uint32_t predictor, int32_t a, int32_t b, int32_t c) {
  switch (predictor) {
    case 1: return a;
    case 2: return b;
    case 3: return c;
    case 4: return a + b - c;
    case 5: return a + half(b - c);
    case 6: return b + half(a - c);
    default: return half(a + b);
  }
}

// The RSTn marker ending a restart interval (expected number `index` mod 8), its padding bits
// dropped; the bit reader then continues after it.
Status restart(JpegBits& bits, uint32_t index) {
  if (bits.count >= 8) {
    return jpeg_error(StatusCode::kParseError,
                      "entropy-coded data continues past a restart interval", bits.pos);
  }
  bits.align();
  size_t p = bits.pos;
  while (p < bits.size && bits.data[p] == 0xFF) ++p;
  if (p >= bits.size) return jpeg_error(StatusCode::kTruncated, "data ends before RSTn", bits.size);
  if (p == bits.pos || bits.data[p] != 0xD0 + (index & 7)) {
    return jpeg_error(StatusCode::kParseError, "expected the next RSTn marker", bits.pos);
  }
  bits.pos = p + 1;
  bits.at_marker = false;
  return Status::ok();
}

// The scan's samples (H.1.2, H.2): predicted, plus the Huffman-coded differences.
Status decode_scan(const JpegFrame& f, JpegBits& stream, uint8_t* out) {
  // Locals, not the frame's fields or the caller's reader: `out` is bytes, and a store through
  // it could alias them, forcing a reload or store of each per sample.
  JpegBits bits = stream;
  const JpegHuffman& table = f.tables[f.table];
  const uint32_t rows = f.sof.rows, columns = f.sof.columns, pt = f.point_transform;
  const uint32_t predictor = f.predictor, interval = f.restart;
  const int32_t initial = int32_t{1} << (f.sof.precision - pt - 1);
  uint32_t left_in_interval = interval, restarts = 0, interval_row = 0;
  for (uint32_t y = 0; y < rows; ++y) {
    if (interval != 0 && left_in_interval == 0) {
      SPLINTCORE_RETURN_IF_ERROR(restart(bits, restarts++));
      left_in_interval = interval;
      interval_row = y;
    }
    const uint64_t row = uint64_t{y} * columns;
    int32_t a = 0;  // the sample to the left
    for (uint32_t x = 0; x < columns; ++x) {
      int32_t px;
      if (y == interval_row) {
        px = x == 0 ? initial : a;
      } else if (x == 0) {
        px = static_cast<int32_t>(load16(out, row - columns) >> pt);
      } else {
        const int32_t b = static_cast<int32_t>(load16(out, row - columns + x) >> pt);
        const int32_t c = static_cast<int32_t>(load16(out, row - columns + x - 1) >> pt);
        px = predict(predictor, a, b, c);
      }
      uint32_t category = 0;
      if (!bits.decode_fast(table, &category)) {
        Status s = bits.decode(table, &category);
        if (!s.is_ok()) return s;
      }
      int32_t diff = 0;
      if (category == 16) {
        diff = 32768;
      } else if (category > 0) {
        uint32_t v = 0;
        if (!bits.bits(category, &v)) {
          return jpeg_error(StatusCode::kTruncated, "entropy-coded data ends inside a sample",
                            bits.pos);
        }
        diff = v < (1u << (category - 1)) ? static_cast<int32_t>(v) - (int32_t{1} << category) + 1
                                          : static_cast<int32_t>(v);
      }
      const uint32_t value = static_cast<uint32_t>(px + diff) & 0xFFFFu;
      // The neighbours are read back as stored (shifted up, cut to 16 bits, then down).
      const uint32_t sample = (value << pt) & 0xFFFFu;
      a = static_cast<int32_t>(sample >> pt);
      out[2 * (row + x)] = static_cast<uint8_t>(sample);
      out[2 * (row + x) + 1] = static_cast<uint8_t>(sample >> 8);
    }
    if (interval != 0) left_in_interval -= columns;  // intervals are whole lines
  }
  if (bits.count >= 8) {
    return jpeg_error(StatusCode::kParseError, "entropy-coded data continues past the last sample",
                      bits.pos);
  }
  bits.align();
  stream = bits;
  return Status::ok();
}

// The marker segments and the scan, up to EOI.
Status decode_stream(JpegFrame& f, const uint8_t* data, size_t size, uint32_t rows,
                     uint32_t columns, uint32_t max_precision, uint8_t* out) {
  JpegParser p{{data, size, "JPEG lossless"}};
  SPLINTCORE_RETURN_IF_ERROR(p.start("JPEG"));
  for (;;) {
    uint32_t code = 0;
    size_t at = 0;
    SPLINTCORE_RETURN_IF_ERROR(p.next_marker(&code, &at));
    if (code == 0xD9) {
      if (!f.scanned) return jpeg_error(StatusCode::kParseError, "EOI before the scan", at);
      return Status::ok();
    }
    if (code == 0xC3) {
      SPLINTCORE_RETURN_IF_ERROR(p.frame(at, "SOF3", &f.sof));
      if (f.sof.rows == 0) {
        return jpeg_error(StatusCode::kUnsupported, "image height 0 (given by a DNL marker)", at);
      }
      SPLINTCORE_RETURN_IF_ERROR(p.check_frame(at, "SOF3", f.sof, rows, columns, max_precision));
    } else if (code == 0xC4) {
      SPLINTCORE_RETURN_IF_ERROR(p.huffman(at, &f));
    } else if (code == 0xDD) {
      SPLINTCORE_RETURN_IF_ERROR(p.restart_interval(at, &f));
    } else if (code == 0xDA) {
      SPLINTCORE_RETURN_IF_ERROR(p.scan_header(at, &f));
      JpegBits bits;
      bits.data = data;
      bits.size = size;
      bits.pos = p.pos;
      SPLINTCORE_RETURN_IF_ERROR(decode_scan(f, bits, out));
      p.pos = bits.pos;
    } else if ((code >= 0xC0 && code <= 0xCF) || code == 0xDC) {
      // Other SOFn (lossy DCT, hierarchical, arithmetic), DAC (C8 is reserved: JPG), DNL.
      return jpeg_error(StatusCode::kUnsupported,
                        "not lossless process 14 (a SOF other than SOF3, DAC or DNL)", at);
    } else if (code == 0xD8 || (code >= 0xD0 && code <= 0xD7) || code == 0x00 || code == 0x01) {
      return jpeg_error(StatusCode::kParseError, "unexpected marker (SOI, RSTn or TEM)", at);
    } else {
      uint32_t length = 0;
      size_t body = 0;
      SPLINTCORE_RETURN_IF_ERROR(p.segment(at, &length, &body));  // APPn, COM, DQT, ...
    }
  }
}

}  // namespace

Status jpeg_build_huffman(const uint8_t counts[16], const uint8_t* symbols, size_t symbol_count,
                          JpegHuffman* table) {
  size_t total = 0;
  for (int l = 0; l < 16; ++l) total += counts[l];
  if (total != symbol_count || total > 256) {
    return make_error(StatusCode::kParseError, "JPEG Huffman table: ", total, " codes for ",
                      symbol_count, " symbols (at most 256)");
  }
  int32_t code = 0, k = 0;
  for (int l = 1; l <= 16; ++l) {
    const int32_t n = counts[l - 1];
    table->value_index[l] = k;
    table->min_code[l] = code;
    table->max_code[l] = n > 0 ? code + n - 1 : -1;
    code += n;
    k += n;
    if (code > (int32_t{1} << l)) {
      return make_error(StatusCode::kParseError, "JPEG Huffman table: more codes of length ", l,
                        " than the code space holds (over-subscribed)");
    }
    code <<= 1;
  }
  for (size_t i = 0; i < total; ++i) {
    if (symbols[i] > 16) {
      return make_error(StatusCode::kParseError, "JPEG Huffman table: symbol ", symbols[i],
                        " is not a lossless difference category (0..16)");
    }
    table->values[i] = symbols[i];
  }
  // The look-up table: each code of up to kJpegFastBits bits fills the entries it prefixes.
  std::memset(table->fast, 0, sizeof(table->fast));
  for (uint32_t l = 1; l <= kJpegFastBits; ++l) {
    for (int32_t c = table->min_code[l]; c <= table->max_code[l]; ++c) {
      const uint32_t symbol = table->values[table->value_index[l] + c - table->min_code[l]];
      const uint32_t first = static_cast<uint32_t>(c) << (kJpegFastBits - l);
      for (uint32_t e = 0; e < (1u << (kJpegFastBits - l)); ++e) {
        table->fast[first + e] = static_cast<uint16_t>((l << 8) | symbol);
      }
    }
  }
  table->defined = true;
  return Status::ok();
}

void JpegBits::refill() {
  while (count <= 56 && !at_marker) {
    if (pos >= size) {
      at_marker = true;
      break;
    }
    const uint8_t b = data[pos];
    if (b == 0xFF) {
      if (pos + 1 >= size || data[pos + 1] != 0x00) {
        at_marker = true;
        break;
      }
      ++pos;  // 0xFF 0x00: a stuffed 0xFF
    }
    ++pos;
    buffer = (buffer << 8) | b;
    count += 8;
  }
}

bool JpegBits::bits(uint32_t n, uint32_t* out) {
  if (count < n) refill();
  if (count < n) return false;
  *out = static_cast<uint32_t>(buffer >> (count - n)) & ((1u << n) - 1);
  count -= n;
  return true;
}

Status JpegBits::decode(const JpegHuffman& table, uint32_t* symbol) {
  if (count < 16) refill();
  for (uint32_t l = 1; l <= 16; ++l) {
    if (l > count) {
      return jpeg_error(StatusCode::kTruncated, "entropy-coded data ends inside a Huffman code",
                        pos);
    }
    const int32_t code = static_cast<int32_t>((buffer >> (count - l)) & ((1u << l) - 1));
    if (code <= table.max_code[l]) {
      *symbol = table.values[table.value_index[l] + code - table.min_code[l]];
      count -= l;
      return Status::ok();
    }
  }
  return jpeg_error(StatusCode::kParseError, "invalid Huffman code", pos);
}

void JpegBits::align() {
  buffer = 0;
  count = 0;
}

size_t jpeg_lossless_arena_bytes() { return sizeof(JpegFrame) + Arena::kDefaultAlignment - 1; }

Status jpeg_lossless_decode(Arena& arena, const uint8_t* data, size_t size, uint32_t rows,
                            uint32_t columns, uint32_t max_precision, uint8_t* out) {
  ArenaScope scope(arena);
  JpegFrame* f = arena.allocate_array<JpegFrame>(1);
  if (f == nullptr) return arena.exhausted_status();
  *f = JpegFrame();
  return decode_stream(*f, data, size, rows, columns, max_precision, out);
}

}  // namespace ct_detail
}  // namespace splintcore
