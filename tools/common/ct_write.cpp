// CT volume writers (NRRD, MetaImage, DICOM series) for tests and the phantom tool. Formats as
// read by src/ct/ct_nrrd.cpp, ct_metaimage.cpp and ct_dicom.cpp (sources named there).
#include "ct_write.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <set>
#include <vector>

#include "cli.h"
#include "jpeg_lossless_write.h"
#include "splintcore/platform.h"

namespace splintcore {
namespace cli {

namespace {

namespace fs = std::filesystem;

std::string num(double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

// DICOM DS: at most 16 characters. The shortest round-trip form when it fits (then the
// reader gets the same double back), else the most significant digits that fit.
std::string ds(double v) {
  std::string s = num(v);
  if (s.size() <= 16) return s;
  for (int precision = 16; precision > 1; --precision) {
    char buf[40];
    std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
    if (std::strlen(buf) <= 16) return buf;
  }
  return "0";
}

bool ends_with(const std::string& s, const char* ext) {
  std::string lower = s;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const size_t n = std::strlen(ext);
  return lower.size() >= n && lower.compare(lower.size() - n, n, ext) == 0;
}

Status check_volume(const CtVolume& v) {
  if (v.nx == 0 || v.ny == 0 || v.nz == 0 || v.hu == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "cannot write an empty CT volume");
  }
  return Status::ok();
}

// A header and its data: one file, or (`data_path` not empty) two placed together.
Status write_header_and_data(const std::string& path, const std::string& header,
                             const std::string& data_path, const std::vector<uint8_t>& data) {
  const ByteSpan head{header.data(), header.size()};
  const ByteSpan voxels{data.data(), data.size()};
  if (data_path.empty()) return write_bytes_atomically(path, {head, voxels});
  OutputSet set;
  SPLINTCORE_RETURN_IF_ERROR(write_bytes_atomically(data_path, {voxels}, &set));
  SPLINTCORE_RETURN_IF_ERROR(write_bytes_atomically(path, {head}, &set));
  return set.commit();
}

std::vector<uint8_t> voxel_bytes(const CtVolume& v, bool big_endian) {
  const uint64_t n = v.voxel_count();
  std::vector<uint8_t> out(static_cast<size_t>(n * 2));
  for (size_t i = 0; i < static_cast<size_t>(n); ++i) {  // n * 2 bytes fit: allocated above
    const uint16_t u = static_cast<uint16_t>(v.hu[i]);
    out[2 * i + (big_endian ? 1 : 0)] = static_cast<uint8_t>(u & 0xFF);
    out[2 * i + (big_endian ? 0 : 1)] = static_cast<uint8_t>(u >> 8);
  }
  return out;
}

std::string vec3(const Vec3& v, const char* sep) {
  return num(v.x) + sep + num(v.y) + sep + num(v.z);
}

// "<folder>/<stem>.raw" and its file name.
void raw_path(const std::string& header_path, std::string* path, std::string* name) {
  fs::path p(header_path);
  p.replace_extension(".raw");
  *path = p.string();
  *name = p.filename().string();
}

}  // namespace

Status write_nrrd(const CtVolume& v, const std::string& path, const CtWriteOptions& options) {
  SPLINTCORE_RETURN_IF_ERROR(check_volume(v));
  const bool detached = ends_with(path, ".nhdr");
  if (!detached && !ends_with(path, ".nrrd")) {
    return make_error(StatusCode::kInvalidArgument,
                      "NRRD output must end in .nrrd or .nhdr: ", path.c_str());
  }
  std::string h = "NRRD0004\n# written by splintcore\ntype: int16\ndimension: 3\n";
  h += "space: " + options.space + "\n";
  h += "sizes: " + std::to_string(v.nx) + " " + std::to_string(v.ny) + " " + std::to_string(v.nz) +
       "\n";
  h += "space directions: (" + vec3(v.axis_x * v.spacing.x, ",") + ") (" +
       vec3(v.axis_y * v.spacing.y, ",") + ") (" + vec3(v.axis_z * v.spacing.z, ",") + ")\n";
  h += "kinds: domain domain domain\n";
  h += std::string("endian: ") + (options.big_endian ? "big" : "little") + "\n";
  h += "encoding: raw\n";
  h += "space origin: (" + vec3(v.origin, ",") + ")\n";
  const std::vector<uint8_t> data = voxel_bytes(v, options.big_endian);
  if (detached) {
    std::string data_path, data_name;
    raw_path(path, &data_path, &data_name);
    h += "data file: " + data_name + "\n";
    return write_header_and_data(path, h, data_path, data);
  }
  h += "\n";
  return write_header_and_data(path, h, std::string(), data);
}

Status write_metaimage(const CtVolume& v, const std::string& path, const CtWriteOptions& options) {
  (void)options;
  SPLINTCORE_RETURN_IF_ERROR(check_volume(v));
  const bool detached = ends_with(path, ".mhd");
  if (!detached && !ends_with(path, ".mha")) {
    return make_error(StatusCode::kInvalidArgument,
                      "MetaImage output must end in .mha or .mhd: ", path.c_str());
  }
  std::string h =
      "ObjectType = Image\nNDims = 3\nBinaryData = True\n"
      "BinaryDataByteOrderMSB = False\nCompressedData = False\n";
  h += "TransformMatrix = " + vec3(v.axis_x, " ") + " " + vec3(v.axis_y, " ") + " " +
       vec3(v.axis_z, " ") + "\n";
  h += "Offset = " + vec3(v.origin, " ") + "\n";
  h += "CenterOfRotation = 0 0 0\n";
  h += "ElementSpacing = " + vec3(v.spacing, " ") + "\n";
  h += "DimSize = " + std::to_string(v.nx) + " " + std::to_string(v.ny) + " " +
       std::to_string(v.nz) + "\n";
  h += "ElementType = MET_SHORT\n";
  const std::vector<uint8_t> data = voxel_bytes(v, false);
  if (detached) {
    std::string data_path, data_name;
    raw_path(path, &data_path, &data_name);
    h += "ElementDataFile = " + data_name + "\n";
    return write_header_and_data(path, h, data_path, data);
  }
  h += "ElementDataFile = LOCAL\n";
  return write_header_and_data(path, h, std::string(), data);
}

namespace {

// Little-endian DICOM element writer.
struct DicomBuffer {
  std::vector<uint8_t> b;
  bool implicit = false;

  void u16(uint32_t v) {
    b.push_back(static_cast<uint8_t>(v & 0xFF));
    b.push_back(static_cast<uint8_t>((v >> 8) & 0xFF));
  }
  void u32(uint32_t v) {
    u16(v & 0xFFFF);
    u16(v >> 16);
  }
  void element(uint32_t group, uint32_t elem, const char* vr, const uint8_t* data, size_t n,
               uint8_t pad) {
    const size_t padded = n + (n % 2);
    u16(group);
    u16(elem);
    if (implicit && group != 0x0002) {
      u32(static_cast<uint32_t>(padded));
    } else {
      b.push_back(static_cast<uint8_t>(vr[0]));
      b.push_back(static_cast<uint8_t>(vr[1]));
      const std::string v(vr);
      if (v == "OB" || v == "OW" || v == "SQ" || v == "UN" || v == "UT") {
        u16(0);
        u32(static_cast<uint32_t>(padded));
      } else {
        u16(static_cast<uint32_t>(padded));
      }
    }
    b.insert(b.end(), data, data + n);
    if (padded != n) b.push_back(pad);
  }
  void str(uint32_t group, uint32_t elem, const char* vr, const std::string& s) {
    const std::string v(vr);
    element(group, elem, vr, reinterpret_cast<const uint8_t*>(s.data()), s.size(),
            v == "UI" ? 0 : ' ');
  }
  void us(uint32_t group, uint32_t elem, uint32_t value) {
    const uint8_t d[2] = {static_cast<uint8_t>(value & 0xFF), static_cast<uint8_t>(value >> 8)};
    element(group, elem, "US", d, 2, 0);
  }
  // Encapsulated Pixel Data (PS3.5 A.4): undefined length, an empty Basic Offset Table item,
  // one fragment (padded to even length with 0), the sequence delimiter.
  void encapsulated(const std::vector<uint8_t>& frame) {
    u16(0x7FE0);
    u16(0x0010);
    b.insert(b.end(), {'O', 'B', 0, 0});
    u32(0xFFFFFFFFu);
    const uint32_t items[2] = {0, static_cast<uint32_t>(frame.size() + frame.size() % 2)};
    for (uint32_t length : items) {
      u16(0xFFFE);
      u16(0xE000);
      u32(length);
    }
    b.insert(b.end(), frame.begin(), frame.end());
    if (frame.size() % 2 != 0) b.push_back(0);
    u16(0xFFFE);
    u16(0xE0DD);
    u32(0);
  }
};

uint32_t gcd(uint32_t a, uint32_t b) {
  while (b != 0) {
    const uint32_t t = a % b;
    a = b;
    b = t;
  }
  return a;
}

// Makes `folder` (if needed) and checks it holds no file but the series' own `names`.
Status series_folder(const std::string& folder, const std::vector<std::string>& names) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (!fs::is_directory(folder, ec)) {
    return make_error(StatusCode::kIoError, "cannot create folder ", folder.c_str())
        .in_file(folder.c_str());
  }
  const std::set<std::string> ours(names.begin(), names.end());
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (ours.count(name) == 0) {
      return make_error(StatusCode::kInvalidArgument, "folder ", folder.c_str(),
                        " already holds other files (e.g. ", name.c_str(),
                        "); write a DICOM series into an empty or new folder")
          .in_file(folder.c_str());
    }
  }
  return Status::ok();
}

// File number (1..n) and file name of slice k of n: a fixed permutation (k p + (n + 1) / 2)
// mod n, p coprime with n and not n - 1 (for n > 2 neither the slice order nor its reverse).
void slice_names(uint32_t n, std::vector<std::string>* names, std::vector<uint32_t>* number) {
  uint32_t p = 1;
  for (uint32_t c = n / 2 + 1; c + 1 < n; ++c) {
    if (gcd(c, n) == 1) {
      p = c;
      break;
    }
  }
  const int width = n < 10000 ? 4 : 10;
  names->assign(n, std::string());
  number->assign(n, 0);
  for (uint32_t k = 0; k < n; ++k) {
    (*number)[k] = static_cast<uint32_t>((uint64_t{k} * p + (n + 1) / 2) % n) + 1;
    char buf[32];
    std::snprintf(buf, sizeof(buf), "CT%0*u.dcm", width, (*number)[k]);
    (*names)[k] = buf;
  }
}

// The root of a series' UIDs, from a hash of the volume (deterministic, distinct per volume).
std::string series_uid_root(const CtVolume& v) {
  Sha256 sha;
  sha.update(v.hu, static_cast<size_t>(v.voxel_count() * 2));
  const double geometry[15] = {v.spacing.x, v.spacing.y, v.spacing.z, v.origin.x, v.origin.y,
                               v.origin.z,  v.axis_x.x,  v.axis_x.y,  v.axis_x.z, v.axis_y.x,
                               v.axis_y.y,  v.axis_y.z,  v.axis_z.x,  v.axis_z.y, v.axis_z.z};
  sha.update(geometry, sizeof(geometry));
  const uint32_t dims[3] = {v.nx, v.ny, v.nz};
  sha.update(dims, sizeof(dims));
  uint8_t digest[32];
  sha.finish(digest);
  uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | digest[i];
  return "2.25." + std::to_string(h >> 1);
}

constexpr const char* kCtImageStorage = "1.2.840.10008.5.1.4.1.1.2";  // the SOP class

// What the slices of one series share.
struct Series {
  const CtVolume& v;
  const CtWriteOptions& options;
  std::string root;         // of the UIDs
  std::string syntax;       // the transfer syntax's UID
  std::string orientation;  // Image Orientation (Patient)
  int32_t intercept;        // Rescale Intercept: stored value + intercept = HU
};

// The preamble, "DICM" and the file meta group of one slice's file.
void slice_file_meta(const Series& series, const std::string& instance, DicomBuffer* file) {
  DicomBuffer meta;
  meta.str(0x0002, 0x0001, "OB", std::string("\0\1", 2));
  meta.str(0x0002, 0x0002, "UI", kCtImageStorage);
  meta.str(0x0002, 0x0003, "UI", instance);
  meta.str(0x0002, 0x0010, "UI", series.syntax);
  meta.str(0x0002, 0x0012, "UI", "2.25.329800735698586629295641978511506172918");
  meta.str(0x0002, 0x0013, "SH", "SPLINTCORE");
  file->b.assign(128, 0);
  file->b.insert(file->b.end(), {'D', 'I', 'C', 'M'});
  DicomBuffer length;
  const uint32_t meta_bytes = static_cast<uint32_t>(meta.b.size());
  const uint8_t d[4] = {static_cast<uint8_t>(meta_bytes), static_cast<uint8_t>(meta_bytes >> 8),
                        static_cast<uint8_t>(meta_bytes >> 16),
                        static_cast<uint8_t>(meta_bytes >> 24)};
  length.element(0x0002, 0x0000, "UL", d, 4, 0);
  file->b.insert(file->b.end(), length.b.begin(), length.b.end());
  file->b.insert(file->b.end(), meta.b.begin(), meta.b.end());
}

// Slice k's Pixel Data: its stored values, native or JPEG lossless.
void slice_pixels(const Series& series, uint32_t k, DicomBuffer* d) {
  const CtVolume& v = series.v;
  const uint64_t per_slice = uint64_t{v.nx} * v.ny;
  std::vector<uint16_t> stored(static_cast<size_t>(per_slice));
  const int16_t* slice = v.hu + static_cast<size_t>(k * per_slice);
  for (size_t i = 0; i < stored.size(); ++i) {
    stored[i] = static_cast<uint16_t>(static_cast<int32_t>(slice[i]) - series.intercept);
  }
  if (series.options.dicom_jpeg_lossless) {
    d->encapsulated(jpeg_lossless_encode(stored.data(), v.ny, v.nx, 1));
    return;
  }
  std::vector<uint8_t> pixels(stored.size() * 2);
  for (size_t i = 0; i < stored.size(); ++i) {
    pixels[2 * i] = static_cast<uint8_t>(stored[i] & 0xFF);
    pixels[2 * i + 1] = static_cast<uint8_t>(stored[i] >> 8);
  }
  d->element(0x7FE0, 0x0010, "OW", pixels.data(), pixels.size(), 0);
}

// The whole file of slice k, whose file and Instance Number is `number`.
std::vector<uint8_t> slice_file(const Series& series, uint32_t k, uint32_t number) {
  const CtVolume& v = series.v;
  const CtWriteOptions& options = series.options;
  const std::string& root = series.root;
  const std::string instance = root + ".3." + std::to_string(number);
  DicomBuffer file;
  slice_file_meta(series, instance, &file);
  DicomBuffer d;
  d.implicit = options.dicom_implicit_vr;
  const Vec3 position = options.slice_positions.empty()
                            ? v.origin + v.axis_z * (static_cast<double>(k) * v.spacing.z)
                            : options.slice_positions[k];
  d.str(0x0008, 0x0008, "CS", "ORIGINAL\\PRIMARY\\AXIAL");
  d.str(0x0008, 0x0016, "UI", kCtImageStorage);
  d.str(0x0008, 0x0018, "UI", instance);
  d.str(0x0008, 0x0060, "CS", "CT");
  d.str(0x0008, 0x103E, "LO", "splintcore phantom");
  d.str(0x0010, 0x0010, "PN", "Phantom");
  d.str(0x0010, 0x0020, "LO", "PHANTOM");
  d.str(0x0018, 0x0050, "DS", ds(v.spacing.z));
  d.str(0x0018, 0x0088, "DS", ds(v.spacing.z));
  d.str(0x0020, 0x000D, "UI", root + ".1");
  d.str(0x0020, 0x000E, "UI", root + ".2");
  d.str(0x0020, 0x0011, "IS", "1");
  d.str(0x0020, 0x0013, "IS", std::to_string(number));
  d.str(0x0020, 0x0032, "DS", ds(position.x) + "\\" + ds(position.y) + "\\" + ds(position.z));
  d.str(0x0020, 0x0037, "DS", series.orientation);
  d.str(0x0020, 0x0052, "UI", root + ".4");
  d.us(0x0028, 0x0002, 1);
  d.str(0x0028, 0x0004, "CS", "MONOCHROME2");
  d.us(0x0028, 0x0010, v.ny);
  d.us(0x0028, 0x0011, v.nx);
  d.str(0x0028, 0x0030, "DS", ds(v.spacing.y) + "\\" + ds(v.spacing.x));
  d.us(0x0028, 0x0100, 16);
  d.us(0x0028, 0x0101, 16);
  d.us(0x0028, 0x0102, 15);
  d.us(0x0028, 0x0103, options.dicom_signed ? 1 : 0);
  d.str(0x0028, 0x1052, "DS", std::to_string(series.intercept));
  d.str(0x0028, 0x1053, "DS", "1");
  slice_pixels(series, k, &d);
  file.b.insert(file.b.end(), d.b.begin(), d.b.end());
  return std::move(file.b);
}

}  // namespace

Status write_dicom_series(const CtVolume& v, const std::string& folder,
                          const CtWriteOptions& options) {
  SPLINTCORE_RETURN_IF_ERROR(check_volume(v));
  if (v.nx > 65535 || v.ny > 65535) {
    return make_error(StatusCode::kInvalidArgument, "DICOM images are at most 65535 x 65535");
  }
  const uint32_t n = v.nz;
  if (!options.slice_positions.empty() && options.slice_positions.size() != n) {
    return make_error(StatusCode::kInvalidArgument, "slice_positions holds ",
                      static_cast<uint64_t>(options.slice_positions.size()),
                      " positions for a volume of ", n, " slices");
  }
  if (options.dicom_jpeg_lossless && options.dicom_implicit_vr) {
    return make_error(StatusCode::kInvalidArgument,
                      "JPEG lossless DICOM is explicit VR: not with implicit VR");
  }
  std::vector<std::string> names;
  std::vector<uint32_t> number;
  slice_names(n, &names, &number);
  SPLINTCORE_RETURN_IF_ERROR(series_folder(folder, names));

  // Stored values: unsigned with intercept min(-1024, min HU), or signed with intercept 0.
  const uint64_t count = v.voxel_count();
  int32_t min_hu = -1024;
  for (uint64_t i = 0; i < count; ++i) min_hu = std::min<int32_t>(min_hu, v.hu[i]);
  const int32_t intercept = options.dicom_signed ? 0 : min_hu;

  const Series series{v,
                      options,
                      series_uid_root(v),
                      options.dicom_jpeg_lossless ? "1.2.840.10008.1.2.4.70"
                      : options.dicom_implicit_vr ? "1.2.840.10008.1.2"
                                                  : "1.2.840.10008.1.2.1",
                      ds(v.axis_x.x) + "\\" + ds(v.axis_x.y) + "\\" + ds(v.axis_x.z) + "\\" +
                          ds(v.axis_y.x) + "\\" + ds(v.axis_y.y) + "\\" + ds(v.axis_y.z),
                      intercept};
  OutputSet slices;  // a series placed whole: no new slices among an earlier run's
  for (uint32_t k = 0; k < n; ++k) {
    const std::vector<uint8_t> file = slice_file(series, k, number[k]);
    SPLINTCORE_RETURN_IF_ERROR(write_bytes_atomically((fs::path(folder) / names[k]).string(),
                                                      file.data(), file.size(), &slices));
  }
  return slices.commit();
}

}  // namespace cli
}  // namespace splintcore
