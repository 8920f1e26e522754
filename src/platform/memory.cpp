// Memory for a tool's arena, from the operating system's allocator (the hosted layer only).
#include <sys/mman.h>

#include <cstdlib>

#include "splintcore/platform.h"

namespace splintcore {

void* acquire_arena_memory(uint64_t bytes) {
  constexpr uint64_t kHuge = uint64_t{2} << 20;
  if (bytes == 0 || bytes > UINT64_MAX - kHuge) return nullptr;
  const uint64_t rounded = (bytes + kHuge - 1) / kHuge * kHuge;
  if (rounded > SIZE_MAX) return nullptr;
  void* p = std::aligned_alloc(static_cast<size_t>(kHuge), static_cast<size_t>(rounded));
#ifdef MADV_HUGEPAGE
  if (p != nullptr) (void)::madvise(p, static_cast<size_t>(rounded), MADV_HUGEPAGE);
#endif
  return p;
}

void release_arena_memory(void* p) { std::free(p); }

}  // namespace splintcore
