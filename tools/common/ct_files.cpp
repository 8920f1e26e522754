// Opening CT volumes from disk: the hosted file openers for the core readers (splintcore/ct.h).
#include "ct_files.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "splintcore/platform.h"

namespace splintcore {
namespace cli {

namespace {

namespace fs = std::filesystem;

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// Named files relative to a header's folder.
struct FolderOpener {
  fs::path folder;
  FileSource file;
  std::string path;
};
Status folder_open(void* user, const char* name, ByteSource* out) {
  FolderOpener* o = static_cast<FolderOpener*>(user);
  const fs::path p(name);
  o->path = (p.is_absolute() ? p : o->folder / p).string();
  SPLINTCORE_RETURN_IF_ERROR(o->file.open(o->path.c_str()));
  *out = o->file.source();
  return Status::ok();
}
void folder_close(void* user, ByteSource* source) {
  (void)source;
  static_cast<FolderOpener*>(user)->file.close();
}

// A DICOM series: files by index.
struct SeriesFiles {
  std::vector<std::string> paths;
  FileSource file;
};
Status series_open(void* user, uint32_t index, ByteSource* out) {
  SeriesFiles* s = static_cast<SeriesFiles*>(user);
  if (index >= s->paths.size()) {
    return make_error(StatusCode::kInvalidArgument, "no series file ", index);
  }
  SPLINTCORE_RETURN_IF_ERROR(s->file.open(s->paths[index].c_str()));
  *out = s->file.source();
  return Status::ok();
}
void series_close(void* user, uint32_t index, ByteSource* source) {
  (void)index;
  (void)source;
  static_cast<SeriesFiles*>(user)->file.close();
}

}  // namespace

// A DICOM Part 10 file: "DICM" after the 128-byte preamble (PS3.10 7.1).
bool has_dicom_preamble(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[132] = {};
  if (!in.read(head, sizeof head)) return false;
  return std::memcmp(head + 128, "DICM", 4) == 0;
}

// A DICOM directory (DICOMDIR, or Philips' DIRFILE in each series folder): a Part 10 file whose
// (0002,0002) Media Storage SOP Class UID is 1.2.840.10008.1.3.10 (Media Storage Directory
// Storage, PS3.4 annex F), found in the file meta's first 512 bytes. It holds no pixels.
bool is_dicom_directory(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[512] = {};
  in.read(head, sizeof head);
  const size_t n = static_cast<size_t>(in.gcount());
  if (n < 132 || std::memcmp(head + 128, "DICM", 4) != 0) return false;
  static const char kUid[] = "1.2.840.10008.1.3.10";
  const size_t uid = sizeof kUid - 1;
  for (size_t at = 132; at + 8 + uid <= n; ++at) {
    if (std::memcmp(head + at, "\x02\x00\x02\x00UI", 6) != 0) continue;
    const size_t length = size_t{static_cast<uint8_t>(head[at + 6])} |
                          (size_t{static_cast<uint8_t>(head[at + 7])} << 8);
    return (length == uid || length == uid + 1) && std::memcmp(head + at + 8, kUid, uid) == 0 &&
           (length == uid || head[at + 8 + uid] == '\0');
  }
  return false;
}

CtFormat ct_format_of_path(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return CtFormat::kDicom;
  const std::string ext = lower_extension(path);
  if (ext == ".nrrd" || ext == ".nhdr") return CtFormat::kNrrd;
  if (ext == ".mha" || ext == ".mhd") return CtFormat::kMetaImage;
  if (ext == ".dcm" || ext == ".dicom" || has_dicom_preamble(path)) return CtFormat::kDicom;
  return CtFormat::kUnknown;
}

Status list_dicom_folder(const std::string& folder, std::vector<std::string>* files) {
  files->clear();
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    return make_error(StatusCode::kIoError, "not a folder: ", folder.c_str())
        .in_file(folder.c_str());
  }
  fs::directory_iterator it(folder, ec), end;
  if (ec) {
    return make_error(StatusCode::kIoError, "cannot list ", folder.c_str(), ": ",
                      ec.message().c_str())
        .in_file(folder.c_str());
  }
  for (; it != end; it.increment(ec)) {
    if (ec) break;
    const std::string name = it->path().filename().string();
    if (name.empty() || name[0] == '.') continue;
    std::error_code type_ec;
    if (!it->is_regular_file(type_ec)) continue;
    if (is_dicom_directory(it->path().string())) continue;  // an index, not a slice
    files->push_back(it->path().string());
  }
  if (ec) {
    return make_error(StatusCode::kIoError, "cannot list ", folder.c_str(), ": ",
                      ec.message().c_str())
        .in_file(folder.c_str());
  }
  std::sort(files->begin(), files->end());  // names are distinct: a total order
  if (files->empty()) {
    return make_error(StatusCode::kInvalidArgument, "folder ", folder.c_str(), " holds no files")
        .in_file(folder.c_str());
  }
  return Status::ok();
}

Status read_ct_path(const Context& ctx, const std::string& path, const CtReadOptions& options,
                    CtVolume* out, CtInfo* info) {
  const CtFormat format = ct_format_of_path(path);
  if (format == CtFormat::kDicom) {
    SeriesFiles series;
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      SPLINTCORE_RETURN_IF_ERROR(list_dicom_folder(path, &series.paths));
    } else {
      series.paths.push_back(path);  // one file: a series of one (a single slice's spacing
                                     // from its Spacing Between Slices or Slice Thickness)
    }
    if (series.paths.size() > options.max_dimension) {
      return make_error(StatusCode::kLimitExceeded, "folder ", path.c_str(), " holds ",
                        series.paths.size(), " files, more than the limit ", options.max_dimension,
                        " (CtReadOptions::max_dimension)")
          .in_file(path.c_str());
    }
    CtSeries s;
    s.count = static_cast<uint32_t>(series.paths.size());
    s.open = series_open;
    s.close = series_close;
    s.user = &series;
    return read_dicom_series(ctx, s, options, out, info);
  }
  if (format == CtFormat::kUnknown) {
    return make_error(
               StatusCode::kUnsupported, "cannot tell the CT format of ", path.c_str(),
               ": give a .nrrd, .nhdr, .mha or .mhd file, a DICOM file or a folder of DICOM files")
        .in_file(path.c_str());
  }
  FileSource header;
  SPLINTCORE_RETURN_IF_ERROR(header.open(path.c_str()));
  FolderOpener opener;
  opener.folder = fs::path(path).parent_path();
  CtFileOpener o;
  o.open = folder_open;
  o.close = folder_close;
  o.user = &opener;
  const ByteSource source = header.source();
  if (format == CtFormat::kNrrd) return read_nrrd(ctx, source, &o, options, out, info);
  return read_metaimage(ctx, source, &o, options, out, info);
}

}  // namespace cli
}  // namespace splintcore
