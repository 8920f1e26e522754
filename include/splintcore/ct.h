// splintcore ct: CT volumes in Hounsfield units and their readers (DICOM series, NRRD, MetaImage).
//
// The voxel data of a volume lives in the caller's arena; its size (2 bytes per voxel) is
// known from the header and checked against the arena's cap before anything is allocated.
#ifndef SPLINTCORE_CT_H
#define SPLINTCORE_CT_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/io.h"
#include "splintcore/volume.h"

namespace splintcore {

// A CT volume. Voxel (i, j, k), 0 <= i < nx and so on, is hu[(k * ny + j) * nx + i]: x (the
// image columns) fastest, then y (rows), then z (slices). Its centre in patient coordinates (mm)
// is ct_to_patient(v, {spacing.x i, spacing.y j, spacing.z k}).
//
// Values are Hounsfield units after the file's rescale (HU = slope * stored + intercept),
// rounded to the nearest integer (halves away from zero) and saturated to the int16 range;
// `saturated` counts voxels that were clamped.
struct CtVolume {
  uint32_t nx = 0, ny = 0, nz = 0;
  Vec3 spacing{};         // mm between voxel centres along x, y, z; each > 0
  Vec3 origin{};          // patient position of voxel (0, 0, 0), mm
  Vec3 axis_x{1, 0, 0};   // unit directions of +i, +j, +k in patient space:
  Vec3 axis_y{0, 1, 0};   // orthonormal (readers check it; a right-handed frame is
  Vec3 axis_z{0, 0, 1};   // not required: axis_z follows the slice order)
  int16_t* hu = nullptr;  // nx * ny * nz values in the arena
  uint64_t saturated = 0;

  uint64_t voxel_count() const { return uint64_t{nx} * ny * nz; }
  int16_t at(uint32_t i, uint32_t j, uint32_t k) const {
    return hu[(uint64_t{k} * ny + j) * nx + i];
  }
};

// The volume's grid in its own (voxel-aligned) frame: origin (0, 0, 0), its spacing and size.
// Meshes made on this grid are in that frame; ct_to_patient() maps them into the patient's.
inline VolumeGrid ct_local_grid(const CtVolume& v) {
  VolumeGrid g;
  g.origin = Vec3{0, 0, 0};
  g.spacing = v.spacing;
  g.nx = v.nx;
  g.ny = v.ny;
  g.nz = v.nz;
  return g;
}

// origin + axis_x p.x + axis_y p.y + axis_z p.z, in that order of operations (no fused
// multiply-add), so the bits are the same everywhere. With identity axes this is exactly
// origin + p.
inline Vec3 ct_to_patient(const CtVolume& v, const Vec3& p) {
  const Vec3 a = v.axis_x * p.x;
  const Vec3 b = v.axis_y * p.y;
  const Vec3 c = v.axis_z * p.z;
  return v.origin + ((a + b) + c);
}

// ---------------------------------------------------------------------------------------------
// Readers: DICOM series (PS3.5 / PS3.10, uncompressed or deflated), NRRD (teem NRRD0001-0005, raw,
// gzip) and MetaImage (.mha / .mhd, raw). No dependencies: bytes come through ByteSource, files a
// header points to (NRRD "data file", MetaImage ElementDataFile, the files of a DICOM series)
// through caller callbacks, so firmware can serve them from flash and a tool from disk.
//
// Memory: everything comes from ctx.arena. The voxels (2 bytes each) are the only thing left
// there on success, at the position the arena's top had on entry; temporaries (a read chunk
// of options.chunk_bytes; for DICOM 96 bytes per slice file) are taken above them and rewound.
// The total is computed from the header (after the limits below are checked, with overflow
// checks) and compared with the arena's free space before anything is allocated: a shortfall
// is kArenaExhausted naming the bytes needed. Headers are parsed in a fixed 1 KiB stack window.
// On error nothing is left in the arena and *out is untouched.
//
// Conversion: HU = slope * stored + intercept in double, in that order (no FMA), rounded to
// nearest with halves away from zero, saturated to int16 (counted in CtVolume::saturated). NRRD
// and MetaImage have no rescale (slope 1, intercept 0): their values are taken as HU.
// Floating-point voxels that are NaN or infinite are kNonFinite naming the voxel index.
//
// Frames: the axes and origin are taken as the file states them, in the file's patient space
// (DICOM: LPS; NRRD: its `space` field, MetaImage: its AnatomicalOrientation, both recorded in
// CtInfo::space but NOT converted: a RAS file stays RAS).
//
// Trailing bytes: NRRD and MetaImage data (attached or detached) may be followed by more bytes,
// which are ignored (both formats' reference readers read only what the header describes);
// DICOM Pixel Data must hold exactly rows x columns x bytes per sample, plus at most one pad
// byte to an even length; elements after Pixel Data are ignored.

enum class CtFormat : uint8_t { kUnknown = 0, kDicom, kNrrd, kMetaImage };

// "dicom", "nrrd", "metaimage", "unknown".
const char* ct_format_name(CtFormat format);

struct CtReadOptions {
  uint32_t max_dimension = 4096;            // per axis (and DICOM files per series)
  uint64_t max_voxels = uint64_t{1} << 31;  // nx * ny * nz
  uint64_t max_header_bytes = 1u << 20;     // text headers and DICOM data before Pixel Data
  size_t chunk_bytes = 64 * 1024;           // read buffer for voxel data, from the arena
                                            // (at least 1024 is used)
  double min_spacing = 1.0e-3;              // mm; smaller is an error ("wrong units?")
  double max_spacing = 100.0;               // mm; larger is an error ("wrong units?")
  // A DICOM stack is uniform when each gap is within max(tolerance_mm, relative x mean) of
  // the mean gap and each slice within max(tolerance_mm, relative x its distance along the
  // normal) of the normal through slice 0; it is then read as it is.
  double slice_spacing_tolerance_mm = 0.01;
  double slice_spacing_tolerance_relative = 0.01;
  // Otherwise (gantry tilt or shear, uneven spacing, missing slices) it is resampled onto a
  // regular grid when every gap is at most resample_max_gap times the median gap (plus the
  // tolerance; 3: up to two missing slices in a row); a wider gap is refused. 0: every stack
  // that is not uniform is refused.
  double resample_max_gap = 3.0;
  // Direction cosines: |length - 1| and |dot| of two axes at most this; DICOM slices must agree
  // on orientation and pixel spacing within it too (per component / in mm).
  double orientation_tolerance = 1.0e-4;
};

// What a reader found: for a tool to print.
struct CtInfo {
  CtFormat format = CtFormat::kUnknown;
  uint32_t nx = 0, ny = 0, nz = 0;
  Vec3 spacing{};
  char stored_type[16] = {};  // "int16", "uint16", "int8", "uint8", "int32", "uint32",
                              // "float32", "float64"
  uint8_t bits_stored = 0;    // DICOM Bits Stored; otherwise the type's width
  bool big_endian = false;
  double slope = 1.0;  // DICOM: of the first slice (each slice uses its own)
  double intercept = 0.0;
  bool rescale_varies = false;    // DICOM: slices had different slope or intercept
  char transfer_syntax[65] = {};  // DICOM: of the series' file 0
  char photometric[17] = {};      // DICOM: MONOCHROME1 or MONOCHROME2
  char space[64] = {};            // NRRD `space`, MetaImage AnatomicalOrientation, DICOM "LPS"
  uint32_t slice_count = 0;       // DICOM files, otherwise nz
  // DICOM stacks resampled onto a regular grid (CtReadOptions::resample_max_gap): what was
  // corrected. tilt_degrees: the angle between the normal and the line from the first slice's
  // position to the last's (gantry tilt; 0 when the slices were not shifted); max_shift_mm: the
  // largest in-plane shift of a slice; max_slice_offset_mm: the largest distance from an
  // output slice to its nearest input slice (0 when none was interpolated along the normal).
  bool resampled = false;
  double tilt_degrees = 0;
  double max_shift_mm = 0;
  double max_slice_offset_mm = 0;
  bool detached = false;  // NRRD / MetaImage data in another file
  uint64_t saturated = 0;
};

// Opens files named by a header (NRRD `data file`, MetaImage ElementDataFile). `name` is as
// written in the header (relative names are the opener's business, e.g. relative to the
// header's folder). open() fills *out and returns ok, or an error (e.g. kIoError naming the
// file); close() is called once for every successful open(). At most one file is open at a time.
struct CtFileOpener {
  Status (*open)(void* user, const char* name, ByteSource* out) = nullptr;
  void (*close)(void* user, ByteSource* source) = nullptr;
  void* user = nullptr;
};

// The files of a DICOM series, opened by index 0..count-1 (in any order: slices are ordered by
// position). Each file may be opened twice: once for its header, once for its pixels. At most
// one is open at a time; close() is called once for every successful open().
struct CtSeries {
  uint32_t count = 0;
  Status (*open)(void* user, uint32_t index, ByteSource* out) = nullptr;
  void (*close)(void* user, uint32_t index, ByteSource* source) = nullptr;
  void* user = nullptr;
};

// Files in memory (firmware flash, tests, fuzzers): the opener matches names exactly, the
// series serves files[0..count). Holds the state of the one open file.
struct CtMemoryFile {
  const char* name = nullptr;
  const uint8_t* data = nullptr;
  uint64_t size = 0;
};
struct CtMemoryFiles {
  const CtMemoryFile* files = nullptr;
  uint32_t count = 0;
  size_t max_chunk = 0;  // MemorySource::max_chunk of every opened file
  MemorySource current{};
};
CtFileOpener ct_memory_opener(CtMemoryFiles* files);
CtSeries ct_memory_series(CtMemoryFiles* files);

// NRRD (attached .nrrd, or a detached .nhdr header whose data file comes through `opener`;
// opener may be null for attached data). Fields: type (8/16/32-bit integers, float, double),
// dimension 3, sizes, encoding raw or gzip (gz), endian, space directions or spacings (neither:
// 1 mm, identity axes), space origin, space, data file, byte skip (-1: data at the end, needs a
// known size; raw only), line skip. Gzip data (one or more members, nothing after them) is
// inflated as it is read, never held compressed: line skip counts lines of the file, byte skip
// inflated bytes, and the arena holds a second read chunk and inflate_state_bytes() more. Space
// directions give spacing = vector lengths and axes = normalised vectors. Errors: kParseError (file
// and line), kUnsupported (encoding, type, dimension, LIST / pattern data files), kLimitExceeded,
// kTruncated (byte offset and file), kNonFinite (voxel index), kIoError, kArenaExhausted.
Status read_nrrd(const Context& ctx, const ByteSource& source, const CtFileOpener* opener,
                 const CtReadOptions& options, CtVolume* out, CtInfo* info);

// MetaImage (.mha with ElementDataFile = LOCAL, or .mhd naming a data file opened through
// `opener`). Keys: ObjectType Image, NDims 3, DimSize, ElementSpacing (or ElementSize),
// Offset / Origin / Position, TransformMatrix / Rotation / Orientation (row k = direction of
// axis k), ElementType MET_CHAR/UCHAR/SHORT/USHORT/INT/UINT/FLOAT/DOUBLE, BinaryData True,
// BinaryDataByteOrderMSB / ElementByteOrderMSB, CompressedData (True: kUnsupported),
// ElementNumberOfChannels 1, HeaderSize, AnatomicalOrientation, ElementDataFile (last key).
// Errors as read_nrrd().
Status read_metaimage(const Context& ctx, const ByteSource& source, const CtFileOpener* opener,
                      const CtReadOptions& options, CtVolume* out, CtInfo* info);

// A DICOM series, one single-frame CT image per file: 128-byte preamble, "DICM", group 0002 in
// explicit VR little endian; transfer syntax 1.2.840.10008.1.2, 1.2.840.10008.1.2.1,
// 1.2.840.10008.1.2.2 (explicit VR big endian: the data set and 16-bit pixels big endian) or
// 1.2.840.10008.1.2.1.99 (deflated explicit VR little endian: the data set after the file meta
// is inflated as it is read, twice per file (header, then pixels), an inflater of
// inflate_state_bytes() in the arena each time; offsets in errors about its elements are
// offsets in the inflated data set, errors of the stream itself offsets in the file); or
// encapsulated (PS3.5 A.4: Pixel Data of undefined length, a basic offset table item, fragment
// items, the sequence delimiter; all fragments of a file are its one frame) in
// 1.2.840.10008.1.2.5 (RLE Lossless, 8 or 16 bits) or 1.2.840.10008.1.2.4.57 / .70 (JPEG
// lossless process 14, one component, 2..16 bits): pass 1 reads each file whole to sum its
// fragments; pass 2 reads a file's fragments into one buffer of the largest file's total
// (from the arena, as are the JPEG decoder's tables, about 6 KiB) and decodes it into the
// slice; errors name the byte offset in the file (in the fragments when there are several).
// Compressed data may be at most 8 bytes a sample + 64 KiB (kLimitExceeded). Others:
// kUnsupported "unsupported transfer syntax <UID> (<name>)". Sequences and items of defined or
// undefined length are skipped (nesting bounded at 32, iteratively); only top-level elements
// count, and those of the functional group macros below. Or ONE enhanced multi-frame file
// (PS3.3 C.7.6.16, e.g. Enhanced CT; Number of Frames > 1): its frames are the slices, frame
// i's pixels at Pixel Data + i x frame bytes when native; when encapsulated, frame i is one or
// more whole fragments from entry i of the Basic Offset Table or the Extended Offset Table
// (7FE0,0001) (then the basic one empty), else (no table) RLE frames are one fragment each and
// JPEG, JPEG-LS and JPEG 2000 frames start at the fragments that begin with SOI / SOC; the
// fragments are mapped to frames in the header pass (errors name the frame and the byte offset
// of the item or table entry at fault), then each frame is read into the fragment buffer (the
// largest frame's bytes) and decoded in its slice, in file order (errors name the frame, its
// fragments, and the byte offset in the file); a frame may hold 8 bytes a sample + 64 KiB;
// every frame's (5200,9230) Per-frame Functional Groups item holds its (0020,9113) Plane
// Position (required: else kParseError naming the frame and its item's byte offset), and may
// hold its (0028,9145) rescale; orientation (0020,9116) and pixel measures (0028,9110) are
// shared (5200,9229) or per frame (then equal in all frames). The items must be as many as the
// frames, Number of Frames 1..max_dimension. The arena need is that of the same slices as a
// folder of single-frame files.
// Slices are ordered by Image Position projected on the normal row x column; positions must be
// distinct along the normal, and all slices must share size, orientation, pixel spacing and
// pixel format. A single slice takes its z spacing from Spacing Between Slices or Slice
// Thickness. A uniform stack along the normal (CtReadOptions tolerances) is read as it is.
// Geometry as scanners write it is resampled onto a regular grid while the slices stream in
// (CtReadOptions::resample_max_gap; CtInfo says what was corrected): gantry tilt or shear
// (slice origins offset in-plane) -- each slice shifted in-plane onto the output's columns and
// rows by bilinear interpolation, samples from outside the slice -1000 HU (air), the output's
// in-plane origin the centre of the slices' offsets rounded to whole pixels, the size and pixel
// spacing kept; uneven spacing or missing slices -- output slices every median gap from the
// first slice, each interpolated linearly between the two input slices around it; a gap wider
// than resample_max_gap medians is kUnsupported naming the two slices. A multi-frame file is
// resampled as it streams, in file order, when its frames are stored in slice order: ascending,
// or descending (then read with the normal reversed: axis_z = -(row x column), the origin at
// the last frame's end of the stack, a left-handed frame); other orders are kUnsupported.
// Axes: axis_x = row direction (+column index), axis_y = column direction, axis_z = normal
// pointing to increasing slice position; origin = position of the first slice (moved in-plane
// when the slices were shifted).
// Errors: kParseError (file, byte offset, tag), kUnsupported, kLimitExceeded, kTruncated,
// kInvalidArgument (count 0), kIoError, kArenaExhausted.
// Arena (all three readers): the voxels (2 bytes each) stay; the read buffer and, for DICOM,
// the slice table are returned. A resampled DICOM stack also takes 32 bytes a slice and three
// slices (2 bytes a pixel) of temporaries; resampled onto more slices than files, it is read
// twice (the first read finds the output's size) and the voxels are those of the output. Before
// reading voxels each reader checks that they and its temporaries fit, and otherwise says how much
// it needs. The need of a file is the high water of a first read (the two-step contract,
// docs/embedding.md): it then reads in exactly that.
Status read_dicom_series(const Context& ctx, const CtSeries& series, const CtReadOptions& options,
                         CtVolume* out, CtInfo* info);

}  // namespace splintcore

#endif  // SPLINTCORE_CT_H
