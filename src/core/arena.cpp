// Arena: a stack allocator with a hard cap (after Jolt's TempAllocatorImpl: one fixed budget,
// strict LIFO, failures reported with the size that would have been enough).
#include <new>

#include "splintcore/core.h"

// Under AddressSanitizer (g++ defines __SANITIZE_ADDRESS__, clang++ has the feature) the
// alignment gap an allocation skips is poisoned, so that an array overrun by an element, or
// read one before its start, is reported where a gap follows or precedes it (an arena is one
// block to ASan, and without this it sees nothing inside). Everything above the top is kept
// unpoisoned: a rewind unpoisons what it frees (callers may read rewound bytes to move a
// result down, and every destination's gap lies below its source), and so does the end of the
// arena. The gaps are whole allocations' padding only: sizes, bounds and bytes are the same.
#if defined(__SANITIZE_ADDRESS__)
#define SPLINTCORE_ARENA_POISON 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SPLINTCORE_ARENA_POISON 1
#endif
#endif
#ifdef SPLINTCORE_ARENA_POISON
extern "C" void __asan_poison_memory_region(void const volatile* addr, size_t size);
extern "C" void __asan_unpoison_memory_region(void const volatile* addr, size_t size);
#endif

namespace splintcore {

// Every block starts with this header; the payload follows it. In buffer mode the one block
// is described by root_storage_ and its payload is the caller's buffer.
struct Arena::Block {
  Block* previous;  // the block below this one in the stack
  Block* next;      // a cached block above (after a rewind), reused before asking the hooks
  unsigned char* payload;
  size_t payload_bytes;
  size_t used_before;  // arena bytes in use below this block's payload
  size_t total_bytes;  // what the hooks handed out (0 for the caller's buffer)
};

namespace {
constexpr size_t kHeaderBytes = 64;  // header rounded up so payloads stay 64-byte aligned

#ifdef SPLINTCORE_ARENA_POISON
void poison(const unsigned char* p, size_t bytes) {
  if (bytes > 0) __asan_poison_memory_region(p, bytes);
}
void unpoison(const unsigned char* p, size_t bytes) {
  if (bytes > 0) __asan_unpoison_memory_region(p, bytes);
}
#else
void poison(const unsigned char*, size_t) {}
void unpoison(const unsigned char*, size_t) {}
#endif

size_t align_up(size_t value, size_t alignment) {
  return (value + alignment - 1) & ~(alignment - 1);
}
}  // namespace

Arena::Arena(void* buffer, size_t bytes) : cap_(bytes) {
  static_assert(sizeof(Block) <= sizeof(root_storage_), "root_storage_ too small");
  current_ = ::new (static_cast<void*>(root_storage_)) Block{};
  current_->payload = static_cast<unsigned char*>(buffer);
  current_->payload_bytes = buffer != nullptr ? bytes : 0;
  if (buffer == nullptr) cap_ = 0;
}

Arena::Arena(const AllocatorHooks& hooks, size_t cap, size_t block_bytes)
    : cap_(cap),
      block_bytes_(block_bytes < 4096 ? 4096 : block_bytes),
      hooks_(hooks),
      owns_blocks_(true) {
  SPLINTCORE_ASSERT(hooks.allocate != nullptr && hooks.release != nullptr);
  // An empty root block so current_ is never null.
  current_ = ::new (static_cast<void*>(root_storage_)) Block{};
}

Arena::~Arena() {
  if (!owns_blocks_) {
    if (current_->payload != nullptr) unpoison(current_->payload, offset_);  // the caller's
    return;
  }
  reset();
  release_unused_blocks();
}

// Failed requests in a row add up: code that makes several allocations and then checks them
// (or a caller that goes on after one fails) needs all of them, so the reported need is the
// first failure's need plus what each later failed request would have added on top of the
// current use. A successful allocation or a rewind starts a new count.
void Arena::note_failure(size_t need) {
  const size_t base = owns_blocks_ ? reserved_ : used_;
  if (failing_ && need >= base && last_need_ <= SIZE_MAX - (need - base)) {
    last_need_ += need - base;
  } else {
    last_need_ = need;
  }
  failing_ = true;
}

Status Arena::exhausted_status() const {
  return make_error(StatusCode::kArenaExhausted, "arena exhausted: need ", last_need_,
                    " bytes, cap ", cap_, "; increase the memory cap to at least ", last_need_,
                    " bytes");
}

bool Arena::new_block(size_t min_payload, size_t alignment) {
  // Reuse the cached block above the current one if it is big enough. A cached block that is
  // too small is kept (not released): callers may still read data there after a rewind, e.g.
  // to move a result down over its temporaries. A fresh block is linked in before it.
  Block* cached = current_->next;
  const size_t used_here = used_;
  if (cached != nullptr) {
    size_t start = align_up(reinterpret_cast<uintptr_t>(cached->payload), alignment) -
                   reinterpret_cast<uintptr_t>(cached->payload);
    if (start <= cached->payload_bytes && min_payload <= cached->payload_bytes - start) {
      cached->used_before = used_here;
      current_ = cached;
      offset_ = 0;
      return true;
    }
  }
  uint64_t payload = uint64_t{min_payload} + alignment;
  if (payload < block_bytes_ - kHeaderBytes) payload = block_bytes_ - kHeaderBytes;
  uint64_t total = payload + kHeaderBytes;
  if (reserved_ + total > cap_) {
    // The smallest block that would do, before giving up.
    payload = uint64_t{min_payload} + alignment;
    total = payload + kHeaderBytes;
    if (total > SIZE_MAX || reserved_ + total > cap_) {
      note_failure(total > SIZE_MAX - reserved_ ? SIZE_MAX
                                                : reserved_ + static_cast<size_t>(total));
      return false;
    }
  }
  void* memory = hooks_.allocate(hooks_.user, static_cast<size_t>(total));
  if (memory == nullptr) {
    note_failure(reserved_ + static_cast<size_t>(total));
    return false;
  }
  reserved_ += static_cast<size_t>(total);
  Block* block = ::new (memory) Block{};
  block->payload = static_cast<unsigned char*>(memory) + kHeaderBytes;
  block->payload_bytes = static_cast<size_t>(payload);
  block->total_bytes = static_cast<size_t>(total);
  block->previous = current_;
  block->next = cached;
  block->used_before = used_here;
  if (cached != nullptr) cached->previous = block;
  current_->next = block;
  current_ = block;
  offset_ = 0;
  return true;
}

void* Arena::allocate(size_t bytes, size_t alignment) {
  SPLINTCORE_ASSERT(alignment != 0 && (alignment & (alignment - 1)) == 0);
  if (current_->payload != nullptr) {
    const uintptr_t base = reinterpret_cast<uintptr_t>(current_->payload);
    const size_t start = align_up(base + offset_, alignment) - base;
    if (start <= current_->payload_bytes && bytes <= current_->payload_bytes - start) {
      failing_ = false;
      const size_t gap = offset_;
      offset_ = start + bytes;
      used_ = current_->used_before + offset_;
      if (used_ > high_water_) new_high_water();
      poison(current_->payload + gap, start - gap);  // after the touch hook, which writes there
      return current_->payload + start;
    }
    if (!owns_blocks_) {
      // The need includes the alignment padding, so a cap of exactly `need` succeeds.
      uint64_t need = 0;
      if (!checked_add(uint64_t{current_->used_before} + start, bytes, &need) || need > SIZE_MAX) {
        need = SIZE_MAX;
      }
      note_failure(static_cast<size_t>(need));
      return nullptr;
    }
  } else if (!owns_blocks_) {
    note_failure(bytes);  // no buffer at all (cap 0)
    return nullptr;
  }
  if (!new_block(bytes, alignment)) return nullptr;
  return allocate(bytes, alignment);
}

// A new high water; in buffer mode with a touch hook, the buffer up to it told first.
void Arena::new_high_water() {
  high_water_ = used_;
  if (touch_.touch != nullptr && used_ > touched_) touch_up_to(used_);
}

// Tells touch_ of the buffer from touched_ to `end`, at least a step of it (less at the end).
void Arena::touch_up_to(size_t end) {
  const size_t room = current_->payload_bytes - touched_;
  const size_t want = end - touched_ > touch_.step ? end - touched_ : touch_.step;
  const size_t bytes = want < room ? want : room;
  touch_.touch(touch_.user, current_->payload + touched_, bytes);
  touched_ += bytes;
}

void Arena::set_touch_hook(const TouchHook& hook) {
  if (owns_blocks_ || current_->payload == nullptr) return;
  touch_ = hook;
  if (touch_.step == 0) touch_.step = 1;
  touched_ = 0;
  if (touch_.touch != nullptr && used_ > 0) touch_up_to(used_);
}

bool Arena::try_extend(void* pointer, size_t old_bytes, size_t new_bytes) {
  // An opportunistic attempt: failing here is not a failure of the caller (who then copies),
  // so nothing is noted.
  unsigned char* p = static_cast<unsigned char*>(pointer);
  if (current_->payload == nullptr || p < current_->payload) return false;
  const size_t start = static_cast<size_t>(p - current_->payload);
  if (start + old_bytes != offset_) return false;  // not the top allocation
  if (new_bytes < old_bytes) return false;
  if (new_bytes - old_bytes > current_->payload_bytes - offset_) return false;
  failing_ = false;
  offset_ = start + new_bytes;
  used_ = current_->used_before + offset_;
  if (used_ > high_water_) new_high_water();
  return true;
}

bool Arena::try_shrink(void* pointer, size_t old_bytes, size_t new_bytes) {
  unsigned char* p = static_cast<unsigned char*>(pointer);
  if (current_->payload == nullptr || p < current_->payload || new_bytes > old_bytes) return false;
  const size_t start = static_cast<size_t>(p - current_->payload);
  if (start + old_bytes != offset_) return false;  // not the top allocation
  offset_ = start + new_bytes;
  used_ = current_->used_before + offset_;
  return true;
}

Arena::Marker Arena::mark() const {
  Marker m;
  m.block = current_;
  m.offset = offset_;
  m.used = used_;
  return m;
}

void Arena::rewind(const Marker& marker) {
  unpoison_down_to(static_cast<Block*>(marker.block), marker.offset);
  // Blocks above the marker stay cached (linked through next) for reuse.
  current_ = static_cast<Block*>(marker.block);
  offset_ = marker.offset;
  used_ = marker.used;
  failing_ = false;
}

void Arena::reset() {
  Block* b = current_;
  while (b->previous != nullptr) b = b->previous;
  unpoison_down_to(b, 0);
  current_ = b;
  offset_ = 0;
  used_ = 0;
}

// (AddressSanitizer builds) The gaps from the top down to `offset` in `block` unpoisoned:
// the current block's up to the top, each block between them whole.
void Arena::unpoison_down_to(Block* block, size_t offset) {
#ifdef SPLINTCORE_ARENA_POISON
  size_t end = offset_;
  for (Block* b = current_; b != nullptr; b = b->previous) {
    if (b == block) {
      if (b->payload != nullptr && end > offset) unpoison(b->payload + offset, end - offset);
      return;
    }
    if (b->payload != nullptr) unpoison(b->payload, end);
    if (b->previous != nullptr) end = b->previous->payload_bytes;
  }
#else
  (void)block;
  (void)offset;
#endif
}

void Arena::release_unused_blocks() {
  if (!owns_blocks_) return;
  Block* b = current_->next;
  current_->next = nullptr;
  while (b != nullptr) {
    Block* next = b->next;
    reserved_ -= b->total_bytes;
    hooks_.release(hooks_.user, b, b->total_bytes);
    b = next;
  }
}

bool arena_slice_size(uint64_t bytes, size_t* out) {
  constexpr uint64_t kAlign = Arena::kDefaultAlignment;
  if (bytes > SIZE_MAX - kAlign) return false;
  *out = static_cast<size_t>((bytes + kAlign - 1) / kAlign * kAlign);
  return true;
}

unsigned char* take_arena_slices(Arena& arena, const uint64_t need[2], size_t sizes[2]) {
  if (!arena_slice_size(need[0], &sizes[0]) || !arena_slice_size(need[1], &sizes[1]) ||
      sizes[0] > SIZE_MAX - sizes[1]) {
    return nullptr;
  }
  void* p = arena.allocate(sizes[0] + sizes[1]);
  if (p == nullptr) arena.forget_failure();
  return static_cast<unsigned char*>(p);
}

}  // namespace splintcore
