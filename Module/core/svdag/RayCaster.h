// Casts rays through a whole Volume on the CPU: the reference the GPU renderer is tested against,
// and the engine behind picking.
//
// Rays are given in index space (see Traversal.h: voxel (i, j, k) occupies [i, i+1) x [j, j+1) x
// [k, k+1)) in double precision. A 3D DDA walks the grid of 16^3 cells; in each cell the ray is
// re-anchored at the cell's integer corner (and at its entry point) and converted to float, so the
// float traversal of the cell's blocks (Traversal.h) is equally precise anywhere in a huge
// volume. The blocks of one cell are disjoint in voxels, so the nearest of their hits is the hit
// in that cell, and the first cell with a hit ends the walk.
#pragma once

#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <array>
#include <cstdint>
#include <vector>

namespace svdag
{

enum class Lod : uint32_t
{
  Block = 0, // the block's tight bounds box
  Leaf = 1,  // the first non-empty 4^3 region (leaf cube clipped to the block bounds)
  Voxel = 2  // the first solid voxel (lossless)
};

struct Ray
{
  std::array<double, 3> origin{ { 0, 0, 0 } };
  std::array<double, 3> direction{ { 0, 0, 1 } }; // need not be unit length
  double tmin = 0;
  double tmax = 1e300;
  // Entry only: in each block whose solid the ray is inside at tmin, that solid run is skipped and
  // the next entry into a solid of the block is reported (Traversal.h, "Entry only"). For rays
  // that continue through a surface they have just crossed; such hits always have a normal.
  bool entryOnly = false;
};

struct RayHit
{
  bool hit = false;
  // Ray parameter of the entry into the hit box: origin + t * direction is the entry point (the
  // index-space distance when direction has unit length); tmin when the ray starts inside.
  double t = 0;
  uint32_t label = 0;                   // label index (Volume::labels)
  uint64_t block = 0;                   // block index
  std::array<int32_t, 3> voxel{ {} };   // voxel where the ray enters the hit box (Lod::Voxel: the voxel hit)
  std::array<int32_t, 3> normal{ {} };  // entry face, e.g. (-1, 0, 0); zero when starting inside
                                        // (never for entryOnly rays)
};

class RayCaster
{
public:
  // Keeps a reference to the volume, which must outlive the caster and be valid (built by the
  // Builder or loaded and checked with Volume::validate: the traversal trusts its references).
  explicit RayCaster(const Volume& volume);

  // The first hit along the ray within [tmin, tmax] (an empty interval is a miss). Throws
  // std::invalid_argument for a non-finite origin or direction, a zero direction, or a NaN tmin
  // or tmax (infinite ones are fine).
  RayHit cast(const Ray& ray, Lod lod) const;

  // Casts rays[i] into hits[i] (resized) with the given parallel-for. Throws like cast().
  void castMany(const std::vector<Ray>& rays, Lod lod, std::vector<RayHit>& hits,
    const ParallelFor& parallel = sequentialFor) const;

private:
  struct UnitRay;
  // Nearest hit among the blocks of one cell, the ray anchored at the cell's corner and at
  // parameter s (distance along the unit direction) where it enters the cell.
  RayHit castCell(const UnitRay& ray, const std::array<int32_t, 3>& cell, double s, Lod lod) const;
  const Volume& volume;
};

} // namespace svdag
