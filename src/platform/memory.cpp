// Memory for a tool's arena, mapped from the operating system (the hosted layer only).
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>

#include "splintcore/platform.h"

namespace splintcore {
namespace {

constexpr uint64_t kHuge = uint64_t{2} << 20;
constexpr size_t kTouchChunk = size_t{256} << 10;  // ArenaToucher's unit of work, its hook's step

// The size actually mapped for `bytes`: whole 2 MiB pages; 0 when that does not fit.
uint64_t mapped_size(uint64_t bytes) {
  if (bytes == 0 || bytes > UINT64_MAX - kHuge) return 0;
  const uint64_t rounded = (bytes + kHuge - 1) / kHuge * kHuge;
  return rounded > SIZE_MAX - kHuge ? 0 : rounded;
}

// The system's page size (4 KiB where it cannot say).
size_t page_size() {
  static const long kPage = ::sysconf(_SC_PAGESIZE);
  return kPage > 0 ? static_cast<size_t>(kPage) : 4096;
}

// The touch hook of arena_prefault_hook(): the pages of [begin, begin + bytes) made resident
// in one system call; where MADV_POPULATE_WRITE is missing or refused they fault in on use.
void prefault(void*, void* begin, size_t bytes) {
#ifdef MADV_POPULATE_WRITE
  // The stretch starts anywhere in a page: madvise takes whole pages.
  const uintptr_t page = page_size();
  const uintptr_t start = reinterpret_cast<uintptr_t>(begin) & ~(page - 1);
  const uintptr_t end = reinterpret_cast<uintptr_t>(begin) + bytes;
  (void)::madvise(reinterpret_cast<void*>(start), static_cast<size_t>(end - start),
                  MADV_POPULATE_WRITE);
#else
  (void)begin;
  (void)bytes;
#endif
}

}  // namespace

// Mapped, not taken from malloc: the block is the tool's whole arena (1 GiB by default), which
// malloc would map anyway, and a sanitizer's allocator writes the shadow of a whole heap block
// when it is allocated and freed (256 MB of shadow for 1 GiB: about a second of each command's
// run under ASan). One 2 MiB page more is mapped and the ends trimmed, for the alignment.
// No madvise(MADV_HUGEPAGE) (it was offered until issue 32's measurements): measured on the
// project's 2-core VM (virtio-balloon free page reporting), 1.5 s after the previous run, with
// /usr/bin/time, 8 runs each alternated: `check` of the 543k phantom maxilla median 0.16 s
// wall (0.11 s sys) with the advice, 0.06 s (0.01 s sys) without; the real case's automatic
// design at 2 threads 0.75 s (0.22 s sys) with, 0.61 s (0.05 s sys) without. Back to back
// (no pause) the wall times were within noise, and without the advice the user time was about
// 11% more (4 KiB pages' TLB misses: 0.74 s, not 0.665 s, at 1 thread) and the system time
// about 0.15 s less. In 4 KiB pages the first touch of 64 MB costs about 40 ms here; in huge
// pages just handed back to the host, 150-280 ms (10 ms when they were not). On a machine
// without free page reporting the advice would save that user time.
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
  return reinterpret_cast<void*>(aligned);
}

TouchHook arena_prefault_hook() {
  TouchHook h;
  h.touch = &prefault;
  return h;
}

ArenaToucher::ArenaToucher(void* buffer, size_t bytes, size_t ahead)
    : buffer_(static_cast<unsigned char*>(buffer)),
      bytes_(buffer != nullptr ? bytes : 0),
      ahead_(ahead) {
  if (bytes_ == 0) return;
  target_ = ahead_ < bytes_ ? ahead_ : bytes_;
  thread_ = std::thread([this] { loop(); });
}

ArenaToucher::~ArenaToucher() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  more_.notify_one();
  thread_.join();
}

TouchHook ArenaToucher::hook() {
  if (bytes_ == 0) return arena_prefault_hook();
  TouchHook h;
  h.touch = &ArenaToucher::touch;
  h.user = this;
  h.step = kTouchChunk;  // (see platform.h)
  return h;
}

// The arena is about to use [begin, begin + bytes): the target moved to `ahead` beyond it,
// then a wait until the thread has touched all of it (of it within the toucher's bytes: an
// arena over more than those uses the rest as it is).
void ArenaToucher::touch(void* self, void* begin, size_t bytes) {
  ArenaToucher* t = static_cast<ArenaToucher*>(self);
  size_t end = static_cast<size_t>(static_cast<unsigned char*>(begin) - t->buffer_) + bytes;
  if (end > t->bytes_) end = t->bytes_;
  std::unique_lock<std::mutex> lock(t->mutex_);
  const size_t want = t->bytes_ - end > t->ahead_ ? end + t->ahead_ : t->bytes_;
  if (want > t->target_) {
    t->target_ = want;
    t->more_.notify_one();
  }
  t->done_.wait(lock, [t, end] { return t->done_bytes_ >= end; });
}

// A chunk (256 KiB) at a time: prefaulted, then a byte of each page read (the host maps the
// page then).
void ArenaToucher::loop() {
  constexpr size_t kChunk = kTouchChunk;
  const size_t page = page_size();
  unsigned sink = 0;
  for (;;) {
    size_t from, to;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      more_.wait(lock, [this] { return stopping_ || done_bytes_ < target_; });
      if (stopping_) break;
      from = done_bytes_;
      to = target_ - from > kChunk ? from + kChunk : target_;
    }
    prefault(nullptr, buffer_ + from, to - from);
    const volatile unsigned char* p = buffer_;
    // (From the first page that starts in the chunk: one starting before it was read with
    // the chunk before, and may be in the arena's use now.)
    for (size_t i = (from + page - 1) / page * page; i < to; i += page) sink += p[i];
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_bytes_ = to;
    }
    done_.notify_all();
  }
  static_cast<void>(sink);
}

void release_arena_memory(void* p, uint64_t bytes) {
  const uint64_t size = mapped_size(bytes);
  if (p != nullptr && size != 0) (void)::munmap(p, static_cast<size_t>(size));
}

}  // namespace splintcore
