// Round trips through the CT writers (tools/common/ct_write) and the hosted opener
// (tools/common/ct_files): every format and variant reads back the same voxels and geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/ct_files.h"
#include "common/ct_write.h"
#include "common/jpeg_lossless_write.h"
#include "ct/jpeg_lossless.h"
#include "splintcore/ct.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

namespace fs = std::filesystem;
using cli::CtWriteOptions;

struct TempDir {
  fs::path path;
  explicit TempDir(const char* name) {
    path = fs::temp_directory_path() /
           (std::string("splintcore_ct_write_") + name + "_" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

// A 5 x 4 x 3 volume with extreme values, anisotropic spacing and rotated axes (a rotation
// about (1,1,1) by 120 degrees permutes the axes; left-handed: the z axis is flipped on top).
struct Phantom {
  std::vector<int16_t> hu;
  CtVolume v;
  explicit Phantom(bool left_handed = true) {
    v.nx = 5;
    v.ny = 4;
    v.nz = 3;
    for (uint32_t i = 0; i < 60; ++i) {
      hu.push_back(static_cast<int16_t>(static_cast<int>(i * 1117 % 4000) - 2000));
    }
    hu[0] = -32768;
    hu[1] = 32767;
    hu[2] = -1024;
    hu[3] = 0;
    v.hu = hu.data();
    v.spacing = Vec3{0.5, 0.75, 1.25};
    v.origin = Vec3{-10.5, 20.25, 3};
    v.axis_x = Vec3{0, 1, 0};
    v.axis_y = Vec3{0, 0, 1};
    v.axis_z = Vec3{left_handed ? -1.0 : 1.0, 0, 0};
  }
};

void expect_same(const CtVolume& a, const CtVolume& b, double tol) {
  ASSERT_EQ(a.nx, b.nx);
  ASSERT_EQ(a.ny, b.ny);
  ASSERT_EQ(a.nz, b.nz);
  EXPECT_EQ(std::memcmp(a.hu, b.hu, static_cast<size_t>(a.voxel_count() * 2)), 0);
  const Vec3 pa[5] = {a.spacing, a.origin, a.axis_x, a.axis_y, a.axis_z};
  const Vec3 pb[5] = {b.spacing, b.origin, b.axis_x, b.axis_y, b.axis_z};
  for (int k = 0; k < 5; ++k) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(pa[k][c], pb[k][c], tol) << k << " " << c;
  }
}

// The same voxels at the same patient positions, whatever the index order (a DICOM series is
// always read with axis_z = row x column, so a left-handed volume comes back with its slices
// reversed and axis_z flipped).
void expect_same_in_patient_space(const CtVolume& a, const CtVolume& b, double tol) {
  ASSERT_EQ(a.voxel_count(), b.voxel_count());
  for (uint32_t k = 0; k < a.nz; ++k) {
    for (uint32_t j = 0; j < a.ny; ++j) {
      for (uint32_t i = 0; i < a.nx; ++i) {
        const Vec3 pa = ct_to_patient(a, Vec3{a.spacing.x * i, a.spacing.y * j, a.spacing.z * k});
        const Vec3 d = pa - b.origin;
        const double fi = dot(d, b.axis_x) / b.spacing.x;
        const double fj = dot(d, b.axis_y) / b.spacing.y;
        const double fk = dot(d, b.axis_z) / b.spacing.z;
        const long bi = std::lround(fi), bj = std::lround(fj), bk = std::lround(fk);
        ASSERT_NEAR(fi, static_cast<double>(bi), tol);
        ASSERT_NEAR(fj, static_cast<double>(bj), tol);
        ASSERT_NEAR(fk, static_cast<double>(bk), tol);
        ASSERT_TRUE(bi >= 0 && bj >= 0 && bk >= 0 && bi < static_cast<long>(b.nx) &&
                    bj < static_cast<long>(b.ny) && bk < static_cast<long>(b.nz));
        ASSERT_EQ(a.at(i, j, k), b.at(static_cast<uint32_t>(bi), static_cast<uint32_t>(bj),
                                      static_cast<uint32_t>(bk)));
      }
    }
  }
}

Status read_back(Arena& arena, const std::string& path, CtVolume* out, CtInfo* info) {
  arena.reset();
  Context ctx(&arena);
  return cli::read_ct_path(ctx, path, CtReadOptions{}, out, info);
}

TEST(CtWrite, NrrdRoundTrips) {
  Phantom p;
  TempDir dir("nrrd");
  test::TestArena arena(size_t{4} << 20);
  for (bool big : {false, true}) {
    for (const char* name : {"v.nrrd", "v.nhdr"}) {
      CtWriteOptions o;
      o.big_endian = big;
      const std::string path = dir / name;
      SPLINTCORE_ASSERT_OK(cli::write_nrrd(p.v, path, o));
      CtVolume back;
      CtInfo info;
      SPLINTCORE_ASSERT_OK(read_back(arena.arena, path, &back, &info));
      expect_same(p.v, back, 1e-14);
      EXPECT_EQ(info.format, CtFormat::kNrrd);
      EXPECT_EQ(info.big_endian, big);
      EXPECT_EQ(info.detached, std::string(name) == "v.nhdr");
      EXPECT_STREQ(info.space, "left-posterior-superior");
    }
  }
  EXPECT_TRUE(fs::exists(dir / "v.raw"));
  EXPECT_EQ(cli::write_nrrd(p.v, dir / "v.txt", CtWriteOptions{}).code(),
            StatusCode::kInvalidArgument);
}

TEST(CtWrite, MetaImageRoundTripsExactly) {
  Phantom p;
  TempDir dir("mha");
  test::TestArena arena(size_t{4} << 20);
  for (const char* name : {"v.mha", "v.mhd"}) {
    const std::string path = dir / name;
    SPLINTCORE_ASSERT_OK(cli::write_metaimage(p.v, path, CtWriteOptions{}));
    CtVolume back;
    CtInfo info;
    SPLINTCORE_ASSERT_OK(read_back(arena.arena, path, &back, &info));
    expect_same(p.v, back, 0);  // spacing, axes and origin are written separately: exact
    EXPECT_EQ(info.format, CtFormat::kMetaImage);
  }
}

TEST(CtWrite, DicomSeriesRoundTripsAndIsOrderedByPosition) {
  test::TestArena arena(size_t{4} << 20);
  int variant = 0;
  for (bool left_handed : {false, true})
    for (bool implicit : {false, true}) {
      Phantom p(left_handed);
      for (bool is_signed : {false, true}) {
        TempDir dir(("dicom" + std::to_string(variant++)).c_str());
        CtWriteOptions o;
        o.dicom_implicit_vr = implicit;
        o.dicom_signed = is_signed;
        const std::string folder = dir / "series";
        SPLINTCORE_ASSERT_OK(cli::write_dicom_series(p.v, folder, o));
        std::vector<std::string> files;
        SPLINTCORE_ASSERT_OK(cli::list_dicom_folder(folder, &files));
        ASSERT_EQ(files.size(), 3u);
        CtVolume back;
        CtInfo info;
        SPLINTCORE_ASSERT_OK(read_back(arena.arena, folder, &back, &info));
        if (left_handed) {
          expect_same_in_patient_space(p.v, back, 1e-9);
          EXPECT_NEAR(back.axis_z.x, 1.0, 1e-15);  // row x column
        } else {
          expect_same(p.v, back, 1e-12);
        }
        EXPECT_EQ(info.format, CtFormat::kDicom);
        EXPECT_STREQ(info.transfer_syntax, implicit ? "1.2.840.10008.1.2" : "1.2.840.10008.1.2.1");
        EXPECT_STREQ(info.stored_type, is_signed ? "int16" : "uint16");
        EXPECT_EQ(info.intercept, is_signed ? 0.0 : -32768.0);  // min HU is -32768

        // The file names are not in slice order: reading the files in name order as a series of
        // one file each gives origins that are not increasing along axis_z.
        std::vector<double> along;
        for (const std::string& f : files) {
          std::vector<uint8_t> bytes = test::read_file_bytes(f);
          CtMemoryFile m{"one.dcm", bytes.data(), bytes.size()};
          CtMemoryFiles mf{&m, 1, 0, {}};
          CtVolume one;
          arena.arena.reset();
          Context ctx(&arena.arena);
          SPLINTCORE_ASSERT_OK(
              read_dicom_series(ctx, ct_memory_series(&mf), CtReadOptions{}, &one, nullptr));
          along.push_back(dot(one.origin, p.v.axis_z));
        }
        EXPECT_FALSE(along[0] < along[1] && along[1] < along[2]);
        EXPECT_FALSE(along[0] > along[1] && along[1] > along[2]);
      }
    }
}

// The JPEG lossless series (the speed proof's input, tools/bench): the same HU back through the
// core reader's decoder, stored signed or unsigned (the extremes -32768 and 32767 side by side
// make the difference category 16).
TEST(CtWrite, DicomJpegLosslessSeriesRoundTrips) {
  test::TestArena arena(size_t{4} << 20);
  for (bool is_signed : {false, true}) {
    Phantom p(false);
    TempDir dir(is_signed ? "jpeg_signed" : "jpeg_unsigned");
    CtWriteOptions o;
    o.dicom_jpeg_lossless = true;
    o.dicom_signed = is_signed;
    const std::string folder = dir / "series";
    SPLINTCORE_ASSERT_OK(cli::write_dicom_series(p.v, folder, o));
    CtVolume back;
    CtInfo info;
    SPLINTCORE_ASSERT_OK(read_back(arena.arena, folder, &back, &info));
    expect_same(p.v, back, 1e-12);
    EXPECT_STREQ(info.transfer_syntax, "1.2.840.10008.1.2.4.70");
  }
  Phantom p;
  TempDir dir("jpeg_implicit");
  CtWriteOptions o;
  o.dicom_jpeg_lossless = true;
  o.dicom_implicit_vr = true;
  EXPECT_EQ(cli::write_dicom_series(p.v, dir / "series", o).code(), StatusCode::kInvalidArgument);
}

// Every predictor of the encoder, on samples that jump across the whole 16-bit range, decoded
// by the core decoder to the same samples.
TEST(CtWrite, JpegLosslessEncoderEveryPredictor) {
  const uint32_t rows = 9, columns = 13;
  std::vector<uint16_t> samples(rows * columns);
  uint32_t state = 12345;
  for (size_t i = 0; i < samples.size(); ++i) {
    state = state * 1103515245u + 12345u;
    samples[i] = i % 5 == 0 ? static_cast<uint16_t>(state >> 16)
                            : static_cast<uint16_t>(1000 + i * 7 + (state >> 28));
  }
  samples[3] = 0;
  samples[4] = 65535;
  for (uint32_t predictor = 1; predictor <= 7; ++predictor) {
    const std::vector<uint8_t> jpeg =
        cli::jpeg_lossless_encode(samples.data(), rows, columns, predictor);
    test::TestArena arena(ct_detail::jpeg_lossless_arena_bytes());
    std::vector<uint8_t> out(samples.size() * 2);
    SPLINTCORE_ASSERT_OK(ct_detail::jpeg_lossless_decode(arena.arena, jpeg.data(), jpeg.size(),
                                                         rows, columns, 16, out.data()));
    for (size_t i = 0; i < samples.size(); ++i) {
      ASSERT_EQ(out[2 * i] | (out[2 * i + 1] << 8), samples[i]) << predictor << " " << i;
    }
  }
}

TEST(CtWrite, DicomWriterRefusesAFolderWithOtherFiles) {
  Phantom p;
  TempDir dir("dicom_stale");
  const std::string folder = dir / "series";
  fs::create_directories(folder);
  {
    std::FILE* f = std::fopen((dir / "series/old.dcm").c_str(), "wb");
    std::fclose(f);
  }
  Status s = cli::write_dicom_series(p.v, folder, CtWriteOptions{});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(test::format(s).find("old.dcm"), std::string::npos);
  // Writing again over its own files is fine, and gives the same bytes.
  fs::remove(dir / "series/old.dcm");
  SPLINTCORE_ASSERT_OK(cli::write_dicom_series(p.v, folder, CtWriteOptions{}));
  std::vector<std::string> files;
  SPLINTCORE_ASSERT_OK(cli::list_dicom_folder(folder, &files));
  const std::vector<uint8_t> first = test::read_file_bytes(files[1]);
  SPLINTCORE_ASSERT_OK(cli::write_dicom_series(p.v, folder, CtWriteOptions{}));
  EXPECT_EQ(test::read_file_bytes(files[1]), first);
}

// The files of one call are placed together: a call that fails at its last file (here a
// folder with that file's name, refused when they are placed) leaves the files of an earlier
// call as they were, not new data under an old header or new slices among old ones.
TEST(CtWrite, AFailedCallLeavesTheEarlierFilesAsTheyWere) {
  Phantom p;
  TempDir dir("together");
  SPLINTCORE_ASSERT_OK(cli::write_nrrd(p.v, dir / "v.nhdr", CtWriteOptions{}));
  const std::vector<uint8_t> raw = test::read_file_bytes(dir / "v.raw");
  fs::remove(dir / "v.nhdr");
  fs::create_directories(dir / "v.nhdr/inside");
  Phantom q;
  q.hu[5] = static_cast<int16_t>(q.hu[5] + 1);
  Status s = cli::write_nrrd(q.v, dir / "v.nhdr", CtWriteOptions{});
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_STREQ(s.message(), "cannot move the output into place: a folder has its name");
  EXPECT_EQ(test::read_file_bytes(dir / "v.raw"), raw);

  const std::string folder = dir / "series";
  SPLINTCORE_ASSERT_OK(cli::write_dicom_series(p.v, folder, CtWriteOptions{}));
  std::vector<std::string> files;
  SPLINTCORE_ASSERT_OK(cli::list_dicom_folder(folder, &files));
  ASSERT_EQ(files.size(), 3u);
  std::vector<std::vector<uint8_t>> before;
  for (const std::string& f : files) before.push_back(test::read_file_bytes(f));
  for (size_t blocked = 0; blocked < files.size(); ++blocked) {  // whichever is written last
    fs::remove(files[blocked]);
    fs::create_directories(files[blocked] + "/inside");
    s = cli::write_dicom_series(q.v, folder, CtWriteOptions{});
    EXPECT_EQ(s.code(), StatusCode::kIoError) << blocked;
    for (size_t i = 0; i < files.size(); ++i) {
      if (i != blocked) {
        EXPECT_EQ(test::read_file_bytes(files[i]), before[i]) << blocked << " " << i;
      }
    }
    fs::remove_all(files[blocked]);
    std::ofstream(files[blocked], std::ios::binary)
        .write(reinterpret_cast<const char*>(before[blocked].data()),
               static_cast<std::streamsize>(before[blocked].size()));
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 3);
}

TEST(CtWrite, WritersAreDeterministic) {
  Phantom p;
  TempDir dir("determinism");
  SPLINTCORE_ASSERT_OK(cli::write_nrrd(p.v, dir / "a.nrrd", CtWriteOptions{}));
  SPLINTCORE_ASSERT_OK(cli::write_nrrd(p.v, dir / "b.nrrd", CtWriteOptions{}));
  EXPECT_EQ(test::read_file_bytes(dir / "a.nrrd"), test::read_file_bytes(dir / "b.nrrd"));
  SPLINTCORE_ASSERT_OK(cli::write_metaimage(p.v, dir / "a.mha", CtWriteOptions{}));
  const std::vector<uint8_t> mha = test::read_file_bytes(dir / "a.mha");
  const std::string text(mha.begin(), mha.begin() + 60);
  EXPECT_EQ(text.rfind("ObjectType = Image\nNDims = 3\n", 0), 0u);
}

TEST(CtFiles, FormatOfPathAndErrors) {
  TempDir dir("files");
  EXPECT_EQ(cli::ct_format_of_path(dir / "a.NRRD"), CtFormat::kNrrd);
  EXPECT_EQ(cli::ct_format_of_path(dir / "a.nhdr"), CtFormat::kNrrd);
  EXPECT_EQ(cli::ct_format_of_path(dir / "a.mhd"), CtFormat::kMetaImage);
  EXPECT_EQ(cli::ct_format_of_path(dir.path.string()), CtFormat::kDicom);
  // One DICOM file: by its extension, or by the "DICM" preamble; other files are unknown.
  EXPECT_EQ(cli::ct_format_of_path(dir / "a.dcm"), CtFormat::kDicom);
  EXPECT_EQ(cli::ct_format_of_path(dir / "a.DICOM"), CtFormat::kDicom);
  EXPECT_EQ(cli::ct_format_of_path(dir / "a.bin"), CtFormat::kUnknown);  // no such file
  {
    std::string part10(128, '\0');
    part10 += "DICM";
    std::ofstream(dir / "slice", std::ios::binary) << part10;
    std::ofstream(dir / "short", std::ios::binary) << "DICM";
  }
  EXPECT_EQ(cli::ct_format_of_path(dir / "slice"), CtFormat::kDicom);
  EXPECT_EQ(cli::ct_format_of_path(dir / "short"), CtFormat::kUnknown);
  test::TestArena arena(1 << 20);
  CtVolume v;
  EXPECT_EQ(read_back(arena.arena, dir / "a.bin", &v, nullptr).code(), StatusCode::kUnsupported);
  EXPECT_EQ(read_back(arena.arena, dir / "a.dcm", &v, nullptr).code(), StatusCode::kIoError);
  fs::remove(dir / "slice");
  fs::remove(dir / "short");
  EXPECT_EQ(read_back(arena.arena, dir / "missing.nrrd", &v, nullptr).code(), StatusCode::kIoError);
  EXPECT_EQ(read_back(arena.arena, dir.path.string(), &v, nullptr).code(),
            StatusCode::kInvalidArgument);  // an empty folder
  // A detached header whose data file is missing names the data file.
  Phantom p;
  SPLINTCORE_ASSERT_OK(cli::write_nrrd(p.v, dir / "d.nhdr", CtWriteOptions{}));
  fs::remove(dir / "d.raw");
  Status s = read_back(arena.arena, dir / "d.nhdr", &v, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(test::format(s).find("d.raw"), std::string::npos) << test::format(s);
}

}  // namespace
}  // namespace splintcore
