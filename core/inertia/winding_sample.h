// Where a link's solids count volume twice, or subtract it. The mass kernel integrates each closed
// surface by the divergence theorem, which gives the integral of the surfaces' winding number over
// space: a region inside two parts at once (objects joined with Ctrl+J where they overlap, a
// motor sunk into a plate, a shell inside another wound the same way) is counted twice, and a
// shell wound inward outside any solid is subtracted. Neither is visible to the surface check
// (every edge is used twice, in opposite directions) and the result is a mass off by that volume
// without a word. This samples the winding number along parallel rays to find and size such
// regions. It is an estimate (the rays are a grid), so it decides a warning, never a mass.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "rdtf/triangle_mesh.h"

namespace rdtf::internal {

// One closed, consistently wound solid of a link: a mesh's triangles placed in the link frame L.
struct PlacedSolid {
  std::span<const TriangleMeshView> pieces;
  Eigen::Affine3d X_LM = Eigen::Affine3d::Identity();  // the mesh frame M in the link frame L
  // -1 where the whole mesh winds clockwise (its signed volume is negative): the mass kernel
  // turns it right (MESH_INSIDE_OUT), and so does this.
  int orientation = 1;
};

struct WindingSample {
  // Estimates, m^3: the volume counted more than once (a region inside k solids counts k - 1
  // times here), and the volume a solid counts negative (where its own winding number is below 0,
  // even where another solid fills the place).
  double excess = 0;
  double deficit = 0;
  // m^3 inside at least one solid, by the direction that gave the excess and by the one that gave
  // the deficit: the scale each is judged against where the solids' signed volumes cancel.
  double covered = 0;
  double deficit_covered = 0;
  // The two solids whose common region holds most of the excess (equal where one solid overlaps
  // itself), and the solid whose inward shell holds most of the deficit; -1 where there is none.
  int excess_a = -1;
  int excess_b = -1;
  int deficit_solid = -1;
  // The direction (0: x, 1: y, 2: z of the link frame) whose rays gave each estimate.
  int excess_axis = 0;
  int deficit_axis = 0;
  std::size_t rays = 0;               // Rays cast, in the three directions together.
  std::size_t inconsistent_rays = 0;  // Left out: the winding did not come back to 0 along them.
};

// Casts about `rays` rays parallel to each axis of the link frame, on grids spread evenly over the
// solids' bounding box seen along that axis, and sums the winding number's excess and deficit
// along them. Each direction measures a region exactly along its rays and samples it across them;
// the direction whose rays met the region most often gives the estimate, so that a region thin
// across one direction (two plates overlapping by a millimetre) is measured along its thickness.
// A ray whose winding does not return to 0 past the solids (one that met the surface exactly at an
// edge in a way the tie rule could not settle, or an open surface) adds nothing. The error is that
// of the grid: the cells the region's outline passes through, seen along the chosen direction.
// A direction whose crossings would pass 1.4 Mi (a stack of many layers along it) is left out and
// the others give the estimate; where all three are, the sample is cast again with a quarter of
// the rays (down to 256 a direction; below, nothing is found).
//
// `scratch`, where given, holds the crossings and their sorting space from one call to the next,
// so that the bodies of one model reuse the pages the first one touched: a fresh page costs a
// fault, and on a small model the faults were as much as the arithmetic. Null: memory of its own.
struct WindingScratch;
WindingSample sample_winding(std::span<const PlacedSolid> solids, std::size_t rays = 4096,
                             WindingScratch* scratch = nullptr);

// The memory sample_winding may reuse; it holds nothing a result depends on.
struct WindingScratch {
  WindingScratch();
  ~WindingScratch();
  WindingScratch(const WindingScratch&) = delete;
  WindingScratch& operator=(const WindingScratch&) = delete;
  struct Buffers;
  std::unique_ptr<Buffers> buffers;
};

}  // namespace rdtf::internal
