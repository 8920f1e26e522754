// Tiled iso-surface extraction by marching tetrahedra.
//
// Sources: Lorensen and Cline, "Marching cubes: a high resolution 3D surface construction
// algorithm", SIGGRAPH 1987 (the sweep); Doi and Koide, "An efficient method of triangulating
// equi-valued surfaces by using tetrahedral cells", IEICE Trans. 1991 (marching tetrahedra);
// Freudenthal, "Simplizialzerlegungen von beschraenkter Flachheit", Annals of Mathematics 1942
// and Kuhn, "Some combinatorial lemmas in topology", IBM J. 1960 (the subdivision of a cube into
// six tetrahedra along its diagonal, which is consistent across neighbouring cubes).
//
// Sweep: cell layers z = -1 .. nz-1 in order; a slab of sample layers is filled per call and
// the last layer is carried into the next slab. Edge vertex ids live in three per-layer tables
// (in-plane edges of the lower and upper sample layer of the current cells, and the edges that
// leave the lower layer upwards); the upper in-plane table becomes the lower one for the next
// cell layer. Nothing else is kept, so the output order is the global cell order whatever the
// slab size. See volume.h for the conventions.
#include <cmath>

#include "splintcore/volume.h"

namespace splintcore {

namespace {

constexpr uint32_t kNoVertex = ~uint32_t{0};
constexpr uint64_t kAlign = 16;

// --- the tetrahedra and their 16 cases ---------------------------------------------------------

// Cube corner k is at (k & 1, (k >> 1) & 1, (k >> 2) & 1). The six Kuhn tetrahedra are the
// chains 0 -> e_a -> e_a + e_b -> 7 over the axis permutations (a, b, c); listed positively
// oriented (det(p1 - p0, p2 - p0, p3 - p0) > 0): odd permutations have their last two swapped.
// Every edge of a chain joins a corner to a componentwise larger one.
constexpr uint8_t kTets[6][4] = {
    {0, 1, 3, 7},  // x y z (even)
    {0, 1, 7, 5},  // x z y (odd)
    {0, 2, 7, 3},  // y x z (odd)
    {0, 2, 6, 7},  // y z x (even)
    {0, 4, 5, 7},  // z x y (even)
    {0, 4, 7, 6},  // z y x (odd)
};

// The 19 edges of the Freudenthal cube (every pair of corners u < w with u's bits a subset of
// w's: 19 of the 28 pairs), numbered 0..18 by (u, w) in order; other entries unused.
constexpr int count_cell_edges() {
  int n = 0;
  for (unsigned u = 0; u < 8; ++u) {
    for (unsigned w = 0; w < 8; ++w) n += (u != w && (u & w) == u) ? 1 : 0;
  }
  return n;
}
struct CellEdges {
  uint8_t index[64];
};
constexpr CellEdges make_cell_edges() {
  CellEdges t{};
  uint8_t n = 0;
  for (unsigned u = 0; u < 8; ++u) {
    for (unsigned w = 0; w < 8; ++w) {
      t.index[u * 8 + w] = (u != w && (u & w) == u) ? n++ : 0;
    }
  }
  return t;
}
static_assert(count_cell_edges() == 19, "the Freudenthal cube has 19 edges");
constexpr CellEdges kCellEdges = make_cell_edges();
constexpr const uint8_t* kCellEdge = kCellEdges.index;

struct TetCase {
  uint8_t triangles = 0;
  uint8_t edge[2][3][2] = {};  // per triangle corner: the two tetrahedron vertices (local)
};
struct TetCases {
  TetCase c[16];
};

constexpr bool even_permutation(const uint8_t p[4]) {
  int inversions = 0;
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) inversions += p[i] > p[j] ? 1 : 0;
  }
  return (inversions & 1) == 0;
}

// For a positive tetrahedron (0,1,2,3), face (1,2,3) is counter-clockwise seen from outside,
// i.e. its normal points away from vertex 0; even permutations keep this. So with one inside
// vertex i and (i, j, k, l) even, the triangle (ij, ik, il) faces away from i (outward); with
// one outside vertex it is reversed; with inside {a, b}, outside {c, d}, (a, b, c, d) even, the
// quad (ac, ad, bd, bc) faces the outside pair.
constexpr TetCases make_tet_cases() {
  TetCases t{};
  constexpr uint8_t kEven[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 0, 1, 3}, {3, 0, 2, 1}};
  for (int m = 1; m < 15; ++m) {
    int count = 0;
    for (int i = 0; i < 4; ++i) count += (m >> i) & 1;
    TetCase& c = t.c[m];
    if (count == 1 || count == 3) {
      int lone = 0;
      for (int i = 0; i < 4; ++i) {
        if ((((m >> i) & 1) == 1) == (count == 1)) lone = i;
      }
      const uint8_t* e = kEven[lone];
      const int order[3] = {1, count == 1 ? 2 : 3, count == 1 ? 3 : 2};
      c.triangles = 1;
      for (int k = 0; k < 3; ++k) {
        c.edge[0][k][0] = e[0];
        c.edge[0][k][1] = e[order[k]];
      }
    } else {
      uint8_t p[4] = {0, 0, 0, 0};
      int in = 0, out = 2;
      for (int i = 0; i < 4; ++i) {
        if ((m >> i) & 1) {
          p[in++] = static_cast<uint8_t>(i);
        } else {
          p[out++] = static_cast<uint8_t>(i);
        }
      }
      if (!even_permutation(p)) {
        const uint8_t s = p[2];
        p[2] = p[3];
        p[3] = s;
      }
      const uint8_t a = p[0], b = p[1], cc = p[2], d = p[3];
      const uint8_t quad[4][2] = {{a, cc}, {a, d}, {b, d}, {b, cc}};
      const int split[2][3] = {{0, 1, 2}, {0, 2, 3}};
      c.triangles = 2;
      for (int tri = 0; tri < 2; ++tri) {
        for (int k = 0; k < 3; ++k) {
          c.edge[tri][k][0] = quad[split[tri][k]][0];
          c.edge[tri][k][1] = quad[split[tri][k]][1];
        }
      }
    }
  }
  return t;
}

constexpr TetCases kCases = make_tet_cases();

// --- sizes --------------------------------------------------------------------------------------

bool align_up(uint64_t v, uint64_t* out) {
  if (v > UINT64_MAX - (kAlign - 1)) return false;
  *out = (v + kAlign - 1) & ~(kAlign - 1);
  return true;
}

// Bits set in x (SWAR: without a popcount instruction in the baseline x86-64 and ARM targets
// the builtin becomes a library call, a tenth of the extraction's time).
inline uint64_t popcount64(uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ull);
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return (x * 0x0101010101010101ull) >> 56;
}

// 64-bit words of one row's inside bits: sample x at bit x + 1, the outside beyond both ends
// at bits 0 and nx + 1.
inline uint64_t bit_words(uint32_t nx) { return (uint64_t{nx} + 2 + 63) / 64; }

// Bytes of the fixed part of the working set (the sample buffer of layers + 1 layers with
// their inside bits, and the rank prefixes of ten kinds of edges: three in each of two
// planes, four upward) and of a full id pool (ten ids per grid point: what a layer could need
// at most); false on overflow.
bool working_parts(const VolumeGrid& g, uint32_t layers, uint64_t* samples, uint64_t* edges) {
  uint64_t layer = 0, s = 0, e = 0, pts = 0, bits = 0, prefix = 0;
  if (!checked_mul(g.nx, g.ny, &layer) || !checked_mul(layer, uint64_t{layers} + 1, &s) ||
      !checked_mul(s, 4, &s) || !align_up(s, &s)) {
    return false;
  }
  if (!checked_mul(bit_words(g.nx) * 8, g.ny, &bits) ||
      !checked_mul(bits, uint64_t{layers} + 1, &bits) || !align_up(bits, &bits) ||
      !checked_add(s, bits, &s)) {
    return false;
  }
  if (!checked_mul(bit_words(g.nx) * 8 * 10, uint64_t{g.ny} + 1, &prefix) ||
      !checked_add(s, prefix, &s)) {
    return false;
  }
  if (!checked_mul(uint64_t{g.nx} + 1, uint64_t{g.ny} + 1, &pts) || !checked_mul(pts, 40, &e) ||
      !align_up(e, &e)) {
    return false;
  }
  *samples = s;
  *edges = e;
  return true;
}

Status check_grid(const VolumeGrid& g) {
  if (g.nx == 0 || g.ny == 0 || g.nz == 0) {
    return make_error(StatusCode::kInvalidArgument, "marching cubes: empty grid (", g.nx, " x ",
                      g.ny, " x ", g.nz, " samples)");
  }
  if (!(g.spacing.x > 0) || !(g.spacing.y > 0) || !(g.spacing.z > 0) || !is_finite(g.spacing) ||
      !is_finite(g.origin)) {
    return make_error(StatusCode::kInvalidArgument,
                      "marching cubes: the grid spacing must be finite and > 0 on each axis and "
                      "the origin finite (spacing ",
                      g.spacing.x, ", ", g.spacing.y, ", ", g.spacing.z, ")");
  }
  return Status::ok();
}

// --- the sweep ----------------------------------------------------------------------------------

struct Corner {
  float value;
  bool real;    // a sample of the grid (false: beyond the border)
  bool inside;  // real && value < iso
};

// The inside bits of one sample plane: row y (0 <= y < ny) at bits + y * words; null bits
// for a plane beyond the grid (all outside).
struct PlaneBits {
  const uint64_t* bits = nullptr;
  uint32_t ny = 0;
  uint64_t words = 0;
  uint64_t word(int64_t y, uint64_t w) const {
    if (bits == nullptr || y < 0 || y >= static_cast<int64_t>(ny) || w >= words) return 0;
    return bits[static_cast<uint64_t>(y) * words + w];
  }
  // Word w of the row shifted down by one bit: bit p holds sample p (bit p + 1 of the row).
  uint64_t next(int64_t y, uint64_t w) const { return (word(y, w) >> 1) | (word(y, w + 1) << 63); }
};

// Which grid edges the surface crosses, from the inside bits (a bit differs at the two ends),
// and their vertex ids, stored only for crossed edges. Edges are grouped in sets: the three
// in-plane kinds (+x, +y, +x+y) of one sample plane, or the four kinds (+z, +x+z, +y+z,
// +x+y+z) leaving a plane upwards. Point (px, py), px in 0 .. nx and py in 0 .. ny, is the
// edge's lower sample (px - 1, py - 1); bit px of word row py. An edge's id slot is found by
// rank: prefix[(kind * (ny + 1) + py) * words + w] counts the crossed edges before word w,
// popcount counts those before the bit.
struct EdgeSet {
  uint64_t* prefix = nullptr;
  uint32_t* ids = nullptr;
  uint64_t count = 0;
  uint64_t begin = 0;  // position of ids in the pool
};

// The crossed-edge word of kind `kind` at row py, word w. In a plane: lo is the plane (hi
// unused). Upward: from plane lo to plane hi.
inline uint64_t plane_word(const PlaneBits& p, unsigned kind, int64_t py, uint64_t w) {
  const int64_t y = py - 1;
  const uint64_t a = p.word(y, w);
  switch (kind) {
    case 0: return a ^ p.next(y, w);       // +x
    case 1: return a ^ p.word(y + 1, w);   // +y
    default: return a ^ p.next(y + 1, w);  // +x+y
  }
}
inline uint64_t upward_word(const PlaneBits& lo, const PlaneBits& hi, unsigned kind, int64_t py,
                            uint64_t w) {
  const int64_t y = py - 1;
  const uint64_t a = lo.word(y, w);
  switch (kind) {
    case 0: return a ^ hi.word(y, w);       // +z
    case 1: return a ^ hi.next(y, w);       // +x+z
    case 2: return a ^ hi.word(y + 1, w);   // +y+z
    default: return a ^ hi.next(y + 1, w);  // +x+y+z
  }
}

struct Sweep {
  const VolumeGrid* grid = nullptr;
  double iso = 0;
  double margin = kEdgeMargin;
  const MarchingCubesVisitor* visitor = nullptr;
  uint64_t words = 0;          // bit words per row
  PlaneBits lo_bits, hi_bits;  // sample planes cz and cz + 1 of the current cells
  EdgeSet plane_lo, plane_hi, upward;
  uint64_t* spare_prefix = nullptr;  // the prefix buffer the next plane set takes
  uint32_t* pool = nullptr;          // vertex ids of the crossed edges of the three sets
  uint64_t pool_size = 0;
  uint64_t pool_next = 0;   // where the next set is placed
  bool pool_short = false;  // a set found no room (place_ids failed)
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  int64_t cz = 0;
};

inline Corner corner_at(const float* row, int64_t x, uint32_t nx, double iso) {
  if (row == nullptr || x < 0 || x >= static_cast<int64_t>(nx)) return {0.0f, false, false};
  const float v = row[x];
  return {v, true, static_cast<double>(v) < iso};
}

// The vertex on the edge from corner `lo` to corner `hi` of cell (cx, cy, cz).
inline Vec3 edge_vertex(const Sweep& s, int64_t cx, int64_t cy, int64_t cz, unsigned lo, unsigned d,
                        const Corner& f0, const Corner& f1) {
  double t;
  if (!f0.real) {
    t = 1.0 - s.margin;
  } else if (!f1.real) {
    t = s.margin;
  } else {
    const double a = static_cast<double>(f0.value), b = static_cast<double>(f1.value);
    t = (s.iso - a) / (b - a);
    t = t < s.margin ? s.margin : (t > 1.0 - s.margin ? 1.0 - s.margin : t);
  }
  const VolumeGrid& g = *s.grid;
  const double px = static_cast<double>(cx + static_cast<int64_t>(lo & 1u));
  const double py = static_cast<double>(cy + static_cast<int64_t>((lo >> 1) & 1u));
  const double pz = static_cast<double>(cz + static_cast<int64_t>((lo >> 2) & 1u));
  return {(d & 1u) ? g.origin.x + g.spacing.x * (px + t) : g.origin.x + g.spacing.x * px,
          (d & 2u) ? g.origin.y + g.spacing.y * (py + t) : g.origin.y + g.spacing.y * py,
          (d & 4u) ? g.origin.z + g.spacing.z * (pz + t) : g.origin.z + g.spacing.z * pz};
}

// One cell: corners[k] for cube corner k. Emits its tetrahedra's triangles.
Status march_cell(Sweep& s, int64_t cx, int64_t cy, int64_t cz, const Corner corners[8]) {
  const uint64_t row_count = uint64_t{s.grid->ny} + 1;
  // The cell's edges (lower corner u, upper w: index u * 8 + w) met so far in this cell: the
  // six tetrahedra share them, so each edge's id and position are found once per cell.
  uint32_t known = 0;  // bit e of the 19 edges below: found
  uint32_t ids[19];
  Vec3 pos[19];
  for (int tet = 0; tet < 6; ++tet) {
    const uint8_t* v = kTets[tet];
    unsigned m = 0;
    for (unsigned i = 0; i < 4; ++i) m |= corners[v[i]].inside ? (1u << i) : 0u;
    const TetCase& c = kCases.c[m];
    for (int tri = 0; tri < c.triangles; ++tri) {
      Triangle out{};
      Vec3 p[3];
      for (int k = 0; k < 3; ++k) {
        unsigned u = v[c.edge[tri][k][0]], w = v[c.edge[tri][k][1]];
        if ((u & w) != u) {  // u must be the lower endpoint (its bits a subset of w's)
          const unsigned swap = u;
          u = w;
          w = swap;
        }
        const unsigned e = kCellEdge[u * 8 + w];
        if ((known >> e) & 1u) {
          p[k] = pos[e];
          out.v[k] = ids[e];
          continue;
        }
        const unsigned d = u ^ w;
        const uint64_t px = static_cast<uint64_t>(cx + 1 + static_cast<int64_t>(u & 1u));
        const uint64_t py = static_cast<uint64_t>(cy + 1 + static_cast<int64_t>((u >> 1) & 1u));
        const uint64_t w64 = px >> 6;
        const uint64_t below = (uint64_t{1} << (px & 63)) - 1;
        const EdgeSet* set;
        unsigned kind;
        uint64_t word;
        if (d & 4u) {
          set = &s.upward;
          kind = d & 3u;
          word = upward_word(s.lo_bits, s.hi_bits, kind, static_cast<int64_t>(py), w64);
        } else {
          set = (u & 4u) ? &s.plane_hi : &s.plane_lo;
          kind = d - 1;
          word = plane_word((u & 4u) ? s.hi_bits : s.lo_bits, kind, static_cast<int64_t>(py), w64);
        }
        const uint64_t rank =
            set->prefix[(kind * (row_count) + py) * s.words + w64] + popcount64(word & below);
        SPLINTCORE_ASSERT(((word >> (px & 63)) & 1u) != 0 && rank < set->count);
        uint32_t* slot = &set->ids[rank];
        p[k] = edge_vertex(s, cx, cy, cz, u, d, corners[u], corners[w]);
        if (*slot == kNoVertex) {
          if (s.vertices >= kNoVertex) {
            return make_error(StatusCode::kLimitExceeded, "marching cubes: more than ",
                              uint64_t{kNoVertex}, " vertices (32-bit vertex ids)");
          }
          *slot = static_cast<uint32_t>(s.vertices++);
          if (s.visitor->vertex != nullptr) {
            SPLINTCORE_RETURN_IF_ERROR(s.visitor->vertex(s.visitor->user, *slot, p[k]));
          }
        }
        out.v[k] = *slot;
        known |= 1u << e;
        ids[e] = *slot;
        pos[e] = p[k];
      }
      ++s.triangles;
      if (s.visitor->triangle != nullptr) {
        SPLINTCORE_RETURN_IF_ERROR(s.visitor->triangle(s.visitor->user, out, p[0], p[1], p[2]));
      }
    }
  }
  return Status::ok();
}

// The float t with (double)v < iso exactly when v < t, for every float v: the least float not
// below iso (comparing in float then needs no conversion per sample).
float float_threshold(double iso) {
  constexpr double kMaxFloat = 3.4028234663852886e38;
  if (iso > kMaxFloat) return HUGE_VALF;    // every finite sample is below
  if (iso < -kMaxFloat) return -HUGE_VALF;  // none is
  float t = static_cast<float>(iso);        // nearest
  if (static_cast<double>(t) < iso) {
    uint32_t bits;
    std::memcpy(&bits, &t, 4);
    // The next float up (iso is finite and within float range here, or t is infinite).
    if ((bits & 0x80000000u) == 0) {
      ++bits;
    } else if (bits == 0x80000000u) {
      bits = 1;  // -0 -> the least positive
    } else {
      --bits;
    }
    std::memcpy(&t, &bits, 4);
  }
  return t;
}

// The inside bits of one sample layer (bit x + 1 of row y: sample (x, y) < iso), in the same
// pass as the finite check: returns the largest exponent field seen (0x7f800000 when some
// sample is NaN or infinite; its bit is then meaningless and the caller stops).
uint32_t classify_layer(const float* layer, uint32_t nx, uint32_t ny, float threshold,
                        uint64_t* bits) {
  const uint64_t words = bit_words(nx);
  uint32_t lane[4] = {0, 0, 0, 0};
  auto exponent = [](const float* v, uint32_t* l) {
    uint32_t w;
    std::memcpy(&w, v, 4);
    const uint32_t e = w & 0x7f800000u;
    *l = *l > e ? *l : e;
  };
  for (uint32_t y = 0; y < ny; ++y) {
    const float* row = layer + uint64_t{y} * nx;
    uint64_t* out = bits + uint64_t{y} * words;
    // Word w holds samples x = 64 w - 1 .. 64 w + 62 at bits 0 .. 63.
    for (uint64_t w = 0; w < words; ++w) {
      const int64_t x0 = static_cast<int64_t>(w * 64) - 1;
      const int64_t from = x0 < 0 ? 0 : x0;
      const int64_t to = x0 + 64 < static_cast<int64_t>(nx) ? x0 + 64 : static_cast<int64_t>(nx);
      uint64_t word = 0;
      int64_t x = from;
      for (; x + 4 <= to; x += 4) {
        const uint64_t b0 = static_cast<uint64_t>(row[x] < threshold);
        const uint64_t b1 = static_cast<uint64_t>(row[x + 1] < threshold);
        const uint64_t b2 = static_cast<uint64_t>(row[x + 2] < threshold);
        const uint64_t b3 = static_cast<uint64_t>(row[x + 3] < threshold);
        word |= (b0 | (b1 << 1) | (b2 << 2) | (b3 << 3)) << (x - x0);
        exponent(row + x, &lane[0]);
        exponent(row + x + 1, &lane[1]);
        exponent(row + x + 2, &lane[2]);
        exponent(row + x + 3, &lane[3]);
      }
      for (; x < to; ++x) {
        word |= static_cast<uint64_t>(row[x] < threshold) << (x - x0);
        exponent(row + x, &lane[0]);
      }
      out[w] = word;
    }
  }
  uint32_t top = lane[0];
  for (int k = 1; k < 4; ++k) top = top > lane[k] ? top : lane[k];
  return top;
}

// Cell layer cz: samples of layer cz in `lo`, of cz + 1 in `hi` (null: beyond the grid), and
// their inside bits. Only cells whose eight corners are not all inside or all outside are
// visited (found 64 at a time from the bits); they are visited in the same order as a full
// scan would, so the output does not change.
// Ranks the crossed edges of `kinds` kinds into set->prefix (word(kind, py, w) gives them).
template <class WordFn>
void rank_edges(const Sweep& s, EdgeSet* set, unsigned kinds, WordFn word) {
  const uint64_t rows = uint64_t{s.grid->ny} + 1;
  uint64_t n = 0;
  for (unsigned kind = 0; kind < kinds; ++kind) {
    for (uint64_t py = 0; py < rows; ++py) {
      uint64_t* prefix = set->prefix + (kind * rows + py) * s.words;
      for (uint64_t w = 0; w < s.words; ++w) {
        prefix[w] = n;
        n += popcount64(word(kind, static_cast<int64_t>(py), w));
      }
    }
  }
  set->count = n;
}

inline bool overlaps(uint64_t a, uint64_t n, const EdgeSet& e) {
  return n > 0 && e.count > 0 && a < e.begin + e.count && e.begin < a + n;
}

// Places set's ids in the pool clear of the live sets, all kNoVertex.
Status place_ids(Sweep& s, EdgeSet* set, const EdgeSet& keep1, const EdgeSet& keep2) {
  const uint64_t n = set->count;
  const uint64_t candidates[4] = {s.pool_next, 0, keep1.begin + keep1.count,
                                  keep2.begin + keep2.count};
  for (uint64_t at : candidates) {
    if (at <= s.pool_size && n <= s.pool_size - at && !overlaps(at, n, keep1) &&
        !overlaps(at, n, keep2)) {
      set->begin = at;
      set->ids = s.pool + at;
      for (uint64_t i = 0; i < n; ++i) set->ids[i] = kNoVertex;
      s.pool_next = at + n;
      return Status::ok();
    }
  }
  const uint64_t live = keep1.count + keep2.count;
  s.pool_short = true;
  return make_error(StatusCode::kArenaExhausted, "marching cubes: cell layer ", s.cz,
                    " needs ids for ", n, " crossed grid edges beside the ", live,
                    " still in use, and the id pool holds ", s.pool_size,
                    " (4 bytes each); increase the memory cap by at least ",
                    4 * (n + live > s.pool_size ? n + live - s.pool_size : n), " bytes");
}

// Cell layer cz: samples of layer cz in `lo`, of cz + 1 in `hi` (null: beyond the grid), and
// their inside bits. Only cells whose eight corners are not all inside or all outside are
// visited (found 64 at a time from the bits); they are visited in the same order as a full
// scan would, so the output does not change.
Status march_layer(Sweep& s, int64_t cz, const float* lo, const float* hi, const uint64_t* lo_bits,
                   const uint64_t* hi_bits) {
  const uint32_t nx = s.grid->nx, ny = s.grid->ny;
  s.cz = cz;
  s.lo_bits = PlaneBits{lo != nullptr ? lo_bits : nullptr, ny, s.words};
  s.hi_bits = PlaneBits{hi != nullptr ? hi_bits : nullptr, ny, s.words};
  {
    // The upper plane's edges become the lower's; the old lower's prefix buffer is reused.
    uint64_t* free_prefix = s.plane_lo.prefix;
    s.plane_lo = s.plane_hi;
    s.plane_hi = EdgeSet{};
    s.plane_hi.prefix = free_prefix;
    const PlaneBits& h = s.hi_bits;
    rank_edges(s, &s.plane_hi, 3,
               [&](unsigned kind, int64_t py, uint64_t w) { return plane_word(h, kind, py, w); });
    SPLINTCORE_RETURN_IF_ERROR(place_ids(s, &s.plane_hi, s.plane_lo, EdgeSet{}));
    const PlaneBits& l = s.lo_bits;
    rank_edges(s, &s.upward, 4, [&](unsigned kind, int64_t py, uint64_t w) {
      return upward_word(l, h, kind, py, w);
    });
    SPLINTCORE_RETURN_IF_ERROR(place_ids(s, &s.upward, s.plane_lo, s.plane_hi));
  }
  const uint64_t words = s.words;
  for (int64_t cy = -1; cy < static_cast<int64_t>(ny); ++cy) {
    // Rows (y, z) of the four columns: column c = dy + 2 dz holds corners k = x + 2c.
    const float* rows[4];
    const uint64_t* bit_rows[4];
    for (int c = 0; c < 4; ++c) {
      const int64_t y = cy + (c & 1);
      const float* layer = (c & 2) ? hi : lo;
      const uint64_t* layer_bits = (c & 2) ? hi_bits : lo_bits;
      const bool real = layer != nullptr && y >= 0 && y < static_cast<int64_t>(ny);
      rows[c] = real ? layer + static_cast<uint64_t>(y) * nx : nullptr;
      bit_rows[c] = real ? layer_bits + static_cast<uint64_t>(y) * words : nullptr;
    }
    if (rows[0] == nullptr && rows[1] == nullptr && rows[2] == nullptr && rows[3] == nullptr) {
      continue;  // all outside
    }
    // Cell cx has its corners at bits cx + 1 and cx + 2; it is mixed unless all eight are set
    // (all inside) or all clear. mixed bit p stands for the cell with lower corner bit p.
    uint64_t all_next = 0, any_next = 0;
    auto load = [&](uint64_t w, uint64_t* all, uint64_t* any) {
      uint64_t a = ~uint64_t{0}, o = 0;
      for (int c = 0; c < 4; ++c) {
        const uint64_t v = (bit_rows[c] != nullptr && w < words) ? bit_rows[c][w] : 0;
        a &= v;
        o |= v;
      }
      *all = a;
      *any = o;
    };
    load(0, &all_next, &any_next);
    for (uint64_t w = 0; w < words; ++w) {
      const uint64_t all = all_next, any = any_next;
      load(w + 1, &all_next, &any_next);
      // The corner above bit p is bit p + 1 (the next word's bit 0 for p = 63).
      const uint64_t all_up = (all >> 1) | (all_next << 63);
      const uint64_t any_up = (any >> 1) | (any_next << 63);
      uint64_t mixed = ~((all & all_up) | ~(any | any_up));
      // Lower corner bits 0 .. nx: cells -1 .. nx - 1.
      const uint64_t first_bit = w * 64;
      const uint64_t last_bit = uint64_t{nx};  // inclusive
      if (first_bit + 63 > last_bit) {
        const uint64_t keep = last_bit >= first_bit ? last_bit - first_bit + 1 : 0;
        mixed &= keep >= 64 ? ~uint64_t{0} : ((uint64_t{1} << keep) - 1);
      }
      while (mixed != 0) {
        const unsigned b = static_cast<unsigned>(__builtin_ctzll(mixed));
        mixed &= mixed - 1;
        const int64_t cx = static_cast<int64_t>(first_bit + b) - 1;
        Corner corners[8];
        for (int c = 0; c < 4; ++c) {
          corners[2 * c] = corner_at(rows[c], cx, nx, s.iso);
          corners[2 * c + 1] = corner_at(rows[c], cx + 1, nx, s.iso);
        }
        SPLINTCORE_RETURN_IF_ERROR(march_cell(s, cx, cy, cz, corners));
      }
    }
  }
  return Status::ok();
}

uint32_t choose_layers(const Arena& arena, const VolumeGrid& grid, uint32_t requested,
                       uint64_t share_divisor) {
  if (requested != 0) return requested < grid.nz ? requested : grid.nz;
  const uint64_t free_bytes = arena.cap() > arena.used() ? arena.cap() - arena.used() : 0;
  const uint64_t budget = free_bytes / share_divisor;
  uint32_t best = 1;
  const uint32_t limit =
      grid.nz < kMarchingCubesDefaultLayers ? grid.nz : kMarchingCubesDefaultLayers;
  for (uint32_t k = 2; k <= limit; ++k) {
    const uint64_t need = marching_cubes_bound(grid, k);
    if (need == 0 || need > budget) break;
    best = k;
  }
  return best;
}

// The checks of a sweep's arguments (no memory needed).
Status check_sweep_input(const VolumeGrid& grid, const LayerSource& source,
                         const MarchingCubesOptions& options) {
  SPLINTCORE_RETURN_IF_ERROR(check_grid(grid));
  if (!is_finite(options.iso)) {
    return make_error(StatusCode::kInvalidArgument, "marching cubes: the iso value is not finite");
  }
  if (!(options.edge_margin >= kEdgeMargin && options.edge_margin <= 0.25)) {
    return make_error(StatusCode::kInvalidArgument, "marching cubes: the edge margin must be in [",
                      kEdgeMargin, ", 0.25], not ", options.edge_margin);
  }
  if (source.fill == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "marching cubes: no layer source");
  }
  return Status::ok();
}

// The least free arena a sweep can run in (one layer per slab, no id pool), or an error that
// names it.
Status check_free_arena(const Arena& arena, const VolumeGrid& grid) {
  uint64_t minimum = 0;
  {
    uint64_t fixed = 0, pool = 0;
    if (working_parts(grid, 1, &fixed, &pool)) minimum = fixed + kAlign;
  }
  if (minimum == 0 || minimum > SIZE_MAX) {
    return make_error(StatusCode::kLimitExceeded, "marching cubes: a layer of ", grid.nx, " x ",
                      grid.ny, " samples is too large to address");
  }
  const uint64_t free_bytes = arena.cap() > arena.used() ? arena.cap() - arena.used() : 0;
  if (free_bytes < minimum) {
    uint64_t total = 0;
    if (!checked_add(arena.used(), minimum, &total)) total = UINT64_MAX;
    return make_error(StatusCode::kArenaExhausted, "marching cubes: needs at least ", minimum,
                      " bytes of free arena for one layer of ", grid.nx, " x ", grid.ny, " cells, ",
                      free_bytes, " are free (cap ", arena.cap(), ", in use ", arena.used(),
                      "); increase the memory cap to at least ", total, " bytes");
  }
  return Status::ok();
}

// The working set of a sweep. The slab's sample buffer: slot j holds sample layer
// next_z - 1 + j (slot 0: carried from the last slab), with the layers' inside bits; the
// rank prefixes of the three edge sets; the id pool.
struct Slab {
  float* samples = nullptr;
  uint64_t* bits = nullptr;
  uint64_t layer_floats = 0;  // samples per layer
  uint64_t layer_words = 0;   // bit words per layer
  uint64_t* prefix = nullptr;
  uint64_t prefix_words = 0;  // per edge kind
  uint32_t* pool = nullptr;
  uint64_t pool_ids = 0;
};

// Allocates the working set: the slab (`layers` + 1 layers), the prefix buffers (zeroed) and
// the id pool: ten ids per grid point when the budget allows (no layer can need more), else
// what the budget leaves (a layer that needs more is a clean error naming the need).
Status allocate_working_set(Arena& arena, const VolumeGrid& grid, uint32_t layers,
                            uint64_t edge_bytes, uint64_t share_divisor, uint64_t pool_limit,
                            Slab* slab) {
  slab->layer_floats = uint64_t{grid.nx} * grid.ny;
  slab->layer_words = bit_words(grid.nx) * grid.ny;
  const uint64_t prefix_words = bit_words(grid.nx) * (uint64_t{grid.ny} + 1);
  slab->samples =
      arena.allocate_array<float>(static_cast<size_t>(slab->layer_floats * (layers + 1)));
  slab->bits =
      slab->samples == nullptr
          ? nullptr
          : arena.allocate_array<uint64_t>(static_cast<size_t>(slab->layer_words * (layers + 1)));
  uint64_t* prefix = slab->bits == nullptr
                         ? nullptr
                         : arena.allocate_array<uint64_t>(static_cast<size_t>(prefix_words * 10));
  if (prefix == nullptr) return arena.exhausted_status();
  uint64_t pool_ids = edge_bytes / 4;
  if (pool_limit != 0 && pool_limit < pool_ids) pool_ids = pool_limit;
  {
    const uint64_t now_free = arena.cap() > arena.used() ? arena.cap() - arena.used() : 0;
    const uint64_t budget = now_free / share_divisor;
    const uint64_t fit = budget > kAlign ? (budget - kAlign) / 4 : 0;
    if (fit < pool_ids) pool_ids = fit;
  }
  uint32_t* pool =
      pool_ids == 0 ? nullptr : arena.allocate_array<uint32_t>(static_cast<size_t>(pool_ids));
  if (pool_ids > 0 && pool == nullptr) return arena.exhausted_status();
  for (uint64_t i = 0; i < prefix_words * 10; ++i) prefix[i] = 0;
  slab->prefix = prefix;
  slab->prefix_words = prefix_words;
  slab->pool = pool;
  slab->pool_ids = pool_ids;
  return Status::ok();
}

// Fills slots 1 .. n of the slab with sample layers next_z .. next_z + n - 1 and classifies
// them, with the finite check in one pass (the position only when something is wrong).
Status fill_slab(const LayerSource& source, const VolumeGrid& grid, float threshold,
                 uint32_t next_z, uint32_t n, const Slab& slab) {
  const uint64_t layer_floats = slab.layer_floats;
  float* fresh = slab.samples + layer_floats;
  SPLINTCORE_RETURN_IF_ERROR(source.fill(
      source.user, next_z, next_z + n, Span<float>(fresh, static_cast<size_t>(layer_floats * n))));
  uint32_t exponent_top = 0;
  for (uint32_t j = 1; j <= n; ++j) {
    const uint32_t e = classify_layer(slab.samples + layer_floats * j, grid.nx, grid.ny, threshold,
                                      slab.bits + slab.layer_words * j);
    exponent_top = exponent_top > e ? exponent_top : e;
  }
  for (uint64_t i = 0; exponent_top == 0x7f800000u && i < layer_floats * n; ++i) {
    if (!is_finite(fresh[i])) {
      const uint64_t x = i % grid.nx, y = (i / grid.nx) % grid.ny;
      const uint64_t z = next_z + i / layer_floats;
      return make_error(StatusCode::kNonFinite, "marching cubes: sample (", x, ", ", y, ", ", z,
                        ") is not finite (NaN or infinity)")
          .at_index(z * layer_floats + i % layer_floats);
    }
  }
  return Status::ok();
}

// Marches the cell layers of a filled slab (from next_z - 1, the layer below the slab's
// first, up to its last, or the grid's last), then carries its top layer to slot 0.
Status march_slab(Sweep& s, uint32_t next_z, uint32_t n, const Slab& slab) {
  const int64_t nz = s.grid->nz;
  const uint64_t layer_floats = slab.layer_floats, layer_words = slab.layer_words;
  const int64_t first = static_cast<int64_t>(next_z) - 1;
  const int64_t last = static_cast<int64_t>(next_z) + n == nz ? nz - 1 : first + n - 1;
  for (int64_t cz = first; cz <= last; ++cz) {
    const int64_t slot = cz - first;  // layer cz is in slot cz - (next_z - 1)
    const float* lo = cz < 0 ? nullptr : slab.samples + static_cast<uint64_t>(slot) * layer_floats;
    const float* hi =
        cz + 1 >= nz ? nullptr : slab.samples + static_cast<uint64_t>(slot + 1) * layer_floats;
    const uint64_t* lo_bits = slab.bits + static_cast<uint64_t>(slot) * layer_words;
    SPLINTCORE_RETURN_IF_ERROR(march_layer(s, cz, lo, hi, lo_bits, lo_bits + layer_words));
    if (s.visitor->layer_done != nullptr) {
      SPLINTCORE_RETURN_IF_ERROR(s.visitor->layer_done(s.visitor->user, cz));
    }
  }
  std::memcpy(slab.samples, slab.samples + layer_floats * n, static_cast<size_t>(layer_floats * 4));
  std::memcpy(slab.bits, slab.bits + layer_words * n, static_cast<size_t>(layer_words * 8));
  return Status::ok();
}

Status run_sweep(const Context& ctx, const VolumeGrid& grid, const LayerSource& source,
                 const MarchingCubesOptions& options, const MarchingCubesVisitor& visitor,
                 uint64_t share_divisor, MarchingCubesStats* stats) {
  SPLINTCORE_RETURN_IF_ERROR(check_sweep_input(grid, source, options));
  SPLINTCORE_ASSERT(ctx.arena != nullptr);
  Arena& arena = *ctx.arena;
  SPLINTCORE_RETURN_IF_ERROR(check_free_arena(arena, grid));
  const uint32_t layers = choose_layers(arena, grid, options.layers_per_tile, share_divisor);
  uint64_t sample_bytes = 0, edge_bytes = 0;
  if (!working_parts(grid, layers, &sample_bytes, &edge_bytes) || sample_bytes > SIZE_MAX) {
    return make_error(StatusCode::kLimitExceeded, "marching cubes: a slab of ", layers,
                      " layers is too large to address");
  }
  // Not rewound here: the mesh variant's log grows above the working set (callers rewind).
  Slab slab;
  SPLINTCORE_RETURN_IF_ERROR(allocate_working_set(arena, grid, layers, edge_bytes, share_divisor,
                                                  options.pool_ids, &slab));
  Sweep s;
  s.grid = &grid;
  s.iso = options.iso;
  s.margin = options.edge_margin;
  s.visitor = &visitor;
  s.words = bit_words(grid.nx);
  s.plane_lo.prefix = slab.prefix;
  s.plane_hi.prefix = slab.prefix + slab.prefix_words * 3;
  s.upward.prefix = slab.prefix + slab.prefix_words * 6;
  s.pool = slab.pool;
  s.pool_size = slab.pool_ids;

  uint32_t fill_calls = 0;
  const float threshold = float_threshold(options.iso);
  for (uint32_t next_z = 0; next_z < grid.nz;) {
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "marching cubes", next_z, grid.nz));
    const uint32_t n = grid.nz - next_z < layers ? grid.nz - next_z : layers;
    SPLINTCORE_RETURN_IF_ERROR(fill_slab(source, grid, threshold, next_z, n, slab));
    ++fill_calls;
    const Status marched = march_slab(s, next_z, n, slab);
    if (!marched.is_ok()) {
      if (stats != nullptr) stats->pool_short = s.pool_short;
      return marched;
    }
    next_z += n;
  }
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "marching cubes", grid.nz, grid.nz));
  if (stats != nullptr) {
    stats->vertices = s.vertices;
    stats->triangles = s.triangles;
    stats->layers_per_tile = layers;
    stats->fill_calls = fill_calls;
    stats->working_set_bytes = sample_bytes + edge_bytes;
  }
  return Status::ok();
}

// --- the mesh variant: an output log, split into the mesh arrays at the end ---------------------
//
// The log is one growing array at the top of the arena (it extends in place): per triangle its
// three ids, then the positions (6 words each) of the vertices it introduced, in id order.

constexpr size_t kLogGrowthWords = 1024;

struct MeshLog {
  ArenaArray<uint32_t> words;
  Vec3 pending[3];
  uint32_t pending_count = 0;
  uint64_t vertices = 0;
  uint64_t triangles = 0;
};

Status log_vertex(void* user, uint32_t, const Vec3& position) {
  MeshLog& log = *static_cast<MeshLog*>(user);
  SPLINTCORE_ASSERT(log.pending_count < 3);
  log.pending[log.pending_count++] = position;
  return Status::ok();
}

Status log_triangle(void* user, const Triangle& t, const Vec3&, const Vec3&, const Vec3&) {
  MeshLog& log = *static_cast<MeshLog*>(user);
  const size_t start = log.words.size();
  const size_t need = start + 3 + 6 * size_t{log.pending_count};
  if (need > log.words.capacity()) {
    // Amortised growth (resize() alone grows to the exact size: a copy each time the array
    // cannot extend in place), by an eighth so that the slack stays small under a tight cap;
    // the exact size when the larger request does not fit.
    Arena& arena = *log.words.arena();
    if (!log.words.reserve(need + need / 8 + kLogGrowthWords)) {
      arena.forget_failure();
      if (!log.words.reserve(need)) return arena.exhausted_status();
    }
  }
  if (!log.words.resize(need)) return log.words.arena()->exhausted_status();
  uint32_t* w = log.words.data() + start;
  std::memcpy(w, t.v, 12);
  std::memcpy(w + 3, log.pending, 24 * size_t{log.pending_count});
  log.vertices += log.pending_count;
  log.pending_count = 0;
  ++log.triangles;
  return Status::ok();
}

}  // namespace

uint64_t marching_cubes_bound(const VolumeGrid& grid, uint32_t layers) {
  if (grid.nx == 0 || grid.ny == 0 || layers == 0) return 0;
  uint64_t samples = 0, edges = 0, total = 0;
  if (!working_parts(grid, layers, &samples, &edges) || !checked_add(samples, edges, &total) ||
      !checked_add(total, kAlign, &total)) {
    return 0;
  }
  return total;
}

Status marching_cubes_memory(const VolumeGrid& grid, MarchingCubesMemory* out) {
  if (grid.nx == 0 || grid.ny == 0 || grid.nz == 0) return check_grid(grid);
  const uint32_t layers =
      grid.nz < kMarchingCubesDefaultLayers ? grid.nz : kMarchingCubesDefaultLayers;
  uint64_t minimum = 0;
  {
    uint64_t fixed = 0, pool = 0;
    if (working_parts(grid, 1, &fixed, &pool)) minimum = fixed + kAlign;
  }
  const uint64_t comfortable = marching_cubes_bound(grid, layers);
  if (minimum == 0 || comfortable == 0) {
    return make_error(StatusCode::kLimitExceeded, "marching cubes: a grid of ", grid.nx, " x ",
                      grid.ny, " samples per layer overflows 64-bit sizes");
  }
  out->minimum = minimum;
  out->comfortable = comfortable;
  out->comfortable_layers = layers;
  return Status::ok();
}

uint64_t marching_cubes_mesh_extra_bound(uint64_t vertex_count, uint64_t triangle_count) {
  // The log (24 V + 12 T, with up to an eighth and 4 KiB of growth slack), the triangle copy
  // (12 T) and alignment padding.
  uint64_t v = 0, t = 0, log = 0, copy = 0, total = 0;
  if (!checked_mul(vertex_count, 24, &v) || !checked_mul(triangle_count, 12, &t) ||
      !checked_add(v, t, &log) || !checked_add(log, log / 8 + 4 * kLogGrowthWords, &log) ||
      !checked_add(log, t, &copy) || !checked_add(copy, 4 * kAlign, &total)) {
    return UINT64_MAX;
  }
  return total;
}

Status marching_cubes(const Context& ctx, const VolumeGrid& grid, const LayerSource& source,
                      const MarchingCubesOptions& options, const MarchingCubesVisitor& visitor,
                      MarchingCubesStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr);
  ArenaScope scope(*ctx.arena);
  return run_sweep(ctx, grid, source, options, visitor, 1, stats);
}

Status marching_cubes_mesh(const Context& ctx, const VolumeGrid& grid, const LayerSource& source,
                           const MarchingCubesOptions& options, Mesh* out,
                           MarchingCubesStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && out != nullptr);
  SPLINTCORE_ASSERT(out->vertices.arena() == ctx.arena && out->triangles.arena() == ctx.arena);
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return make_error(StatusCode::kInvalidArgument,
                      "marching_cubes_mesh: the output mesh must be empty");
  }
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // on an error, or with no triangles, the arena is as it was
  // The log sits above the working set, which run_sweep allocates first: it is bound now and
  // first grows inside the sweep. Both are dropped by the rewind below; their bytes stay
  // readable (an arena never clears them) while the mesh is moved down over them.
  MeshLog log;
  log.words.bind(&arena);
  MarchingCubesVisitor visitor;
  visitor.vertex = log_vertex;
  visitor.triangle = log_triangle;
  visitor.user = &log;
  MarchingCubesStats local;
  SPLINTCORE_RETURN_IF_ERROR(run_sweep(ctx, grid, source, options, visitor, 4, &local));
  SPLINTCORE_ASSERT(log.vertices == local.vertices && log.triangles == local.triangles);
  const uint64_t vertex_count = log.vertices, triangle_count = log.triangles;
  if (triangle_count == 0) {
    if (stats != nullptr) *stats = local;
    return Status::ok();
  }
  // The triangles out of the log, to a copy at the top (the log is the last allocation, so
  // the copy is above it).
  const uint32_t* words = log.words.data();
  Triangle* tris = arena.allocate_array<Triangle>(static_cast<size_t>(triangle_count));
  if (tris == nullptr) return arena.exhausted_status();
  {
    size_t at = 0;
    uint64_t seen = 0;
    for (uint64_t t = 0; t < triangle_count; ++t) {
      std::memcpy(tris[t].v, words + at, 12);
      uint32_t fresh = 0;
      for (int k = 0; k < 3; ++k) fresh += tris[t].v[k] >= seen ? 1u : 0u;
      seen += fresh;
      at += 3 + 6 * size_t{fresh};
    }
  }
  // Vertices down to where the arena's top was: each destination is at or below its source
  // (the log starts at or above it and holds more than the vertices before any record).
  arena.rewind(scope.start());
  Vec3* verts = arena.allocate_array<Vec3>(static_cast<size_t>(vertex_count));
  if (verts == nullptr) return arena.exhausted_status();
  {
    size_t at = 0;
    uint64_t seen = 0;
    for (uint64_t t = 0; t < triangle_count; ++t) {
      uint32_t fresh = 0;
      for (int k = 0; k < 3; ++k) fresh += tris[t].v[k] >= seen ? 1u : 0u;
      if (fresh > 0) {
        std::memmove(static_cast<void*>(verts + seen), words + at + 3, 24 * size_t{fresh});
      }
      seen += fresh;
      at += 3 + 6 * size_t{fresh};
    }
  }
  Triangle* final_tris = arena.allocate_array<Triangle>(static_cast<size_t>(triangle_count));
  if (final_tris == nullptr) return arena.exhausted_status();
  std::memmove(static_cast<void*>(final_tris), tris, static_cast<size_t>(triangle_count) * 12);
  out->vertices.adopt(verts, static_cast<size_t>(vertex_count), static_cast<size_t>(vertex_count));
  out->triangles.adopt(final_tris, static_cast<size_t>(triangle_count),
                       static_cast<size_t>(triangle_count));
  scope.commit();
  if (stats != nullptr) *stats = local;
  return Status::ok();
}

}  // namespace splintcore
