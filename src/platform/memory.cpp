// Memory for a tool's arena, mapped from the operating system (the hosted layer only).
#include <sys/mman.h>

#include <cstdint>

#include "splintcore/platform.h"

namespace splintcore {
namespace {

constexpr uint64_t kHuge = uint64_t{2} << 20;

// The size actually mapped for `bytes`: whole 2 MiB pages; 0 when that does not fit.
uint64_t mapped_size(uint64_t bytes) {
  if (bytes == 0 || bytes > UINT64_MAX - kHuge) return 0;
  const uint64_t rounded = (bytes + kHuge - 1) / kHuge * kHuge;
  return rounded > SIZE_MAX - kHuge ? 0 : rounded;
}

}  // namespace

// Mapped, not taken from malloc: the block is the tool's whole arena (1 GiB by default), which
// malloc would map anyway, and a sanitizer's allocator writes the shadow of a whole heap block
// when it is allocated and freed (256 MB of shadow for 1 GiB: about a second of each command's
// run under ASan). One 2 MiB page more is mapped and the ends trimmed, for the alignment.
void* acquire_arena_memory(uint64_t bytes) {
  const uint64_t size = mapped_size(bytes);
  if (size == 0) return nullptr;
  const size_t span = static_cast<size_t>(size + kHuge);
  void* p = ::mmap(nullptr, span, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) return nullptr;
  const uintptr_t start = reinterpret_cast<uintptr_t>(p);
  const uintptr_t aligned = (start + (kHuge - 1)) & ~static_cast<uintptr_t>(kHuge - 1);
  const size_t head = static_cast<size_t>(aligned - start);
  const size_t tail = span - head - static_cast<size_t>(size);
  if (head > 0) (void)::munmap(p, head);
  if (tail > 0)
    (void)::munmap(reinterpret_cast<void*>(aligned + static_cast<uintptr_t>(size)), tail);
  void* block = reinterpret_cast<void*>(aligned);
#ifdef MADV_HUGEPAGE
  (void)::madvise(block, static_cast<size_t>(size), MADV_HUGEPAGE);
#endif
  return block;
}

void release_arena_memory(void* p, uint64_t bytes) {
  const uint64_t size = mapped_size(bytes);
  if (p != nullptr && size != 0) (void)::munmap(p, static_cast<size_t>(size));
}

}  // namespace splintcore
