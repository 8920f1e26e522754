// Union-find over arena arrays, deterministic: the smaller index always becomes the root, so
// the roots (and anything numbered by them) depend only on the unions made, not their order.
#ifndef SPLINTCORE_SRC_CORE_UNION_FIND_H
#define SPLINTCORE_SRC_CORE_UNION_FIND_H

#include "splintcore/core.h"

namespace splintcore {

class UnionFind {
 public:
  // Takes n entries from the arena, every one a set of its own; false when it is exhausted.
  [[nodiscard]] bool init(Arena& arena, uint32_t n) {
    if (!allocate(arena, n)) return false;
    reset();
    return true;
  }
  // Takes n entries from the arena without setting them (reset() does, before any other use):
  // for a union-find that is rarely needed, whose memory is then never touched.
  [[nodiscard]] bool allocate(Arena& arena, uint32_t n) {
    parent_ = arena.allocate_array<uint32_t>(n);
    if (parent_ == nullptr && n > 0) return false;
    size_ = n;
    return true;
  }
  // Every entry a set of its own.
  void reset() {
    for (uint32_t i = 0; i < size_; ++i) parent_[i] = i;
  }
  uint32_t find(uint32_t x) {
    SPLINTCORE_ASSERT(x < size_);
    uint32_t root = x;
    while (parent_[root] != root) root = parent_[root];
    while (parent_[x] != root) {  // path compression, iterative
      uint32_t next = parent_[x];
      parent_[x] = root;
      x = next;
    }
    return root;
  }
  // Returns true when a and b were in different sets.
  bool unite(uint32_t a, uint32_t b) {
    SPLINTCORE_ASSERT(a < size_ && b < size_);
    // One parent: one set already (the common case of neighbours, without the two finds).
    if (parent_[a] == parent_[b]) return false;
    uint32_t ra = find(a);
    uint32_t rb = find(b);
    if (ra == rb) return false;
    if (ra < rb) {
      parent_[rb] = ra;
    } else {
      parent_[ra] = rb;
    }
    return true;
  }
  // find(x) == x, without the walk: a root is its own parent.
  bool is_root(uint32_t x) const {
    SPLINTCORE_ASSERT(x < size_);
    return parent_[x] == x;
  }
  uint32_t size() const { return size_; }

 private:
  uint32_t* parent_ = nullptr;
  uint32_t size_ = 0;
};

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_CORE_UNION_FIND_H
