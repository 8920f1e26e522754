// libFuzzer target: arbitrary bytes through the DICOM series reader, under a small arena. The
// input is split into up to 8 files at each "SPLINTCORE-NEXT-FILE" (so one input can be a
// whole series; tests/fuzz/ct_corpus.py writes the seeds). Any crash, sanitizer report or
// broken invariant (ct_fuzz_common.h) is a bug.
//   cmake -B build/fuzz -DCMAKE_CXX_COMPILER=clang++ -DSPLINTCORE_FUZZ=ON
//   build/fuzz/tests/splintcore_fuzz_ct_dicom -max_total_time=60 fixtures/fuzz/ct_dicom
#include <cstring>

#include "ct_fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace splintcore;
  static unsigned char memory[4 << 20];
  static const char kSeparator[] = "SPLINTCORE-NEXT-FILE";
  static const char* kNames[8] = {"f0.dcm", "f1.dcm", "f2.dcm", "f3.dcm",
                                  "f4.dcm", "f5.dcm", "f6.dcm", "f7.dcm"};
  const size_t sep = sizeof(kSeparator) - 1;
  CtMemoryFile files[8];
  uint32_t count = 0;
  size_t start = 0;
  for (size_t i = 0; count < 7 && i + sep <= size; ++i) {
    if (std::memcmp(data + i, kSeparator, sep) == 0) {
      files[count] = CtMemoryFile{kNames[count], data + start, i - start};
      ++count;
      start = i + sep;
      i += sep - 1;
    }
  }
  files[count] = CtMemoryFile{kNames[count], data + start, size - start};
  ++count;

  Arena arena(memory, sizeof(memory));
  Context ctx(&arena);
  const CtReadOptions options = fuzz::small_options(size);
  CtMemoryFiles memory_files{files, count, 1 + size % 89, {}};
  CtVolume volume;
  CtInfo info;
  Status s = read_dicom_series(ctx, ct_memory_series(&memory_files), options, &volume, &info);
  fuzz::check(s, arena, volume, options);
  return 0;
}
