// splintcore core: status, arena, arena arrays, executor, progress, deterministic sort/hash,
// SHA-256.
//
// Rules that hold for every function in splintcore:
// - Nothing here or above calls new/malloc or throws. Memory comes from an Arena the caller
//   owns, with a hard cap; running out is a Status (kArenaExhausted) naming the bytes needed.
// - Errors in data (files, geometry, caps) are Status values with a message a person can act
//   on and, where it applies, the file, byte offset, line and element index.
// - Broken preconditions (programmer errors) go to SPLINTCORE_ASSERT.
#ifndef SPLINTCORE_CORE_H
#define SPLINTCORE_CORE_H

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#if defined(__FAST_MATH__)
#error "splintcore must not be built with -ffast-math: it breaks bit-identical output"
#endif

namespace splintcore {

// ---------------------------------------------------------------------------------------------
// Assertions for programmer errors. The handler may be replaced (e.g. by firmware); the default
// prints to stderr (hosted) and aborts.
using AssertHandler = void (*)(const char* expression, const char* file, int line);
void set_assert_handler(AssertHandler handler);
[[noreturn]] void assert_failed(const char* expression, const char* file, int line);

#define SPLINTCORE_ASSERT(expr) \
  ((expr) ? static_cast<void>(0) : ::splintcore::assert_failed(#expr, __FILE__, __LINE__))

// ---------------------------------------------------------------------------------------------
// Status: one error type for the whole library.

enum class StatusCode : uint8_t {
  kOk = 0,
  kInvalidArgument,  // a parameter is out of its documented range
  kArenaExhausted,   // the memory cap is too small; the message says how much is needed
  kParseError,       // malformed input syntax (line and column, or byte offset)
  kTruncated,        // input ended early
  kNonFinite,        // NaN or infinity in input
  kLimitExceeded,    // input larger than a caller-set limit
  kIoError,          // the byte source or sink failed
  kInvalidMesh,      // the mesh is not what the operation needs (open, non-manifold, ...)
  kCancelled,        // the progress callback asked to stop
  kUnsupported,      // valid input that this version does not handle
  kInternal,         // a bug: please report it
};

// The library's version, "MAJOR.MINOR.PATCH" (for reports that must say what made a file).
const char* library_version();

// Short stable name of a code, e.g. "arena_exhausted" (used in JSON output).
const char* status_code_name(StatusCode code);

constexpr uint64_t kNoPosition = ~uint64_t{0};

class [[nodiscard]] Status {
 public:
  static constexpr size_t kMessageCapacity = 256;
  static constexpr size_t kFileCapacity = 128;

  // Ok. Only the first byte of each text buffer is set: a Status is made on every return,
  // so constructing one must not touch 400 bytes.
  Status() {
    message_[0] = '\0';
    file_[0] = '\0';
  }
  static Status ok() { return Status(); }
  static Status error(StatusCode code, const char* message);

  bool is_ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const char* message() const { return message_; }
  const char* file() const { return file_; }
  uint64_t byte_offset() const { return byte_offset_; }
  uint64_t line() const { return line_; }
  uint64_t column() const { return column_; }
  uint64_t index() const { return index_; }

  // Where the problem is. Each returns *this so they chain on a returned error.
  Status& in_file(const char* name);
  Status& at_byte(uint64_t offset) {
    byte_offset_ = offset;
    return *this;
  }
  Status& at_line(uint64_t line, uint64_t column = kNoPosition) {
    line_ = line;
    column_ = column;
    return *this;
  }
  Status& at_index(uint64_t index) {
    index_ = index;
    return *this;
  }

  // Appends to the message (truncated at capacity, always NUL-terminated).
  Status& append(const char* text);
  Status& append(const char* text, size_t length);
  Status& append_u64(uint64_t value);
  Status& append_i64(int64_t value);
  Status& append_f64(double value);  // shortest round-trip form

  // "FILE:LINE:COL: byte B: element I: message" with the parts that are known.
  // Returns the length it would have (snprintf-like); always NUL-terminates when cap > 0.
  size_t format(char* out, size_t cap) const;

 private:
  StatusCode code_ = StatusCode::kOk;
  uint16_t message_length_ = 0;
  char message_[kMessageCapacity];
  char file_[kFileCapacity];
  uint64_t byte_offset_ = kNoPosition;
  uint64_t line_ = kNoPosition;
  uint64_t column_ = kNoPosition;
  uint64_t index_ = kNoPosition;
};

namespace detail {
inline void append_part(Status& s, const char* v) { s.append(v); }
inline void append_part(Status& s, char* v) { s.append(v); }
inline void append_part(Status& s, double v) { s.append_f64(v); }
inline void append_part(Status& s, float v) { s.append_f64(static_cast<double>(v)); }
template <class T, typename std::enable_if<std::is_integral<T>::value, int>::type = 0>
void append_part(Status& s, T v) {
  if (std::is_signed<T>::value) {
    s.append_i64(static_cast<int64_t>(v));
  } else {
    s.append_u64(static_cast<uint64_t>(v));
  }
}
}  // namespace detail

// make_error(code, "need ", n, " bytes, cap ", m): message from parts (strings, integers,
// doubles), without printf (the core must not pull in the printf family).
template <class... Parts>
Status make_error(StatusCode code, const Parts&... parts) {
  Status s = Status::error(code, "");
  int dummy[] = {0, (detail::append_part(s, parts), 0)...};
  (void)dummy;
  return s;
}

#define SPLINTCORE_RETURN_IF_ERROR(expr)                        \
  do {                                                          \
    ::splintcore::Status splintcore_status_ = (expr);           \
    if (!splintcore_status_.is_ok()) return splintcore_status_; \
  } while (0)

// ---------------------------------------------------------------------------------------------
// Overflow-checked size arithmetic (never trust a count from a file).

[[nodiscard]] inline bool checked_mul(uint64_t a, uint64_t b, uint64_t* out) {
  return !__builtin_mul_overflow(a, b, out);
}
[[nodiscard]] inline bool checked_add(uint64_t a, uint64_t b, uint64_t* out) {
  return !__builtin_add_overflow(a, b, out);
}

// "64M", "2G", "512K" (binary multiples, either case) or a plain byte count -> bytes. False
// when malformed or overflowing. Used for memory caps in case files and on command lines.
[[nodiscard]] bool parse_byte_size(const char* text, uint64_t* out);

// 1..max_length characters of A-Z a-z 0-9 '_' '-' '.': safe in file names, STL solid names,
// reports and labels.
[[nodiscard]] bool is_plain_name(const char* text, size_t max_length);

// ---------------------------------------------------------------------------------------------
// Arena: a strict stack allocator with a hard cap.
//
// Two ways to give it memory:
// - a caller buffer (firmware: a static array): the cap is the buffer size;
// - caller allocate/release hooks with a cap: memory is taken in blocks as needed and
//   counted against the cap (block headers and block tails included). Blocks above the top
//   after a rewind stay cached for reuse (and so still count) until release_unused_blocks()
//   or ~Arena: data there stays readable after a rewind, which lets a function move its
//   result down over its temporaries.
// Allocation never fails silently: it returns nullptr and records the need, and
// exhausted_status() turns that into "arena exhausted: need N bytes, cap M".
// Not thread-safe: give each worker its own Arena (e.g. over a slice of the parent's).

struct AllocatorHooks {
  void* (*allocate)(void* user, size_t bytes) = nullptr;  // 16-byte aligned or better
  void (*release)(void* user, void* pointer, size_t bytes) = nullptr;
  void* user = nullptr;
};

// Buffer mode: `touch(user, begin, bytes)` is told of each stretch of the buffer before the
// arena hands any of it out for the first time, from the buffer's start on, in stretches of at
// least `step` bytes (or what is left of the buffer). A hosted tool prefaults them
// (arena_prefault_hook, platform.h): one system call where the first writes would take a
// page fault each 4 KiB. It changes nothing the arena hands out.
struct TouchHook {
  void (*touch)(void* user, void* begin, size_t bytes) = nullptr;
  void* user = nullptr;
  size_t step = size_t{4} << 20;
};

class Arena {
 public:
  static constexpr size_t kDefaultAlignment = 16;

  struct Marker {
    void* block = nullptr;
    size_t offset = 0;
    size_t used = 0;
  };

  Arena(void* buffer, size_t bytes);
  Arena(const AllocatorHooks& hooks, size_t cap, size_t block_bytes = size_t{1} << 22);
  ~Arena();
  Arena(const Arena&) = delete;
  Arena& operator=(const Arena&) = delete;

  // Returns nullptr when the cap would be exceeded (or the hooks return nullptr).
  void* allocate(size_t bytes, size_t alignment = kDefaultAlignment);

  template <class T>
  T* allocate_array(size_t count) {
    static_assert(std::is_trivially_destructible<T>::value, "arena memory is never destroyed");
    uint64_t bytes = 0;
    if (!checked_mul(count, sizeof(T), &bytes) || bytes > SIZE_MAX) {
      note_failure(SIZE_MAX);
      return nullptr;
    }
    size_t align = alignof(T) > kDefaultAlignment ? alignof(T) : kDefaultAlignment;
    return static_cast<T*>(allocate(static_cast<size_t>(bytes), align));
  }

  // Grows the most recent allocation in place (it must end at the top of the arena).
  [[nodiscard]] bool try_extend(void* pointer, size_t old_bytes, size_t new_bytes);
  // Gives back the end of the top allocation (new_bytes <= old_bytes): false, and nothing
  // changes, when `pointer` is not the top allocation.
  bool try_shrink(void* pointer, size_t old_bytes, size_t new_bytes);

  Marker mark() const;
  void rewind(const Marker& marker);  // frees everything allocated after mark()
  void reset();                       // rewind to empty

  size_t used() const { return used_; }  // bytes handed out (with alignment padding)
  size_t cap() const { return cap_; }
  size_t high_water() const { return high_water_; }
  void reset_high_water() { high_water_ = used_; }
  size_t reserved() const { return reserved_; }  // hooks mode: bytes taken from the hooks

  // The last failure: the total the arena would have needed (failed requests in a row add up),
  // and a ready error.
  size_t last_need() const { return last_need_; }
  // Drops the "failed requests add up" state: for a caller whose failed request is replaced
  // by a smaller one (not added to), e.g. a growth that falls back to the exact size.
  void forget_failure() { failing_ = false; }
  Status exhausted_status() const;

  // Hooks mode: give back blocks that rewind() left cached above the current top.
  void release_unused_blocks();

  // Buffer mode (TouchHook); ignored in hooks mode. The stretch below the top is told at once.
  void set_touch_hook(const TouchHook& hook);

 private:
  struct Block;
  void note_failure(size_t need);
  bool new_block(size_t min_payload, size_t alignment);
  void new_high_water();
  void touch_up_to(size_t end);
  void unpoison_down_to(Block* block, size_t offset);

  Block* current_ = nullptr;  // block the top is in (header of 48 bytes at most)
  size_t offset_ = 0;         // top within current_ payload
  size_t used_ = 0;
  size_t high_water_ = 0;
  size_t cap_ = 0;
  size_t reserved_ = 0;
  size_t block_bytes_ = 0;
  size_t last_need_ = 0;
  AllocatorHooks hooks_{};
  TouchHook touch_{};
  size_t touched_ = 0;  // buffer mode: bytes of the buffer told to touch_
  bool owns_blocks_ = false;
  bool failing_ = false;  // the last request failed (needs add up until a success or rewind)
  alignas(16) unsigned char root_storage_[48];  // the Block header for buffer mode
};

// Bytes allocate_array<T>(count) can take from a buffer arena: the array and the alignment
// padding before it (the top may sit anywhere). The sizing functions (`..._bound()`) add these
// up, one term per allocation, so that a bound reads like the allocations it covers.
// Saturates at UINT64_MAX.
template <class T>
constexpr uint64_t arena_array_bound(uint64_t count) {
  constexpr uint64_t align =
      alignof(T) > Arena::kDefaultAlignment ? alignof(T) : Arena::kDefaultAlignment;
  return count > (UINT64_MAX - align) / sizeof(T) ? UINT64_MAX : count * sizeof(T) + align - 1;
}

// Rewinds the arena to where it was at construction when it goes out of scope, unless
// commit() was called: temporary work inside a function, and the rule "on an error the arena
// is as it was" without a rewind on every error path (after Jolt's scope guard). A function
// that keeps a result commits once the result is in place.
class ArenaScope {
 public:
  explicit ArenaScope(Arena& arena) : arena_(arena), marker_(arena.mark()) {}
  ~ArenaScope() {
    if (!committed_) arena_.rewind(marker_);
  }
  ArenaScope(const ArenaScope&) = delete;
  ArenaScope& operator=(const ArenaScope&) = delete;

  void commit() { committed_ = true; }
  const Arena::Marker& start() const { return marker_; }

 private:
  Arena& arena_;
  Arena::Marker marker_;
  bool committed_ = false;
};

// Moves a result's arrays down over the temporaries below them: the arena is rewound to
// `start` (its top kept), then each move() takes the array's room from there and copies it
// (rewound bytes stay readable, Arena). Arrays must be moved in the order they were allocated:
// then no destination lies above bytes not yet copied. In buffer mode every array fits where
// it was. An arena of blocks may need a fresh block for one and its allocator may refuse it:
// that array and the ones after it stay where they are (none of them was overwritten), and the
// mover's end puts the top back above them: the result is whole, only not as low.
class ArenaMover {
 public:
  ArenaMover(Arena& arena, const Arena::Marker& start) : arena_(arena), top_(arena.mark()) {
    arena.rewind(start);
  }
  ~ArenaMover() {
    if (stayed_) arena_.rewind(top_);
  }
  ArenaMover(const ArenaMover&) = delete;
  ArenaMover& operator=(const ArenaMover&) = delete;

  // The array's place now: moved, or where it was (nullptr for an empty or absent array).
  template <class T>
  T* move(const T* source, size_t count) {
    if (source == nullptr || count == 0) return nullptr;
    T* to = stayed_ ? nullptr : arena_.allocate_array<T>(count);
    if (to == nullptr) {
      stayed_ = true;
      return const_cast<T*>(source);  // (the caller's own array, not a constant)
    }
    std::memmove(static_cast<void*>(to), source, count * sizeof(T));
    return to;
  }

 private:
  Arena& arena_;
  Arena::Marker top_;
  bool stayed_ = false;
};

// Two tasks' own arenas (Arena(buffer, size), one each) carved from a caller's: `bytes`
// rounded up to the arena's alignment, which each slice starts at (false on overflow); and two
// slices at the top of `arena` of need[0] and need[1] bytes (rounded up, into sizes), one
// after the other: their start, or nullptr with the arena's failure forgotten (for a caller
// that then runs serially, whose requests do not add to this one).
bool arena_slice_size(uint64_t bytes, size_t* out);
unsigned char* take_arena_slices(Arena& arena, const uint64_t need[2], size_t sizes[2]);

// ---------------------------------------------------------------------------------------------
// Span: a non-owning view.

template <class T>
class Span {
 public:
  Span() = default;
  Span(T* data, size_t size) : data_(data), size_(size) {}
  template <class U, typename std::enable_if<std::is_convertible<U*, T*>::value, int>::type = 0>
  Span(const Span<U>& other) : data_(other.data()), size_(other.size()) {}

  T* data() const { return data_; }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T& operator[](size_t i) const {
    SPLINTCORE_ASSERT(i < size_);
    return data_[i];
  }
  T* begin() const { return data_; }
  T* end() const { return data_ + size_; }
  Span subspan(size_t offset, size_t count) const {
    SPLINTCORE_ASSERT(offset <= size_ && count <= size_ - offset);
    return Span(data_ + offset, count);
  }

 private:
  T* data_ = nullptr;
  size_t size_ = 0;
};

// ---------------------------------------------------------------------------------------------
// ArenaArray: a growable array of trivially copyable T in an arena. It never frees: its memory
// goes back when the arena is rewound past it (which also invalidates it). Growth extends in
// place when the array is at the top of the arena, otherwise it copies.

template <class T>
class ArenaArray {
  static_assert(std::is_trivially_copyable<T>::value, "ArenaArray holds plain data only");

 public:
  ArenaArray() = default;
  explicit ArenaArray(Arena* arena) : arena_(arena) {}

  void bind(Arena* arena) {
    arena_ = arena;
    data_ = nullptr;
    size_ = capacity_ = 0;
  }
  Arena* arena() const { return arena_; }

  [[nodiscard]] bool reserve(size_t n) {
    if (n <= capacity_) return true;
    return grow_to(n, n);
  }
  // New elements are zeroed (so outputs never depend on stale memory).
  [[nodiscard]] bool resize(size_t n) {
    if (n > capacity_ && !grow_to(n, n)) return false;
    if (n > size_) std::memset(static_cast<void*>(data_ + size_), 0, (n - size_) * sizeof(T));
    size_ = n;
    return true;
  }
  // The capacity push_back grows a full array of `capacity` elements to, when the arena has
  // it (otherwise to one more element).
  static size_t grown_capacity(size_t capacity) {
    return capacity < 8 ? 16 : capacity + capacity / 2;
  }
  [[nodiscard]] bool push_back(const T& value) {
    if (size_ == capacity_) {
      size_t wanted = grown_capacity(capacity_);
      if (!grow_to(wanted, size_ + 1)) return false;
    }
    data_[size_++] = value;
    return true;
  }
  void pop_back() {
    SPLINTCORE_ASSERT(size_ > 0);
    --size_;
  }
  void clear() { size_ = 0; }
  void shrink_size(size_t n) {
    SPLINTCORE_ASSERT(n <= size_);
    size_ = n;
  }

  T* data() { return data_; }
  const T* data() const { return data_; }
  size_t size() const { return size_; }
  size_t capacity() const { return capacity_; }
  bool empty() const { return size_ == 0; }
  T& operator[](size_t i) {
    SPLINTCORE_ASSERT(i < size_);
    return data_[i];
  }
  const T& operator[](size_t i) const {
    SPLINTCORE_ASSERT(i < size_);
    return data_[i];
  }
  T& back() {
    SPLINTCORE_ASSERT(size_ > 0);
    return data_[size_ - 1];
  }
  T* begin() { return data_; }
  T* end() { return data_ + size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  Span<T> span() { return Span<T>(data_, size_); }
  Span<const T> span() const { return Span<const T>(data_, size_); }

  // Returns the unused capacity to the arena when the array is its top allocation (a grown
  // array's spare half, before the next stage allocates above it).
  void shrink_to_fit() {
    if (data_ != nullptr && arena_->try_shrink(data_, capacity_ * sizeof(T), size_ * sizeof(T))) {
      capacity_ = size_;
    }
  }

  // Points the array at memory already holding `size` elements (used when compacting).
  void adopt(T* data, size_t size, size_t capacity) {
    data_ = data;
    size_ = size;
    capacity_ = capacity;
  }

 private:
  // Tries `wanted` elements, then falls back to `needed` so the cap can be used to the byte.
  bool grow_to(size_t wanted, size_t needed) {
    SPLINTCORE_ASSERT(arena_ != nullptr);
    if (try_capacity(wanted)) return true;
    if (wanted == needed) return false;
    arena_->forget_failure();  // the exact size replaces the failed larger request
    return try_capacity(needed);
  }
  bool try_capacity(size_t n) {
    if (n > SIZE_MAX / sizeof(T)) return false;
    if (data_ != nullptr && arena_->try_extend(data_, capacity_ * sizeof(T), n * sizeof(T))) {
      capacity_ = n;
      return true;
    }
    T* fresh = arena_->allocate_array<T>(n);
    if (fresh == nullptr) return false;
    if (size_ > 0) std::memcpy(static_cast<void*>(fresh), data_, size_ * sizeof(T));
    data_ = fresh;
    capacity_ = n;
    return true;
  }

  Arena* arena_ = nullptr;
  T* data_ = nullptr;
  size_t size_ = 0;
  size_t capacity_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Executor: the caller's threads. run(self, count, task, context) must call task(context, i)
// exactly once for each i in [0, count) and return when all have finished. Tasks write only to
// their own slots, so results never depend on the thread count or scheduling.

using TaskFunction = void (*)(void* context, uint32_t index);

struct Executor {
  void (*run)(void* self, uint32_t count, TaskFunction task, void* context) = nullptr;
  void* self = nullptr;
  uint32_t concurrency = 1;  // how many tasks may run at once (a hint for splitting work)
};

// The serial executor: runs tasks in index order on the calling thread.
const Executor& serial_executor();

// Whether work split into tasks can run on more than one thread at once (else a split only
// costs: callers keep their one-pass serial code for this case).
inline bool has_threads(const Executor* executor) {
  return executor != nullptr && executor->concurrency > 1;
}

// Where task i of `tasks` starts when n things are shared out in order: task i does
// [task_start(n, i, tasks), task_start(n, i + 1, tasks)).
inline size_t task_start(size_t n, uint32_t i, uint32_t tasks) {
  return static_cast<size_t>(uint64_t{n} * i / tasks);
}

void parallel_for(const Executor* executor, uint32_t count, TaskFunction task, void* context);

template <class F>
void parallel_for_each(const Executor* executor, uint32_t count, F& function) {
  parallel_for(
      executor, count, [](void* context, uint32_t index) { (*static_cast<F*>(context))(index); },
      &function);
}

// ---------------------------------------------------------------------------------------------
// Progress and cancellation. report() returns false to cancel; the operation then returns
// kCancelled at its next check (checks are at most a bounded amount of work apart).

struct Progress {
  bool (*report)(void* user, const char* stage, uint64_t done, uint64_t total) = nullptr;
  void* user = nullptr;
};

// The explicit context every core operation takes.
struct Context {
  Arena* arena = nullptr;
  const Executor* executor = nullptr;  // nullptr: serial
  const Progress* progress = nullptr;  // nullptr: none

  explicit Context(Arena* a) : arena(a) {}
  Context(Arena* a, const Executor* e, const Progress* p) : arena(a), executor(e), progress(p) {}
};

// Reports progress; returns kCancelled when the callback asks to stop.
Status report_progress(const Context& ctx, const char* stage, uint64_t done, uint64_t total);

// ---------------------------------------------------------------------------------------------
// Deterministic sorting and hashing (std::sort is not stable and its order of equal keys is
// not the same everywhere; hash iteration order must never reach output).

struct KeyIndex {
  uint64_t key;
  uint32_t index;
  uint32_t pad;  // zero; keeps the struct 16 bytes
};

// Stable LSD radix sort by key; `scratch` must hold items.size() elements.
void radix_sort(Span<KeyIndex> items, Span<KeyIndex> scratch);
// The same, taking scratch from the arena (rewound before return).
Status radix_sort(Arena& arena, Span<KeyIndex> items);
// Plain 64-bit keys (half the memory traffic when a key and an index fit in 64 bits).
void radix_sort(Span<uint64_t> items, Span<uint64_t> scratch);
// Stable sort by bits [lo_bit, hi_bit) of each key alone (lo_bit < hi_bit <= 64): keys equal
// there keep their input order, whatever their other bits. When the bits below lo_bit already
// rise in input order (an index packed under a code), that is the order of the whole key, in
// passes of up to 11 bits over the range only (four for a 42-bit code, not eight).
void radix_sort_bits(Span<uint64_t> items, Span<uint64_t> scratch, unsigned lo_bit,
                     unsigned hi_bit);

// 64-bit mixer (splitmix64 finaliser): fixed on every platform.
inline uint64_t hash_mix(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  x ^= x >> 31;
  return x;
}

// ---------------------------------------------------------------------------------------------
// SHA-256 (FIPS 180-4): for golden files and audit reports.

class Sha256 {
 public:
  Sha256();
  void update(const void* data, size_t bytes);
  void finish(uint8_t digest[32]);
  static void to_hex(const uint8_t digest[32], char out[65]);

 private:
  void blocks(const uint8_t* p, size_t n);  // n whole 64-byte blocks
  uint32_t state_[8];
  uint64_t length_ = 0;
  uint8_t buffer_[64];
  size_t buffered_ = 0;
};

}  // namespace splintcore

#endif  // SPLINTCORE_CORE_H
