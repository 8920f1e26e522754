// JPEG-LS decoder, one component. Source: ITU-T T.87 (06/1998) | ISO/IEC 14495-1:1999,
// "Lossless and near-lossless compression of continuous-tone still images - Baseline":
// Annex A (A.2.1 the initialisation of the coding variables; A.3 the context: local gradients,
// their quantisation with T1, T2, T3 and NEAR, the sign merge into 365 contexts; A.4 the
// median edge predictor and its bias correction C[Q]; A.5 the error mapping, with its special
// case for k = 0, and the limited-length Golomb code LG(k, LIMIT) with its escape in qbpp bits;
// A.6 the update of A, B, C, N with RESET; A.7 run mode: the run segments of 2^J[RUNindex]
// samples, the run interruption sample with its two contexts and the Nn counts), Annex C (the
// markers: SOF55, SOS with NEAR and ILV, LSE preset parameters id 1 and the default thresholds
// of C.2.4.1.1, DRI) and Annex D (D.1: after a 0xFF byte in the coded data one 0 bit is
// stuffed, so 0xFF followed by a byte with its top bit set is a marker; restart intervals count
// lines, and each starts as the scan does: the coding variables reset, the line above zeros, as
// CharLS 2.4 decodes them). DICOM PS3.5 A.4.3. Decodes line by line into the
// slice: the two lines of context live in the arena, the samples go straight to `out`.
#include "ct/jpeg_ls.h"

#include <cstring>

#include "ct/ct_common.h"

namespace splintcore {
namespace ct_detail {

namespace {

Status jls_error(StatusCode code, const char* what, uint64_t at) {
  return make_error(code, "JPEG-LS: ", what).at_byte(at);
}

constexpr int32_t kRegularContexts = 365;  // A.3.4: (9 x 9 x 9 + 1) / 2
constexpr int32_t kContexts = 367;         // and the two of the run interruption (A.7.2)
constexpr uint32_t kLseMaxLength = 13;     // LSE id 1: Ll, id, MAXVAL, T1, T2, T3, RESET
constexpr uint8_t kJ[32] = {0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,  2,  3,  3,  3,  3,
                            4, 4, 5, 5, 6, 6, 7, 7, 8, 9, 10, 11, 12, 13, 14, 15};  // A.7.1.2

// One context's statistics (A.2.1): A (sum of |errors|; up to about 2^33 when RESET is 65535),
// B (bias), C (correction), N (count), Nn (negative errors, run interruption contexts only).
struct JlsContext {
  int64_t a;
  int32_t b, c, n, nn;
};

// What the marker segments before the scan said.
struct JlsFrame {
  JpegFrameHeader sof;
  uint32_t restart = 0;  // lines per restart interval; 0: none
  // LSE id 1 (C.2.4.1.1); 0: the default.
  uint32_t maxval = 0, t1 = 0, t2 = 0, t3 = 0, reset = 0;
  size_t lse_at = 0;  // the LSE segment's offset, for its errors
  uint32_t near = 0;
  bool scanned = false;
};

// The scan's coding parameters (A.2.1, C.2.4.1.1).
struct JlsCoding {
  int32_t near, maxval, range, qbpp, limit, t1, t2, t3, reset;
  int32_t step;        // 2 NEAR + 1
  int32_t wrap;        // RANGE (2 NEAR + 1): the modulo of the reconstruction
  uint64_t max_error;  // a bound on mapped errors (a valid stream stays under RANGE + 2)
};

// ceil(log2(v)) for v >= 1.
int32_t ceil_log2(int32_t v) {
  int32_t bits = 0;
  while ((int32_t{1} << bits) < v) ++bits;
  return bits;
}

// C.2.4.1.1: a threshold given by LSE (non-zero) or its default, clamped as the default is.
int32_t threshold(uint32_t given, int32_t computed, int32_t low, int32_t maxval) {
  if (given != 0) return static_cast<int32_t>(given);
  return computed > maxval || computed < low ? low : computed;
}

// The parameters of a scan: MAXVAL, T1..T3 and RESET from LSE or their defaults, checked
// against the ranges of C.2.4.1.1 and C.2.3 (NEAR).
Status coding_parameters(const JlsFrame& f, size_t at, JlsCoding* c) {
  const int32_t top = (int32_t{1} << f.sof.precision) - 1;
  c->maxval = f.maxval != 0 ? static_cast<int32_t>(f.maxval) : top;
  if (c->maxval > top) {
    return jls_error(StatusCode::kParseError, "LSE MAXVAL over 2^P - 1", f.lse_at);
  }
  c->near = static_cast<int32_t>(f.near);
  if (c->near > c->maxval / 2) {
    return jls_error(StatusCode::kParseError, "SOS NEAR over MAXVAL / 2", at);
  }
  const int32_t near = c->near, maxval = c->maxval;
  int32_t t1 = 0, t2 = 0, t3 = 0;
  if (maxval >= 128) {
    const int32_t factor = ((maxval < 4095 ? maxval : 4095) + 128) >> 8;
    t1 = factor * (3 - 2) + 2 + 3 * near;
    t2 = factor * (7 - 3) + 3 + 5 * near;
    t3 = factor * (21 - 4) + 4 + 7 * near;
  } else {
    // FACTOR >= 2 here, so max(2, 3 / FACTOR) is 2 and max(3, 7 / FACTOR) is 3.
    const int32_t factor = 256 / (maxval + 1);
    t1 = 2 + 3 * near;
    t2 = 3 + 5 * near;
    t3 = (21 / factor > 4 ? 21 / factor : 4) + 7 * near;
  }
  c->t1 = threshold(f.t1, t1, near + 1, maxval);
  c->t2 = threshold(f.t2, t2, c->t1, maxval);
  c->t3 = threshold(f.t3, t3, c->t2, maxval);
  c->reset = f.reset != 0 ? static_cast<int32_t>(f.reset) : 64;
  if (c->t1 < near + 1 || c->t1 > maxval || c->t2 < c->t1 || c->t2 > maxval || c->t3 < c->t2 ||
      c->t3 > maxval) {
    return jls_error(StatusCode::kParseError,
                     "LSE thresholds not NEAR + 1 <= T1 <= T2 <= T3 <= MAXVAL", f.lse_at);
  }
  if (c->reset < 3 || c->reset > (maxval > 255 ? maxval : 255)) {
    return jls_error(StatusCode::kParseError, "LSE RESET not in 3..max(255, MAXVAL)", f.lse_at);
  }
  c->step = 2 * near + 1;
  c->range = (maxval + 2 * near) / c->step + 1;
  c->wrap = c->range * c->step;
  c->qbpp = ceil_log2(c->range);
  const int32_t bpp = ceil_log2(maxval + 1) > 2 ? ceil_log2(maxval + 1) : 2;
  c->limit = 2 * (bpp + (bpp > 8 ? bpp : 8));
  c->max_error = 2 * static_cast<uint64_t>(c->range) + 2;
  return Status::ok();
}

// The coded bits (D.1): most significant first; after a 0xFF byte the next byte gives 7 bits
// (its top bit is the stuffed 0); 0xFF then a byte >= 0x80 is a marker, where the bits stop.
// Past the marker the reader gives zeros, counted, so that the decoding loop needs no check
// per read: a line that used any is truncated (overrun()).
struct JlsBits {
  const uint8_t* data = nullptr;
  size_t size = 0;
  size_t pos = 0;      // the next byte to take
  uint64_t cache = 0;  // the next `valid` bits, from the top; the bits below are zero
  uint32_t valid = 0;
  bool after_ff = false;
  bool at_marker = false;      // pos is at a marker (or the end of the data)
  uint64_t appended = 0;       // bits put into the cache so far
  uint64_t real = UINT64_MAX;  // bits before the marker, once it is reached

  // At least 57 bits held afterwards (nothing to do when they already are: a shift by 64
  // below, undefined, for a whole-bytes take of 0).
  void refill() {
    if (valid > 56) return;
    // Whole bytes at once while the next 8 hold no 0xFF (most of the time).
    if (!after_ff && size - pos >= 8) {
      uint64_t w = 0;
      for (size_t i = 0; i < 8; ++i) w = (w << 8) | data[pos + i];
      const uint64_t x = ~w;  // a 0xFF byte of w is a zero byte of x
      if (((x - 0x0101010101010101u) & ~x & 0x8080808080808080u) == 0) {
        const uint32_t take = (64 - valid) / 8;
        cache |= (w >> (64 - 8 * take)) << (64 - valid - 8 * take);
        valid += 8 * take;
        appended += 8 * take;
        pos += take;
        return;
      }
    }
    while (valid <= 56) {
      if (at_marker) {
        appended += 64 - valid;  // zeros
        valid = 64;
        break;
      }
      if (pos >= size) {
        at_marker = true;
        real = appended;
        continue;
      }
      const uint32_t b = data[pos];
      if (after_ff) {  // below 0x80: checked with the 0xFF
        cache |= uint64_t{b} << (57 - valid);
        valid += 7;
        appended += 7;
        ++pos;
        after_ff = false;
        continue;
      }
      if (b == 0xFF) {
        if (pos + 1 >= size || data[pos + 1] >= 0x80) {
          at_marker = true;
          real = appended;
          continue;
        }
        after_ff = true;
      }
      cache |= uint64_t{b} << (56 - valid);
      valid += 8;
      appended += 8;
      ++pos;
    }
  }

  // The next n (< 58) bits.
  uint64_t read(uint32_t n) {
    if (valid < n) refill();
    const uint64_t v = (cache >> 1) >> (63 - n);
    cache <<= n;
    valid -= n;
    return v;
  }

  // The number of 0 bits before the next 1 (consumed), or a number over `limit`.
  uint32_t zeros(uint32_t limit) {
    uint32_t q = 0;
    for (;;) {
      if (cache != 0) {
        const uint32_t z = static_cast<uint32_t>(__builtin_clzll(cache));
        cache = (cache << z) << 1;
        valid -= z + 1;
        return q + z;
      }
      q += valid;
      valid = 0;
      if (q > limit) return q;
      refill();
    }
  }

  // A.5.3: LG(k, glimit), the mapped error; false for a code with too many leading zeros.
  bool golomb(uint32_t k, uint32_t glimit, uint32_t qbpp, uint64_t* value) {
    if (valid < 32) refill();
    const uint32_t escape = glimit - qbpp - 1;
    uint32_t q = 0;
    if ((cache >> 40) != 0) {  // the common case: a 1 among the next 24 bits
      q = static_cast<uint32_t>(__builtin_clzll(cache));
      cache <<= q + 1;
      valid -= q + 1;
    } else {
      q = zeros(escape);
    }
    if (q < escape) {
      *value = (uint64_t{q} << k) + read(k);
    } else if (q == escape) {
      *value = read(qbpp) + 1;
    } else {
      return false;
    }
    return true;
  }

  // Whether the bits read so far ran past the marker.
  bool overrun() const { return appended - valid > real; }
  // Bits left before the marker (the padding of the last byte, and of a byte after a 0xFF).
  uint64_t left() const { return real - (appended - valid); }
};

// The decoder of one scan: the coding variables, the two lines, the bits.
struct JlsScan {
  JlsCoding p{};
  JlsContext* ctx = nullptr;
  int32_t* prev = nullptr;  // line y - 1: [0] the Rc of x = 0, [1 + x] sample x, [1 + columns]
                            // its Rd
  int32_t* cur = nullptr;   // line y: [0] the Ra of x = 0
  uint32_t columns = 0;
  uint32_t run_index = 0;
  JlsBits bits;

  // A.2.1.
  void reset_variables() {
    const int32_t a = (p.range + 32) / 64 > 2 ? (p.range + 32) / 64 : 2;
    for (int32_t q = 0; q < kContexts; ++q) ctx[q] = JlsContext{a, 0, 0, 1, 0};
    run_index = 0;
  }

  // A.3.3: one gradient quantised to -4..4, as a count of the bounds it passes (no branch:
  // CT noise spreads the gradients over all nine regions, and mispredicted branches were
  // most of the decoding time). -T3 <= -T2 <= -T1 < -NEAR <= NEAR < T1 <= T2 <= T3.
  int32_t quantize(int32_t d) const {
    return -4 + (d > -p.t3) + (d > -p.t2) + (d > -p.t1) + (d >= -p.near) + (d > p.near) +
           (d >= p.t1) + (d >= p.t2) + (d >= p.t3);
  }

  // The reconstruction: Px plus the dequantised error, modulo RANGE (2 NEAR + 1), clamped.
  int32_t reconstruct(int32_t px, int32_t error) const {
    int32_t x = px + error;
    if (x < -p.near) {
      x += p.wrap;
    } else if (x > p.maxval + p.near) {
      x -= p.wrap;
    }
    return x < 0 ? 0 : (x > p.maxval ? p.maxval : x);
  }

  // Golomb parameter k (A.5.1, A.7.2.1): the least k with N 2^k >= A (N >= 1). With
  // d = bitlength(A) - bitlength(N), k is d or d + 1.
  static uint32_t golomb_k(int64_t n, int64_t a) {
    if (n >= a) return 0;
    uint32_t k = static_cast<uint32_t>(__builtin_clzll(static_cast<uint64_t>(n)) -
                                       __builtin_clzll(static_cast<uint64_t>(a)));
    k += (n << k) < a ? 1u : 0u;
    return k;
  }

  // A.4 - A.6: one sample in regular mode; false for an invalid code.
  // q: 81 Q1 + 9 Q2 + Q3 (A.3.4), not 0.
  bool regular(int32_t q, int32_t ra, int32_t rb, int32_t rc, int32_t* out) {
    const int32_t negative = q < 0 ? -1 : 0;  // SIGN -1: the context of -Q, errors negated
    q = (q ^ negative) - negative;
    JlsContext& cx = ctx[q];
    // A.4.1, the median edge detector: the median of Ra, Rb and Ra + Rb - Rc.
    const int32_t low = ra < rb ? ra : rb, high = ra < rb ? rb : ra, plane = ra + rb - rc;
    int32_t px = plane < high ? plane : high;
    px = px > low ? px : low;
    px += (cx.c ^ negative) - negative;
    px = px < 0 ? 0 : (px > p.maxval ? p.maxval : px);
    const uint32_t k = golomb_k(cx.n, cx.a);
    uint64_t mapped = 0;
    if (!bits.golomb(k, static_cast<uint32_t>(p.limit), static_cast<uint32_t>(p.qbpp), &mapped) ||
        mapped > p.max_error) {
      return false;
    }
    const int32_t m = static_cast<int32_t>(mapped);
    // A.5.2 inverted: an even m is 2 Errval, an odd one -2 Errval - 1; in the special case
    // (lossless, k 0, 2 B <= -N) the parity is the other way round.
    const int32_t special = (p.near == 0 && k == 0 && 2 * cx.b <= -cx.n) ? 1 : 0;
    const int32_t error = (m >> 1) ^ -((m & 1) ^ special);
    cx.b += error * p.step;
    cx.a += error < 0 ? -error : error;
    if (cx.n == p.reset) {
      cx.a >>= 1;
      cx.b = cx.b >= 0 ? cx.b / 2 : -((1 - cx.b) / 2);
      cx.n >>= 1;
    }
    const int32_t n = cx.n + 1;
    cx.n = n;
    // A.6.2 without branches (the bias moves either way on CT noise): B <= -N moves B up by N
    // and C down by one, B > 0 the other way; B is then kept in (-N, 0].
    int32_t b = cx.b, c = cx.c;
    const int32_t down = b <= -n ? 1 : 0, up = b > 0 ? 1 : 0;
    b += (down - up) * n;
    c += up & (c < 127 ? 1 : 0);
    c -= down & (c > -128 ? 1 : 0);
    b = b <= -n ? -n + 1 : (b > 0 ? 0 : b);
    cx.b = b;
    cx.c = c;
    const int32_t e = error * p.step;
    *out = reconstruct(px, (e ^ negative) - negative);
    return true;
  }

  // A.7.2: the sample that ends a run before the line's end, at x; false for an invalid code.
  bool interruption(uint32_t x, int32_t ra) {
    const int32_t rb = prev[1 + x];
    const int32_t type = (ra - rb <= p.near && rb - ra <= p.near) ? 1 : 0;
    JlsContext& cx = ctx[kRegularContexts + type];
    const uint32_t k = golomb_k(cx.n, type != 0 ? cx.a + (cx.n >> 1) : cx.a);
    uint64_t mapped = 0;
    const uint32_t glimit = static_cast<uint32_t>(p.limit) - kJ[run_index] - 1;
    if (!bits.golomb(k, glimit, static_cast<uint32_t>(p.qbpp), &mapped) || mapped > p.max_error) {
      return false;
    }
    // EMErrval = 2 |Errval| - RItype - map: the parity of EMErrval + RItype is map.
    const int32_t t = static_cast<int32_t>(mapped) + type;
    const int32_t map = t & 1;
    const int32_t magnitude = (t + map) / 2;
    const bool flipped = k == 0 && 2 * cx.nn < cx.n;  // map 1 marks a positive error
    const int32_t error = (flipped ? map == 0 : map == 1) ? -magnitude : magnitude;
    if (error < 0) ++cx.nn;
    cx.a += (static_cast<int32_t>(mapped) + 1 - type) / 2;
    if (cx.n == p.reset) {
      cx.a >>= 1;
      cx.n >>= 1;
      cx.nn >>= 1;
    }
    ++cx.n;
    int32_t e = error * p.step;
    if (type == 0 && ra > rb) e = -e;
    cur[1 + x] = reconstruct(type != 0 ? ra : rb, e);
    if (run_index > 0) --run_index;
    return true;
  }

  // A.7.1: a run from x (its value Ra), then the interruption sample if the line goes on.
  // Returns the samples decoded, 0 for an invalid code.
  uint32_t run(uint32_t x) {
    const int32_t ra = cur[x];
    const uint32_t left = columns - x;
    uint32_t count = 0;
    bool ended = false;  // the run reaches the line's end
    while (bits.read(1) != 0) {
      const uint32_t segment = 1u << kJ[run_index];
      if (segment > left - count) {  // a shorter last segment: the line's end
        count = left;
        ended = true;
        break;
      }
      count += segment;
      if (run_index < 31) ++run_index;
      if (count == left) {
        ended = true;
        break;
      }
    }
    if (!ended) {
      count += static_cast<uint32_t>(bits.read(kJ[run_index]));
      if (count >= left) return 0;
    }
    for (uint32_t i = 0; i < count; ++i) cur[1 + x + i] = ra;
    if (ended) return count;
    return interruption(x + count, ra) ? count + 1 : 0;
  }

  // One line into cur[1, 1 + columns); false for an invalid code.
  bool line() {
    cur[0] = prev[1];
    prev[1 + columns] = prev[columns];
    // The neighbours move along in registers (a sample's Ra is the one just decoded: read
    // back from memory it would wait for the store), and so does the quantised D1 (Rd - Rb),
    // which is the next sample's D2 (its Rb - Rc).
    int32_t ra = cur[0], rb = prev[1], rc = prev[0];
    int32_t q2 = quantize(rb - rc);
    uint32_t x = 0;
    while (x < columns) {
      const int32_t rd = prev[2 + x];
      const int32_t q1 = quantize(rd - rb), q3 = quantize(rc - ra);
      if ((q1 | q2 | q3) == 0) {  // all three |D| <= NEAR: run mode
        const uint32_t n = run(x);
        if (n == 0) return false;
        x += n;
        ra = cur[x];
        rb = prev[1 + x];
        rc = prev[x];
        q2 = quantize(rb - rc);
      } else {
        int32_t rx = 0;
        if (!regular(81 * q1 + 9 * q2 + q3, ra, rb, rc, &rx)) return false;
        cur[1 + x] = rx;
        ra = rx;
        rc = rb;
        rb = rd;
        q2 = q1;
        ++x;
      }
    }
    return true;
  }

  // The end of the coded data of a scan or a restart interval (`what`): the marker must follow
  // the last sample's byte (with at most the padding of that byte and of one after a 0xFF).
  Status end_of_data(const char* what) {
    bits.refill();  // (the lines checked that they did not run past the data)
    if (bits.left() > 14) {
      Status s = jls_error(StatusCode::kParseError, "coded data continues past ", bits.pos);
      return s.append(what);
    }
    return Status::ok();
  }

  // The RSTm marker ending restart interval `index`; after it the coding variables and the
  // line above start as at the top of the scan.
  Status restart(uint32_t index) {
    SPLINTCORE_RETURN_IF_ERROR(end_of_data("the end of a restart interval"));
    size_t q = bits.pos;
    while (q < bits.size && bits.data[q] == 0xFF) ++q;
    if (q >= bits.size) {
      return jls_error(StatusCode::kTruncated, "data ends before RSTm", bits.size);
    }
    if (bits.data[q] != 0xD0 + (index & 7)) {  // (at a marker: data[pos] is 0xFF)
      return jls_error(StatusCode::kParseError, "expected the next RSTm marker", bits.pos);
    }
    const JlsBits fresh{bits.data, bits.size, q + 1};
    bits = fresh;
    reset_variables();
    for (uint32_t i = 0; i < columns + 2; ++i) prev[i] = 0;
    return Status::ok();
  }
};

// The scan: lines decoded and written to out as 16-bit little-endian samples.
Status decode_scan(JlsScan& s, const JlsFrame& f, uint8_t* out) {
  s.reset_variables();
  for (uint32_t i = 0; i < f.sof.columns + 2; ++i) s.prev[i] = 0;  // the line above the first
  uint32_t restarts = 0;
  for (uint32_t y = 0; y < f.sof.rows; ++y) {
    if (f.restart != 0 && y != 0 && y % f.restart == 0) {
      SPLINTCORE_RETURN_IF_ERROR(s.restart(restarts++));
    }
    const bool ok = s.line();
    if (s.bits.overrun()) {
      return jls_error(StatusCode::kTruncated, "coded data ends inside a line", s.bits.pos);
    }
    if (!ok) return jls_error(StatusCode::kParseError, "invalid code", s.bits.pos);
    uint8_t* row = out + 2 * size_t{y} * f.sof.columns;  // (out holds them all: no overflow)
    const int32_t* line = s.cur + 1;
    for (uint32_t x = 0; x < f.sof.columns; ++x) {
      row[2 * x] = static_cast<uint8_t>(line[x]);
      row[2 * x + 1] = static_cast<uint8_t>(line[x] >> 8);
    }
    int32_t* t = s.prev;
    s.prev = s.cur;
    s.cur = t;
  }
  return s.end_of_data("the last sample");
}

// The segments of T.87 on the shared marker walk (ct_common.h).
struct JlsParser : JpegMarkers {
  // LSE (C.2.4.1): id 1, the preset coding parameters; mapping tables are not supported.
  Status preset(size_t at, JlsFrame* f) {
    uint32_t length = 0;
    size_t b = 0;
    SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
    if (length < 3) return jls_error(StatusCode::kParseError, "LSE segment too short", at);
    const uint32_t id = u8(b);
    if (id == 2 || id == 3) {
      return jls_error(StatusCode::kUnsupported, "LSE mapping table (id 2 or 3)", at);
    }
    if (id == 4) {
      return jls_error(StatusCode::kUnsupported, "LSE oversize image dimension (id 4)", at);
    }
    if (id != 1) return jls_error(StatusCode::kParseError, "LSE id not 1..4", at);
    if (length != kLseMaxLength) {
      return jls_error(StatusCode::kParseError, "LSE id 1 length not 13", at);
    }
    f->lse_at = at;
    f->maxval = u16(b + 1);
    f->t1 = u16(b + 3);
    f->t2 = u16(b + 5);
    f->t3 = u16(b + 7);
    f->reset = u16(b + 9);
    return Status::ok();
  }

  // DRI (C.2.5): a restart interval of 2, 3 or 4 bytes.
  Status restart_interval(size_t at, JlsFrame* f) {
    uint32_t length = 0;
    size_t b = 0;
    SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
    if (length < 4 || length > 6) {
      return jls_error(StatusCode::kParseError, "DRI length not 4..6", at);
    }
    uint64_t interval = 0;
    for (size_t i = b; i < b + length - 2; ++i) interval = (interval << 8) | data[i];
    f->restart = static_cast<uint32_t>(interval);  // at most 4 bytes
    return Status::ok();
  }

  // SOS (C.2.3): one component, no mapping table, NEAR, ILV, no point transform.
  Status scan_header(size_t at, JlsFrame* f) {
    uint32_t length = 0;
    size_t b = 0;
    if (!f->sof.read) return jls_error(StatusCode::kParseError, "SOS before SOF55", at);
    if (f->scanned) return jls_error(StatusCode::kParseError, "more than one scan", at);
    SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
    if (length != 8 || u8(b) != 1) {
      return jls_error(StatusCode::kParseError, "SOS must have one component (length 8)", at);
    }
    if (u8(b + 1) != f->sof.component) {
      return jls_error(StatusCode::kParseError, "SOS names another component than SOF55", at);
    }
    if (u8(b + 2) != 0) {
      return jls_error(StatusCode::kUnsupported, "SOS selects a mapping table", at);
    }
    f->near = u8(b + 3);
    if (u8(b + 4) > 2) return jls_error(StatusCode::kParseError, "SOS ILV not 0..2", at);
    if (u8(b + 5) != 0) {
      return jls_error(StatusCode::kUnsupported, "SOS point transform (Al, Ah) not 0", at);
    }
    f->scanned = true;
    return Status::ok();
  }
};

// The marker segments and the scan, up to EOI.
Status decode_stream(JlsScan& scan, const uint8_t* data, size_t size, uint32_t rows,
                     uint32_t columns, uint32_t max_precision, uint8_t* out) {
  JlsParser p{{data, size, "JPEG-LS"}};
  JlsFrame f;
  SPLINTCORE_RETURN_IF_ERROR(p.start("JPEG-LS"));
  for (;;) {
    uint32_t code = 0;
    size_t at = 0;
    SPLINTCORE_RETURN_IF_ERROR(p.next_marker(&code, &at));
    if (code == 0xD9) {
      if (!f.scanned) return jls_error(StatusCode::kParseError, "EOI before the scan", at);
      return Status::ok();
    }
    if (code == 0xF7) {
      SPLINTCORE_RETURN_IF_ERROR(p.frame(at, "SOF55", &f.sof));
      if (f.sof.rows == 0 || f.sof.columns == 0) {
        return jls_error(StatusCode::kUnsupported,
                         "image size 0 in SOF55 (given by DNL or LSE id 4)", at);
      }
      SPLINTCORE_RETURN_IF_ERROR(p.check_frame(at, "SOF55", f.sof, rows, columns, max_precision));
    } else if (code == 0xF8) {
      SPLINTCORE_RETURN_IF_ERROR(p.preset(at, &f));
    } else if (code == 0xDD) {
      SPLINTCORE_RETURN_IF_ERROR(p.restart_interval(at, &f));
    } else if (code == 0xDA) {
      SPLINTCORE_RETURN_IF_ERROR(p.scan_header(at, &f));
      SPLINTCORE_RETURN_IF_ERROR(coding_parameters(f, at, &scan.p));
      scan.bits = JlsBits{data, size, p.pos};
      SPLINTCORE_RETURN_IF_ERROR(decode_scan(scan, f, out));
      p.pos = scan.bits.pos;
    } else if ((code >= 0xC0 && code <= 0xCF && code != 0xC4 && code != 0xCC) || code == 0xF9) {
      return jls_error(StatusCode::kUnsupported,
                       "not JPEG-LS baseline (SOFn of another JPEG process, or SOF57)", at);
    } else if (code == 0xDC) {
      return jls_error(StatusCode::kUnsupported, "DNL marker (height after the scan)", at);
    } else if (code < 0xC0 || code == 0xD8 || (code >= 0xD0 && code <= 0xD7)) {
      return jls_error(StatusCode::kParseError, "unexpected marker (SOI, RSTm or reserved)", at);
    } else {
      uint32_t length = 0;
      size_t body = 0;
      SPLINTCORE_RETURN_IF_ERROR(p.segment(at, &length, &body));  // APPn, COM, ...
    }
  }
}

uint64_t jls_work_bytes(uint32_t columns) {
  return sizeof(JlsContext) * kContexts + 2 * sizeof(int32_t) * (uint64_t{columns} + 2);
}

}  // namespace

uint64_t jpeg_ls_arena_bytes(uint32_t columns) {
  return jls_work_bytes(columns) + Arena::kDefaultAlignment - 1;
}

Status jpeg_ls_decode(Arena& arena, const uint8_t* data, size_t size, uint32_t rows,
                      uint32_t columns, uint32_t max_precision, uint8_t* out) {
  ArenaScope scope(arena);
  uint8_t* work = arena.allocate_array<uint8_t>(static_cast<size_t>(jls_work_bytes(columns)));
  if (work == nullptr) return arena.exhausted_status();
  JlsScan scan;
  // The block is aligned for both (Arena::kDefaultAlignment); the lines start after the
  // contexts, a multiple of 8 bytes.
  static_assert(sizeof(JlsContext) % alignof(int32_t) == 0, "the lines follow the contexts");
  scan.ctx = static_cast<JlsContext*>(static_cast<void*>(work));
  scan.prev = static_cast<int32_t*>(static_cast<void*>(work + sizeof(JlsContext) * kContexts));
  scan.cur = scan.prev + columns + 2;
  scan.columns = columns;
  return decode_stream(scan, data, size, rows, columns, max_precision, out);
}

}  // namespace ct_detail
}  // namespace splintcore
