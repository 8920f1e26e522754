// The exact weld fed one triangle at a time (private to src/mesh and src/io): weld_exact() runs
// it over a soup, and the binary STL reader straight from its read buffer, so a file's
// triangles never sit in memory as soup.
//
// Vertex ids are handed out in order of first appearance (so they depend only on the corners,
// never on hashing). The table holds 1 + a vertex id per slot and is compared against the
// vertex positions (the float corners converted to double, exactly; -0 and +0 compare equal,
// and the positions get +0). It is allocated for the worst case (every corner a new vertex:
// weld_exact_bound's table) but only a power-of-two prefix sized for the vertices seen so far
// is used (cleared, touched); it doubles and is rebuilt from the positions as they grow, so a
// mesh with one vertex per two triangles touches a sixth of it.
#ifndef SPLINTCORE_SRC_MESH_EXACT_WELD_H
#define SPLINTCORE_SRC_MESH_EXACT_WELD_H

#include "splintcore/mesh.h"

namespace splintcore {

class ExactWelder {
 public:
  // Reserves the positions (for about one vertex per two triangles), then allocates the table;
  // false when the arena is exhausted. `triangle_count` <= (2^32 - 2) / 3.
  [[nodiscard]] bool init(Arena& arena, uint64_t triangle_count);
  // The same for at most `corners` corners (<= 2^32 - 2), about `expected` of them distinct.
  [[nodiscard]] bool init_corners(Arena& arena, uint64_t corners, uint64_t expected);

  // The id add() gives when the arena is exhausted (the positions could not grow).
  static constexpr uint32_t kFull = ~uint32_t{0};

  // Welds the three corners p[0..8] (finite floats) into `out`; false when the arena is
  // exhausted (the positions could not grow).
  [[nodiscard]] bool add(const float* p, Triangle* out) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t x = bits_of(p[3 * k]), y = bits_of(p[3 * k + 1]), z = bits_of(p[3 * k + 2]);
      const uint32_t id = vertex(x, y, z, hash_bits(x, y, z));
      if (id == kFull) return false;
      out->v[k] = id;
    }
    return true;
  }

  // The vertex id of the corner whose coordinates have the float bit patterns x, y, z (finite)
  // and hash_bits(x, y, z) `h`: a new id (the next) the first time; kFull when the arena is
  // exhausted. The binary STL reader welds straight from its buffer through this (one scalar
  // load per coordinate: copying a record's corners into an array costs a `rep movs` there).
  [[nodiscard]] uint32_t vertex(uint32_t x, uint32_t y, uint32_t z, uint64_t h) {
    return vertex_at(to_double(x), to_double(y), to_double(z), h);
  }

  // The hash of corner p (three floats): where its search begins (first_slot) and its tag.
  static uint64_t hash(const float* p) {
    return hash_bits(bits_of(p[0]), bits_of(p[1]), bits_of(p[2]));
  }
  // hash() of a corner given as its coordinates' float bit patterns.
  static uint64_t hash_bits(uint32_t x, uint32_t y, uint32_t z) {
    // Three odd multipliers and one fold (each coordinate's bits reach the high half, which
    // the fold brings down to the slot bits; the tag takes the high bits). Only the speed
    // depends on it: ids go by first appearance.
    const uint64_t h = uint64_t{key(x)} * 0x9e3779b97f4a7c15ull +
                       uint64_t{key(y)} * 0xc2b2ae3d27d4eb4full +
                       uint64_t{key(z)} * 0x165667b19e3779f9ull;
    return (h ^ (h >> 29)) * 0xbf58476d1ce4e5b9ull;
  }

  // The table slot where the search for a corner of hash h begins: callers prefetch the
  // slots of a triangle a few dozen ahead with __builtin_prefetch (GCC 12 deletes the
  // prefetches when they sit in a member function like this one).
  const uint32_t* first_slot(uint64_t h) const { return table_ + (h & mask_); }

  // Points `vertices` at the positions and gives back everything above them: the reserve's
  // unused end, or (when they outgrew it) everything above `marker`, where init() began, after
  // moving them down there. Never fails.
  void finish(Arena& arena, const Arena::Marker& marker, ArenaArray<Vec3>* vertices);

 private:
  static uint32_t bits_of(float f) {
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof(bits));
    return bits;
  }
  static double to_double(uint32_t bits) {
    float f;
    std::memcpy(&f, &bits, sizeof(f));
    return static_cast<double>(f);
  }
  static uint32_t key(uint32_t bits) {
    return bits == 0x80000000u ? 0u : bits;  // -0 welds with +0
  }

  // A slot holds 1 + the vertex id in its low id_bits_ bits and, above them, the top bits of
  // the corner's hash: most slots of other corners are passed over without reading their
  // position (which would be a cache miss each).
  // The search is inline (most corners are found: five in six of a closed mesh's); a new
  // vertex goes in out of line (add_vertex).
  uint32_t vertex_at(double x, double y, double z, uint64_t h) {
    const uint32_t tag = tag_of(h);
    uint64_t slot = h & mask_;
    for (;;) {
      const uint32_t entry = table_[slot];
      if (entry == 0) return add_vertex(x, y, z, tag, slot);
      if ((entry & ~id_mask_) == tag) {
        const Vec3& v = positions_.data()[(entry & id_mask_) - 1];
        if (v.x == x && v.y == y && v.z == z) return (entry & id_mask_) - 1;
      }
      slot = (slot + 1) & mask_;
    }
  }
  // A new vertex at x, y, z into the empty `slot` with `tag`: its id, or kFull.
  uint32_t add_vertex(double x, double y, double z, uint32_t tag, uint64_t slot);
  uint32_t tag_of(uint64_t h) const { return static_cast<uint32_t>(h >> 32) & ~id_mask_; }

  void grow();

  uint32_t* table_ = nullptr;
  uint64_t table_slots_ = 0;  // allocated (a power of two)
  uint64_t mask_ = 0;         // slots in use - 1
  uint64_t grow_at_ = 0;      // vertex count above which the slots in use double
  uint32_t id_mask_ = 0;      // the low bits that hold 1 + a vertex id (at most 3 T)
  ArenaArray<Vec3> positions_;
  Vec3* reserved_ = nullptr;  // where the positions were first reserved
  Arena::Marker after_reserve_;
};

// Slots of the exact weld's table for `corners` corners (a power of two, at least 1.5 a corner).
uint64_t exact_weld_table_slots(uint64_t corners);

// weld_exact() of an indexed mesh's triangles, in place: `mesh` (its coordinates float32
// values, finite) ends up with the vertices and triangles weld_exact() gives for its triangles
// as a soup (ids by first use in the triangles, unreferenced vertices dropped, -0 as +0), but
// the weld hashes each vertex once, not each corner, and no soup is made. The triangles'
// indices must be in range. Temporaries above the mesh are given back; the vertex array keeps
// its capacity. Arena: at most weld_indexed_exact_bound(vertex count). Errors: kArenaExhausted,
// kLimitExceeded (as weld_exact's; or 2^32 - 1 vertices or more), kCancelled.
Status weld_indexed_exact(const Context& ctx, Mesh* mesh);
uint64_t weld_indexed_exact_bound(uint64_t vertex_count);

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_MESH_EXACT_WELD_H
