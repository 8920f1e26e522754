// Competitive region growing: multi-source breadth-first search over the voxels of an HU
// window, each voxel claimed by the seed region that reaches it in the fewest voxel steps.
//
// Sources: Adams and Bischof, "Seeded region growing", IEEE TPAMI 16(6), 1994 (regions grown
// from seeds in competition, one pixel at a time); Chen et al., "EasySplint", 2016, section
// 2.1 (maxilla and mandible separated by region growing from seed points); the breadth-first
// multi-source formulation is the discrete geodesic Voronoi partition of the window (e.g.
// Soille, "Morphological Image Analysis", 2nd ed. 2003, section 4.2.4, geodesic influence
// zones). The rule and its tie-break are stated in segment.h.
//
// One FIFO queue of 32-bit voxel indices, each window voxel queued at most once: no recursion,
// memory stated up front (grow_regions_bound), output independent of any executor.
#include "splintcore/segment.h"

namespace splintcore {

namespace {

struct PlaneSide {
  bool enabled = false;
  SplitPlane plane{};
  // Allowed for label l at voxel (i, j, k)?
  bool allows(const CtVolume& v, uint8_t label, uint32_t i, uint32_t j, uint32_t k) const {
    if (!enabled) return true;
    if (label != plane.label_positive && label != plane.label_negative) return true;
    const Vec3 local{v.spacing.x * static_cast<double>(i), v.spacing.y * static_cast<double>(j),
                     v.spacing.z * static_cast<double>(k)};
    const double s = dot(plane.normal, ct_to_patient(v, local) - plane.point);
    return (s > 0.0) == (label == plane.label_positive);
  }
};

// The checks of grow_regions' arguments (no memory needed); *side: the split plane, if any.
Status check_grow_input(const CtVolume& volume, Span<const RegionSeed> seeds,
                        const RegionGrowOptions& options, const LabelVolume* labels,
                        PlaneSide* side) {
  if (labels == nullptr || labels->labels == nullptr || labels->nx != volume.nx ||
      labels->ny != volume.ny || labels->nz != volume.nz || volume.voxel_count() == 0) {
    return make_error(StatusCode::kInvalidArgument,
                      "region growing: the label volume does not match the CT volume (", volume.nx,
                      " x ", volume.ny, " x ", volume.nz, ")");
  }
  if (seeds.empty()) {
    return make_error(StatusCode::kInvalidArgument, "region growing needs at least one seed");
  }
  if (seeds.size() > kMaxSeeds) {
    return make_error(StatusCode::kInvalidArgument, "region growing: ", seeds.size(),
                      " seeds, at most ", kMaxSeeds);
  }
  const uint64_t total = volume.voxel_count();
  if (total > uint64_t{0xFFFFFFFFu}) {
    return make_error(StatusCode::kLimitExceeded, "region growing: ", total,
                      " voxels; at most 4294967295 (32-bit voxel indices)");
  }
  if (options.plane != nullptr) {
    const SplitPlane& pl = *options.plane;
    if (!is_finite(pl.normal.x) || !is_finite(pl.normal.y) || !is_finite(pl.normal.z) ||
        !is_finite(pl.point.x) || !is_finite(pl.point.y) || !is_finite(pl.point.z) ||
        (pl.normal.x == 0.0 && pl.normal.y == 0.0 && pl.normal.z == 0.0)) {
      return make_error(StatusCode::kInvalidArgument,
                        "split plane: the point and normal must be finite and the normal "
                        "not zero");
    }
    if (pl.label_positive == pl.label_negative || pl.label_positive == 0 ||
        pl.label_negative == 0 || pl.label_positive > kMaxRegionLabel ||
        pl.label_negative > kMaxRegionLabel) {
      return make_error(StatusCode::kInvalidArgument,
                        "split plane: its two labels must differ and lie in 1..", kMaxRegionLabel);
    }
    side->enabled = true;
    side->plane = pl;
  }
  for (size_t s = 0; s < seeds.size(); ++s) {
    if (seeds[s].label == 0 || seeds[s].label > kMaxRegionLabel) {
      return make_error(StatusCode::kInvalidArgument, "seed ", s, " has label ",
                        static_cast<uint32_t>(seeds[s].label), "; labels are 1..", kMaxRegionLabel)
          .at_index(s);
    }
  }
  return Status::ok();
}

// Window voxels (unclaimed labels): the queue's capacity (each is queued at most once).
uint64_t count_window(const uint8_t* lab, uint64_t total) {
  uint64_t in_window = 0;
  uint64_t v = 0;
  for (; v + 64 <= total; v += 64) {  // fixed-size blocks: vectorised at -O2
    uint32_t in = 0;
    for (uint32_t b = 0; b < 64; ++b) in += lab[v + b] == kLabelUnclaimed ? 1u : 0u;
    in_window += in;
  }
  for (; v < total; ++v) in_window += lab[v] == kLabelUnclaimed ? 1u : 0u;
  return in_window;
}

// The state of one grow_regions call: the labels (claimed in place), the FIFO queue and the
// counts; one method per stage: the seeds, the neighbour offsets, the growth, its check.
struct RegionGrower {
  RegionGrower(const CtVolume& v, const PlaneSide& s, uint8_t* labels)
      : volume(v),
        side(s),
        lab(labels),
        nx(v.nx),
        ny(v.ny),
        nz(v.nz),
        slice(uint64_t{v.nx} * v.ny) {}

  const CtVolume& volume;
  const PlaneSide& side;
  uint8_t* lab;
  const uint32_t nx, ny, nz;
  const uint64_t slice;
  uint32_t* queue = nullptr;
  uint64_t tail = 0;
  RegionStats st;
  uint64_t seed_voxels[kMaxRegionLabel + 1] = {};
  int8_t off[26][3] = {};
  int64_t delta[26] = {};

  // Seeds in label order, then in the order given: the FIFO's first layer.
  Status place_seeds(Span<const RegionSeed> seeds) {
    for (uint8_t label = 1; label <= kMaxRegionLabel; ++label) {
      for (size_t s = 0; s < seeds.size(); ++s) {
        const RegionSeed& seed = seeds[s];
        if (seed.label != label) continue;
        uint32_t i = 0, j = 0, k = 0;
        Status vs = seed_voxel(volume, seed, &i, &j, &k);
        if (!vs.is_ok()) {
          return make_error(StatusCode::kInvalidArgument, "seed ", s, " (label ",
                            static_cast<uint32_t>(label), "): ", vs.message())
              .at_index(s);
        }
        const uint64_t idx = (uint64_t{k} * ny + j) * nx + i;
        const uint8_t now = lab[idx];
        if (now == kLabelBackground) {
          return make_error(StatusCode::kInvalidArgument, "seed ", s, " (label ",
                            static_cast<uint32_t>(label), ") at voxel (", i, ", ", j, ", ", k,
                            ") is not in the HU window: its value is ", volume.hu[idx],
                            " HU; place it in bone")
              .at_index(s);
        }
        if (now == label) continue;  // two seeds of one region in one voxel
        if (now != kLabelUnclaimed) {
          return make_error(StatusCode::kInvalidArgument, "seed ", s, " (label ",
                            static_cast<uint32_t>(label), ") at voxel (", i, ", ", j, ", ", k,
                            ") is in the same voxel as a seed of label ",
                            static_cast<uint32_t>(now))
              .at_index(s);
        }
        if (!side.allows(volume, label, i, j, k)) {
          return make_error(StatusCode::kInvalidArgument, "seed ", s, " (label ",
                            static_cast<uint32_t>(label), ") at voxel (", i, ", ", j, ", ", k,
                            ") is on the split plane's side of label ",
                            static_cast<uint32_t>(label == side.plane.label_positive
                                                      ? side.plane.label_negative
                                                      : side.plane.label_positive))
              .at_index(s);
        }
        lab[idx] = label;
        queue[tail++] = static_cast<uint32_t>(idx);
        ++seed_voxels[label];
      }
    }
    return Status::ok();
  }

  // Neighbour offsets in a fixed order (the labels do not depend on it; see segment.h): the six
  // faces first, then the twenty edges and corners.
  void set_neighbours() {
    const int8_t six[6][3] = {{0, 0, -1}, {0, -1, 0}, {-1, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int n = 0; n < 6; ++n) {
      for (int a = 0; a < 3; ++a) off[n][a] = six[n][a];
    }
    int count = 6;
    for (int dk = -1; dk <= 1; ++dk) {
      for (int dj = -1; dj <= 1; ++dj) {
        for (int di = -1; di <= 1; ++di) {
          if ((di != 0) + (dj != 0) + (dk != 0) < 2) continue;
          off[count][0] = static_cast<int8_t>(di);
          off[count][1] = static_cast<int8_t>(dj);
          off[count][2] = static_cast<int8_t>(dk);
          ++count;
        }
      }
    }
    for (int n = 0; n < 26; ++n) {
      delta[n] = (static_cast<int64_t>(off[n][2]) * static_cast<int64_t>(ny) + off[n][1]) *
                     static_cast<int64_t>(nx) +
                 off[n][0];
    }
  }

  // Claims the unclaimed neighbours [first, last) of the offsets around queue entry `idx`.
  void expand(uint64_t idx, int first, int last) {
    const uint8_t label = lab[idx];
    const uint32_t i = static_cast<uint32_t>(idx % nx);
    const uint32_t j = static_cast<uint32_t>((idx / nx) % ny);
    const uint32_t k = static_cast<uint32_t>(idx / slice);
    const bool border = i == 0 || j == 0 || k == 0 || i + 1 == nx || j + 1 == ny || k + 1 == nz;
    if (border) st.touches_border[label] = true;
    for (int n = first; n < last; ++n) {
      const int64_t ni = static_cast<int64_t>(i) + off[n][0];
      const int64_t nj = static_cast<int64_t>(j) + off[n][1];
      const int64_t nk = static_cast<int64_t>(k) + off[n][2];
      if (border && (ni < 0 || nj < 0 || nk < 0 || ni >= nx || nj >= ny || nk >= nz)) continue;
      const uint64_t nidx = static_cast<uint64_t>(static_cast<int64_t>(idx) + delta[n]);
      const uint8_t b = lab[nidx];
      if (b == kLabelUnclaimed) {
        if (side.enabled && !side.allows(volume, label, static_cast<uint32_t>(ni),
                                         static_cast<uint32_t>(nj), static_cast<uint32_t>(nk))) {
          continue;
        }
        lab[nidx] = label;
        queue[tail++] = static_cast<uint32_t>(nidx);
        ++st.voxels[label];
      } else if (b != kLabelBackground && b != label) {
        st.meets_other_region[label] = true;
        st.meets_other_region[b] = true;
      }
    }
  }

  // The growth from the seeds; *layers: the breadth-first layers of pass 1.
  Status grow(const Context& ctx, Connectivity connectivity, uint64_t in_window, uint32_t* layers) {
    for (uint8_t label = 1; label <= kMaxRegionLabel; ++label) {
      st.voxels[label] = seed_voxels[label];
    }
    // Pass 1: the competition, breadth-first over face neighbours.
    uint64_t head = 0;
    uint64_t layer_end = tail;
    *layers = tail > 0 ? 1 : 0;
    uint64_t next_report = uint64_t{1} << 20;
    while (head < tail) {
      if (head >= next_report) {
        next_report += uint64_t{1} << 20;
        SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "region growing", tail, in_window));
      }
      if (head == layer_end) {
        layer_end = tail;
        ++*layers;
      }
      expand(queue[head++], 0, 6);
    }
    // Pass 2 (26-connectivity): every claimed voxel, in queue order, claims the window voxels
    // it touches through an edge or a corner, and so on breadth-first by 26-neighbour steps.
    if (connectivity == Connectivity::k26) {
      head = 0;
      while (head < tail) {
        if (head >= next_report) {
          next_report += uint64_t{1} << 20;
          SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "region growing", tail, in_window));
        }
        expand(queue[head++], 0, 26);
      }
    }
    return report_progress(ctx, "region growing", in_window, in_window);
  }

  // Every seeded region must have grown past its seeds; the error names its first seed.
  Status check_grown(Span<const RegionSeed> seeds, Connectivity connectivity) const {
    for (uint8_t label = 1; label <= kMaxRegionLabel; ++label) {
      if (seed_voxels[label] == 0 || st.voxels[label] > seed_voxels[label]) continue;
      for (size_t s = 0; s < seeds.size(); ++s) {
        if (seeds[s].label != label) continue;
        uint32_t i = 0, j = 0, k = 0;
        (void)seed_voxel(volume, seeds[s], &i, &j, &k);
        return make_error(StatusCode::kInvalidArgument, "region ", static_cast<uint32_t>(label),
                          " grows no further than its seeds: seed ", s, " at voxel (", i, ", ", j,
                          ", ", k, ") has no unclaimed ",
                          connectivity == Connectivity::k26 ? 26 : 6,
                          "-neighbour in the HU window (a speck of noise rather than bone?)")
            .at_index(s);
      }
    }
    return Status::ok();
  }
};

}  // namespace

uint64_t grow_regions_bound(uint64_t in_window) {
  uint64_t bytes = 0;
  if (!checked_mul(in_window, 4, &bytes) || !checked_add(bytes, 16, &bytes)) return 0;
  return bytes;
}

Status grow_regions(const Context& ctx, const CtVolume& volume, Span<const RegionSeed> seeds,
                    const RegionGrowOptions& options, LabelVolume* labels, RegionStats* stats) {
  PlaneSide side;
  SPLINTCORE_RETURN_IF_ERROR(check_grow_input(volume, seeds, options, labels, &side));
  const uint64_t in_window = count_window(labels->labels, volume.voxel_count());

  ArenaScope scope(*ctx.arena);
  const uint64_t capacity = in_window > 0 ? in_window : 1;
  RegionGrower g(volume, side, labels->labels);
  g.queue = ctx.arena->allocate_array<uint32_t>(static_cast<size_t>(capacity));
  if (g.queue == nullptr) return ctx.arena->exhausted_status();
  g.st.queue_bytes = grow_regions_bound(capacity);
  SPLINTCORE_RETURN_IF_ERROR(g.place_seeds(seeds));
  g.set_neighbours();
  uint32_t layers = 0;
  SPLINTCORE_RETURN_IF_ERROR(g.grow(ctx, options.connectivity, in_window, &layers));
  SPLINTCORE_RETURN_IF_ERROR(g.check_grown(seeds, options.connectivity));
  g.st.unclaimed = in_window - g.tail;
  g.st.layers = layers;
  if (stats != nullptr) *stats = g.st;
  return Status::ok();
}

}  // namespace splintcore
