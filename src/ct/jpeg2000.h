// JPEG 2000 Part 1 (ITU-T T.800 | ISO/IEC 15444-1) decoder for the DICOM transfer syntaxes
// 1.2.840.10008.1.2.4.90 and .91: private to the DICOM reader (src/ct/ct_dicom.cpp), exposed for
// its unit tests. jpeg2000_codestream.cpp reads the codestream (markers, tiles, packets: Annex A
// and B), jpeg2000_tier1.cpp decodes code-blocks (Annexes C, D) and inverts the wavelet
// transform (Annex F).
#ifndef SPLINTCORE_SRC_CT_JPEG2000_H
#define SPLINTCORE_SRC_CT_JPEG2000_H

#include "splintcore/core.h"

namespace splintcore {
namespace ct_detail {

// The MQ arithmetic decoder (T.800 Annex C, the software conventions of C.3) over one
// codeword segment data[0, size); past its end the decoder reads 0xFF bytes as C.3.4 does at
// a marker. Contexts hold 2 x the state index (Table C.2) + the MPS.
constexpr uint32_t kMqContexts = 19;
struct MqDecoder {
  const uint8_t* data = nullptr;
  size_t size = 0;
  size_t pos = 0;  // the byte B of C.3.4
  uint32_t c = 0, a = 0, ct = 0;
  uint8_t contexts[kMqContexts] = {};

  void init(const uint8_t* bytes, size_t count);  // INITDEC (C.3.5)
  // Table D.7: every context at state 0 but the uniform (18, state 46), run-length (17,
  // state 3) and all-zero-neighbour significance (0, state 4) contexts.
  void reset_contexts();
  uint32_t decode(uint32_t context);  // DECODE (C.3.2): the decision, 0 or 1
};

// The bits of a packet header (B.10.1): most significant first; after a 0xFF byte the next
// byte holds 7 bits (its top bit is a stuffed 0).
struct J2kBits {
  const uint8_t* data = nullptr;
  size_t size = 0;
  size_t pos = 0;  // next byte to load
  uint32_t byte = 0;
  uint32_t left = 0;  // bits of `byte` still unread
  bool truncated = false;

  uint32_t bit();  // 0 past the end (and truncated set)
  uint32_t bits(uint32_t n);
  // The header ends at a byte boundary; a last 0xFF byte is followed by one more (stuffed).
  void align();
};

// A tag tree (B.10.2) over w x h leaves: node i's parent is nodes[i].parent (the root's is
// itself). Leaves are nodes [0, w * h) in raster order.
struct J2kTagNode {
  int32_t value;  // kTagUnknown until decoded
  int32_t low;    // the value is known to be at least this
  uint32_t parent;
};
constexpr int32_t kTagUnknown = 0x7FFFFFFF;
size_t j2k_tag_tree_nodes(uint32_t w, uint32_t h);  // 0 if w or h is 0
void j2k_tag_tree_init(J2kTagNode* nodes, uint32_t w, uint32_t h);
// Reads bits until it is known whether leaf's value is below `threshold`: *below says it.
void j2k_tag_tree_decode(J2kTagNode* nodes, uint32_t leaf, int32_t threshold, J2kBits& bits,
                         bool* below);

// Code-block styles (Table A.19) this decoder reads: the default, plus the ones that cost no
// more than a flag: reset of the contexts (0x02), vertically causal contexts (0x08),
// predictable termination (0x10: nothing to do when decoding), segmentation symbols (0x20).
constexpr uint32_t kJ2kStyleReset = 0x02;
constexpr uint32_t kJ2kStyleCausal = 0x08;
constexpr uint32_t kJ2kStyleSegmentation = 0x20;
constexpr uint32_t kJ2kStylesRead = 0x02 | 0x08 | 0x10 | 0x20;
constexpr uint32_t kJ2kMaxBitplanes = 30;  // magnitudes held with one fractional bit in 32 bits

// One code-block to decode (Annex D): its codeword segment (all its layers' bytes in order),
// size w x h (w * h <= 4096), the subband (0 LL, 1 HL, 2 LH, 3 HH), M_b (E-2), the zero bit
// planes and the coding passes included.
struct J2kBlockJob {
  const uint8_t* data;
  size_t size;
  uint32_t w, h;
  uint32_t band;
  uint32_t bitplanes;
  uint32_t zero_planes;
  uint32_t passes;
  uint32_t style;
};

// The tier-1 working state: flags with a one-sample border and the magnitudes of the largest
// code-block (64 x 64 samples; 1024 x 4 and 4 x 1024 fit in the same 4096 + borders).
constexpr uint32_t kJ2kMaxBlockSamples = 4096;
struct J2kTier1 {
  MqDecoder mq;
  uint32_t flags[(1024 + 2) * (4 + 2) > (64 + 2) * (64 + 2) ? (1024 + 2) * (4 + 2)
                                                            : (64 + 2) * (64 + 2)];
  uint32_t magnitude[kJ2kMaxBlockSamples];
  int32_t coefficients[kJ2kMaxBlockSamples];  // j2k_decode_block's output for the caller
  uint8_t zero_context[4][256];               // Table D.1 per subband, by the 8 neighbour bits
  uint8_t sign_context[256];  // Table D.3: the context, and in bit 7 whether the sign flips
};
void j2k_tier1_init(J2kTier1& t1);  // fills zero_context and sign_context

// Decodes one code-block into out[y * stride + x]: the signed coefficient times 2 (one
// fractional bit: the midpoint of the last decoded bit plane, as C code decoders round). The
// caller checked passes <= 3 * (bitplanes - zero_planes) - 2 and bitplanes <= kJ2kMaxBitplanes.
void j2k_decode_block(J2kTier1& t1, const J2kBlockJob& job, int32_t* out, size_t stride);

// A rectangle [x0, x1) x [y0, y1) on the reference grid or in a resolution.
struct J2kRect {
  int32_t x0, y0, x1, y1;
};

// The inverse wavelet transforms (F.3): tile[y * stride + x] holds the subbands of levels
// `levels` as Annex F's 2D_DEINTERLEAVE leaves them (resolution r's LL in the top-left
// res[r - 1] corner); res[0..levels] are the resolutions' rectangles; `line` has room for
// max(width, height) + 8 values. 5/3 reversible (F.3.8.1) in integers, 9/7 irreversible
// (F.3.8.2) in doubles.
void j2k_inverse_53(int32_t* tile, size_t stride, const J2kRect* res, uint32_t levels,
                    int32_t* line);
void j2k_inverse_97(double* tile, size_t stride, const J2kRect* res, uint32_t levels, double* line);

// Bytes of arena jpeg2000_decode() may take for a rows x columns frame of `size` codestream
// bytes: the samples of the largest tile (8 bytes each), a line of the wavelet transform, the
// code-blocks' bytes (at most `size`), the tier-1 state and the precinct, code-block and tag
// tree records of one tile, at most 64 * (rows * columns / 64 + 1024) bytes (a codestream
// needing more, with tiny code-blocks or precincts, is refused as kUnsupported), alignment
// included.
uint64_t jpeg2000_arena_bytes(uint32_t rows, uint32_t columns, uint64_t size);

// Decodes one JPEG 2000 codestream, data[0, size) (SOC ... EOC; a JP2 file's boxes are skipped
// to its codestream box), of `columns` x `rows` samples, one component of at most
// `max_precision` bits (the DICOM Bits Allocated), into out[0, 2 * rows * columns) as 16-bit
// little-endian values (signed ones in two's complement). Read: SIZ, COD, COC, QCD, QCC, SOT,
// SOD, EOC (COM, TLM, PLM, PLT, CRG skipped), SOP and EPH markers, any tiling (tile-parts of a
// tile together), progression orders LRCP, RLCP, RPCL (PCRL and CPRL with one precinct per
// resolution), 5/3 and 9/7 with no, derived or expounded quantisation. Errors name the cause
// and the byte offset in data: kUnsupported (several components, subsampling, RGN, POC,
// PPM/PPT, other code-block styles, ...), kParseError, kTruncated. Arena:
// jpeg2000_arena_bytes(), all returned before it returns.
Status jpeg2000_decode(Arena& arena, const uint8_t* data, size_t size, uint32_t rows,
                       uint32_t columns, uint32_t max_precision, uint8_t* out);

}  // namespace ct_detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_CT_JPEG2000_H
