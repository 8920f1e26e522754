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
}  // namespace

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
