/* Ray traversal of ONE block of the SVDAG, written once for C++ (with GLM) and GLSL 4.60.
 *
 * Like Layout.h (which must be included first) this file uses only the common subset of both
 * languages: 32-bit float and integer math, GLSL vector types, no recursion, no pointers, no
 * dynamic arrays and loops with a fixed bound.
 *
 * Storage access (defined by the including file; C++ gets defaults below):
 *   SVDAG_WORD(stream, i)   32-bit word i of a word stream (used by SVDAG_READ_BITS)
 *   SVDAG_ROOT_STREAM       the root node stream, as an argument for SVDAG_WORD
 *   SVDAG_MID_STREAM        the mid node stream
 *   SVDAG_LEAF(i)           leaf mask i as a uvec2 (x = bits 0..31, y = bits 32..63), so that GLSL
 *                           needs no 64-bit integers
 *   SVDAG_STREAMS_PARAM     optional leading parameter declaration that carries the streams (C++:
 *                           "const svdag::traversal::Streams& svdagStreams,"; GLSL: empty, the
 *                           buffers are globals), and SVDAG_STREAMS_ARG the matching argument.
 *
 * Conventions
 *   - Index space: voxel (i, j, k) occupies the box [i, i+1) x [j, j+1) x [k, k+1). The VTK point
 *     at index i is the voxel's CENTER: index-space position p is VTK continuous index p - 0.5.
 *   - Cell c = (cx, cy, cz) has its integer corner at 16 * c. The traversal works in CELL-LOCAL
 *     coordinates (index space minus the corner), so its float precision does not depend on where
 *     the cell lies in a huge volume. A block's voxels are the cell-local voxels 0..15.
 *   - The ray is origin + t * dir for t in [tmin, tmax]; t is in units of |dir| (pass a unit
 *     vector to get distances). Components with |dir| < SVDAG_PARALLEL_EPS count as zero: along
 *     such an axis the ray is inside a slab [a, b) iff a <= origin < b (half-open, like voxels).
 *     A direction with all components below that is no ray and never hits; nor does an empty
 *     (or NaN) interval [tmin, tmax].
 *   - Boxes are otherwise closed: a ray that only touches a box at a face, edge or corner may or
 *     may not hit it (a zero-length contact); everything with a positive length inside is found.
 *   - Result: hit flag; t = where the ray enters the hit box (block box, leaf box or voxel),
 *     clamped to tmin when the ray starts inside; normal = the entry face as an integer axis and
 *     sign (e.g. (-1, 0, 0) when entering through the face x = min), zero when the ray starts
 *     inside (entry t < tmin); voxel = the cell-local voxel where the ray is when it enters the
 *     hit box (for SVDAG_LOD_VOXEL the solid voxel hit).
 *   - LOD: SVDAG_LOD_BLOCK hits the block's tight bounds box; SVDAG_LOD_LEAF hits the first
 *     non-empty 4^3 region, as the box (leaf cube intersected with the block bounds); SVDAG_LOD_VOXEL
 *     hits the first solid voxel (lossless).
 *   - Entry only (entryOnly = true): for rays that continue through a surface they have just
 *     crossed (specular transmission), which start inside a solid. If the ray is inside the block
 *     box at tmin (a point on a face counts as inside the box it moves into), the solid run it
 *     starts in (solid voxels, non-empty leaf boxes or, for SVDAG_LOD_BLOCK, the whole block box)
 *     is skipped: the DDA walks through solid regions until it reaches an empty one and then
 *     reports the next solid region it enters, with that entry face as the normal. So an
 *     entry-only hit always has a non-zero normal, and at SVDAG_LOD_BLOCK a ray starting inside the
 *     box never hits that block. "Solid" is per block, i.e. per (cell, label): voxels of other
 *     labels are empty here, and the same label in the next cell is another block, whose box the
 *     ray enters (an entry there). The traversal needs no knowledge of which label the ray is in.
 *
 * Method: a slab test against the block bounds, then a 3D DDA that, at each step, classifies the
 * largest aligned region (8^3 octant, 4^3 leaf or voxel) around the current voxel by descending
 * the DAG from the root (complement bits accumulate down the path; full children are solid at any
 * level; the last mid node and leaf read are cached), and either reports the hit or jumps to the
 * exit of that empty region, clipped to the block bounds.
 *
 * Loop bound: the current voxel stays inside the block bounds, each coordinate moves monotonically
 * in the ray's direction, and every non-final step moves the exit axis by at least one voxel. So
 * there are at most 3 * 15 non-final steps plus the final one: SVDAG_MAX_STEPS = 64 is never
 * reached by a valid block (reaching it reports a miss). Entry-only mode steps through the solid
 * regions of its initial run exactly as through empty ones (same exit computation, same
 * monotonic moves), so those steps count against the same 3 * 15 and the bound holds unchanged.
 */
#ifndef SVDAG_TRAVERSAL_H
#define SVDAG_TRAVERSAL_H

#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
namespace svdag
{
namespace traversal
{
using namespace ::svdag::layout;
using glm::ivec3;
using glm::max;
using glm::min;
using glm::uvec2;
using glm::uvec3;
using glm::vec3;

// The streams of a Volume, as the C++ traversal reads them.
struct Streams
{
  const uint32_t* roots;
  const uint32_t* mids;
  const uint64_t* leaves;
};

#ifndef SVDAG_WORD
#define SVDAG_WORD(stream, i) (stream)[(i)]
#endif
#ifndef SVDAG_STREAMS_PARAM
#define SVDAG_STREAMS_PARAM const ::svdag::traversal::Streams &svdagStreams,
#define SVDAG_STREAMS_ARG svdagStreams,
#define SVDAG_ROOT_STREAM svdagStreams.roots
#define SVDAG_MID_STREAM svdagStreams.mids
#define SVDAG_LEAF(i)                                                                              \
  uvec2(uint32_t(svdagStreams.leaves[(i)]), uint32_t(svdagStreams.leaves[(i)] >> 32u))
#endif
#define SVDAG_INOUT(T) T&
#define SVDAG_FLOOR(x) glm::floor(x)
#define SVDAG_CEIL(x) glm::ceil(x)

#else // GLSL

#ifndef SVDAG_STREAMS_PARAM
#define SVDAG_STREAMS_PARAM
#define SVDAG_STREAMS_ARG
#endif
#define SVDAG_INOUT(T) inout T
#define SVDAG_FLOOR(x) floor(x)
#define SVDAG_CEIL(x) ceil(x)
#endif

// svdag::render::Lod's and svdag::Lod's values (static_asserts in Rendering/core/RenderSettings.cpp).
SVDAG_CONST SVDAG_LOD_BLOCK = 0u;
SVDAG_CONST SVDAG_LOD_LEAF = 1u;
SVDAG_CONST SVDAG_LOD_VOXEL = 2u;
SVDAG_CONST SVDAG_MAX_STEPS = 64u;

/* Step statistics: SVDAG_STAT(counter) is called where a ray spends work (here and in
 * GridTraversal.h); an includer that counts defines it (the compute backend's statistics
 * variant, camera.comp; a test), everyone else gets nothing. The counters: */
SVDAG_CONST SVDAG_STAT_RAYS = 0u;        // grid walks (camera, bounce and shadow rays)
SVDAG_CONST SVDAG_STAT_CELLS = 1u;       // cells visited
SVDAG_CONST SVDAG_STAT_FULL_CELLS = 2u;  // cells visited that hold blocks
SVDAG_CONST SVDAG_STAT_BLOCKS = 3u;      // block records read (the cells' blocks tested)
SVDAG_CONST SVDAG_STAT_WALKS = 4u;       // DAG walks (the ray enters the block's box)
SVDAG_CONST SVDAG_STAT_NODE_STEPS = 5u;  // iterations of the DAG walks (regions classified)
SVDAG_CONST SVDAG_STAT_SHADOW_RAYS = 6u; // grid walks of occlusion rays (among RAYS)
SVDAG_CONST SVDAG_STAT_HITS = 7u;        // grid walks that hit
SVDAG_CONST SVDAG_STAT_COUNT = 8u;
#ifndef SVDAG_STAT
#define SVDAG_STAT(counter)
#endif

/* Direction components below this magnitude are treated as zero (their reciprocal, at most 1e30,
 * keeps every t finite: no inf, and never 0 * inf = NaN). Beyond every finite t below. */
#define SVDAG_PARALLEL_EPS 1.0e-30f
#define SVDAG_T_FAR 1.0e36f

struct SvdagBlockHit
{
  bool hit;
  float t;
  ivec3 normal;
  ivec3 voxel; // cell-local
};

/* Per-axis stepping of a ray: step is -1, 0 (parallel) or +1; invDir is 0 for parallel axes. */
struct SvdagRay
{
  vec3 origin;
  vec3 invDir;
  vec3 dir;
  ivec3 step;
};

SVDAG_FN SvdagRay svdagMakeRay(vec3 origin, vec3 dir)
{
  SvdagRay r;
  r.origin = origin;
  r.dir = dir;
  r.invDir = vec3(0.0f);
  r.step = ivec3(0);
  for (int a = 0; a < 3; ++a)
  {
    if (dir[a] > SVDAG_PARALLEL_EPS)
      r.step[a] = 1;
    else if (dir[a] < -SVDAG_PARALLEL_EPS)
      r.step[a] = -1;
    if (r.step[a] != 0)
      r.invDir[a] = 1.0f / dir[a];
  }
  return r;
}

/* Slab test of the ray against the box [bmin, bmax] (half-open along parallel axes). On return,
 * [tEnter, tExit] is the ray's parameter interval in the box (not clipped to [tmin, tmax]) and
 * enterAxis the axis whose face it enters through (-1 if only parallel axes). */
SVDAG_FN bool svdagSlab(SvdagRay r, vec3 bmin, vec3 bmax, SVDAG_INOUT(float) tEnter,
  SVDAG_INOUT(float) tExit, SVDAG_INOUT(int) enterAxis)
{
  tEnter = -SVDAG_T_FAR;
  tExit = SVDAG_T_FAR;
  enterAxis = -1;
  for (int a = 0; a < 3; ++a)
  {
    if (r.step[a] == 0)
    {
      if (r.origin[a] < bmin[a] || r.origin[a] >= bmax[a])
        return false;
      continue;
    }
    float tLo = (bmin[a] - r.origin[a]) * r.invDir[a];
    float tHi = (bmax[a] - r.origin[a]) * r.invDir[a];
    float tNear = r.step[a] > 0 ? tLo : tHi;
    float tFar = r.step[a] > 0 ? tHi : tLo;
    if (tNear > tEnter)
    {
      tEnter = tNear;
      enterAxis = a;
    }
    tExit = tFar < tExit ? tFar : tExit;
  }
  return enterAxis >= 0 && tEnter <= tExit;
}

/* The voxel coordinate the ray is in (or about to enter) at position p along one axis: a point
 * on a voxel face belongs to the voxel the ray moves into; clamped to [lo, hi] so that rounding
 * at the block's faces cannot leave the bounds (and no huge float is ever converted to int). */
SVDAG_FN int svdagVoxelCoord(float p, int step, int lo, int hi)
{
  float c = p < -1.0f ? -1.0f : (p > 17.0f ? 17.0f : p);
  int v = step < 0 ? int(SVDAG_CEIL(c)) - 1 : int(SVDAG_FLOOR(c));
  return v < lo ? lo : (v > hi ? hi : v);
}

SVDAG_FN bool svdagLeafBit(uvec2 mask, uint bit)
{
  uint word = bit < 32u ? mask.x : mask.y;
  return ((word >> (bit & 31u)) & 1u) != 0u;
}

/* The compact form's child lookups (Layout.h), shared by the traversal, the smooth normals and
 * the C++ readers. `header` is the node's first COMPACT_HEADER_BITS bits, `rank` the mixed
 * child's rank.
 *
 * The mid node of a root's child: its offset in the mid stream; `inverted` (the root's
 * polarity on entry) becomes the mid's. A chained mid is found by stepping over the chained
 * siblings before it (at most 7 header reads). */
SVDAG_FN SVDAG_OFFSET_T svdagRootChildMid(SVDAG_STREAMS_PARAM SVDAG_OFFSET_T rootOffset,
  uint header, uint rank, uint midRefBits, uint leafRefBits, SVDAG_INOUT(bool) inverted)
{
  if (!compactChildFlagged(header, rank))
  {
    uint ref;
    SVDAG_READ_BITS(ref, SVDAG_ROOT_STREAM,
      rootOffset + SVDAG_OFFSET_T(compactRootRefOffset(header, rank, midRefBits)), midRefBits);
    inverted = inverted != refComplement(ref);
    return SVDAG_OFFSET_T(refTarget(ref));
  }
  uint base;
  SVDAG_READ_BITS(base, SVDAG_ROOT_STREAM, rootOffset + SVDAG_OFFSET_T(compactPrefixBits(header)),
    midRefBits - 1u);
  SVDAG_OFFSET_T at = SVDAG_OFFSET_T(base);
  uint before = compactFlaggedBefore(header, rank);
  for (uint sibling = 0u; sibling < 7u; ++sibling)
  {
    if (sibling >= before)
      break;
    uint siblingHeader;
    SVDAG_READ_BITS(siblingHeader, SVDAG_MID_STREAM, at, COMPACT_HEADER_BITS);
    at += SVDAG_OFFSET_T(compactMidBits(siblingHeader, leafRefBits));
  }
  return at;
}

/* The occupancy of a mid node's child as the mid node sees it (the caller applies the mid's
 * polarity): voxel (x, y, z) is bit leafSymmetryBit(symmetry, x, y, z) of the returned mask
 * (x = bits 0..31, y = bits 32..63). */
SVDAG_FN uvec2 svdagMidChildLeaf(SVDAG_STREAMS_PARAM SVDAG_OFFSET_T midOffset, uint header,
  uint rank, uint leafRefBits, SVDAG_INOUT(uint) symmetry)
{
  uvec2 mask;
  if (compactChildFlagged(header, rank))
  {
    SVDAG_OFFSET_T at = midOffset + SVDAG_OFFSET_T(compactMidMaskOffset(header, rank, leafRefBits));
    SVDAG_READ_BITS(mask.x, SVDAG_MID_STREAM, at, 32u);
    SVDAG_READ_BITS(mask.y, SVDAG_MID_STREAM, at + SVDAG_OFFSET_T(32u), 32u);
    symmetry = 0u; // the identity
    return mask;
  }
  uint ref;
  SVDAG_READ_BITS(ref, SVDAG_MID_STREAM,
    midOffset + SVDAG_OFFSET_T(compactMidRefOffset(header, rank, leafRefBits)), leafRefBits);
  mask = SVDAG_LEAF(leafRefIndex(ref));
  symmetry = leafRefSymmetry(ref);
  return refComplement(ref) ? ~mask : mask;
}

/* Intersects one block with a ray in cell-local coordinates.
 *   lo, hi       inclusive cell-local voxel bounds of the block (Layout.h block record)
 *   rootRef      the block's root reference (offset << 1 | complement)
 *   midRefBits, leafRefBits   the volume's reference widths (root -> mid, mid -> leaf)
 *   origin, dir  the ray, origin relative to the cell's corner
 *   tmin, tmax   the parameter interval searched
 *   lod          SVDAG_LOD_BLOCK, SVDAG_LOD_LEAF or SVDAG_LOD_VOXEL
 *   entryOnly    skip the solid run the ray starts in (see "Entry only" above); false: the
 *                plain first-hit query */
SVDAG_FN SvdagBlockHit svdagIntersectBlock(SVDAG_STREAMS_PARAM uvec3 lo, uvec3 hi, uint rootRef,
  uint midRefBits, uint leafRefBits, vec3 origin, vec3 dir, float tmin, float tmax, uint lod,
  bool entryOnly)
{
  SvdagBlockHit result;
  result.hit = false;
  result.t = tmax;
  result.normal = ivec3(0);
  result.voxel = ivec3(0);

  if (!(tmin <= tmax)) // an empty interval (or NaN) is a miss
    return result;
  SvdagRay ray = svdagMakeRay(origin, dir);
  ivec3 boxLo = ivec3(lo);
  ivec3 boxHi = ivec3(hi);
  float tEnter;
  float tExit;
  int enterAxis;
  if (!svdagSlab(ray, vec3(boxLo), vec3(boxHi + ivec3(1)), tEnter, tExit, enterAxis))
    return result;
  if (tExit < tmin || tEnter > tmax)
    return result;

  // Entry point and its voxel; the entry face unless the ray starts inside the box.
  float t = tEnter > tmin ? tEnter : tmin;
  ivec3 normal = ivec3(0);
  if (tEnter >= tmin)
    normal[enterAxis] = -ray.step[enterAxis];
  ivec3 voxel;
  for (int a = 0; a < 3; ++a)
    voxel[a] = svdagVoxelCoord(origin[a] + t * dir[a], ray.step[a], boxLo[a], boxHi[a]);

  // Entry-only rays that start inside the box skip the solid run they start in; one that starts
  // outside enters the box, and whatever is solid at the entry is an entry.
  bool skipping = entryOnly && tEnter <= tmin;
  if (lod == SVDAG_LOD_BLOCK)
  {
    if (skipping)
      return result; // the whole box is the solid run
    result.hit = true;
    result.t = t;
    result.normal = normal;
    result.voxel = voxel;
    return result;
  }

  SVDAG_STAT(SVDAG_STAT_WALKS);
  bool rootInverted = refComplement(rootRef);
  SVDAG_OFFSET_T rootOffset = SVDAG_OFFSET_T(refTarget(rootRef));
  uint rootHeader;
  SVDAG_READ_BITS(rootHeader, SVDAG_ROOT_STREAM, rootOffset, COMPACT_HEADER_BITS);

  // Cache of the last mid node (by root octant) and leaf (by octant * 8 + mid child) read.
  uint cachedOctant = 8u;
  SVDAG_OFFSET_T midOffset = SVDAG_OFFSET_T(0u);
  uint midHeader = 0u;
  bool midInverted = false;
  uint cachedLeaf = 64u;
  uvec2 leafMask = uvec2(0u);
  uint leafSymmetry = 0u; // of the cached leaf (Layout.h)

  for (uint iteration = 0u; iteration < SVDAG_MAX_STEPS; ++iteration)
  {
    SVDAG_STAT(SVDAG_STAT_NODE_STEPS);
    // Classify the largest uniform aligned region around the voxel: size 8, 4 or 1.
    uvec3 local = uvec3(voxel);
    uint octant8 = octant(local.x, local.y, local.z, MID_SIZE);
    int size = int(MID_SIZE);
    bool solid;
    uint rootMixed = nodeMixedMask(rootHeader);
    if ((rootMixed & (1u << octant8)) == 0u)
    {
      solid = ((nodeFullMask(rootHeader) >> octant8) & 1u) != (rootInverted ? 1u : 0u);
    }
    else
    {
      if (cachedOctant != octant8)
      {
        midInverted = rootInverted;
        midOffset = svdagRootChildMid(SVDAG_STREAMS_ARG rootOffset, rootHeader,
          childRank(rootMixed, octant8), midRefBits, leafRefBits, midInverted);
        SVDAG_READ_BITS(midHeader, SVDAG_MID_STREAM, midOffset, COMPACT_HEADER_BITS);
        cachedOctant = octant8;
      }
      uvec3 inMid = local % uvec3(MID_SIZE);
      uint octant4 = octant(inMid.x, inMid.y, inMid.z, LEAF_SIZE);
      size = int(LEAF_SIZE);
      uint midMixed = nodeMixedMask(midHeader);
      if ((midMixed & (1u << octant4)) == 0u)
      {
        solid = ((nodeFullMask(midHeader) >> octant4) & 1u) != (midInverted ? 1u : 0u);
      }
      else
      {
        uint leafKey = octant8 * 8u + octant4;
        if (cachedLeaf != leafKey)
        {
          leafMask = svdagMidChildLeaf(SVDAG_STREAMS_ARG midOffset, midHeader,
            childRank(midMixed, octant4), leafRefBits, leafSymmetry);
          if (midInverted)
            leafMask = ~leafMask;
          cachedLeaf = leafKey;
        }
        if (lod == SVDAG_LOD_LEAF)
        {
          solid = leafMask.x != 0u || leafMask.y != 0u;
        }
        else
        {
          uvec3 inLeaf = local % uvec3(LEAF_SIZE);
          size = 1;
          solid = svdagLeafBit(leafMask, leafSymmetryBit(leafSymmetry, inLeaf.x, inLeaf.y, inLeaf.z));
        }
      }
    }

    if (!solid)
      skipping = false; // the initial solid run has ended: the next solid region is an entry
    else if (!skipping)
    {
      result.hit = true;
      result.t = t;
      result.normal = normal;
      result.voxel = voxel;
      return result;
    }

    // Leave the empty region (or, while skipping, the solid one), clipped to the block bounds,
    // through its nearest exit face.
    ivec3 regionLo = voxel - (voxel % ivec3(size));
    ivec3 clipLo = max(regionLo, boxLo);
    ivec3 clipHi = min(regionLo + ivec3(size - 1), boxHi);
    int exitAxis = -1;
    float tNext = SVDAG_T_FAR;
    for (int a = 0; a < 3; ++a)
    {
      if (ray.step[a] == 0)
        continue;
      float face = float(ray.step[a] > 0 ? clipHi[a] + 1 : clipLo[a]);
      float tFace = (face - origin[a]) * ray.invDir[a];
      if (tFace < tNext)
      {
        tNext = tFace;
        exitAxis = a;
      }
    }
    if (exitAxis < 0 || tNext > tmax)
      return result;
    int next = ray.step[exitAxis] > 0 ? clipHi[exitAxis] + 1 : clipLo[exitAxis] - 1;
    if (next < boxLo[exitAxis] || next > boxHi[exitAxis])
      return result; // left the block
    // The other axes stay inside the region and never move backwards (this bounds the loop).
    for (int a = 0; a < 3; ++a)
    {
      if (a == exitAxis || ray.step[a] == 0)
        continue;
      int lowest = ray.step[a] > 0 ? voxel[a] : clipLo[a];
      int highest = ray.step[a] > 0 ? clipHi[a] : voxel[a];
      voxel[a] = svdagVoxelCoord(origin[a] + tNext * dir[a], ray.step[a], lowest, highest);
    }
    voxel[exitAxis] = next;
    t = tNext > t ? tNext : t;
    normal = ivec3(0);
    normal[exitAxis] = -ray.step[exitAxis];
  }
  return result;
}

#ifdef __cplusplus
} // namespace traversal
} // namespace svdag
#endif

#endif
