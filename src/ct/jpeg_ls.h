// JPEG-LS (ITU-T T.87 | ISO/IEC 14495-1: DICOM transfer syntaxes 1.2.840.10008.1.2.4.80
// lossless and .81 near-lossless): private to the DICOM reader (src/ct/ct_dicom.cpp), exposed
// for its unit tests.
#ifndef SPLINTCORE_SRC_CT_JPEG_LS_H
#define SPLINTCORE_SRC_CT_JPEG_LS_H

#include "splintcore/core.h"

namespace splintcore {
namespace ct_detail {

// Bytes of arena jpeg_ls_decode() takes for an image `columns` wide, alignment included: the
// context statistics (367 contexts, about 9 KiB) and two lines of columns + 2 32-bit samples
// (at most about 512 KiB for the largest width, 65535).
uint64_t jpeg_ls_arena_bytes(uint32_t columns);

// Decodes one JPEG-LS image, data[0, size) (SOI ... EOI: SOF55 with one component of 2..16
// bits, SOS with NEAR >= 0 and no mapping table, LSE preset parameters (id 1: MAXVAL, T1, T2,
// T3, RESET), DRI with its RSTm markers; APPn and COM are skipped), which must be `columns` x
// `rows` samples of at most `max_precision` bits (the DICOM Bits Allocated), into
// out[0, 2 * rows * columns) as 16-bit little-endian values. Errors name what and the byte
// offset in data: kUnsupported (more than one component, LSE mapping tables (ids 2, 3) and
// oversize dimensions (id 4), a point transform, a height given by DNL, other JPEG processes),
// kParseError (bad marker segments or parameters, invalid codes, restart markers out of
// order, data past the last sample), kTruncated (data ends first).
// Arena: jpeg_ls_arena_bytes(columns), returned before it returns.
Status jpeg_ls_decode(Arena& arena, const uint8_t* data, size_t size, uint32_t rows,
                      uint32_t columns, uint32_t max_precision, uint8_t* out);

}  // namespace ct_detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_CT_JPEG_LS_H
