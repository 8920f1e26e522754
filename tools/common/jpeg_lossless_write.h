// A JPEG lossless encoder (ITU-T T.81 Annex H, process 14, one component) for test and benchmark
// inputs: the DICOM writer's JPEG lossless series (ct_write.h) and the decoder's speed proof
// (tools/bench). Hosted code (std::vector), not a core component.
#ifndef SPLINTCORE_TOOLS_JPEG_LOSSLESS_WRITE_H
#define SPLINTCORE_TOOLS_JPEG_LOSSLESS_WRITE_H

#include <cstdint>
#include <vector>

namespace splintcore {
namespace cli {

// SOI, SOF3 (precision 16, `columns` x `rows`, one component), one DHT (a Huffman code of the
// image's own difference categories, lengths limited to 16 as in T.81 K.2), SOS with
// `predictor` (1..7; DICOM 1.2.840.10008.1.2.4.70 is predictor 1) and point transform 0, the
// entropy-coded data (0xFF stuffed, the last byte padded with 1 bits), EOI. `samples` are
// rows x columns 16-bit values, row by row.
std::vector<uint8_t> jpeg_lossless_encode(const uint16_t* samples, uint32_t rows, uint32_t columns,
                                          uint32_t predictor);

}  // namespace cli
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_JPEG_LOSSLESS_WRITE_H
