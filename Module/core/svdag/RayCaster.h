// Casts rays through a whole Volume on the CPU: the reference the GPU renderer is tested against,
// and the engine behind picking.
//
// Rays are given in index space (see Traversal.h: voxel (i, j, k) occupies [i, i+1) x [j, j+1) x
// [k, k+1)) in double precision and walked by GridTraversal.h (the code the renderer's compute
// backend runs, there in float): a 3D DDA over the grid of 16^3 cells, in each cell the ray
// re-anchored at the cell's integer corner (and at its entry point) and converted to float for
// the traversal of the cell's blocks (Traversal.h), so it is equally precise anywhere in a huge
// volume.
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
  // The clipping plane whose cut face was hit (setClipPlanes: the ray entered the kept region
  // inside the hit voxel or box, at t; normal is zero then), or -1.
  int32_t clipPlane = -1;
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

  // The smooth shading normal (SmoothNormal.h: the gradient of the hit label's smoothed
  // occupancy, facing the ray) of a hit that cast(ray, lod) returned, as a unit vector in index
  // space; the entry face normal for Lod::Block and Lod::Leaf hits and where the gradient
  // vanishes; zero for a miss or where the ray started inside.
  std::array<float, 3> smoothNormal(const Ray& ray, const RayHit& hit, Lod lod) const;

  // Clipping planes (svdag/Clipping.h, the code the GPU renderer runs): every ray's interval is
  // clipped to the region kept by all planes, each (a, b, c, d) keeping the index-space points p
  // with a p.x + b p.y + c p.z + d >= 0. A ray that enters the region inside a solid hits there
  // (RayHit::clipPlane). Callers that mirror the GPU renderer give planes whose function is a
  // world distance, moved into the kept side by a small margin (Clipping.h). Throws
  // std::invalid_argument for more than SVDAG_CLIP_MAX_SLOTS (12) planes or non-finite values.
  void setClipPlanes(const std::vector<std::array<double, 4>>& planes);
  const std::vector<std::array<double, 4>>& clipPlanes() const { return this->ClipPlanes; }

private:
  const Volume& volume;
  std::vector<std::array<double, 4>> ClipPlanes;
};

// Root references of the blocks of block b's label in the 3 x 3 x 3 cells around b's cell, at
// (dx + 1) + 3 (dy + 1) + 9 (dz + 1) (13: b itself), 0xFFFFFFFF (SmoothNormal.h's SVDAG_NO_BLOCK)
// where that cell holds none of the label or lies outside the volume.
std::array<uint32_t, 27> neighbourRoots(const Volume& volume, uint64_t block);
// neighbourRoots of every block, 27 words per block in block order: the renderer's neighbour
// table for smooth shading. Throws std::runtime_error if a root reference equals the marker.
std::vector<uint32_t> neighbourTable(const Volume& volume,
  const ParallelFor& parallel = sequentialFor);

} // namespace svdag
