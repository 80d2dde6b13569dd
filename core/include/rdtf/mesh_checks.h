// Is a triangle surface closed and consistently wound? Signed-tetrahedra volumes are only right
// for closed, consistently oriented surfaces, and a wrong one is silent (facts.md: 10% of
// triangles flipped gave a 20% mass error), so every mesh is checked before its mass is trusted.
#pragma once

#include <cstddef>
#include <span>

#include "rdtf/triangle_mesh.h"

namespace rdtf {

struct SurfaceTopology {
  std::size_t triangles = 0;
  std::size_t degenerate_triangles = 0;  // Two corners at the same position.
  std::size_t boundary_edges = 0;        // Used by one triangle only: the surface is open.
  std::size_t misoriented_edges = 0;     // Used twice in the same direction: winding flips.
  std::size_t nonmanifold_edges = 0;     // Used by more than two triangles, not as many each way.
  // Used by four or more triangles, as many each way: parts that touch along the edge (the copies
  // of an Array modifier, boxes joined where they meet). The surface is still closed (its edges
  // cancel as a chain's do), so the divergence theorem gives each part's volume, summed.
  std::size_t shared_edges = 0;
  bool closed() const { return boundary_edges == 0 && nonmanifold_edges == 0; }
  bool consistently_oriented() const { return misoriented_edges == 0; }
};

// Vertices are welded by exact position first: glTF exporters split vertices along UV and normal
// seams, which does not open the surface. A surface still open is welded again within 2^-30 of
// its largest coordinate (seams a rounding apart), and the fewer boundary edges count.
SurfaceTopology analyze_surface(std::span<const TriangleMesh> pieces);

// The same on meshes read in place (the same result for the same positions and triangles).
SurfaceTopology analyze_surface(std::span<const TriangleMeshView> pieces);

// The same, its work shared by `threads` threads (this one and threads - 1 more, at most 64 in
// all; 1 or 0: this one alone). The result does not depend on it. Where no thread can be had,
// the shares run here.
SurfaceTopology analyze_surface(std::span<const TriangleMeshView> pieces, unsigned threads);

}  // namespace rdtf
