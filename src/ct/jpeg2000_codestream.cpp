// JPEG 2000 codestream decoder, one component. Source: ITU-T T.800 (2019) | ISO/IEC 15444-1:
// Annex A (codestream syntax: A.4 SOC, SOT, SOD, EOC; A.5.1 SIZ; A.6.1 COD and A.6.2 COC with
// Tables A.13-A.21; A.6.4 QCD and A.6.5 QCC with Tables A.28-A.30; A.8.1 SOP, A.8.2 EPH),
// Annex B (B.3 tiles, B.5 resolutions and subbands (equations B-14, B-15), B.6 precincts, B.7
// code-blocks, B.9 layers, B.10 packet headers: B.10.2 tag trees, B.10.4 inclusion, B.10.5 zero
// bit planes, B.10.6 number of coding passes (Table B.4), B.10.7 lengths and Lblock, B.12
// progression orders), Annex E (E.1 dequantisation: equations E-2 M_b, E-3 the step size,
// E-5 derived exponents; Table E.1 subband gains) and G.1.2 (the DC level shift). Annex I
// (the JP2 file format) only to find the codestream box. Code-blocks are decoded by
// jpeg2000_tier1.cpp.
#include "ct/jpeg2000.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "ct/ct_common.h"

namespace splintcore {
namespace ct_detail {

namespace {

constexpr uint32_t kMaxLevels = 32;
constexpr uint32_t kMaxBands = 3 * kMaxLevels + 1;

Status j2k_error(StatusCode code, const char* what, uint64_t at) {
  return make_error(code, "JPEG 2000: ", what).at_byte(at);
}

uint32_t be16(const uint8_t* p) { return (uint32_t{p[0]} << 8) | p[1]; }
uint32_t be32(const uint8_t* p) { return (be16(p) << 16) | be16(p + 2); }

int64_t ceil_div(int64_t a, int64_t b) { return a >= 0 ? (a + b - 1) / b : -((-a) / b); }
int64_t floor_div(int64_t a, int64_t b) { return a / b; }  // a >= 0 (reference grid)

// The coding style of the one component (COD with COC applied: A.6.1, A.6.2).
struct CodingStyle {
  uint32_t sop = 0, eph = 0;  // COD's Scod bits 1 and 2
  uint32_t progression = 0, layers = 1;
  uint32_t levels = 5, xcb = 6, ycb = 6, block_style = 0, reversible = 1;
  uint8_t ppx[kMaxLevels + 1] = {}, ppy[kMaxLevels + 1] = {};
};

// QCD or QCC (A.6.4, A.6.5): Sqcd's style and guard bits, then SPqcd per band.
struct Quantization {
  uint32_t style = 0, guard = 0, count = 0;
  uint16_t values[kMaxBands] = {};
};

// The marker segments of one header (main or tile), applied after it is read in the order of
// A.6: COC over COD, QCC over QCD; a tile's over the main header's.
struct HeaderSegments {
  bool cod = false, coc = false, qcd = false, qcc = false;
  CodingStyle cod_style, coc_style;
  Quantization qcd_values, qcc_values;

  void apply(CodingStyle* style, Quantization* quant) const {
    if (cod) *style = cod_style;
    if (coc) {  // the component fields only
      const CodingStyle keep = *style;
      *style = coc_style;
      style->sop = keep.sop;
      style->eph = keep.eph;
      style->progression = keep.progression;
      style->layers = keep.layers;
    }
    if (qcd) *quant = qcd_values;
    if (qcc) *quant = qcc_values;
  }
};

struct Image {
  uint32_t x1 = 0, y1 = 0, x0 = 0, y0 = 0;    // Xsiz, Ysiz, XOsiz, YOsiz
  uint32_t tw = 0, th = 0, tx0 = 0, ty0 = 0;  // XTsiz, YTsiz, XTOsiz, YTOsiz
  uint32_t tiles_x = 0, tiles_y = 0;
  uint32_t precision = 0;
  bool is_signed = false;
  CodingStyle style;
  Quantization quant;
  bool have_cod = false, have_qcd = false;
};

struct Band {
  J2kRect r;
  uint32_t type;       // 0 LL, 1 HL, 2 LH, 3 HH
  uint32_t bitplanes;  // M_b
  double step;         // the dequantisation step (irreversible)
  int32_t bx, by;      // where it sits in the tile buffer
};

struct Resolution {
  J2kRect r;
  uint32_t bands;  // 1 at resolution 0, else 3
  Band band[3];
  uint32_t ppx, ppy, pw, ph;  // precinct size exponents and counts
  int32_t px0, py0;           // the first precinct's index on the anchored grid
  uint32_t xcb, ycb;          // code-block size exponents in this resolution's subbands
  size_t first_precinct;
};

struct PrecinctBand {
  uint32_t cbx0, cby0, cw, ch;  // the code-block grid (indices on the band's anchored grid)
  size_t first_block;
  size_t inclusion, zero_planes;  // their tag trees' first nodes
};

struct Precinct {
  PrecinctBand band[3];
};

struct Block {
  J2kRect r;
  uint32_t length;   // bytes of all its layers
  uint32_t write;    // copy pass: where its next bytes go in the tile's data
  uint32_t pending;  // the current packet's contribution
  uint32_t passes;
  uint32_t zero_planes;
  uint32_t lblock;
  uint32_t included;
};

// The tile being decoded and its records (arena).
struct Tile {
  J2kRect r;
  CodingStyle style;
  Quantization quant;
  Resolution res[kMaxLevels + 1];
  Precinct* precincts = nullptr;
  size_t precinct_count = 0;
  Block* blocks = nullptr;
  size_t block_count = 0;
  J2kTagNode* nodes = nullptr;
  size_t node_count = 0;
  uint8_t* bytes = nullptr;  // the code-blocks' data, each contiguous
  // Its tile-parts' bodies (packet data), in order.
  static constexpr uint32_t kMaxParts = 256;
  size_t part_begin[kMaxParts];
  size_t part_end[kMaxParts];
  uint32_t parts = 0;
};

// Marker codes (Table A.2).
constexpr uint32_t kSoc = 0xFF4F, kSiz = 0xFF51, kCod = 0xFF52, kCoc = 0xFF53, kTlm = 0xFF55;
constexpr uint32_t kPlm = 0xFF57, kPlt = 0xFF58, kQcd = 0xFF5C, kQcc = 0xFF5D, kRgn = 0xFF5E;
constexpr uint32_t kPoc = 0xFF5F, kPpm = 0xFF60, kPpt = 0xFF61, kCrg = 0xFF63, kCom = 0xFF64;
constexpr uint32_t kCap = 0xFF50, kSot = 0xFF90, kSod = 0xFF93, kEoc = 0xFFD9;
constexpr uint32_t kSop = 0xFF91, kEph = 0xFF92;

// Bytes of the per-tile records (precincts, code-blocks, tag tree nodes) a frame of n samples
// may use: code-blocks of 64 samples on average, and room for the small subbands.
uint64_t records_cap(uint64_t samples) { return (samples / 64 + 1024) * 64; }

double pow2(int32_t e) {  // exact
  double v = 1.0;
  for (; e > 0; --e) v *= 2.0;
  for (; e < 0; ++e) v *= 0.5;
  return v;
}

uint32_t floor_log2(uint32_t v) {
  uint32_t n = 0;
  while (v > 1) {
    v >>= 1;
    ++n;
  }
  return n;
}

struct Decoder {
  Arena& arena;
  const uint8_t* data;
  size_t size;
  uint32_t rows, columns, max_precision;
  uint8_t* out;
  Image image;
  J2kTier1* t1 = nullptr;
  Tile* tile = nullptr;
  size_t pos = 0;

  // The segment whose marker is at `at` (pos just after the marker): its length (>= 2, inside
  // the data) and first byte after the length; pos moves past it. T.800 A.1.3 keeps T.81's
  // segment lengths: the JPEG decoders' walk (ct_common.h) reads them.
  Status segment(size_t at, uint32_t* length, size_t* body) {
    JpegMarkers markers{data, size, "JPEG 2000", pos};
    SPLINTCORE_RETURN_IF_ERROR(markers.segment(at, length, body));
    pos = markers.pos;
    return Status::ok();
  }

  Status read_siz(size_t at);
  Status read_coding_style(size_t at, bool coc, CodingStyle* style);
  Status read_quantization(size_t at, bool qcc, Quantization* quant);
  Status read_header(size_t at, bool main, HeaderSegments* segments);
  Status read_tile_parts();
  Status decode_tile(uint32_t index, const HeaderSegments& segments, size_t at);
};

Status Decoder::read_siz(size_t at) {
  uint32_t length = 0;
  size_t b = 0;
  SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
  if (length < 41) return j2k_error(StatusCode::kParseError, "SIZ segment too short", at);
  const uint32_t rsiz = be16(data + b);
  if ((rsiz & 0xC000) != 0) {
    return j2k_error(StatusCode::kUnsupported,
                     "SIZ capabilities (Rsiz) ask for Part 2 extensions or HTJ2K", at + 4);
  }
  Image& im = image;
  im.x1 = be32(data + b + 2);
  im.y1 = be32(data + b + 6);
  im.x0 = be32(data + b + 10);
  im.y0 = be32(data + b + 14);
  im.tw = be32(data + b + 18);
  im.th = be32(data + b + 22);
  im.tx0 = be32(data + b + 26);
  im.ty0 = be32(data + b + 30);
  const uint32_t components = be16(data + b + 34);
  if (components != 1) {
    Status s = j2k_error(StatusCode::kUnsupported, "", b + 34);
    s.append_u64(components);
    return s.append(" components: only one (grayscale) is supported");
  }
  if (length != 41) return j2k_error(StatusCode::kParseError, "SIZ length not 41", at);
  const uint32_t ssiz = data[b + 36];
  im.precision = (ssiz & 0x7F) + 1;
  im.is_signed = (ssiz & 0x80) != 0;
  if (data[b + 37] != 1 || data[b + 38] != 1) {
    return j2k_error(StatusCode::kUnsupported, "subsampled component (XRsiz, YRsiz not 1)", b + 37);
  }
  if (im.precision > 16 || im.precision > max_precision) {
    Status s = make_error(StatusCode::kParseError, "JPEG 2000: ", im.precision,
                          "-bit samples, more than the ", max_precision < 16 ? max_precision : 16,
                          " bits allocated");
    return s.at_byte(b + 36);
  }
  if (im.x1 > 0x7FFFFFFFu || im.y1 > 0x7FFFFFFFu) {
    return j2k_error(StatusCode::kUnsupported, "SIZ image offsets of 2^31 or more", b + 2);
  }
  if (im.x1 <= im.x0 || im.y1 <= im.y0 || im.x1 - im.x0 != columns || im.y1 - im.y0 != rows) {
    Status s = make_error(StatusCode::kParseError, "JPEG 2000: SIZ image area does not match the ",
                          columns, " x ", rows, " samples expected");
    return s.at_byte(b + 2);
  }
  if (im.tw == 0 || im.th == 0 || im.tx0 > im.x0 || im.ty0 > im.y0 ||
      uint64_t{im.tx0} + im.tw <= im.x0 || uint64_t{im.ty0} + im.th <= im.y0) {
    return j2k_error(StatusCode::kParseError, "SIZ tile grid does not cover the image", b + 18);
  }
  im.tiles_x = static_cast<uint32_t>(ceil_div(int64_t{im.x1} - im.tx0, im.tw));
  im.tiles_y = static_cast<uint32_t>(ceil_div(int64_t{im.y1} - im.ty0, im.th));
  if (uint64_t{im.tiles_x} * im.tiles_y > 65535) {
    return j2k_error(StatusCode::kParseError, "SIZ: more than 65535 tiles", b + 18);
  }
  return Status::ok();
}

Status Decoder::read_coding_style(size_t at, bool coc, CodingStyle* style) {
  uint32_t length = 0;
  size_t b = 0;
  SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
  const char* name = coc ? "COC" : "COD";
  if (length < (coc ? 9u : 12u)) {
    return make_error(StatusCode::kParseError, "JPEG 2000: ", name, " segment too short")
        .at_byte(at);
  }
  if (coc && data[b] != 0) {
    return j2k_error(StatusCode::kParseError, "COC for a component other than 0", b);
  }
  const size_t scod_at = coc ? b + 1 : b;
  const uint32_t scod = data[scod_at];
  size_t sp = scod_at + 1;  // SPcod / SPcoc
  if (!coc) {
    style->sop = (scod >> 1) & 1;
    style->eph = (scod >> 2) & 1;
    style->progression = data[b + 1];
    style->layers = be16(data + b + 2);
    if (style->progression > 4) {
      return j2k_error(StatusCode::kParseError, "COD progression order over 4", b + 1);
    }
    if (style->layers == 0) return j2k_error(StatusCode::kParseError, "COD: 0 layers", b + 2);
    sp = b + 5;
  }
  style->levels = data[sp];
  style->xcb = data[sp + 1] + 2u;
  style->ycb = data[sp + 2] + 2u;
  style->block_style = data[sp + 3];
  const uint32_t transform = data[sp + 4];
  if (style->levels > kMaxLevels) {
    return make_error(StatusCode::kParseError, "JPEG 2000: ", name, ": more than 32 levels")
        .at_byte(sp);
  }
  if (style->xcb > 10 || style->ycb > 10 || style->xcb + style->ycb > 12) {
    return make_error(StatusCode::kParseError, "JPEG 2000: ", name,
                      ": code-block size over 1024 or 4096 samples")
        .at_byte(sp + 1);
  }
  if ((style->block_style & ~kJ2kStylesRead) != 0) {
    return make_error(StatusCode::kUnsupported, "JPEG 2000: ", name, ": code-block style 0x",
                      style->block_style,
                      " (decimal) asks for arithmetic coding bypass (1), termination on each "
                      "pass (4) or HT blocks (64), which this decoder does not read")
        .at_byte(sp + 3);
  }
  if (transform > 1) {
    return make_error(StatusCode::kUnsupported, "JPEG 2000: ", name,
                      ": a wavelet transform other than 9/7 and 5/3")
        .at_byte(sp + 4);
  }
  style->reversible = transform;
  const size_t precincts_at = sp + 5;
  const uint32_t expected = (coc ? 9 : 12) + ((scod & 1) != 0 ? style->levels + 1 : 0);
  if (length != expected) {
    return make_error(StatusCode::kParseError, "JPEG 2000: ", name, " length ", length,
                      ", expected ", expected)
        .at_byte(at);
  }
  for (uint32_t r = 0; r <= style->levels; ++r) {
    const uint32_t v = (scod & 1) != 0 ? data[precincts_at + r] : 0xFF;
    style->ppx[r] = static_cast<uint8_t>(v & 15);
    style->ppy[r] = static_cast<uint8_t>(v >> 4);
    if (r > 0 && (style->ppx[r] == 0 || style->ppy[r] == 0)) {
      return j2k_error(StatusCode::kParseError, "precinct size 1 above resolution 0",
                       precincts_at + r);
    }
  }
  return Status::ok();
}

Status Decoder::read_quantization(size_t at, bool qcc, Quantization* quant) {
  uint32_t length = 0;
  size_t b = 0;
  SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
  const size_t s_at = qcc ? b + 1 : b;
  const uint32_t head = qcc ? 4 : 3;
  if (length < head + 1) return j2k_error(StatusCode::kParseError, "QCD/QCC too short", at);
  if (qcc && data[b] != 0) {
    return j2k_error(StatusCode::kParseError, "QCC for a component other than 0", b);
  }
  quant->style = data[s_at] & 0x1F;
  quant->guard = data[s_at] >> 5;
  const uint32_t bytes = length - head;
  if (quant->style > 2) return j2k_error(StatusCode::kParseError, "QCD/QCC style over 2", s_at);
  const uint32_t each = quant->style == 0 ? 1 : 2;
  quant->count = bytes / each;
  if (bytes % each != 0 || quant->count > kMaxBands || (quant->style == 1 && quant->count != 1)) {
    return j2k_error(StatusCode::kParseError, "QCD/QCC length does not fit its style", at);
  }
  for (uint32_t i = 0; i < quant->count; ++i) {
    quant->values[i] =
        static_cast<uint16_t>(each == 1 ? data[s_at + 1 + i] : be16(data + s_at + 1 + 2 * i));
  }
  return Status::ok();
}

// A marker no header of this decoder reads: named when Part 1 defines it.
Status refused_marker(uint32_t code, bool main, size_t at) {
  struct Refused {
    uint32_t code;
    const char* what;
  };
  static const Refused kRefused[] = {{kRgn, "RGN (region of interest) not supported"},
                                     {kPoc, "POC (progression changes) not supported"},
                                     {kPpm, "packed packet headers (PPM) not supported"},
                                     {kPpt, "packed packet headers (PPT) not supported"},
                                     {kCap, "CAP (HTJ2K capabilities) not supported"}};
  for (const Refused& r : kRefused) {
    if (r.code == code) return j2k_error(StatusCode::kUnsupported, r.what, at);
  }
  return j2k_error(
      StatusCode::kParseError,
      main ? "unexpected marker in the main header" : "unexpected marker in a tile-part header",
      at);
}

// Marker segments until SOT (main header: pos is left on the SOT) or SOD (tile-part header:
// pos is left after it). `at` is where the header starts.
Status Decoder::read_header(size_t at, bool main, HeaderSegments* h) {
  (void)at;
  for (;;) {
    const size_t m = pos;
    if (size - pos < 2) {
      return j2k_error(StatusCode::kTruncated,
                       main ? "data ends in the main header" : "data ends in a tile-part header",
                       size);
    }
    if (data[pos] != 0xFF) return j2k_error(StatusCode::kParseError, "expected a marker", pos);
    const uint32_t code = be16(data + pos);
    pos += 2;
    if (main && code == kSot) {
      pos = m;
      return Status::ok();
    }
    if (!main && code == kSod) return Status::ok();
    switch (code) {
      case kCod:
      case kCoc: {
        const bool coc = code == kCoc;
        if (coc ? h->coc : h->cod) {
          return j2k_error(StatusCode::kParseError, "a second COD or COC in one header", m);
        }
        SPLINTCORE_RETURN_IF_ERROR(read_coding_style(m, coc, coc ? &h->coc_style : &h->cod_style));
        (coc ? h->coc : h->cod) = true;
        break;
      }
      case kQcd:
      case kQcc: {
        const bool qcc = code == kQcc;
        SPLINTCORE_RETURN_IF_ERROR(
            read_quantization(m, qcc, qcc ? &h->qcc_values : &h->qcd_values));
        (qcc ? h->qcc : h->qcd) = true;
        break;
      }
      case kTlm:
      case kPlm:
      case kPlt:
      case kCrg:
      case kCom: {
        uint32_t length = 0;
        size_t b = 0;
        SPLINTCORE_RETURN_IF_ERROR(segment(m, &length, &b));
        break;
      }
      default: return refused_marker(code, main, m);
    }
  }
}

// The band's M_b and step size (E-2, E-3, E-5; Table E.1's gains: LL 0, HL and LH 1, HH 2).
Status band_quantization(const Tile& t, const Image& im, uint32_t r, Band* band, size_t at) {
  const Quantization& q = t.quant;
  const uint32_t levels = t.style.levels;
  const uint32_t index = r == 0 ? 0 : 1 + 3 * (r - 1) + (band->type - 1);
  const uint32_t nb = r == 0 ? levels : levels - r + 1;
  int32_t epsilon = 0;
  uint32_t mu = 0;
  if (q.style == 1) {
    epsilon = static_cast<int32_t>(q.values[0] >> 11) - static_cast<int32_t>(levels) +
              static_cast<int32_t>(nb);
    mu = q.values[0] & 0x7FF;
  } else if (index < q.count) {
    epsilon = q.style == 0 ? q.values[index] >> 3 : q.values[index] >> 11;
    mu = q.style == 0 ? 0 : q.values[index] & 0x7FF;
  } else {
    return j2k_error(StatusCode::kParseError, "QCD/QCC has fewer values than subbands", at);
  }
  const int32_t bitplanes = static_cast<int32_t>(q.guard) + epsilon - 1;
  if (epsilon < 0 || bitplanes > static_cast<int32_t>(kJ2kMaxBitplanes)) {
    return j2k_error(StatusCode::kUnsupported,
                     "a subband of more than 30 bit planes (or a negative exponent)", at);
  }
  band->bitplanes = static_cast<uint32_t>(bitplanes < 0 ? 0 : bitplanes);
  const int32_t gain = band->type == 0 ? 0 : (band->type == 3 ? 2 : 1);
  band->step = pow2(static_cast<int32_t>(im.precision) + gain - epsilon) *
               (1.0 + static_cast<double>(mu) / 2048.0);
  return Status::ok();
}

// Resolutions and subbands of the tile (B-14, B-15), their precinct grids (B-16) and
// code-block sizes (B.7).
Status tile_resolutions(Tile& t, const Image& im, size_t at) {
  const uint32_t levels = t.style.levels;
  for (uint32_t r = 0; r <= levels; ++r) {
    Resolution& res = t.res[r];
    const int64_t scale = int64_t{1} << (levels - r);
    res.r = {static_cast<int32_t>(ceil_div(t.r.x0, scale)),
             static_cast<int32_t>(ceil_div(t.r.y0, scale)),
             static_cast<int32_t>(ceil_div(t.r.x1, scale)),
             static_cast<int32_t>(ceil_div(t.r.y1, scale))};
    res.bands = r == 0 ? 1 : 3;
    const uint32_t nb = r == 0 ? levels : levels - r + 1;
    const int64_t bscale = int64_t{1} << nb, half = nb > 0 ? bscale / 2 : 0;
    const int32_t lw = r == 0 ? 0 : t.res[r - 1].r.x1 - t.res[r - 1].r.x0;
    const int32_t lh = r == 0 ? 0 : t.res[r - 1].r.y1 - t.res[r - 1].r.y0;
    for (uint32_t b = 0; b < res.bands; ++b) {
      Band& band = res.band[b];
      band.type = r == 0 ? 0 : b + 1;
      const int64_t xo = (band.type & 1) != 0 ? half : 0, yo = (band.type & 2) != 0 ? half : 0;
      band.r = {static_cast<int32_t>(ceil_div(t.r.x0 - xo, bscale)),
                static_cast<int32_t>(ceil_div(t.r.y0 - yo, bscale)),
                static_cast<int32_t>(ceil_div(t.r.x1 - xo, bscale)),
                static_cast<int32_t>(ceil_div(t.r.y1 - yo, bscale))};
      band.bx = (band.type & 1) != 0 ? lw : 0;
      band.by = (band.type & 2) != 0 ? lh : 0;
      SPLINTCORE_RETURN_IF_ERROR(band_quantization(t, im, r, &band, at));
    }
    res.ppx = t.style.ppx[r];
    res.ppy = t.style.ppy[r];
    const int64_t pw = int64_t{1} << res.ppx, ph = int64_t{1} << res.ppy;
    const bool empty = res.r.x1 <= res.r.x0 || res.r.y1 <= res.r.y0;
    res.px0 = static_cast<int32_t>(floor_div(res.r.x0, pw));
    res.py0 = static_cast<int32_t>(floor_div(res.r.y0, ph));
    res.pw = empty ? 0 : static_cast<uint32_t>(ceil_div(res.r.x1, pw) - res.px0);
    res.ph = empty ? 0 : static_cast<uint32_t>(ceil_div(res.r.y1, ph) - res.py0);
    const uint32_t cap_x = r == 0 ? res.ppx : res.ppx - 1, cap_y = r == 0 ? res.ppy : res.ppy - 1;
    res.xcb = t.style.xcb < cap_x ? t.style.xcb : cap_x;
    res.ycb = t.style.ycb < cap_y ? t.style.ycb : cap_y;
  }
  return Status::ok();
}

// The code-block grid of precinct (i, j) of resolution r in band b (empty: cw = ch = 0).
void precinct_band_grid(const Resolution& res, uint32_t r, uint32_t b, uint32_t i, uint32_t j,
                        PrecinctBand* pb, J2kRect* area) {
  const Band& band = res.band[b];
  const uint32_t sx = r == 0 ? res.ppx : res.ppx - 1, sy = r == 0 ? res.ppy : res.ppy - 1;
  const int64_t x0 = (int64_t{res.px0} + i) << sx, y0 = (int64_t{res.py0} + j) << sy;
  const int64_t x1 = x0 + (int64_t{1} << sx), y1 = y0 + (int64_t{1} << sy);
  area->x0 = static_cast<int32_t>(std::max<int64_t>(x0, band.r.x0));
  area->y0 = static_cast<int32_t>(std::max<int64_t>(y0, band.r.y0));
  area->x1 = static_cast<int32_t>(std::min<int64_t>(x1, band.r.x1));
  area->y1 = static_cast<int32_t>(std::min<int64_t>(y1, band.r.y1));
  if (area->x1 <= area->x0 || area->y1 <= area->y0) {
    pb->cbx0 = pb->cby0 = pb->cw = pb->ch = 0;
    return;
  }
  const int64_t bw = int64_t{1} << res.xcb, bh = int64_t{1} << res.ycb;
  pb->cbx0 = static_cast<uint32_t>(floor_div(area->x0, bw));
  pb->cby0 = static_cast<uint32_t>(floor_div(area->y0, bh));
  pb->cw = static_cast<uint32_t>(ceil_div(area->x1, bw) - pb->cbx0);
  pb->ch = static_cast<uint32_t>(ceil_div(area->y1, bh) - pb->cby0);
}

// Counts (fill false) or lays out (fill true) the precincts, code-blocks and tag trees.
void tile_records(Tile& t, bool fill) {
  size_t precincts = 0, blocks = 0, nodes = 0;
  for (uint32_t r = 0; r <= t.style.levels; ++r) {
    Resolution& res = t.res[r];
    res.first_precinct = precincts;
    for (uint32_t j = 0; j < res.ph; ++j) {
      for (uint32_t i = 0; i < res.pw; ++i, ++precincts) {
        if (fill) std::memset(&t.precincts[precincts], 0, sizeof(Precinct));  // unused bands
        for (uint32_t b = 0; b < res.bands; ++b) {
          PrecinctBand pb;
          J2kRect area;
          precinct_band_grid(res, r, b, i, j, &pb, &area);
          pb.first_block = blocks;
          pb.inclusion = nodes;
          const size_t n = pb.cw == 0 ? 0 : j2k_tag_tree_nodes(pb.cw, pb.ch);
          pb.zero_planes = nodes + n;
          nodes += 2 * n;
          blocks += size_t{pb.cw} * pb.ch;
          if (!fill) continue;
          t.precincts[precincts].band[b] = pb;
          const int32_t bw = 1 << res.xcb, bh = 1 << res.ycb;
          for (uint32_t y = 0; y < pb.ch; ++y) {
            for (uint32_t x = 0; x < pb.cw; ++x) {
              Block& k = t.blocks[pb.first_block + size_t{y} * pb.cw + x];
              std::memset(&k, 0, sizeof(k));
              const int32_t bx0 = static_cast<int32_t>(pb.cbx0 + x) * bw;
              const int32_t by0 = static_cast<int32_t>(pb.cby0 + y) * bh;
              k.r = {bx0 > area.x0 ? bx0 : area.x0, by0 > area.y0 ? by0 : area.y0,
                     bx0 + bw < area.x1 ? bx0 + bw : area.x1,
                     by0 + bh < area.y1 ? by0 + bh : area.y1};
              k.lblock = 3;
            }
          }
        }
      }
    }
  }
  t.precinct_count = precincts;
  t.block_count = blocks;
  t.node_count = nodes;
}

// The tier-2 state back to its start (before the second pass over the packets).
void reset_tier2(Tile& t) {
  for (size_t p = 0; p < t.precinct_count; ++p) {
    for (const PrecinctBand& pb : t.precincts[p].band) {
      if (pb.cw == 0) continue;
      j2k_tag_tree_init(t.nodes + pb.inclusion, pb.cw, pb.ch);
      j2k_tag_tree_init(t.nodes + pb.zero_planes, pb.cw, pb.ch);
    }
  }
  for (size_t k = 0; k < t.block_count; ++k) {
    Block& b = t.blocks[k];
    b.pending = 0;
    b.passes = 0;
    b.zero_planes = 0;
    b.lblock = 3;
    b.included = 0;
  }
}

// Where the packets are read: the tile-part bodies one after the other (a packet never crosses
// from one tile-part into the next).
struct PacketCursor {
  uint32_t part = 0;
  size_t pos = 0;
};

// B.10.6, Table B.4.
uint32_t read_pass_count(J2kBits& bits) {
  if (!bits.bit()) return 1;
  if (!bits.bit()) return 2;
  const uint32_t two = bits.bits(2);
  if (two < 3) return 3 + two;
  const uint32_t five = bits.bits(5);
  if (five < 31) return 6 + five;
  return 37 + bits.bits(7);
}

// One code-block's part of a packet header (B.10.4 - B.10.7): sets its pending length.
Status read_block_header(Tile& t, const PrecinctBand& pb, const Band& band, uint32_t leaf,
                         uint32_t layer, J2kBits& bits, size_t at) {
  Block& k = t.blocks[pb.first_block + leaf];
  J2kTagNode* inclusion = t.nodes + pb.inclusion;
  J2kTagNode* zero = t.nodes + pb.zero_planes;
  bool below = false;
  if (k.included == 0) {
    j2k_tag_tree_decode(inclusion, leaf, static_cast<int32_t>(layer) + 1, bits, &below);
    if (!below) return Status::ok();
    // Zero bit planes beyond M_b <= 30 fail the pass count check below; a cut header
    // (bits read as 0) stops here and is reported by the caller.
    below = false;
    for (int32_t threshold = 1; !below && threshold <= 64; ++threshold) {
      j2k_tag_tree_decode(zero, leaf, threshold, bits, &below);
    }
    k.zero_planes = static_cast<uint32_t>(zero[leaf].value);
    k.included = 1;
  } else if (!bits.bit()) {
    return Status::ok();
  }
  const uint32_t passes = read_pass_count(bits);
  while (bits.bit()) {
    if (++k.lblock > 32) return j2k_error(StatusCode::kParseError, "Lblock over 32", at);
  }
  const uint32_t length_bits = k.lblock + floor_log2(passes);
  if (length_bits > 32) {
    return j2k_error(StatusCode::kParseError, "a code-block length of more than 32 bits", at);
  }
  k.pending = bits.bits(length_bits);
  const uint32_t planes = band.bitplanes > k.zero_planes ? band.bitplanes - k.zero_planes : 0;
  if (k.passes + passes > (planes == 0 ? 0 : 3 * planes - 2)) {
    return j2k_error(StatusCode::kParseError,
                     "a code-block has more coding passes than its bit planes allow", at);
  }
  k.passes += passes;
  return Status::ok();
}

// Packet (layer, resolution r, precinct p): its header (with SOP and EPH when COD asks),
// then its body, whose bytes are counted (copy false) or copied to the code-blocks (copy).
Status read_packet(Tile& t, const uint8_t* data, PacketCursor& c, uint32_t layer, uint32_t r,
                   size_t p, bool copy) {
  while (c.part < t.parts && c.pos >= t.part_end[c.part]) {
    if (++c.part < t.parts) c.pos = t.part_begin[c.part];
  }
  if (c.part >= t.parts) {
    return make_error(StatusCode::kTruncated, "JPEG 2000: the tile's data ends before packet ",
                      "(layer ", layer, ", resolution ", r, ", precinct ", p, ")")
        .at_byte(t.part_end[t.parts - 1]);
  }
  const size_t end = t.part_end[c.part];
  if (t.style.sop != 0 && end - c.pos >= 6 && be16(data + c.pos) == kSop) c.pos += 6;
  const size_t header_at = c.pos;
  J2kBits bits;
  bits.data = data + c.pos;
  bits.size = end - c.pos;
  const Resolution& res = t.res[r];
  const Precinct& precinct = t.precincts[p];
  if (bits.bit()) {
    for (uint32_t b = 0; b < res.bands; ++b) {
      const PrecinctBand& pb = precinct.band[b];
      for (uint32_t leaf = 0; leaf < pb.cw * pb.ch; ++leaf) {
        SPLINTCORE_RETURN_IF_ERROR(
            read_block_header(t, pb, res.band[b], leaf, layer, bits, header_at));
      }
    }
  }
  bits.align();
  if (bits.truncated) {
    return j2k_error(StatusCode::kTruncated, "a packet header runs past its tile-part", header_at);
  }
  c.pos += bits.pos;
  if (t.style.eph != 0) {
    if (end - c.pos < 2 || be16(data + c.pos) != kEph) {
      return j2k_error(StatusCode::kParseError, "EPH marker missing after a packet header", c.pos);
    }
    c.pos += 2;
  }
  for (uint32_t b = 0; b < res.bands; ++b) {
    const PrecinctBand& pb = precinct.band[b];
    for (uint32_t leaf = 0; leaf < pb.cw * pb.ch; ++leaf) {
      Block& k = t.blocks[pb.first_block + leaf];
      if (k.pending == 0) continue;
      if (k.pending > end - c.pos) {
        return j2k_error(StatusCode::kTruncated, "code-block data runs past its tile-part", c.pos);
      }
      if (copy) {
        std::memcpy(t.bytes + k.write, data + c.pos, k.pending);
        k.write += k.pending;
      } else {
        k.length += k.pending;
      }
      c.pos += k.pending;
      k.pending = 0;
    }
  }
  return Status::ok();
}

// Every packet of the tile in its progression order (B.12): LRCP, RLCP, RPCL; PCRL and CPRL
// reduce to RPCL when each resolution has one precinct (all start at the tile's origin).
Status read_packets(Tile& t, const uint8_t* data, bool copy, size_t at) {
  PacketCursor c;
  c.pos = t.part_begin[0];
  const uint32_t layers = t.style.layers, levels = t.style.levels;
  const uint32_t order = t.style.progression;
  if (order >= 3) {
    for (uint32_t r = 0; r <= levels; ++r) {
      if (t.res[r].pw * t.res[r].ph > 1) {
        return j2k_error(StatusCode::kUnsupported,
                         "progression PCRL or CPRL with several precincts per resolution", at);
      }
    }
  }
  if (order == 0) {  // LRCP
    for (uint32_t l = 0; l < layers; ++l) {
      for (uint32_t r = 0; r <= levels; ++r) {
        const Resolution& res = t.res[r];
        for (size_t p = 0; p < size_t{res.pw} * res.ph; ++p) {
          SPLINTCORE_RETURN_IF_ERROR(read_packet(t, data, c, l, r, res.first_precinct + p, copy));
        }
      }
    }
    return Status::ok();
  }
  for (uint32_t r = 0; r <= levels; ++r) {
    const Resolution& res = t.res[r];
    const size_t count = size_t{res.pw} * res.ph;
    if (order == 1) {  // RLCP
      for (uint32_t l = 0; l < layers; ++l) {
        for (size_t p = 0; p < count; ++p) {
          SPLINTCORE_RETURN_IF_ERROR(read_packet(t, data, c, l, r, res.first_precinct + p, copy));
        }
      }
    } else {  // RPCL (and PCRL, CPRL with one precinct)
      for (size_t p = 0; p < count; ++p) {
        for (uint32_t l = 0; l < layers; ++l) {
          SPLINTCORE_RETURN_IF_ERROR(read_packet(t, data, c, l, r, res.first_precinct + p, copy));
        }
      }
    }
  }
  return Status::ok();
}

int64_t round_to_integer(double v) {  // half up; huge values clamp (std::min: NaN too)
  return static_cast<int64_t>(std::floor(std::max(-1e9, std::min(1e9, v)) + 0.5));
}

// Tier-1 of every code-block with passes, dequantised (E.1) into the tile's subbands.
void decode_blocks(Tile& t, J2kTier1& t1, int32_t* ints, double* reals, size_t stride) {
  for (uint32_t r = 0; r <= t.style.levels; ++r) {
    const Resolution& res = t.res[r];
    for (size_t p = 0; p < size_t{res.pw} * res.ph; ++p) {
      for (uint32_t b = 0; b < res.bands; ++b) {
        const PrecinctBand& pb = t.precincts[res.first_precinct + p].band[b];
        const Band& band = res.band[b];
        for (size_t leaf = 0; leaf < size_t{pb.cw} * pb.ch; ++leaf) {
          const Block& k = t.blocks[pb.first_block + leaf];
          if (k.passes == 0) continue;
          J2kBlockJob job;
          job.data = t.bytes + (k.write - k.length);
          job.size = k.length;
          job.w = static_cast<uint32_t>(k.r.x1 - k.r.x0);
          job.h = static_cast<uint32_t>(k.r.y1 - k.r.y0);
          job.band = band.type;
          job.bitplanes = band.bitplanes;
          job.zero_planes = k.zero_planes;
          job.passes = k.passes;
          job.style = t.style.block_style;
          j2k_decode_block(t1, job, t1.coefficients, job.w);
          // >= 0: the block lies inside its band.
          const int64_t bx =
              static_cast<int64_t>(band.bx) + (static_cast<int64_t>(k.r.x0) - band.r.x0);
          const int64_t by =
              static_cast<int64_t>(band.by) + (static_cast<int64_t>(k.r.y0) - band.r.y0);
          const size_t x0 = static_cast<size_t>(bx);
          const size_t y0 = static_cast<size_t>(by);
          const double half_step = band.step * 0.5;
          for (uint32_t y = 0; y < job.h; ++y) {
            const int32_t* from = t1.coefficients + size_t{y} * job.w;
            const size_t row = (y0 + y) * stride + x0;
            for (uint32_t x = 0; x < job.w; ++x) {
              if (ints != nullptr) {
                ints[row + x] = from[x] / 2;
              } else {
                reals[row + x] = static_cast<double>(from[x]) * half_step;
              }
            }
          }
        }
      }
    }
  }
}

// The tile's samples, level shifted (G.1.2) and clamped to the precision, into the frame.
void write_tile(const Tile& t, const Image& im, const int32_t* ints, const double* reals,
                uint32_t columns, uint8_t* out) {
  const int64_t half = int64_t{1} << (im.precision - 1);
  const int64_t shift = im.is_signed ? 0 : half;
  const int64_t lo = im.is_signed ? -half : 0, hi = im.is_signed ? half - 1 : 2 * half - 1;
  const size_t stride = static_cast<size_t>(t.r.x1 - t.r.x0);
  for (int32_t y = t.r.y0; y < t.r.y1; ++y) {
    const size_t row = static_cast<size_t>(y - t.r.y0) * stride;
    uint8_t* o = out + (static_cast<size_t>(static_cast<uint32_t>(y) - im.y0) * columns +
                        (static_cast<uint32_t>(t.r.x0) - im.x0)) *
                           2;
    for (int32_t x = 0; x < t.r.x1 - t.r.x0; ++x) {
      const size_t i = row + static_cast<size_t>(x);
      int64_t v = (ints != nullptr ? int64_t{ints[i]} : round_to_integer(reals[i])) + shift;
      v = v < lo ? lo : (v > hi ? hi : v);
      const uint32_t u = static_cast<uint32_t>(v);
      o[2 * x] = static_cast<uint8_t>(u & 0xFF);
      o[2 * x + 1] = static_cast<uint8_t>((u >> 8) & 0xFF);
    }
  }
}

Status Decoder::decode_tile(uint32_t index, const HeaderSegments& segments, size_t at) {
  Tile& t = *tile;
  t.style = image.style;
  t.quant = image.quant;
  segments.apply(&t.style, &t.quant);
  if (t.style.reversible != 0 && t.quant.style != 0) {
    return j2k_error(StatusCode::kUnsupported, "quantised 5/3 (reversible) coefficients", at);
  }
  const Image& im = image;
  const int64_t p = index % im.tiles_x, q = index / im.tiles_x;
  const int64_t tx0 = im.tx0 + p * im.tw, ty0 = im.ty0 + q * im.th;
  t.r = {static_cast<int32_t>(tx0 > im.x0 ? tx0 : im.x0),
         static_cast<int32_t>(ty0 > im.y0 ? ty0 : im.y0),
         static_cast<int32_t>(tx0 + im.tw < im.x1 ? tx0 + im.tw : im.x1),
         static_cast<int32_t>(ty0 + im.th < im.y1 ? ty0 + im.th : im.y1)};
  SPLINTCORE_RETURN_IF_ERROR(tile_resolutions(t, im, at));
  uint64_t precinct_total = 0;
  for (uint32_t r = 0; r <= t.style.levels; ++r)
    precinct_total += uint64_t{t.res[r].pw} * t.res[r].ph;
  const uint64_t cap = records_cap(uint64_t{rows} * columns);
  if (precinct_total * sizeof(Precinct) > cap) {
    return j2k_error(StatusCode::kUnsupported, "precincts too small (too many in a tile)", at);
  }
  tile_records(t, false);
  const uint64_t record_bytes = t.precinct_count * sizeof(Precinct) +
                                t.block_count * sizeof(Block) + t.node_count * sizeof(J2kTagNode);
  if (record_bytes > cap) {
    return j2k_error(StatusCode::kUnsupported,
                     "code-blocks or precincts too small (more records than the memory bound)", at);
  }
  ArenaScope scope(arena);
  t.precincts = arena.allocate_array<Precinct>(t.precinct_count + 1);
  t.blocks = arena.allocate_array<Block>(t.block_count + 1);
  t.nodes = arena.allocate_array<J2kTagNode>(t.node_count + 1);
  if (t.precincts == nullptr || t.blocks == nullptr || t.nodes == nullptr) {
    return arena.exhausted_status();
  }
  tile_records(t, true);
  reset_tier2(t);
  SPLINTCORE_RETURN_IF_ERROR(read_packets(t, data, false, at));
  uint32_t total = 0;
  for (size_t k = 0; k < t.block_count; ++k) {
    t.blocks[k].write = total;
    total += t.blocks[k].length;
  }
  t.bytes = arena.allocate_array<uint8_t>(size_t{total} + 1);
  if (t.bytes == nullptr) return arena.exhausted_status();
  reset_tier2(t);
  SPLINTCORE_RETURN_IF_ERROR(read_packets(t, data, true, at));

  const size_t w = static_cast<size_t>(t.r.x1 - t.r.x0), h = static_cast<size_t>(t.r.y1 - t.r.y0);
  const bool reversible = t.style.reversible != 0;
  int32_t* ints = nullptr;
  double* reals = nullptr;
  if (reversible) {
    ints = arena.allocate_array<int32_t>(w * h + (w > h ? w : h) + 8);
    if (ints == nullptr) return arena.exhausted_status();
    std::memset(ints, 0, sizeof(int32_t) * w * h);
  } else {
    reals = arena.allocate_array<double>(w * h + (w > h ? w : h) + 8);
    if (reals == nullptr) return arena.exhausted_status();
    for (size_t i = 0; i < w * h; ++i) reals[i] = 0.0;
  }
  decode_blocks(t, *t1, ints, reals, w);
  J2kRect rects[kMaxLevels + 1];
  for (uint32_t r = 0; r <= t.style.levels; ++r) rects[r] = t.res[r].r;
  if (reversible) {
    j2k_inverse_53(ints, w, rects, t.style.levels, ints + w * h);
  } else {
    j2k_inverse_97(reals, w, rects, t.style.levels, reals + w * h);
  }
  write_tile(t, im, ints, reals, columns, out);
  return Status::ok();
}

// The end of a tile-part whose Psot is 0: the EOC at the end of the data (a DICOM pad byte
// may follow it).
size_t last_part_end(const uint8_t* data, size_t size) {
  if (size >= 2 && be16(data + size - 2) == kEoc) return size - 2;
  if (size >= 3 && be16(data + size - 3) == kEoc && data[size - 1] == 0) return size - 3;
  return size;
}

Status Decoder::read_tile_parts() {
  HeaderSegments segments;
  int64_t current = -1;
  size_t current_at = 0;
  uint64_t tiles_seen = 0;
  for (;;) {
    const size_t at = pos;
    if (size - pos < 2) return j2k_error(StatusCode::kTruncated, "data ends before EOC", size);
    const uint32_t code = be16(data + pos);
    if (code == kEoc) break;
    if (code != kSot) return j2k_error(StatusCode::kParseError, "expected SOT or EOC", at);
    pos += 2;
    uint32_t length = 0;
    size_t b = 0;
    SPLINTCORE_RETURN_IF_ERROR(segment(at, &length, &b));
    if (length != 10) return j2k_error(StatusCode::kParseError, "SOT length not 10", at);
    const uint32_t isot = be16(data + b), psot = be32(data + b + 2);
    if (isot >= image.tiles_x * image.tiles_y) {
      return j2k_error(StatusCode::kParseError, "SOT tile index past the tile grid", b);
    }
    if (psot != 0 && psot > size - at) {
      return j2k_error(StatusCode::kTruncated, "tile-part runs past the data (Psot)", b + 2);
    }
    if (psot != 0 && psot < 14) return j2k_error(StatusCode::kParseError, "Psot under 14", b + 2);
    const size_t end = psot == 0 ? last_part_end(data, size) : at + psot;
    if (isot != current) {
      if (current >= 0) {
        SPLINTCORE_RETURN_IF_ERROR(
            decode_tile(static_cast<uint32_t>(current), segments, current_at));
      }
      if (static_cast<int64_t>(isot) < current) {
        return j2k_error(StatusCode::kUnsupported, "tile-parts out of tile order", at);
      }
      segments = HeaderSegments();
      tile->parts = 0;
      current = isot;
      current_at = at;
      ++tiles_seen;
    }
    SPLINTCORE_RETURN_IF_ERROR(read_header(at, false, &segments));
    if (pos > end) {
      return j2k_error(StatusCode::kParseError, "tile-part header runs past its Psot", at);
    }
    if (tile->parts == Tile::kMaxParts) {
      return j2k_error(StatusCode::kUnsupported, "more than 256 tile-parts in a tile", at);
    }
    tile->part_begin[tile->parts] = pos;
    tile->part_end[tile->parts] = end;
    ++tile->parts;
    pos = end;
  }
  // The main header ended at an SOT: there was a tile.
  SPLINTCORE_RETURN_IF_ERROR(decode_tile(static_cast<uint32_t>(current), segments, current_at));
  if (tiles_seen != uint64_t{image.tiles_x} * image.tiles_y) {
    return make_error(StatusCode::kParseError, "JPEG 2000: ", tiles_seen, " of ",
                      uint64_t{image.tiles_x} * image.tiles_y, " tiles present")
        .at_byte(pos);
  }
  return Status::ok();
}

// A JP2 file (Annex I): the boxes up to the contiguous codestream box 'jp2c'.
Status find_codestream(const uint8_t* data, size_t size, size_t* begin, size_t* end) {
  *begin = 0;
  *end = size;
  if (size < 12 || be32(data) != 12 || be32(data + 4) != 0x6A502020) return Status::ok();
  size_t pos = 0;
  while (size - pos >= 8) {
    uint64_t length = be32(data + pos);
    size_t header = 8;
    if (length == 1) {
      if (size - pos < 16) break;
      length = (uint64_t{be32(data + pos + 8)} << 32) | be32(data + pos + 12);
      header = 16;
    } else if (length == 0) {
      length = size - pos;
    }
    if (length < header || length > size - pos) {
      return j2k_error(StatusCode::kParseError, "JP2 box runs past the data", pos);
    }
    if (be32(data + pos + 4) == 0x6A703263) {  // 'jp2c'
      *begin = pos + header;
      *end = pos + static_cast<size_t>(length);
      return Status::ok();
    }
    pos += static_cast<size_t>(length);
  }
  return j2k_error(StatusCode::kParseError, "JP2 file without a codestream box", pos);
}

}  // namespace

uint64_t jpeg2000_arena_bytes(uint32_t rows, uint32_t columns, uint64_t size) {
  const uint64_t samples = uint64_t{rows} * columns;
  const uint64_t line = std::max(rows, columns) + uint64_t{8};
  return sizeof(J2kTier1) + sizeof(Tile) + 8 * (samples + line) + size + 1 + records_cap(samples) +
         8 * Arena::kDefaultAlignment;
}

Status jpeg2000_decode(Arena& arena, const uint8_t* data, size_t size, uint32_t rows,
                       uint32_t columns, uint32_t max_precision, uint8_t* out) {
  if (size > 0xFFFFFFFFu) {
    return j2k_error(StatusCode::kUnsupported, "a codestream of 4 GiB or more", 0);
  }
  size_t begin = 0, end = 0;
  SPLINTCORE_RETURN_IF_ERROR(find_codestream(data, size, &begin, &end));
  ArenaScope scope(arena);
  Decoder d{arena,   data,    end,     rows,    columns, max_precision,
            nullptr, Image(), nullptr, nullptr, begin};
  d.out = out;  // the samples are written through it
  if (end - begin < 4 || be16(data + begin) != kSoc) {
    return j2k_error(StatusCode::kParseError, "no SOC marker (not a JPEG 2000 codestream)", begin);
  }
  if (be16(data + begin + 2) != kSiz) {
    return j2k_error(StatusCode::kParseError, "SIZ must follow SOC", begin + 2);
  }
  d.pos = begin + 4;
  SPLINTCORE_RETURN_IF_ERROR(d.read_siz(begin + 2));
  HeaderSegments main;
  SPLINTCORE_RETURN_IF_ERROR(d.read_header(d.pos, true, &main));
  if (!main.cod || !main.qcd) {
    return j2k_error(StatusCode::kParseError, "the main header lacks COD or QCD", d.pos);
  }
  main.apply(&d.image.style, &d.image.quant);
  d.t1 = arena.allocate_array<J2kTier1>(1);
  d.tile = arena.allocate_array<Tile>(1);
  if (d.t1 == nullptr || d.tile == nullptr) return arena.exhausted_status();
  j2k_tier1_init(*d.t1);
  return d.read_tile_parts();
}

}  // namespace ct_detail
}  // namespace splintcore
