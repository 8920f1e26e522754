// Opening CT volumes from disk (hosted: std::filesystem): a .nrrd / .nhdr / .mha / .mhd file,
// a folder of DICOM files or one DICOM file, read with the core readers of splintcore/ct.h.
#ifndef SPLINTCORE_TOOLS_CT_FILES_H
#define SPLINTCORE_TOOLS_CT_FILES_H

#include <string>
#include <vector>

#include "splintcore/core.h"
#include "splintcore/ct.h"

namespace splintcore {
namespace cli {

// The format a path names: a folder is kDicom; a file by its extension (.nrrd/.nhdr: kNrrd,
// .mha/.mhd: kMetaImage, .dcm/.dicom: kDicom, case-insensitive), else kDicom when it has the
// DICOM preamble ("DICM" at byte 128), else kUnknown.
CtFormat ct_format_of_path(const std::string& path);

// Every regular file in `folder` (not recursing; hidden files, i.e. names starting with '.',
// and DICOM directories such as DICOMDIR or Philips' DIRFILE, are skipped), sorted by name (byte
// order) only for a stable input order: the reader orders slices by position. Errors: kIoError (not
// a folder / unreadable), kInvalidArgument (empty).
Status list_dicom_folder(const std::string& folder, std::vector<std::string>* files);

// Reads the volume at `path` into *out (voxels in ctx.arena, see splintcore/ct.h for the memory
// it takes). Detached data files (NRRD `data file`, MetaImage ElementDataFile) are opened
// relative to the header's folder. Errors: those of the readers; kUnsupported for a path of
// unknown kind; kIoError for files that cannot be opened.
Status read_ct_path(const Context& ctx, const std::string& path, const CtReadOptions& options,
                    CtVolume* out, CtInfo* info);

}  // namespace cli
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_CT_FILES_H
