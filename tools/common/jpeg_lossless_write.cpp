// JPEG lossless encoder, one component, precision 16. Source: ITU-T T.81 (1992): Annex B (the
// markers and segments), C (code lengths to codes), F.1.2.3 (byte stuffing), H.1.2 (predictors,
// the first line and column, difference categories 0..16 with 16 meaning 32768 and no extra
// bits) and K.2 (Huffman code lengths from symbol frequencies, limited to 16 bits, one code
// point reserved so no code is all 1 bits).
#include "jpeg_lossless_write.h"

#include <cstddef>

namespace splintcore {
namespace cli {

namespace {

constexpr int kSymbols = 17;   // difference categories 0..16
constexpr int kReserved = 17;  // K.2's reserved symbol (the 257th of its tables)

// K.2 figures K.1 to K.3: code sizes, BITS adjusted to at most 16 bits, HUFFVAL sorted.
void huffman_lengths(const uint64_t freq_in[kSymbols], uint8_t bits[16],
                     std::vector<uint8_t>* values) {
  uint64_t freq[kSymbols + 1];
  int size[kSymbols + 1], others[kSymbols + 1];
  for (int v = 0; v <= kSymbols; ++v) {
    freq[v] = v < kSymbols ? freq_in[v] : 1;
    size[v] = 0;
    others[v] = -1;
  }
  for (;;) {
    int v1 = -1, v2 = -1;  // the least frequencies (ties: the largest symbol)
    for (int v = 0; v <= kSymbols; ++v) {
      if (freq[v] > 0 && (v1 < 0 || freq[v] <= freq[v1])) v1 = v;
    }
    for (int v = 0; v <= kSymbols; ++v) {
      if (v != v1 && freq[v] > 0 && (v2 < 0 || freq[v] <= freq[v2])) v2 = v;
    }
    if (v2 < 0) break;
    freq[v1] += freq[v2];
    freq[v2] = 0;
    ++size[v1];
    while (others[v1] >= 0) {
      v1 = others[v1];
      ++size[v1];
    }
    others[v1] = v2;
    ++size[v2];
    while (others[v2] >= 0) {
      v2 = others[v2];
      ++size[v2];
    }
  }
  int count[33] = {0};
  for (int v = 0; v <= kSymbols; ++v) {
    if (size[v] > 0) ++count[size[v]];
  }
  for (int i = 32; i > 16; --i) {
    while (count[i] > 0) {
      int j = i - 2;
      while (count[j] == 0) --j;
      count[i] -= 2;
      count[i - 1] += 1;
      count[j + 1] += 2;
      count[j] -= 1;
    }
  }
  int longest = 16;
  while (count[longest] == 0) --longest;
  count[longest] -= 1;  // the reserved code point
  for (int i = 1; i <= 16; ++i) bits[i - 1] = static_cast<uint8_t>(count[i]);
  values->clear();
  for (int s = 1; s <= 32; ++s) {
    for (int v = 0; v < kSymbols; ++v) {
      if (size[v] == s && v != kReserved) values->push_back(static_cast<uint8_t>(v));
    }
  }
}

// floor(v / 2) (T.81's arithmetic right shift by 1).
int32_t half(int32_t v) { return v >= 0 ? v / 2 : -((1 - v) / 2); }

// The difference of every sample to its H.1.2.1 prediction, modulo 2^16 in -32767..32768.
std::vector<int32_t> differences(const uint16_t* s, uint32_t rows, uint32_t columns,
                                 uint32_t predictor) {
  std::vector<int32_t> d(static_cast<size_t>(rows) * columns);
  for (uint32_t y = 0; y < rows; ++y) {
    for (uint32_t x = 0; x < columns; ++x) {
      const size_t i = static_cast<size_t>(y) * columns + x;
      int32_t p;
      if (y == 0) {
        p = x == 0 ? 32768 : s[i - 1];
      } else if (x == 0) {
        p = s[i - columns];
      } else {
        const int32_t a = s[i - 1], b = s[i - columns], c = s[i - columns - 1];
        switch (predictor) {
          case 1: p = a; break;
          case 2: p = b; break;
          case 3: p = c; break;
          case 4: p = a + b - c; break;
          case 5: p = a + half(b - c); break;
          case 6: p = b + half(a - c); break;
          default: p = half(a + b); break;
        }
      }
      int32_t v = static_cast<int32_t>(static_cast<uint32_t>(s[i] - p) & 0xFFFFu);
      if (v > 32768) v -= 65536;
      d[i] = v;
    }
  }
  return d;
}

uint32_t category(int32_t d) {
  uint32_t m = static_cast<uint32_t>(d < 0 ? -d : d), c = 0;
  while (m != 0) {
    ++c;
    m >>= 1;
  }
  return c;
}

struct BitWriter {
  std::vector<uint8_t>* out;
  uint64_t buffer = 0;
  uint32_t count = 0;
  void put(uint32_t value, uint32_t n) {
    buffer = (buffer << n) | (value & ((uint64_t{1} << n) - 1));
    count += n;
    while (count >= 8) {
      const uint8_t b = static_cast<uint8_t>(buffer >> (count - 8));
      out->push_back(b);
      if (b == 0xFF) out->push_back(0x00);
      count -= 8;
    }
  }
  void finish() {
    if (count > 0) put(0x7F, 8 - count);  // pad with 1 bits
  }
};

void put16(std::vector<uint8_t>* o, uint32_t v) {
  o->push_back(static_cast<uint8_t>(v >> 8));
  o->push_back(static_cast<uint8_t>(v));
}

}  // namespace

std::vector<uint8_t> jpeg_lossless_encode(const uint16_t* samples, uint32_t rows, uint32_t columns,
                                          uint32_t predictor) {
  const std::vector<int32_t> d = differences(samples, rows, columns, predictor);
  uint64_t freq[kSymbols] = {0};
  for (int32_t v : d) ++freq[category(v)];
  uint8_t bits[16];
  std::vector<uint8_t> values;
  huffman_lengths(freq, bits, &values);
  // C.2: codes in order of HUFFVAL, lengths ascending.
  uint32_t code_of[kSymbols] = {0}, length_of[kSymbols] = {0};
  uint32_t code = 0;
  size_t k = 0;
  for (uint32_t l = 1; l <= 16; ++l) {
    for (uint32_t n = 0; n < bits[l - 1]; ++n, ++k, ++code) {
      code_of[values[k]] = code;
      length_of[values[k]] = l;
    }
    code <<= 1;
  }
  std::vector<uint8_t> o = {0xFF, 0xD8, 0xFF, 0xC3};
  put16(&o, 11);
  o.push_back(16);
  put16(&o, rows);
  put16(&o, columns);
  o.insert(o.end(), {1, 1, 0x11, 0});
  o.insert(o.end(), {0xFF, 0xC4});
  put16(&o, static_cast<uint32_t>(2 + 17 + values.size()));
  o.push_back(0x00);
  o.insert(o.end(), bits, bits + 16);
  o.insert(o.end(), values.begin(), values.end());
  o.insert(o.end(), {0xFF, 0xDA});
  put16(&o, 8);
  o.insert(o.end(), {1, 1, 0x00, static_cast<uint8_t>(predictor), 0, 0});
  BitWriter w{&o};
  for (int32_t v : d) {
    const uint32_t c = category(v);
    w.put(code_of[c], length_of[c]);
    if (c > 0 && c < 16) w.put(static_cast<uint32_t>(v < 0 ? v - 1 : v), c);
  }
  w.finish();
  o.insert(o.end(), {0xFF, 0xD9});
  return o;
}

}  // namespace cli
}  // namespace splintcore
