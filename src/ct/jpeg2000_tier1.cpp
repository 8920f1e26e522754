// JPEG 2000 code-block decoding and inverse wavelet transforms. Source: ITU-T T.800 (2019) |
// ISO/IEC 15444-1, Annex C (the MQ arithmetic decoder: Table C.2 of probability estimates,
// C.3.2 DECODE with its MPS/LPS exchanges and RENORMD, C.3.4 BYTEIN with bit stuffing after
// 0xFF, C.3.5 INITDEC), Annex D (EBCOT coefficient bit modelling: D.2 the stripe scan of four
// rows, D.3.1 significance propagation with the contexts of Table D.1, D.3.2 the sign contexts
// of Table D.3, D.3.3 magnitude refinement contexts of Table D.4, D.3.4 cleanup with run-length
// and uniform contexts, D.4.1 D.4.2 the RESET and vertically causal modes, D.5 segmentation
// symbols, Table D.7 initial states), B.10.2 (tag trees) and Annex F (F.3.7 1D_SR with the
// periodic symmetric extension, F.3.8.1 the reversible 5/3 and F.3.8.2 the irreversible 9/7
// lifting steps with the constants of Table F.4).
#include "ct/jpeg2000.h"

#include <cstring>

namespace splintcore {
namespace ct_detail {

namespace {

// Table C.2: Qe, the next index after an MPS and after an LPS, and whether an LPS switches the
// MPS sense.
struct MqState {
  uint16_t qe;
  uint8_t next_mps, next_lps, switch_mps;
};
constexpr MqState kMqStates[47] = {
    {0x5601, 1, 1, 1},   {0x3401, 2, 6, 0},   {0x1801, 3, 9, 0},   {0x0AC1, 4, 12, 0},
    {0x0521, 5, 29, 0},  {0x0221, 38, 33, 0}, {0x5601, 7, 6, 1},   {0x5401, 8, 14, 0},
    {0x4801, 9, 14, 0},  {0x3801, 10, 14, 0}, {0x3001, 11, 17, 0}, {0x2401, 12, 18, 0},
    {0x1C01, 13, 20, 0}, {0x1601, 29, 21, 0}, {0x5601, 15, 14, 1}, {0x5401, 16, 14, 0},
    {0x5101, 17, 15, 0}, {0x4801, 18, 16, 0}, {0x3801, 19, 17, 0}, {0x3401, 20, 18, 0},
    {0x3001, 21, 19, 0}, {0x2801, 22, 19, 0}, {0x2401, 23, 20, 0}, {0x2201, 24, 21, 0},
    {0x1C01, 25, 22, 0}, {0x1801, 26, 23, 0}, {0x1601, 27, 24, 0}, {0x1401, 28, 25, 0},
    {0x1201, 29, 26, 0}, {0x1101, 30, 27, 0}, {0x0AC1, 31, 28, 0}, {0x09C1, 32, 29, 0},
    {0x08A1, 33, 30, 0}, {0x0521, 34, 31, 0}, {0x0441, 35, 32, 0}, {0x02A1, 36, 33, 0},
    {0x0221, 37, 34, 0}, {0x0141, 38, 35, 0}, {0x0111, 39, 36, 0}, {0x0085, 40, 37, 0},
    {0x0049, 41, 38, 0}, {0x0025, 42, 39, 0}, {0x0015, 43, 40, 0}, {0x0009, 44, 41, 0},
    {0x0005, 45, 42, 0}, {0x0001, 45, 43, 0}, {0x5601, 46, 46, 0},
};

constexpr uint32_t kRunContext = 17, kUniformContext = 18;

// Per-sample flags: the significance of the 8 neighbours, the signs of the 4 direct ones,
// and the sample's own state.
constexpr uint32_t kSigN = 1u << 0, kSigS = 1u << 1, kSigW = 1u << 2, kSigE = 1u << 3;
constexpr uint32_t kSigNW = 1u << 4, kSigNE = 1u << 5, kSigSW = 1u << 6, kSigSE = 1u << 7;
constexpr uint32_t kNegN = 1u << 8, kNegS = 1u << 9, kNegW = 1u << 10, kNegE = 1u << 11;
constexpr uint32_t kSig = 1u << 12, kVisit = 1u << 13, kRefined = 1u << 14, kNeg = 1u << 15;
// Vertically causal mode: the last row of a stripe does not see the next stripe.
constexpr uint32_t kCausalMask = ~(kSigS | kSigSW | kSigSE | kNegS);

// Table D.1 for one subband orientation from the neighbour counts.
uint8_t zero_context(uint32_t band, uint32_t h, uint32_t v, uint32_t d) {
  if (band == 3) {  // HH
    const uint32_t hv = h + v;
    if (d >= 3) return 8;
    if (d == 2) return hv >= 1 ? 7 : 6;
    if (d == 1) return hv >= 2 ? 5 : (hv == 1 ? 4 : 3);
    return hv >= 2 ? 2 : static_cast<uint8_t>(hv);
  }
  if (band == 1) {  // HL: the roles of the horizontal and vertical neighbours swap
    const uint32_t t = h;
    h = v;
    v = t;
  }
  if (h == 2) return 8;
  if (h == 1) return v >= 1 ? 7 : (d >= 1 ? 6 : 5);
  if (v == 2) return 4;
  if (v == 1) return 3;
  return d >= 2 ? 2 : static_cast<uint8_t>(d);
}

// The decoding of one code-block's passes.
struct BlockDecoder {
  J2kTier1& t1;
  const J2kBlockJob& job;
  uint32_t fs;  // flag row stride
  const uint8_t* zc;

  uint32_t* flag(uint32_t x, uint32_t y) { return &t1.flags[(y + 1) * fs + x + 1]; }
  uint32_t mask(uint32_t y) const {
    return (job.style & kJ2kStyleCausal) != 0 && (y & 3) == 3 ? kCausalMask : ~0u;
  }

  // The sample becomes significant at bit plane p: its sign (Table D.3) and its neighbours.
  void significant(uint32_t x, uint32_t y, uint32_t p) {
    uint32_t* f = flag(x, y);
    const uint32_t m = *f & mask(y);
    const int h =
        ((m & kSigW) ? ((m & kNegW) ? -1 : 1) : 0) + ((m & kSigE) ? ((m & kNegE) ? -1 : 1) : 0);
    const int v =
        ((m & kSigN) ? ((m & kNegN) ? -1 : 1) : 0) + ((m & kSigS) ? ((m & kNegS) ? -1 : 1) : 0);
    const int hc = h > 0 ? 1 : (h < 0 ? -1 : 0), vc = v > 0 ? 1 : (v < 0 ? -1 : 0);
    uint32_t context, flip = 0;
    if (hc == 0) {
      context = vc == 0 ? 9 : 10;
      flip = vc < 0 ? 1u : 0u;
    } else {
      context = vc == 0 ? 12 : (vc == hc ? 13 : 11);
      flip = hc < 0 ? 1u : 0u;
    }
    const uint32_t negative = t1.mq.decode(context) ^ flip;
    t1.magnitude[y * job.w + x] = 3u << p;
    *f |= kSig | (negative ? kNeg : 0);
    f[-static_cast<ptrdiff_t>(fs)] |= kSigS | (negative ? kNegS : 0);
    f[fs] |= kSigN | (negative ? kNegN : 0);
    f[-1] |= kSigE | (negative ? kNegE : 0);
    f[1] |= kSigW | (negative ? kNegW : 0);
    f[-static_cast<ptrdiff_t>(fs) - 1] |= kSigSE;
    f[-static_cast<ptrdiff_t>(fs) + 1] |= kSigSW;
    f[fs - 1] |= kSigNE;
    f[fs + 1] |= kSigNW;
  }

  void significance_pass(uint32_t p) {
    for (uint32_t y0 = 0; y0 < job.h; y0 += 4) {
      const uint32_t y1 = y0 + 4 < job.h ? y0 + 4 : job.h;
      for (uint32_t x = 0; x < job.w; ++x) {
        for (uint32_t y = y0; y < y1; ++y) {
          uint32_t* f = flag(x, y);
          const uint32_t neighbours = *f & mask(y) & 0xFF;
          if ((*f & kSig) != 0 || neighbours == 0) continue;
          *f |= kVisit;
          if (t1.mq.decode(zc[neighbours])) significant(x, y, p);
        }
      }
    }
  }

  void refinement_pass(uint32_t p) {
    for (uint32_t y0 = 0; y0 < job.h; y0 += 4) {
      const uint32_t y1 = y0 + 4 < job.h ? y0 + 4 : job.h;
      for (uint32_t x = 0; x < job.w; ++x) {
        for (uint32_t y = y0; y < y1; ++y) {
          uint32_t* f = flag(x, y);
          if ((*f & (kSig | kVisit)) != kSig) continue;
          const uint32_t context =
              (*f & kRefined) != 0 ? 16 : ((*f & mask(y) & 0xFF) != 0 ? 15 : 14);
          uint32_t& m = t1.magnitude[y * job.w + x];
          if (t1.mq.decode(context)) {
            m += 1u << p;
          } else {
            m -= 1u << p;
          }
          *f |= kRefined;
        }
      }
    }
  }

  // One stripe column of the cleanup pass (D.3.4), the visit flags cleared behind it.
  void cleanup_column(uint32_t x, uint32_t y0, uint32_t y1, uint32_t p) {
    uint32_t y = y0;
    if (y1 - y0 == 4) {
      bool run = true;
      for (uint32_t k = y0; k < y1 && run; ++k) {
        const uint32_t f = *flag(x, k);
        run = (f & (kSig | kVisit)) == 0 && (f & mask(k) & 0xFF) == 0;
      }
      if (run) {
        if (!t1.mq.decode(kRunContext)) return;
        uint32_t r = t1.mq.decode(kUniformContext) << 1;
        r |= t1.mq.decode(kUniformContext);
        y = y0 + r;
        significant(x, y, p);
        ++y;
      }
    }
    for (; y < y1; ++y) {
      uint32_t* f = flag(x, y);
      if ((*f & (kSig | kVisit)) == 0 && t1.mq.decode(zc[*f & mask(y) & 0xFF])) {
        significant(x, y, p);
      }
    }
  }

  void cleanup_pass(uint32_t p) {
    for (uint32_t y0 = 0; y0 < job.h; y0 += 4) {
      const uint32_t y1 = y0 + 4 < job.h ? y0 + 4 : job.h;
      for (uint32_t x = 0; x < job.w; ++x) {
        cleanup_column(x, y0, y1, p);
        for (uint32_t y = y0; y < y1; ++y) *flag(x, y) &= ~kVisit;
      }
    }
    if ((job.style & kJ2kStyleSegmentation) != 0) {
      for (int i = 0; i < 4; ++i) (void)t1.mq.decode(kUniformContext);
    }
  }
};

}  // namespace

void MqDecoder::init(const uint8_t* bytes, size_t count) {
  data = bytes;
  size = count;
  pos = 0;
  c = uint32_t{count > 0 ? bytes[0] : uint8_t{0xFF}} << 16;
  byte_in();
  c <<= 7;
  ct -= 7;
  a = 0x8000;
}

void MqDecoder::reset_contexts() {
  std::memset(contexts, 0, sizeof(contexts));
  contexts[0] = 4;
  contexts[kRunContext] = 3;
  contexts[kUniformContext] = 46;
}

void MqDecoder::byte_in() {
  const uint32_t b = pos < size ? data[pos] : 0xFFu;
  const uint32_t next = pos + 1 < size ? data[pos + 1] : 0xFFu;
  if (b != 0xFF) {
    ++pos;
    c += next << 8;
    ct = 8;
  } else if (next > 0x8F) {  // a marker (or the end): 1 bits from here on
    c += 0xFF00;
    ct = 8;
  } else {
    ++pos;
    c += next << 9;
    ct = 7;
  }
}

uint32_t MqDecoder::decode(uint32_t context) {
  uint8_t& cx = contexts[context];
  const MqState& state = kMqStates[cx & 0x7F];
  uint32_t mps = cx >> 7;
  const uint32_t qe = state.qe;
  uint32_t d;
  a -= qe;
  if ((c >> 16) < qe) {  // the lower sub-interval, Qe: LPS_EXCHANGE
    if (a < qe) {
      d = mps;
      cx = static_cast<uint8_t>(state.next_mps | (mps << 7));
    } else {
      d = 1 - mps;
      if (state.switch_mps) mps = 1 - mps;
      cx = static_cast<uint8_t>(state.next_lps | (mps << 7));
    }
    a = qe;
  } else {
    c -= qe << 16;
    if ((a & 0x8000) != 0) return mps;
    if (a < qe) {  // MPS_EXCHANGE, the LPS branch
      d = 1 - mps;
      if (state.switch_mps) mps = 1 - mps;
      cx = static_cast<uint8_t>(state.next_lps | (mps << 7));
    } else {
      d = mps;
      cx = static_cast<uint8_t>(state.next_mps | (mps << 7));
    }
  }
  do {  // RENORMD
    if (ct == 0) byte_in();
    a <<= 1;
    c <<= 1;
    --ct;
  } while ((a & 0x8000) == 0);
  return d;
}

uint32_t J2kBits::bit() {
  if (left == 0) {
    if (pos >= size) {
      truncated = true;
      return 0;
    }
    left = byte == 0xFF ? 7 : 8;
    byte = data[pos++];
  }
  --left;
  return (byte >> left) & 1;
}

uint32_t J2kBits::bits(uint32_t n) {
  uint32_t v = 0;
  for (uint32_t i = 0; i < n; ++i) v = (v << 1) | bit();
  return v;
}

void J2kBits::align() {
  left = 0;
  if (byte == 0xFF) {  // the stuffed byte after a final 0xFF belongs to the header
    if (pos < size) {
      ++pos;
    } else {
      truncated = true;
    }
    byte = 0;
  }
}

size_t j2k_tag_tree_nodes(uint32_t w, uint32_t h) {
  if (w == 0 || h == 0) return 0;
  size_t n = 0;
  for (;;) {
    n += size_t{w} * h;
    if (w == 1 && h == 1) return n;
    w = (w + 1) / 2;
    h = (h + 1) / 2;
  }
}

void j2k_tag_tree_init(J2kTagNode* nodes, uint32_t w, uint32_t h) {
  if (w == 0 || h == 0) return;
  size_t level = 0;  // first node of the current level
  for (;;) {
    const uint32_t pw = (w + 1) / 2, ph = (h + 1) / 2;
    const size_t parent_level = level + size_t{w} * h;
    const bool root = w == 1 && h == 1;
    for (uint32_t y = 0; y < h; ++y) {
      for (uint32_t x = 0; x < w; ++x) {
        J2kTagNode& n = nodes[level + size_t{y} * w + x];
        n.value = kTagUnknown;
        n.low = 0;
        n.parent = static_cast<uint32_t>(root ? level : parent_level + size_t{y / 2} * pw + x / 2);
      }
    }
    if (root) return;
    level = parent_level;
    w = pw;
    h = ph;
  }
}

void j2k_tag_tree_decode(J2kTagNode* nodes, uint32_t leaf, int32_t threshold, J2kBits& bits,
                         bool* below) {
  uint32_t path[34];  // a tree over fewer than 2^32 x 2^32 leaves has at most 33 levels
  uint32_t depth = 0;
  uint32_t n = leaf;
  for (;;) {
    path[depth++] = n;
    if (nodes[n].parent == n) break;
    n = nodes[n].parent;
  }
  int32_t low = 0;
  while (depth > 0) {  // from the root down to the leaf
    J2kTagNode& node = nodes[path[--depth]];
    if (low > node.low) {
      node.low = low;
    } else {
      low = node.low;
    }
    while (low < threshold && low < node.value) {
      if (bits.bit()) {
        node.value = low;
      } else {
        ++low;
      }
      if (bits.truncated) break;
    }
    node.low = low;
  }
  *below = nodes[leaf].value < threshold;
}

void j2k_tier1_init(J2kTier1& t1) {
  for (uint32_t band = 0; band < 4; ++band) {
    for (uint32_t b = 0; b < 256; ++b) {
      const uint32_t h = ((b & kSigW) ? 1u : 0u) + ((b & kSigE) ? 1u : 0u);
      const uint32_t v = ((b & kSigN) ? 1u : 0u) + ((b & kSigS) ? 1u : 0u);
      const uint32_t d = ((b & kSigNW) ? 1u : 0u) + ((b & kSigNE) ? 1u : 0u) +
                         ((b & kSigSW) ? 1u : 0u) + ((b & kSigSE) ? 1u : 0u);
      t1.zero_context[band][b] = zero_context(band, h, v, d);
    }
  }
}

void j2k_decode_block(J2kTier1& t1, const J2kBlockJob& job, int32_t* out, size_t stride) {
  const uint32_t fs = job.w + 2;
  std::memset(t1.flags, 0, sizeof(uint32_t) * fs * (job.h + 2));
  std::memset(t1.magnitude, 0, sizeof(uint32_t) * job.w * job.h);
  t1.mq.init(job.data, job.size);
  t1.mq.reset_contexts();
  BlockDecoder d{t1, job, fs, t1.zero_context[job.band]};
  uint32_t p = job.bitplanes - 1 - job.zero_planes;
  uint32_t type = 2;  // the first pass is a cleanup pass
  for (uint32_t k = 0; k < job.passes; ++k) {
    if (type == 0) {
      d.significance_pass(p);
    } else if (type == 1) {
      d.refinement_pass(p);
    } else {
      d.cleanup_pass(p);
    }
    if ((job.style & kJ2kStyleReset) != 0) t1.mq.reset_contexts();
    if (type == 2) {
      if (p == 0) break;
      --p;
      type = 0;
    } else {
      ++type;
    }
  }
  for (uint32_t y = 0; y < job.h; ++y) {
    for (uint32_t x = 0; x < job.w; ++x) {
      const int32_t m = static_cast<int32_t>(t1.magnitude[y * job.w + x]);
      out[y * stride + x] = (t1.flags[(y + 1) * fs + x + 1] & kNeg) != 0 ? -m : m;
    }
  }
}

namespace {

// Reflection (F.3.7's periodic symmetric extension, one sample deep, which is all a lifting
// step reads) of the neighbours of x[k] in a signal of n >= 2 samples.
template <class T>
T left_of(const T* x, int32_t k) {
  return k > 0 ? x[k - 1] : x[1];
}
template <class T>
T right_of(const T* x, int32_t k, int32_t n) {
  return k + 1 < n ? x[k + 1] : x[n - 2];
}

// 1D_SR of F.3.7 / F.3.8.1 on x[0, n): x[k] is the sample of absolute index i0 + k.
void synthesis_53(int32_t* x, int32_t i0, int32_t n) {
  if (n == 1) {
    if ((i0 & 1) != 0) x[0] /= 2;
    return;
  }
  const int32_t first_even = i0 & 1;
  for (int32_t k = first_even; k < n; k += 2) {
    x[k] -= (left_of(x, k) + right_of(x, k, n) + 2) >> 2;
  }
  for (int32_t k = 1 - first_even; k < n; k += 2) {
    x[k] += (left_of(x, k) + right_of(x, k, n)) >> 1;
  }
}

// F.3.8.2 with the constants of Table F.4.
constexpr double kAlpha = -1.586134342059924, kBeta = -0.052980118572961;
constexpr double kGamma = 0.882911075530934, kDelta = 0.443506852043971;
constexpr double kK = 1.230174104914001;

void lift(double* x, int32_t start, int32_t n, double factor) {
  for (int32_t k = start; k < n; k += 2) x[k] -= factor * (left_of(x, k) + right_of(x, k, n));
}

void synthesis_97(double* x, int32_t i0, int32_t n) {
  if (n == 1) {
    if ((i0 & 1) != 0) x[0] /= 2;
    return;
  }
  const int32_t first_even = i0 & 1, first_odd = 1 - first_even;
  for (int32_t k = first_even; k < n; k += 2) x[k] *= kK;
  for (int32_t k = first_odd; k < n; k += 2) x[k] *= 1.0 / kK;
  lift(x, first_even, n, kDelta);
  lift(x, first_odd, n, kGamma);
  lift(x, first_even, n, kBeta);
  lift(x, first_odd, n, kAlpha);
}

// One level: every row of resolution r interleaved (2D_INTERLEAVE) and synthesised, then
// every column.
template <class T, void (*Synthesis)(T*, int32_t, int32_t)>
void inverse_level(T* tile, size_t stride, const J2kRect& low, const J2kRect& r, T* line) {
  const int32_t w = r.x1 - r.x0, h = r.y1 - r.y0;
  const int32_t lw = low.x1 - low.x0, lh = low.y1 - low.y0;
  const int32_t xo = r.x0 & 1, yo = r.y0 & 1;  // an odd start begins with a high-pass sample
  for (int32_t y = 0; y < h; ++y) {
    T* row = tile + static_cast<size_t>(y) * stride;
    for (int32_t k = 0; k < w; ++k) {
      line[k] = ((k + xo) & 1) == 0 ? row[(k - xo) / 2] : row[lw + (k + xo - 1) / 2];
    }
    Synthesis(line, r.x0, w);
    for (int32_t k = 0; k < w; ++k) row[k] = line[k];
  }
  for (int32_t x = 0; x < w; ++x) {
    T* column = tile + x;
    for (int32_t k = 0; k < h; ++k) {
      const int32_t index = ((k + yo) & 1) == 0 ? (k - yo) / 2 : lh + (k + yo - 1) / 2;
      line[k] = column[static_cast<size_t>(index) * stride];
    }
    Synthesis(line, r.y0, h);
    for (int32_t k = 0; k < h; ++k) column[static_cast<size_t>(k) * stride] = line[k];
  }
}

}  // namespace

void j2k_inverse_53(int32_t* tile, size_t stride, const J2kRect* res, uint32_t levels,
                    int32_t* line) {
  for (uint32_t r = 1; r <= levels; ++r) {
    inverse_level<int32_t, synthesis_53>(tile, stride, res[r - 1], res[r], line);
  }
}

void j2k_inverse_97(double* tile, size_t stride, const J2kRect* res, uint32_t levels,
                    double* line) {
  for (uint32_t r = 1; r <= levels; ++r) {
    inverse_level<double, synthesis_97>(tile, stride, res[r - 1], res[r], line);
  }
}

}  // namespace ct_detail
}  // namespace splintcore
