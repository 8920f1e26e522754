// Interference elimination (Chen et al. 2016, "The Interference Elimination"): the splint
// minus the jaws' swept volume, by the exact Boolean (boolean.h) on the swept volume's mesh.
#include "splintcore/blockout.h"

namespace splintcore {

Status blockout(const Context& ctx, const Mesh& splint, Span<const Mesh> jaws,
                const BlockoutOptions& options, Mesh* out, BlockoutStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && out != nullptr);
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return make_error(StatusCode::kInvalidArgument, "blockout: the output mesh must be empty");
  }
  BlockoutStats local;
  BlockoutStats* st = stats != nullptr ? stats : &local;
  *st = BlockoutStats{};
  Arena& arena = *ctx.arena;
  out->bind(&arena);

  Aabb bounds;
  for (const Vec3& p : splint.vertices) bounds.add(p);
  if (bounds.empty()) {
    return make_error(StatusCode::kInvalidArgument, "blockout: the splint has no vertices");
  }
  ArenaScope scope(arena);  // on an error the arena is as it was
  const int kAttempts = 4;
  Mesh result;
  Status s;
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    arena.rewind(scope.start());
    result = Mesh();
    SweepOptions so = options.sweep;
    so.has_region = true;
    so.region = bounds;
    so.open_at_region = true;  // the caps lie outside the splint: the Boolean takes an open B
    if (so.edge_margin < 1.0 / 16) so.edge_margin = 1.0 / 16;
    so.float32_vertices = true;  // rounded below anyway; decimating, before the decimation
    if (options.sweep.offset > 0) {
      so.offset = options.sweep.offset + attempt * (options.sweep.voxel / 64);
      if (attempt > 0 && !(so.offset <= 20 * so.voxel)) break;
    } else {
      so.inset = options.sweep.inset + attempt * (options.sweep.voxel / 64);
      if (attempt > 0 && !(so.inset < 2 * so.voxel)) break;
    }
    st->attempts = static_cast<uint32_t>(attempt + 1);
    st->inset_used = so.inset;
    st->offset_used = so.offset;
    Mesh swept;
    s = sweep_volume_mesh(ctx, jaws, so, &swept, &st->sweep);
    if (!s.is_ok()) break;
    st->swept_triangles = swept.triangles.size();
    for (size_t i = 0; i < swept.vertices.size() && s.is_ok(); ++i) {
      if (!round_to_float32(&swept.vertices[i])) {
        s = make_error(StatusCode::kLimitExceeded,
                       "blockout: a vertex of the swept volume is beyond float32 range")
                .at_index(i);
      }
    }
    if (!s.is_ok()) break;
    if (swept.triangles.empty()) {
      // Nothing reaches the splint: a copy (the caller's splint stays theirs).
      result.bind(&arena);
      if (!result.triangles.resize(splint.triangles.size()) ||
          !result.vertices.resize(splint.vertices.size())) {
        s = arena.exhausted_status();
        break;
      }
      for (size_t i = 0; i < splint.triangles.size(); ++i)
        result.triangles[i] = splint.triangles[i];
      for (size_t i = 0; i < splint.vertices.size(); ++i) result.vertices[i] = splint.vertices[i];
      break;
    }
    BooleanOptions bo = options.boolean;
    bo.op = BooleanOp::kDifference;
    s = mesh_boolean(ctx, splint, swept, bo, &result, &st->boolean);
    if (s.is_ok() || s.code() == StatusCode::kArenaExhausted ||
        s.code() == StatusCode::kCancelled || s.code() == StatusCode::kInvalidArgument) {
      break;
    }
  }
  if (!s.is_ok()) {
    out->bind(&arena);
    if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) return s;
    Status e = make_error(s.code(), "blockout: ", s.message());
    if (s.index() != kNoPosition) e.at_index(s.index());
    return e;
  }
  move_mesh_down(arena, scope.start(), result, out);
  scope.commit();
  return Status::ok();
}

}  // namespace splintcore
