// CT volume writers for tests and the phantom tool (hosted: std::string, std::filesystem).
// Each writes files the core readers (splintcore/ct.h) read back with the same voxels, axes,
// origin and spacing (NRRD: spacing and axes are recovered from space directions = axis x
// spacing, so they agree to within an ulp or two, not bit for bit; DICOM: z spacing and the
// normal are recomputed from positions). Output bytes are deterministic (no time stamps;
// numbers in shortest round-trip form; DICOM UIDs derived from a hash of the volume).
// Every file is written through a temporary file and renamed (AtomicFile); the files of one
// call (a header and its data, a series' slices) are placed together (OutputSet), so a failed
// call leaves none of them, and an earlier call's files as they were.
#ifndef SPLINTCORE_TOOLS_CT_WRITE_H
#define SPLINTCORE_TOOLS_CT_WRITE_H

#include <string>
#include <vector>

#include "splintcore/core.h"
#include "splintcore/ct.h"

namespace splintcore {
namespace cli {

struct CtWriteOptions {
  bool big_endian = false;         // NRRD only (MetaImage and DICOM are little endian here)
  bool dicom_implicit_vr = false;  // DICOM: implicit VR LE (1.2.840.10008.1.2) or explicit
  // DICOM stored values: false = unsigned 16-bit with Rescale Intercept min(-1024, min HU)
  // (slope 1); true = signed 16-bit, intercept 0. Either way the HU round-trip exactly.
  bool dicom_signed = false;
  // DICOM: JPEG lossless, first-order prediction (1.2.840.10008.1.2.4.70: encapsulated pixel
  // data, one fragment a slice; explicit VR, so not with dicom_implicit_vr).
  bool dicom_jpeg_lossless = false;
  std::string space = "left-posterior-superior";  // NRRD `space` (written, not converted)
  // DICOM: when not empty (one per slice), slice k is written at slice_positions[k] instead of
  // origin + axis_z * (k * spacing.z): series with gantry tilt, uneven spacing or gaps.
  std::vector<Vec3> slice_positions;
};

// NRRD0004, type int16. `path` ending in ".nhdr": detached header plus "<stem>.raw" next to it
// (`data file: <stem>.raw`); otherwise (".nrrd") attached. Errors: kInvalidArgument (empty
// volume, bad extension), kIoError.
Status write_nrrd(const CtVolume& volume, const std::string& path, const CtWriteOptions& options);

// MetaImage, MET_SHORT little endian. `path` ending in ".mhd": header plus "<stem>.raw";
// ".mha": inline (ElementDataFile = LOCAL). Errors: kInvalidArgument, kIoError.
Status write_metaimage(const CtVolume& volume, const std::string& path,
                       const CtWriteOptions& options);

// One CT Image Storage file per slice in `folder` (created if missing), 16-bit MONOCHROME2.
// File names are "CT<number>.dcm" with the numbers a fixed permutation of the slice order (and
// Instance Number following the file name), so a reader must order by Image Position.
// Decimal strings (DS) are limited to 16 characters by the standard: a position, spacing or
// direction cosine whose shortest form is longer is written rounded to fit (then it reads back
// close, not bit for bit). Slice k is at origin + axis_z * (k * spacing.z).
// Errors: kInvalidArgument (empty volume, or the folder already holds files other than the
// ones this call writes: stale slices would join the series), kIoError.
Status write_dicom_series(const CtVolume& volume, const std::string& folder,
                          const CtWriteOptions& options);

}  // namespace cli
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_CT_WRITE_H
