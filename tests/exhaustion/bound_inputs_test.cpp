// The memory contract of the readers (issue 27): what a file costs to read, sized before the
// read where the file's length says enough (STL, JSON, the case file), and by the two-step
// contract where it does not (PLY, OBJ, the CT readers). bound_util.h has the harness.

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "common/ct_files.h"
#include "common/ct_phantom.h"
#include "common/ct_write.h"
#include "exhaustion/bound_util.h"
#include "splintcore/ct.h"
#include "splintcore/design.h"
#include "splintcore/io.h"
#include "splintcore/json.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using namespace bound_test;
namespace fs = std::filesystem;

// Every input as binary STL and, up to 100k triangles, as ASCII STL (as the writer lays it
// out, and packed: one space between tokens, the shortest numbers, the densest ASCII can be).
std::vector<std::pair<Input, std::vector<uint8_t>>> stl_files() {
  std::vector<std::pair<Input, std::vector<uint8_t>>> out;
  for (const Input& in : inputs()) {
    out.push_back({in, test::binary_stl(in.soup)});
    out.back().first.name += " (binary)";
    if (in.soup.size() > 100000) continue;
    Welded w(in);
    std::vector<uint8_t> ascii;
    SPLINTCORE_EXPECT_OK(test::mesh_to_bytes(w.storage.arena, w.mesh, StlFormat::kAscii, &ascii));
    out.push_back({in, ascii});
    out.back().first.name += " (ASCII)";
    out.back().first.large = false;  // the bound counts 50-byte binary records
    std::string packed = "solid s\n";
    for (size_t t = 0; t < in.soup.size(); ++t) {
      packed += "facet normal 0 0 0 outer loop";
      for (int k = 0; k < 3; ++k) {
        packed += " vertex";
        for (int a = 0; a < 3; ++a) {
          char number[32];
          std::snprintf(number, sizeof number, " %.9g", static_cast<double>(in.soup[t].p[k][a]));
          packed += number;
        }
      }
      packed += " endloop endfacet\n";
    }
    packed += "endsolid s\n";
    out.push_back({in, test::to_bytes(packed)});
    out.back().first.name += " (packed ASCII)";
    out.back().first.large = false;
  }
  // A facet at its shortest: 85 bytes with one-digit numbers (the bound assumes 50).
  std::string tiny = "solid\n";
  for (int t = 0; t < 64; ++t) {
    tiny +=
        "facet normal 0 0 0 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 1 0 endloop endfacet ";
  }
  tiny += "endsolid";
  out.push_back({Input{"64 shortest facets (ASCII)", {}}, test::to_bytes(tiny)});
  return out;
}

TEST(BoundExact, ReadStl) {
  for (const auto& file : stl_files()) {
    const Input& in = file.first;
    const std::vector<uint8_t>& bytes = file.second;
    StlReadOptions options;
    options.chunk_bytes = 8192;
    expect_fits(in, "read_stl", read_stl_bound(bytes.size(), options), [&](Arena& arena) {
      MemorySource ms{bytes.data(), bytes.size(), 0, 0};
      ArenaArray<SoupTriangle> soup(&arena);
      StlInfo info;
      return read_stl(Context(&arena), memory_source(&ms), options, &soup, &info);
    });
    expect_fits(in, "read_stl_mesh", read_stl_mesh_bound(bytes.size(), options), [&](Arena& arena) {
      MemorySource ms{bytes.data(), bytes.size(), 0, 0};
      Mesh mesh(&arena);
      StlInfo info;
      return read_stl_mesh(Context(&arena), memory_source(&ms), options, &mesh, &info);
    });
    MeshReadOptions mo;
    mo.chunk_bytes = options.chunk_bytes;
    expect_fits(in, "read_mesh (STL)", read_stl_mesh_bound(bytes.size(), options),
                [&](Arena& arena) {
                  MemorySource ms{bytes.data(), bytes.size(), 0, 0};
                  Mesh mesh(&arena);
                  MeshReadInfo info;
                  return read_mesh(Context(&arena), memory_source(&ms), mo, &mesh, &info);
                });
  }
}

// Documents built to have the most values for their length (nested and flat arrays, objects,
// strings, documents cut short and over the depth limit), the fixture cases and the fuzz
// seeds for the JSON and case parsers.
std::vector<std::pair<std::string, std::string>> json_texts() {
  std::vector<std::pair<std::string, std::string>> out;
  auto repeat = [](const std::string& s, int n) {
    std::string r;
    for (int i = 0; i < n; ++i) r += s;
    return r;
  };
  out.push_back({"nested 32", repeat("[", 32) + repeat("]", 32)});
  out.push_back({"nested 40 (too deep)", repeat("[", 40) + repeat("]", 40)});
  out.push_back({"open 31 (cut short)", repeat("[", 31)});
  out.push_back({"open 31 then ones", repeat("[", 31) + repeat("1,", 1000)});
  out.push_back({"flat ones", "[" + repeat("1,", 20000) + "1]"});
  out.push_back({"flat empty arrays", "[" + repeat("[],", 5000) + "[]]"});
  out.push_back({"arrays of one", "[" + repeat("[1],", 5000) + "[1]]"});
  out.push_back(
      {"object", "{" + repeat("\"\":{},", 1) + "\"a\":[" + repeat("\"\",", 3000) + "0]}"});
  out.push_back({"one number", "7"});
  out.push_back({"empty", ""});
  for (const char* dir : {"/cases", "/fuzz/json", "/fuzz/case"}) {
    const fs::path folder = fs::path(SPLINTCORE_FIXTURES_DIR + std::string(dir));
    if (!fs::is_directory(folder)) continue;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(folder)) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) {
      const std::vector<uint8_t> bytes = test::read_file_bytes(f.string());
      out.push_back({f.filename().string(), std::string(bytes.begin(), bytes.end())});
    }
  }
  return out;
}

TEST(BoundExact, ParseJsonAndCase) {
  uint64_t texts = 0;
  for (const auto& text : json_texts()) {
    Input in{text.first, {}};
    JsonLimits limits;
    expect_fits(in, "parse_json", parse_json_bound(text.second.size(), limits), [&](Arena& arena) {
      JsonDocument doc;
      return parse_json(Context(&arena), text.second.data(), text.second.size(), limits, "test",
                        &doc);
    });
    expect_fits(in, "parse_case", parse_case_bound(text.second.size()), [&](Arena& arena) {
      CaseFile c;
      return parse_case(Context(&arena), text.second.data(), text.second.size(), "test", &c);
    });
    ++texts;
  }
  EXPECT_GT(texts, 10u);
}

// PLY and OBJ: no a-priori bound (vertex and face records may interleave, and a source of
// unknown size grows its arrays), so the two-step contract, as text and binary.
TEST(BoundTwoStep, ReadPlyObj) {
  for (const Input& in : inputs()) {
    if (in.soup.size() > 100000) continue;
    Welded w(in);
    std::string obj, ply_head;
    std::vector<uint8_t> ply_le;
    char line[160];
    for (const Vec3& v : w.mesh.vertices) {
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", v.x, v.y, v.z);
      obj += line;
    }
    for (const Triangle& t : w.mesh.triangles) {
      std::snprintf(line, sizeof line, "f %u %u %u\n", t.v[0] + 1, t.v[1] + 1, t.v[2] + 1);
      obj += line;
    }
    ply_head = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(w.v()) +
               "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
               std::to_string(w.t()) + "\nproperty list uchar int vertex_indices\nend_header\n";
    ply_le.assign(ply_head.begin(), ply_head.end());
    auto put = [&](const void* p, size_t n) {
      const uint8_t* b = static_cast<const uint8_t*>(p);
      ply_le.insert(ply_le.end(), b, b + n);  // little-endian host (x86-64, AArch64, ARMv7)
    };
    for (const Vec3& v : w.mesh.vertices) {
      const float f[3] = {static_cast<float>(v.x), static_cast<float>(v.y),
                          static_cast<float>(v.z)};
      put(f, sizeof f);
    }
    for (const Triangle& t : w.mesh.triangles) {
      const uint8_t three = 3;
      put(&three, 1);
      const int32_t idx[3] = {static_cast<int32_t>(t.v[0]), static_cast<int32_t>(t.v[1]),
                              static_cast<int32_t>(t.v[2])};
      put(idx, sizeof idx);
    }
    const std::vector<uint8_t> obj_bytes(obj.begin(), obj.end());
    for (bool weld : {false, true}) {
      MeshReadOptions mo;
      mo.weld = weld;
      const std::string what = in.name + (weld ? ", welded" : "");
      expect_two_step(
          "read_obj", what.c_str(),
          [&](Arena& arena) {
            MemorySource ms{obj_bytes.data(), obj_bytes.size(), 0, 0};
            Mesh mesh(&arena);
            MeshReadInfo info;
            return read_obj(Context(&arena), memory_source(&ms), mo, &mesh, &info);
          },
          /*minimal=*/false);
      expect_two_step("read_ply", what.c_str(), [&](Arena& arena) {
        MemorySource ms{ply_le.data(), ply_le.size(), 0, 0};
        Mesh mesh(&arena);
        MeshReadInfo info;
        return read_ply(Context(&arena), memory_source(&ms), mo, &mesh, &info);
      });
      expect_two_step(
          "read_mesh (OBJ)", what.c_str(),
          [&](Arena& arena) {
            MemorySource ms{obj_bytes.data(), obj_bytes.size(), 0, 0};
            Mesh mesh(&arena);
            MeshReadInfo info;
            return read_mesh(Context(&arena), memory_source(&ms), mo, &mesh, &info);
          },
          /*minimal=*/false);
    }
  }
}

// The CT readers: the volume's size is in the header, the reading buffers and a DICOM series'
// slice table come with it; the two-step contract, on a small CT phantom written in every
// format the readers take.
TEST(BoundTwoStep, ReadCt) {
  cli::CtPhantomOptions po;
  po.nx = 96;
  po.ny = 96;
  po.nz = 60;
  po.spacing = Vec3{1.0, 1.0, 1.0};
  cli::CtPhantom phantom;
  SPLINTCORE_ASSERT_OK(phantom.init(po));
  std::vector<int16_t> hu;
  CtVolume volume;
  phantom.generate(&hu, &volume);
  const fs::path dir =
      fs::temp_directory_path() / ("splintcore_bound_ct_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  cli::CtWriteOptions wo;
  SPLINTCORE_ASSERT_OK(cli::write_nrrd(volume, (dir / "v.nrrd").string(), wo));
  SPLINTCORE_ASSERT_OK(cli::write_nrrd(volume, (dir / "d.nhdr").string(), wo));
  SPLINTCORE_ASSERT_OK(cli::write_metaimage(volume, (dir / "v.mha").string(), wo));
  SPLINTCORE_ASSERT_OK(cli::write_metaimage(volume, (dir / "d.mhd").string(), wo));
  SPLINTCORE_ASSERT_OK(cli::write_dicom_series(volume, (dir / "dicom").string(), wo));
  for (const char* name : {"v.nrrd", "d.nhdr", "v.mha", "d.mhd", "dicom"}) {
    const std::string path = (dir / name).string();
    expect_two_step("read_ct_path", name, [&](Arena& arena) {
      CtVolume out;
      CtInfo info;
      return cli::read_ct_path(Context(&arena), path, CtReadOptions{}, &out, &info);
    });
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// The case's jaws from its CT (design.h): the two-step contract, on the CT phantom the
// fixture case ct_phantom.json is made for (its seeds), at 1 mm, with and without the case's
// smoothing and decimation.
TEST(BoundTwoStep, ReconstructCaseJaws) {
  cli::CtPhantomOptions po;
  po.nx = 96;
  po.ny = 96;
  po.nz = 60;
  po.spacing = Vec3{1.0, 1.0, 1.0};
  po.noise_hu = 0;
  cli::CtPhantom phantom;
  SPLINTCORE_ASSERT_OK(phantom.init(po));
  std::vector<int16_t> hu;
  CtVolume volume;
  phantom.generate(&hu, &volume);
  TestArena storage;
  const std::vector<uint8_t> text =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/ct_phantom.json");
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(Context(&storage.arena),
                                  reinterpret_cast<const char*>(text.data()), text.size(),
                                  "ct_phantom.json", &c));
  for (int variant = 0; variant < 2; ++variant) {
    CaseFile cv = c;
    cv.ct_smooth.iterations = variant == 0 ? 0 : 3;
    cv.ct_decimate.target_triangles = variant == 0 ? 0 : 4000;
    expect_two_step("reconstruct_case_jaws",
                    variant == 0 ? "CT phantom 1 mm" : "CT phantom 1 mm, smoothed, decimated",
                    [&](Arena& arena) {
                      Mesh jaws[2] = {Mesh(&arena), Mesh(&arena)};
                      CaseCtReport report;
                      return reconstruct_case_jaws(Context(&arena), cv, volume, Span<Mesh>(jaws, 2),
                                                   &report);
                    });
  }
}

}  // namespace
}  // namespace splintcore
