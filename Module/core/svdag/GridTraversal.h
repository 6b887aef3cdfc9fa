/* Ray traversal of a WHOLE volume: a 3D DDA through its grid of 16^3 cells, front to back, and in
 * each cell the per-block walk of Traversal.h over the cell's blocks, the nearest hit winning.
 * Written once for C++ (with GLM) and GLSL 4.60, in their common subset like Traversal.h (which
 * must be included first): the CPU ray caster (svdag::RayCaster, in double) and the renderer's
 * compute backend (camera.comp, in float) run this code.
 *
 * Precision: the walk runs in SVDAG_GRID_REAL (C++: double, GLSL: float). In each cell the ray is
 * re-anchored at the cell's integer corner and at the point where it enters the cell before it is
 * handed to the float block walk, so the block walk is equally precise anywhere in a huge volume.
 *
 * The ray is origin + s * dir (index space, Traversal.h's conventions; dir need not have unit
 * length), searched for s in [smin, smax]. Cells are visited in the order the ray enters them;
 * the blocks of a cell are disjoint in voxels, so the nearest hit among them is the hit in that
 * cell, and the first cell with a hit ends the walk. Which blocks are intersected, how a block
 * record is read and which level of detail each block walk uses are the includer's:
 *   SVDAG_GRID_PARAM / SVDAG_GRID_ARG   optional leading parameter declaration (and argument)
 *                           that carries the volume (C++: the Volume; GLSL: empty, globals)
 *   SVDAG_GRID_CELL_BLOCKS(cell, first, end)   sets [first, end), the block indices of the cell
 *                           with index cell = cx + nx * (cy + ny * cz)
 *   SVDAG_GRID_BLOCK(b, lo, hi, rootRef, label)   reads block b's bounds (uvec3, inclusive,
 *                           cell-local), root reference and label index
 *   SVDAG_GRID_SKIP(label)  optional: true for blocks to leave out (hidden labels); default false
 *   SVDAG_GRID_LOD(lod, lo, hi, rootRef, origin, dir, tmin, tmax, s)   optional: the level of
 *                           detail of one block walk, origin/dir/tmin/tmax being the re-anchored
 *                           ray and s the walk parameter at the cell entry; default: the lod
 *                           argument
 *   SVDAG_GRID_INDEX        optional: the block index type (C++: uint64_t; GLSL: uint)
 *
 * Loop bound: every step moves one cell coordinate by one, monotonically towards the exit, so
 * nx + ny + nz steps leave the grid.
 */
#ifndef SVDAG_GRID_TRAVERSAL_H
#define SVDAG_GRID_TRAVERSAL_H

#ifdef __cplusplus
#include <cmath>
namespace svdag
{
namespace traversal
{
using glm::dvec3;
using glm::uvec3;
#ifndef SVDAG_GRID_REAL
#define SVDAG_GRID_REAL double
#define SVDAG_GRID_VEC3 dvec3
#endif
#ifndef SVDAG_GRID_INDEX
#define SVDAG_GRID_INDEX uint64_t
#endif
#define SVDAG_GRID_FLOOR(x) std::floor(x)
#define SVDAG_GRID_CEIL(x) std::ceil(x)
#else
#ifndef SVDAG_GRID_REAL
#define SVDAG_GRID_REAL float
#define SVDAG_GRID_VEC3 vec3
#endif
#ifndef SVDAG_GRID_INDEX
#define SVDAG_GRID_INDEX uint
#endif
#define SVDAG_GRID_FLOOR(x) floor(x)
#define SVDAG_GRID_CEIL(x) ceil(x)
#endif

#ifndef SVDAG_GRID_PARAM
#define SVDAG_GRID_PARAM
#define SVDAG_GRID_ARG
#endif
#ifndef SVDAG_GRID_SKIP
#define SVDAG_GRID_SKIP(label) false
#endif
#ifndef SVDAG_GRID_LOD
#define SVDAG_GRID_LOD(lod, lo, hi, rootRef, origin, dir, tmin, tmax, s) (lod)
#endif

/* Block-walk intervals are clamped to this finite magnitude before they become float. */
#define SVDAG_GRID_LOCAL_FAR 1.0e30

struct SvdagGridHit
{
  bool hit;
  SVDAG_GRID_REAL s;        // the walk parameter of the entry into the hit box (smin if inside)
  uint label;               // label index
  SVDAG_GRID_INDEX block;   // block index
  ivec3 cell;               // the hit block's cell
  ivec3 voxel;              // cell-local voxel where the ray enters the hit box (Traversal.h)
  ivec3 normal;             // entry face; zero when the ray starts inside
  uint lod;                 // the level of detail of the hit block's walk
};

SVDAG_FN float svdagGridLocal(SVDAG_GRID_REAL v)
{
  SVDAG_GRID_REAL bound = SVDAG_GRID_REAL(SVDAG_GRID_LOCAL_FAR);
  return float(v < -bound ? -bound : (v > bound ? bound : v));
}

/* The first hit of the ray in a volume of `dims` voxels (cells = ceil(dims / 16)) within
 * [smin, smax]; midRefBits, leafRefBits, lod and entryOnly as for svdagIntersectBlock. anyHit:
 * return the first hit found (occlusion rays), not the nearest. */
SVDAG_FN SvdagGridHit svdagCastGrid(SVDAG_STREAMS_PARAM SVDAG_GRID_PARAM SVDAG_GRID_VEC3 origin,
  SVDAG_GRID_VEC3 dir, SVDAG_GRID_REAL smin, SVDAG_GRID_REAL smax, ivec3 dims, ivec3 cells,
  uint midRefBits, uint leafRefBits, uint lod, bool entryOnly, bool anyHit)
{
  SvdagGridHit result;
  result.hit = false;
  result.s = smax;
  result.label = 0u;
  result.block = SVDAG_GRID_INDEX(0u);
  result.cell = ivec3(0);
  result.voxel = ivec3(0);
  result.normal = ivec3(0);
  result.lod = lod;
  SVDAG_STAT(SVDAG_STAT_RAYS);
  if (anyHit)
  {
    SVDAG_STAT(SVDAG_STAT_SHADOW_RAYS);
  }
  if (!(smin <= smax) || dims.x <= 0 || dims.y <= 0 || dims.z <= 0)
    return result;

  // Slab test against the volume box [0, dims] (half-open along parallel axes).
  ivec3 step = ivec3(0);
  SVDAG_GRID_REAL sEnter = smin;
  SVDAG_GRID_REAL sExit = smax;
  for (int a = 0; a < 3; ++a)
  {
    if (dir[a] > SVDAG_GRID_REAL(SVDAG_PARALLEL_EPS))
      step[a] = 1;
    else if (dir[a] < -SVDAG_GRID_REAL(SVDAG_PARALLEL_EPS))
      step[a] = -1;
    if (step[a] == 0)
    {
      if (origin[a] < SVDAG_GRID_REAL(0) || origin[a] >= SVDAG_GRID_REAL(dims[a]))
        return result;
      continue;
    }
    SVDAG_GRID_REAL s0 = (SVDAG_GRID_REAL(0) - origin[a]) / dir[a];
    SVDAG_GRID_REAL s1 = (SVDAG_GRID_REAL(dims[a]) - origin[a]) / dir[a];
    SVDAG_GRID_REAL sNear = step[a] > 0 ? s0 : s1;
    SVDAG_GRID_REAL sFar = step[a] > 0 ? s1 : s0;
    sEnter = sNear > sEnter ? sNear : sEnter;
    sExit = sFar < sExit ? sFar : sExit;
  }
  if (!(sEnter <= sExit))
    return result;

  // The cell the ray is in (or moves into) at sEnter.
  SVDAG_GRID_REAL size = SVDAG_GRID_REAL(CELL_SIZE);
  ivec3 cell;
  for (int a = 0; a < 3; ++a)
  {
    SVDAG_GRID_REAL p = (origin[a] + sEnter * dir[a]) / size;
    SVDAG_GRID_REAL c = step[a] < 0 ? SVDAG_GRID_CEIL(p) - SVDAG_GRID_REAL(1) : SVDAG_GRID_FLOOR(p);
    SVDAG_GRID_REAL top = SVDAG_GRID_REAL(cells[a] - 1);
    cell[a] = int(c < SVDAG_GRID_REAL(0) ? SVDAG_GRID_REAL(0) : (c > top ? top : c));
  }

  SVDAG_GRID_REAL s = sEnter;
  uint maxSteps = uint(cells.x) + uint(cells.y) + uint(cells.z) + 1u;
  for (uint i = 0u; i < maxSteps; ++i)
  {
    SVDAG_STAT(SVDAG_STAT_CELLS);
    uint cellIndex = uint(cell.x) + uint(cells.x) * (uint(cell.y) + uint(cells.y) * uint(cell.z));
    SVDAG_GRID_INDEX first;
    SVDAG_GRID_INDEX end;
    SVDAG_GRID_CELL_BLOCKS(cellIndex, first, end);
    if (first != end)
    {
      SVDAG_STAT(SVDAG_STAT_FULL_CELLS);
      // Re-anchored: relative to the cell's corner, at the cell entry.
      vec3 local;
      for (int a = 0; a < 3; ++a)
        local[a] = float((origin[a] - size * SVDAG_GRID_REAL(cell[a])) + s * dir[a]);
      vec3 localDir = vec3(dir);
      float tmin = svdagGridLocal(smin - s);
      float tmax = svdagGridLocal(smax - s);
      float best = tmax;
      for (SVDAG_GRID_INDEX b = first; b < end; ++b)
      {
        uvec3 lo;
        uvec3 hi;
        uint rootRef;
        uint label;
        SVDAG_STAT(SVDAG_STAT_BLOCKS);
        SVDAG_GRID_BLOCK(b, lo, hi, rootRef, label);
        if (SVDAG_GRID_SKIP(label))
          continue;
        uint blockLod = SVDAG_GRID_LOD(lod, lo, hi, rootRef, local, localDir, tmin, tmax, s);
        // Searched only up to the nearest hit so far: a block whose box starts beyond it is
        // rejected by the slab test, a walk stops there (a tie at `best` keeps the first).
        SvdagBlockHit h = svdagIntersectBlock(SVDAG_STREAMS_ARG lo, hi, rootRef,
          midRefBits, leafRefBits, local, localDir, tmin, best, blockLod,
          entryOnly);
        if (h.hit && (!result.hit || h.t < best))
        {
          best = h.t;
          result.hit = true;
          result.label = label;
          result.block = b;
          result.voxel = h.voxel;
          result.normal = h.normal;
          result.lod = blockLod;
          if (anyHit)
            break;
        }
      }
      if (result.hit)
      {
        result.s = s + SVDAG_GRID_REAL(best);
        result.cell = cell;
        SVDAG_STAT(SVDAG_STAT_HITS);
        return result;
      }
    }
    // Into the next cell through the nearest exit face.
    int axis = -1;
    SVDAG_GRID_REAL sNext = SVDAG_GRID_REAL(0);
    for (int a = 0; a < 3; ++a)
    {
      if (step[a] == 0)
        continue;
      SVDAG_GRID_REAL face = size * SVDAG_GRID_REAL(cell[a] + (step[a] > 0 ? 1 : 0));
      SVDAG_GRID_REAL sFace = (face - origin[a]) / dir[a];
      if (axis < 0 || sFace < sNext)
      {
        sNext = sFace;
        axis = a;
      }
    }
    if (axis < 0 || sNext > sExit)
      return result;
    cell[axis] += step[axis];
    if (cell[axis] < 0 || cell[axis] >= cells[axis])
      return result;
    s = sNext > s ? sNext : s;
  }
  return result;
}

#ifdef __cplusplus
} // namespace traversal
} // namespace svdag
#endif

#endif
