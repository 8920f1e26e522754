// `splintcore compare`: surface deviation between two meshes, the accuracy measure of Chen et
// al. 2016 (mean / max / RMS distance of one surface's vertices to the other surface; their
// symmetric maximum is the Hausdorff distance over the vertices), and the binary PLY of A
// coloured by that distance. Tool code: uses the standard library.
#ifndef SPLINTCORE_TOOLS_COMPARE_H
#define SPLINTCORE_TOOLS_COMPARE_H

#include <string>
#include <vector>

#include "splintcore/core.h"
#include "splintcore/mesh.h"

namespace splintcore {
namespace cli {

struct Deviation {
  uint64_t vertices = 0;
  double mean = 0;  // mm, summed in vertex order
  double max = 0;
  double rms = 0;
};

struct Comparison {
  Deviation a_to_b;  // every vertex of A to the surface of B
  Deviation b_to_a;
  double hausdorff = 0;  // max of the two maxima
};

// Distances from every vertex of A to B's surface (BVH closest point) and back. The indexes
// are built in ctx.arena and returned before it finishes. Results are the same for any thread
// count. Errors: kInvalidMesh (a mesh without triangles), those of build_distance_index and
// batch_closest_points.
Status compare_meshes(const Context& ctx, const Mesh& a, const Mesh& b,
                      std::vector<double>* a_distances, std::vector<double>* b_distances,
                      Comparison* out);

// Colour of a distance on the blue-green-red ramp over [0, range] (blue at 0, green at half,
// red at range and beyond; range <= 0 gives blue), channels rounded to nearest.
void distance_colour(double distance, double range, uint8_t rgb[3]);

// Binary little-endian PLY of `mesh`: float x y z, uchar red green blue, float quality (the
// distance), faces as lists of three uint. Bytes depend only on the inputs.
std::string distance_ply(const Mesh& mesh, const std::vector<double>& distances, double range);

}  // namespace cli
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_COMPARE_H
