// libFuzzer target: arbitrary bytes through the MetaImage reader, under a small arena. A detached
// header's data file (any name) is served from the input itself. Any crash, sanitizer report
// or broken invariant (ct_fuzz_common.h) is a bug.
//   cmake -B build/fuzz -DCMAKE_CXX_COMPILER=clang++ -DSPLINTCORE_FUZZ=ON
//   build/fuzz/tests/splintcore_fuzz_ct_metaimage -max_total_time=60 fixtures/fuzz/ct_metaimage
#include "ct_fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace splintcore;
  static unsigned char memory[4 << 20];
  Arena arena(memory, sizeof(memory));
  Context ctx(&arena);
  const CtReadOptions options = fuzz::small_options(size);
  MemorySource ms{data, size, 0, 1 + size % 97};
  CtMemoryFile self{"", data, size};
  struct AnyName {
    CtMemoryFile file;
    CtMemoryFiles files;
  } any{self, {}};
  any.files.files = &any.file;
  any.files.count = 1;
  CtFileOpener opener;
  opener.user = &any;
  opener.open = [](void* user, const char* name, ByteSource* out) {
    AnyName* a = static_cast<AnyName*>(user);
    a->file.name = name;  // serve the input under whatever name the header gives
    CtFileOpener inner = ct_memory_opener(&a->files);
    return inner.open(inner.user, name, out);
  };
  opener.close = [](void* user, ByteSource* source) {
    AnyName* a = static_cast<AnyName*>(user);
    CtFileOpener inner = ct_memory_opener(&a->files);
    inner.close(inner.user, source);
  };
  CtVolume volume;
  CtInfo info;
  Status s = read_metaimage(ctx, memory_source(&ms, "fuzz.mha"), &opener, options, &volume, &info);
  fuzz::check(s, arena, volume, options);
  return 0;
}
