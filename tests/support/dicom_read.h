// The DICOM tests' one way to read a series from bytes in memory (tests/ct: codecs, JPEG-LS,
// JPEG 2000, multi-frame): the fixture files and read_dicom_series over them in a test arena.
#ifndef SPLINTCORE_TESTS_SUPPORT_DICOM_READ_H
#define SPLINTCORE_TESTS_SUPPORT_DICOM_READ_H

#include <string>
#include <vector>

#include "splintcore/ct.h"
#include "support/test_util.h"

namespace splintcore {
namespace test {

using Bytes = std::vector<uint8_t>;

inline Bytes ct_fixture(const std::string& name) {
  return read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/ct/" + name);
}

// What a read gave: the volume's header (its voxels, gone with the arena, are in `hu`).
struct DicomRead {
  Status status;
  CtVolume volume;
  CtInfo info;
  std::vector<int16_t> hu;
  size_t high_water = 0;
};

// files[i] named names[i], read in 1 KiB chunks (max_chunk > 0: the memory files hand out at
// most that many bytes a read) in an arena of arena_bytes, with the options given.
inline DicomRead read_dicom_bytes(const std::vector<Bytes>& files,
                                  const std::vector<std::string>& names, size_t arena_bytes,
                                  size_t max_chunk = 0, uint32_t max_dimension = 4096,
                                  double orientation_tolerance = 1.0e-4) {
  TestArena t(arena_bytes);
  std::vector<CtMemoryFile> mem;
  for (size_t i = 0; i < files.size(); ++i) {
    mem.push_back({names[i].c_str(), files[i].data(), files[i].size()});
  }
  CtMemoryFiles m{mem.data(), static_cast<uint32_t>(mem.size()), max_chunk, {}};
  Context ctx(&t.arena);
  CtReadOptions options;
  options.chunk_bytes = 1024;
  options.max_dimension = max_dimension;
  options.orientation_tolerance = orientation_tolerance;
  DicomRead r;
  r.status = read_dicom_series(ctx, ct_memory_series(&m), options, &r.volume, &r.info);
  if (r.status.is_ok()) r.hu.assign(r.volume.hu, r.volume.hu + r.volume.voxel_count());
  r.volume.hu = nullptr;
  r.high_water = t.arena.high_water();
  return r;
}

// Offset of the n-th (0-based) occurrence of `pattern` in b (npos if none).
inline size_t find_bytes(const Bytes& b, const std::string& pattern, int n = 0) {
  const std::string s(b.begin(), b.end());
  size_t at = s.find(pattern);
  for (int i = 0; i < n && at != std::string::npos; ++i) at = s.find(pattern, at + 1);
  return at;
}

// A tag as it is written in explicit little endian: group, then element, each low byte first.
inline std::string dicom_tag(uint16_t group, uint16_t element) {
  const char t[4] = {static_cast<char>(group & 0xFF), static_cast<char>(group >> 8),
                     static_cast<char>(element & 0xFF), static_cast<char>(element >> 8)};
  return std::string(t, 4);
}

inline void put_le32(Bytes* b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i)
    (*b)[at + static_cast<size_t>(i)] = static_cast<uint8_t>(v >> (8 * i));
}

// Explicit VR little endian `b` with the value of the n-th (0-based) element starting with
// `head` (its tag, and its VR if given), a short VR, replaced by `value` (padded to even
// length with a space) and its 16-bit length updated. Containers of undefined length need no
// other change; one of defined length around it must keep its length. False: no such element.
inline bool replace_short_value(Bytes* b, const std::string& head, int n, std::string value) {
  if (value.size() % 2 == 1) value.push_back(' ');
  const size_t at = find_bytes(*b, head, n);
  if (at == std::string::npos) return false;
  const size_t old = (*b)[at + 6] | ((*b)[at + 7] << 8);
  b->erase(b->begin() + static_cast<std::ptrdiff_t>(at + 8),
           b->begin() + static_cast<std::ptrdiff_t>(at + 8 + old));
  b->insert(b->begin() + static_cast<std::ptrdiff_t>(at + 8), value.begin(), value.end());
  (*b)[at + 6] = static_cast<uint8_t>(value.size());
  (*b)[at + 7] = static_cast<uint8_t>(value.size() >> 8);
  return true;
}

// Names "<prefix>0.dcm", "<prefix>1.dcm", ...
inline std::vector<std::string> numbered_names(size_t count, const char* prefix) {
  std::vector<std::string> names;
  for (size_t i = 0; i < count; ++i) names.push_back(prefix + std::to_string(i) + ".dcm");
  return names;
}

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_SUPPORT_DICOM_READ_H
