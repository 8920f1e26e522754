// DICOM RLE Lossless (transfer syntax 1.2.840.10008.1.2.5), PS3.5 Annex G: private to the DICOM
// reader (src/ct/ct_dicom.cpp), exposed for its unit tests.
#ifndef SPLINTCORE_SRC_CT_DICOM_RLE_H
#define SPLINTCORE_SRC_CT_DICOM_RLE_H

#include "splintcore/core.h"

namespace splintcore {
namespace ct_detail {

// Decodes one PackBits segment (PS3.5 G.3.1) in[0, size) into `rows` rows of `columns` bytes,
// byte i written at out[i * stride]. Runs must not cross a row's end; after the last row only
// no-op headers (-128) and one pad byte may follow. Errors (kParseError) name the segment and
// the byte offset, `base` + the offset in `in`. Uses no memory.
Status packbits_decode(const uint8_t* in, size_t size, uint64_t base, uint32_t segment,
                       uint32_t rows, uint32_t columns, uint8_t* out, size_t stride);

// Decodes one RLE frame, frame[0, size) (the 64-byte header: segment count and 15 offsets, then
// the segments, most significant byte plane first) of rows x columns samples of
// `bytes_per_sample` (1 or 2) bytes into out[0, 2 * rows * columns): every sample as a 16-bit
// little-endian value (8-bit samples with a zero high byte). Errors (kParseError, byte offsets
// in the frame): a header that does not fit, a segment count other than bytes_per_sample (more
// than 15 named as such), offsets out of order or past the frame, and the segments' own
// (packbits_decode). Uses no memory.
Status rle_decode_frame(const uint8_t* frame, size_t size, uint32_t rows, uint32_t columns,
                        uint32_t bytes_per_sample, uint8_t* out);

}  // namespace ct_detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_CT_DICOM_RLE_H
