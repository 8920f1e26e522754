// Stable LSD radix sort on 64-bit keys: the same order on every platform and compiler (the
// order of equal keys is their input order), and O(n) for the edge and vertex keys the mesh
// code sorts. Passes whose byte is the same for every key are skipped.
#include "splintcore/core.h"

namespace splintcore {

namespace {
inline uint64_t key_of(const KeyIndex& item) { return item.key; }
inline uint64_t key_of(uint64_t item) { return item; }

template <class T>
void lsd_radix_sort(Span<T> items, Span<T> scratch) {
  const size_t n = items.size();
  if (n < 2) return;
  SPLINTCORE_ASSERT(scratch.size() >= n && n <= UINT32_MAX);
  // One histogram pass over all 8 bytes at once.
  uint32_t counts[8][256] = {};
  for (size_t i = 0; i < n; ++i) {
    const uint64_t k = key_of(items.data()[i]);
    for (int b = 0; b < 8; ++b) ++counts[b][(k >> (8 * b)) & 0xff];
  }
  T* from = items.data();
  T* to = scratch.data();
  for (int b = 0; b < 8; ++b) {
    uint32_t* c = counts[b];
    const uint64_t first_byte = (key_of(from[0]) >> (8 * b)) & 0xff;
    if (c[first_byte] == n) continue;  // every key has this byte: nothing to do
    uint32_t offsets[256];
    uint32_t sum = 0;
    for (int v = 0; v < 256; ++v) {
      offsets[v] = sum;
      sum += c[v];
    }
    const int shift = 8 * b;
    for (size_t i = 0; i < n; ++i) {
      const T& item = from[i];
      to[offsets[(key_of(item) >> shift) & 0xff]++] = item;
    }
    T* t = from;
    from = to;
    to = t;
  }
  if (from != items.data()) std::memcpy(static_cast<void*>(items.data()), from, n * sizeof(T));
}

constexpr unsigned kMaxDigit = 11;

// One stable scatter of from[0, n) into `to` by the digit (k >> shift) & mask: counts, their
// running sums, then each key to its bucket's next slot. offsets[d] ends where bucket d ends.
// False (and nothing moved) when every key has the same digit.
bool scatter_digit(const uint64_t* from, uint64_t* to, size_t n, unsigned shift, uint64_t mask,
                   uint32_t* offsets) {
  const uint32_t buckets = static_cast<uint32_t>(mask) + 1;
  for (uint32_t b = 0; b < buckets; ++b) offsets[b] = 0;
  for (size_t i = 0; i < n; ++i) ++offsets[(from[i] >> shift) & mask];
  if (offsets[(from[0] >> shift) & mask] == n) return false;
  uint32_t sum = 0;
  for (uint32_t b = 0; b < buckets; ++b) {
    const uint32_t c = offsets[b];
    offsets[b] = sum;
    sum += c;
  }
  for (size_t i = 0; i < n; ++i) {
    const uint64_t k = from[i];
    to[offsets[(k >> shift) & mask]++] = k;
  }
  return true;
}

// Stable LSD passes over bits [lo_bit, hi_bit) of from[0, n), ping-ponging with `to`; returns
// where the result is. Digits of equal width, at most 11 bits: the 2048 counts fit in 8 KiB
// of stack.
uint64_t* lsd_bits(uint64_t* from, uint64_t* to, size_t n, unsigned lo_bit, unsigned hi_bit) {
  const unsigned bits = hi_bit - lo_bit;
  const unsigned passes = (bits + kMaxDigit - 1) / kMaxDigit;
  const unsigned width = (bits + passes - 1) / passes;
  uint32_t offsets[1u << kMaxDigit];
  for (unsigned shift = lo_bit; shift < hi_bit; shift += width) {
    const unsigned w = hi_bit - shift < width ? hi_bit - shift : width;
    if (!scatter_digit(from, to, n, shift, (uint64_t{1} << w) - 1, offsets)) continue;
    uint64_t* t = from;
    from = to;
    to = t;
  }
  return from;
}

// LSD passes over from[0, n), with `other` as scratch; the result ends in `dest`, one of the
// two.
void lsd_to(uint64_t* from, uint64_t* other, size_t n, unsigned lo_bit, unsigned hi_bit,
            uint64_t* dest) {
  const uint64_t* result = lsd_bits(from, other, n, lo_bit, hi_bit);
  if (result != dest) std::memcpy(static_cast<void*>(dest), result, n * sizeof(uint64_t));
}

// A large array with a wide range: one pass on the top digit into buckets, then LSD passes
// inside each bucket while it is in cache. Every pass over the whole array scatters its writes
// across megabytes (543k Morton keys of 42 bits: 10.3 ms in four LSD passes, 6.4 ms this way).
// The top digit takes what is left over whole 11-bit digits, 6 to 11 bits. Not inlined: its
// 8 KiB of bucket ends stay off the stack of small sorts (the firmware's high water).
__attribute__((noinline)) void top_digit_first(uint64_t* a, uint64_t* b, size_t n, unsigned lo_bit,
                                               unsigned hi_bit) {
  const unsigned bits = hi_bit - lo_bit;
  unsigned top = bits - kMaxDigit * ((bits - 6) / kMaxDigit);
  top = top > kMaxDigit ? kMaxDigit : top;
  const unsigned shift = hi_bit - top;
  const uint32_t buckets = uint32_t{1} << top;
  uint32_t ends[1u << kMaxDigit];
  if (!scatter_digit(a, b, n, shift, (uint64_t{1} << top) - 1, ends)) {
    lsd_to(a, b, n, lo_bit, shift, a);  // one top digit for all: the rest of the range
    return;
  }
  // ends[k] is now where bucket k ends (and k + 1 begins).
  uint32_t begin = 0;
  for (uint32_t k = 0; k < buckets; ++k) {
    if (ends[k] > begin) lsd_to(b + begin, a + begin, ends[k] - begin, lo_bit, shift, a + begin);
    begin = ends[k];
  }
}

}  // namespace

void radix_sort_bits(Span<uint64_t> items, Span<uint64_t> scratch, unsigned lo_bit,
                     unsigned hi_bit) {
  const size_t n = items.size();
  SPLINTCORE_ASSERT(lo_bit < hi_bit && hi_bit <= 64);
  if (n < 2) return;
  SPLINTCORE_ASSERT(scratch.size() >= n && n <= UINT32_MAX);
  if (n >= (size_t{1} << 16) && hi_bit - lo_bit >= 28) {
    top_digit_first(items.data(), scratch.data(), n, lo_bit, hi_bit);
  } else {
    lsd_to(items.data(), scratch.data(), n, lo_bit, hi_bit, items.data());
  }
}

void radix_sort(Span<KeyIndex> items, Span<KeyIndex> scratch) { lsd_radix_sort(items, scratch); }
void radix_sort(Span<uint64_t> items, Span<uint64_t> scratch) { lsd_radix_sort(items, scratch); }

Status radix_sort(Arena& arena, Span<KeyIndex> items) {
  ArenaScope scope(arena);
  KeyIndex* scratch = arena.allocate_array<KeyIndex>(items.size());
  if (scratch == nullptr && !items.empty()) return arena.exhausted_status();
  radix_sort(items, Span<KeyIndex>(scratch, items.size()));
  return Status::ok();
}

}  // namespace splintcore
