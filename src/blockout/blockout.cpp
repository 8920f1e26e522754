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
  const Arena::Marker start = arena.mark();
  out->bind(&arena);

  Aabb bounds;
  for (const Vec3& p : splint.vertices) bounds.add(p);
  if (bounds.empty()) {
    return make_error(StatusCode::kInvalidArgument, "blockout: the splint has no vertices");
  }
  SweepOptions so = options.sweep;
  so.has_region = true;
  so.region = bounds;
  so.open_at_region = true;  // the caps lie outside the splint: the Boolean takes an open B
  Mesh swept;
  Status s = sweep_volume_mesh(ctx, jaws, so, &swept, &st->sweep);
  if (!s.is_ok()) {
    arena.rewind(start);
    out->bind(&arena);
    return s;
  }
  st->swept_triangles = swept.triangles.size();
  for (size_t i = 0; i < swept.vertices.size(); ++i) {
    if (!round_to_float32(&swept.vertices[i])) {
      arena.rewind(start);
      out->bind(&arena);
      return make_error(StatusCode::kLimitExceeded,
                        "blockout: a vertex of the swept volume is beyond float32 range")
          .at_index(i);
    }
  }
  Mesh result;
  if (swept.triangles.empty()) {
    // Nothing reaches the splint: a copy (the caller's splint stays theirs).
    result.bind(&arena);
    if (!result.triangles.resize(splint.triangles.size()) ||
        !result.vertices.resize(splint.vertices.size())) {
      arena.rewind(start);
      out->bind(&arena);
      return arena.exhausted_status();
    }
    for (size_t i = 0; i < splint.triangles.size(); ++i) result.triangles[i] = splint.triangles[i];
    for (size_t i = 0; i < splint.vertices.size(); ++i) result.vertices[i] = splint.vertices[i];
  } else {
    BooleanOptions bo = options.boolean;
    bo.op = BooleanOp::kDifference;
    s = mesh_boolean(ctx, splint, swept, bo, &result, &st->boolean);
    if (!s.is_ok()) {
      arena.rewind(start);
      out->bind(&arena);
      if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) return s;
      Status e = make_error(s.code(), "blockout: ", s.message());
      if (s.index() != kNoPosition) e.at_index(s.index());
      return e;
    }
  }
  move_mesh_down(arena, start, result, out);
  return Status::ok();
}

}  // namespace splintcore
