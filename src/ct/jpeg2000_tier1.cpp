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

// The MQ decoder's state must stay in registers through the passes: GCC and clang are told to
// inline its steps where -O2's size heuristics would not.
#if defined(__GNUC__)
#define SPLINTCORE_J2K_INLINE inline __attribute__((always_inline))
#else
#define SPLINTCORE_J2K_INLINE inline
#endif

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

// BYTEIN (C.3.4).
SPLINTCORE_J2K_INLINE void mq_byte_in(MqDecoder& m) {
  const uint32_t b = m.pos < m.size ? m.data[m.pos] : 0xFFu;
  const uint32_t next = m.pos + 1 < m.size ? m.data[m.pos + 1] : 0xFFu;
  if (b != 0xFF) {
    ++m.pos;
    m.c += next << 8;
    m.ct = 8;
  } else if (next > 0x8F) {  // a marker (or the end): 1 bits from here on
    m.c += 0xFF00;
    m.ct = 8;
  } else {
    ++m.pos;
    m.c += next << 9;
    m.ct = 7;
  }
}

// Table C.2 unfolded by MPS sense (OpenJPEG's layout): entry 2 state + mps holds Qe, the MPS
// and the entries after an MPS and after an LPS (the switch applied), so a decision is two
// look-ups and no bit fiddling.
struct MqEntry {
  uint16_t qe = 0;
  uint8_t mps = 0, next_mps = 0, next_lps = 0;
};
struct MqTable {
  MqEntry e[2 * 47];
};
constexpr MqTable make_mq_table() {
  MqTable t{};
  for (uint32_t s = 0; s < 47; ++s) {
    for (uint32_t mps = 0; mps < 2; ++mps) {
      MqEntry& x = t.e[2 * s + mps];
      x.qe = kMqStates[s].qe;
      x.mps = static_cast<uint8_t>(mps);
      x.next_mps = static_cast<uint8_t>(2 * kMqStates[s].next_mps + mps);
      x.next_lps = static_cast<uint8_t>(2 * kMqStates[s].next_lps +
                                        (kMqStates[s].switch_mps ? 1 - mps : mps));
    }
  }
  return t;
}
constexpr MqTable kMq = make_mq_table();

// The left shifts that set bit 15 of a in [1, 0x8000).
SPLINTCORE_J2K_INLINE uint32_t renorm_shifts(uint32_t a) {
#if defined(__GNUC__)
  return static_cast<uint32_t>(__builtin_clz(a)) - 16;
#else
  uint32_t n = 0;
  while (((a << n) & 0x8000) == 0) ++n;
  return n;
#endif
}

// DECODE (C.3.2) with its exchanges and RENORMD. Inline on purpose: the passes call it on a
// local copy of the decoder, whose registers no store into the flags can then alias.
SPLINTCORE_J2K_INLINE uint32_t mq_decode(MqDecoder& m, uint32_t context) {
  uint8_t& cx = m.contexts[context];
  const MqEntry& e = kMq.e[cx];
  const uint32_t qe = e.qe;
  uint32_t d;
  m.a -= qe;
  if ((m.c >> 16) < qe) {  // the lower sub-interval, Qe: LPS_EXCHANGE
    if (m.a < qe) {
      d = e.mps;
      cx = e.next_mps;
    } else {
      d = e.mps ^ 1u;
      cx = e.next_lps;
    }
    m.a = qe;
  } else {
    m.c -= qe << 16;
    if ((m.a & 0x8000) != 0) return e.mps;
    if (m.a < qe) {  // MPS_EXCHANGE, the LPS branch
      d = e.mps ^ 1u;
      cx = e.next_lps;
    } else {
      d = e.mps;
      cx = e.next_mps;
    }
  }
  // RENORMD: the shifts that bring A to 0x8000 or more, as many at once as CT allows, a byte
  // read in whenever CT runs out (the same order as bit by bit).
  uint32_t n = renorm_shifts(m.a);
  while (n > m.ct) {
    m.a <<= m.ct;
    m.c <<= m.ct;
    n -= m.ct;
    m.ct = 0;
    mq_byte_in(m);
  }
  m.a <<= n;
  m.c <<= n;
  m.ct -= n;
  return d;
}

// One code-block's arrays: `flags` points at sample (0, 0) of the bordered flag array (row
// stride fs), `mag` at the magnitudes (row stride w).
struct BlockView {
  uint32_t* flags;
  uint32_t* mag;
  uint32_t fs, w, h;
  const uint8_t* zc;  // Table D.1 of the band, by the 8 neighbour bits
  const uint8_t* sc;  // Table D.3 by the 4 direct neighbours' significance and signs
};

// The passes of one code-block (D.3), stripe by stripe, each stripe column by column. Each
// pass takes the view by value and a local copy of the MQ decoder, so that neither can be
// aliased by the stores into the flags and both stay in registers; the decoder is handed back.
// kCausal: the vertically causal mode (the last row of a stripe does not see the stripe below).
template <bool kCausal>
struct Passes {
  // The neighbour bits a sample in stripe row r sees.
  static uint32_t seen(uint32_t f, uint32_t r) { return kCausal && r == 3 ? f & kCausalMask : f; }

  // The sample at f becomes significant at bit plane p: its sign decoded (Table D.3), its
  // magnitude 1.5 2^p (with the fractional bit), its neighbours told.
  SPLINTCORE_J2K_INLINE static void significant(MqDecoder& m, const BlockView& v, uint32_t* f,
                                                uint32_t* magnitude, uint32_t r, uint32_t p) {
    const uint32_t n = seen(*f, r);
    const uint32_t s = v.sc[(n & 0xF) | ((n >> 4) & 0xF0)];
    const uint32_t negative = mq_decode(m, s & 0x7F) ^ (s >> 7);
    *magnitude = 3u << p;
    const size_t fs = v.fs;
    *f |= kSig | (negative ? kNeg : 0);
    *(f - fs) |= kSigS | (negative ? kNegS : 0);
    f[fs] |= kSigN | (negative ? kNegN : 0);
    f[-1] |= kSigE | (negative ? kNegE : 0);
    f[1] |= kSigW | (negative ? kNegW : 0);
    *(f - fs - 1) |= kSigSE;
    *(f - fs + 1) |= kSigSW;
    f[fs - 1] |= kSigNE;
    f[fs + 1] |= kSigNW;
  }

  static void significance(const BlockView v, MqDecoder* decoder, uint32_t p) {
    MqDecoder m = *decoder;
    const size_t fs = v.fs;
    for (uint32_t y0 = 0; y0 < v.h; y0 += 4) {
      const uint32_t rows = v.h - y0 < 4 ? v.h - y0 : 4;
      uint32_t* col = v.flags + y0 * fs;
      uint32_t* mcol = v.mag + size_t{y0} * v.w;
      for (uint32_t x = 0; x < v.w; ++x, ++col, ++mcol) {
        if (rows == 4 && ((col[0] | col[fs] | col[2 * fs] | col[3 * fs]) & 0xFF) == 0) continue;
        uint32_t* f = col;
        for (uint32_t r = 0; r < rows; ++r, f += fs) {
          const uint32_t value = *f;
          const uint32_t neighbours = seen(value, r) & 0xFF;
          if ((value & kSig) != 0 || neighbours == 0) continue;
          *f = value | kVisit;
          if (mq_decode(m, v.zc[neighbours])) significant(m, v, f, mcol + size_t{r} * v.w, r, p);
        }
      }
    }
    *decoder = m;
  }

  static void refinement(const BlockView v, MqDecoder* decoder, uint32_t p) {
    MqDecoder m = *decoder;
    const size_t fs = v.fs;
    const uint32_t bit = 1u << p;
    for (uint32_t y0 = 0; y0 < v.h; y0 += 4) {
      const uint32_t rows = v.h - y0 < 4 ? v.h - y0 : 4;
      uint32_t* col = v.flags + y0 * fs;
      uint32_t* mcol = v.mag + size_t{y0} * v.w;
      for (uint32_t x = 0; x < v.w; ++x, ++col, ++mcol) {
        if (rows == 4 && ((col[0] | col[fs] | col[2 * fs] | col[3 * fs]) & kSig) == 0) continue;
        uint32_t* f = col;
        for (uint32_t r = 0; r < rows; ++r, f += fs) {
          const uint32_t value = *f;
          if ((value & (kSig | kVisit)) != kSig) continue;
          const uint32_t context =
              (value & kRefined) != 0 ? 16 : ((seen(value, r) & 0xFF) != 0 ? 15 : 14);
          uint32_t& magnitude = mcol[size_t{r} * v.w];
          if (mq_decode(m, context)) {
            magnitude += bit;
          } else {
            magnitude -= bit;
          }
          *f = value | kRefined;
        }
      }
    }
    *decoder = m;
  }

  // D.3.4: a column of four samples with nothing significant around and not yet visited is
  // coded as a run; the visit flags are cleared behind each column.
  static void cleanup(const BlockView v, MqDecoder* decoder, uint32_t p, bool segmentation) {
    MqDecoder m = *decoder;
    const size_t fs = v.fs;
    constexpr uint32_t kBusy = kSig | kVisit | 0xFF;
    for (uint32_t y0 = 0; y0 < v.h; y0 += 4) {
      const uint32_t rows = v.h - y0 < 4 ? v.h - y0 : 4;
      uint32_t* col = v.flags + y0 * fs;
      uint32_t* mcol = v.mag + size_t{y0} * v.w;
      for (uint32_t x = 0; x < v.w; ++x, ++col, ++mcol) {
        uint32_t r = 0;
        if (rows == 4 && ((col[0] | col[fs] | col[2 * fs] | seen(col[3 * fs], 3)) & kBusy) == 0) {
          if (!mq_decode(m, kRunContext)) continue;  // four zeros (nothing to clear)
          r = mq_decode(m, kUniformContext) << 1;
          r |= mq_decode(m, kUniformContext);
          significant(m, v, col + r * fs, mcol + size_t{r} * v.w, r, p);
          ++r;
        }
        for (; r < rows; ++r) {
          uint32_t* f = col + r * fs;
          const uint32_t value = *f;
          if ((value & (kSig | kVisit)) == 0 && mq_decode(m, v.zc[seen(value, r) & 0xFF])) {
            significant(m, v, f, mcol + size_t{r} * v.w, r, p);
          }
        }
        for (r = 0; r < rows; ++r) col[r * fs] &= ~kVisit;
      }
    }
    if (segmentation) {
      for (int i = 0; i < 4; ++i) (void)mq_decode(m, kUniformContext);
    }
    *decoder = m;
  }

  static void run(const BlockView& v, J2kTier1& t1, const J2kBlockJob& job) {
    uint32_t p = job.bitplanes - 1 - job.zero_planes;
    uint32_t type = 2;  // the first pass is a cleanup pass
    const bool segmentation = (job.style & kJ2kStyleSegmentation) != 0;
    for (uint32_t k = 0; k < job.passes; ++k) {
      if (type == 0) {
        significance(v, &t1.mq, p);
      } else if (type == 1) {
        refinement(v, &t1.mq, p);
      } else {
        cleanup(v, &t1.mq, p, segmentation);
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
  }
};

}  // namespace

void MqDecoder::init(const uint8_t* bytes, size_t count) {
  data = bytes;
  size = count;
  pos = 0;
  c = uint32_t{count > 0 ? bytes[0] : uint8_t{0xFF}} << 16;
  mq_byte_in(*this);
  c <<= 7;
  ct -= 7;
  a = 0x8000;
}

void MqDecoder::reset_contexts() {
  std::memset(contexts, 0, sizeof(contexts));
  contexts[0] = 2 * 4;  // entries 2 state + mps of kMq, the MPS 0
  contexts[kRunContext] = 2 * 3;
  contexts[kUniformContext] = 2 * 46;
}

uint32_t MqDecoder::decode(uint32_t context) { return mq_decode(*this, context); }
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
  // Table D.3 by index: significance of N, S, W, E in bits 0-3, their signs in bits 4-7.
  for (uint32_t i = 0; i < 256; ++i) {
    auto contribution = [i](uint32_t sig, uint32_t neg) {
      return (i & sig) == 0 ? 0 : ((i & neg) != 0 ? -1 : 1);
    };
    const int h = contribution(kSigW, kNegW >> 4) + contribution(kSigE, kNegE >> 4);
    const int v = contribution(kSigN, kNegN >> 4) + contribution(kSigS, kNegS >> 4);
    const int hc = h > 0 ? 1 : (h < 0 ? -1 : 0), vc = v > 0 ? 1 : (v < 0 ? -1 : 0);
    uint32_t context, flip = 0;
    if (hc == 0) {
      context = vc == 0 ? 9 : 10;
      flip = vc < 0 ? 1u : 0u;
    } else {
      context = vc == 0 ? 12 : (vc == hc ? 13 : 11);
      flip = hc < 0 ? 1u : 0u;
    }
    t1.sign_context[i] = static_cast<uint8_t>(context | (flip << 7));
  }
}

void j2k_decode_block(J2kTier1& t1, const J2kBlockJob& job, int32_t* out, size_t stride) {
  const uint32_t fs = job.w + 2;
  std::memset(t1.flags, 0, sizeof(uint32_t) * fs * (job.h + 2));
  std::memset(t1.magnitude, 0, sizeof(uint32_t) * job.w * job.h);
  t1.mq.init(job.data, job.size);
  t1.mq.reset_contexts();
  uint32_t* flags = t1.flags + fs + 1;
  const BlockView view{flags,          t1.magnitude, fs, job.w, job.h, t1.zero_context[job.band],
                       t1.sign_context};
  if ((job.style & kJ2kStyleCausal) != 0) {
    Passes<true>::run(view, t1, job);
  } else {
    Passes<false>::run(view, t1, job);
  }
  for (uint32_t y = 0; y < job.h; ++y) {
    const uint32_t* f = flags + size_t{y} * fs;
    const uint32_t* m = t1.magnitude + size_t{y} * job.w;
    int32_t* o = out + y * stride;
    for (uint32_t x = 0; x < job.w; ++x) {
      const int32_t v = static_cast<int32_t>(m[x]);
      o[x] = (f[x] & kNeg) != 0 ? -v : v;
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
