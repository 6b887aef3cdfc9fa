#version 460
// The camera of the compute backend: PathTrace.glsl's camera and path tracer, its rays walked
// through the volume's grid of 16^3 cells by GridTraversal.h (the code the CPU ray caster runs),
// each cell's blocks intersected by Traversal.h. No acceleration structure: the cell grid is a
// table of each cell's first block (blocks are sorted by cell), and hidden labels are bits.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_shuffle : require
#include "Common.glsl"
#include "Features.glsl"

// One workgroup: an SVDAG_COMPUTE_GROUP_SIZE^2 pixel tile, its invocations in 4 x 2 pixel
// quads (invocation i: quad i / 8, pixel i % 8 in it), so that the 8 lanes a CPU implementation
// runs side by side (lavapipe: SIMD8) trace neighbouring pixels in both directions, whose rays
// diverge less than those of a row of 8.
layout(local_size_x = SVDAG_COMPUTE_GROUP_SIZE * SVDAG_COMPUTE_GROUP_SIZE) in;

uvec2 pixelOfInvocation()
{
  uint i = gl_LocalInvocationIndex;
  uint quad = i >> 3u;
  uint quadsPerRow = SVDAG_COMPUTE_GROUP_SIZE / 4u;
  uvec2 inTile = uvec2((quad % quadsPerRow) * 4u + (i & 3u), (quad / quadsPerRow) * 2u + ((i >> 2u) & 1u));
  return gl_WorkGroupID.xy * SVDAG_COMPUTE_GROUP_SIZE + inTile;
}

SvdagPayload payload;

// Step statistics (Traversal.h's SVDAG_STAT): this invocation's counts over its pass, written
// per pixel at the end. A specialization constant: off, the counting is compiled out.
layout(constant_id = SVDAG_CONSTANT_STEP_STATISTICS) const bool featureStepStatistics = false;
uint gStepCounts[8];
#define SVDAG_STAT(counter)                                                                        \
  {                                                                                                \
    if (featureStepStatistics)                                                                     \
      gStepCounts[(counter)] += 1u;                                                                \
  }

#include "Streams.glsl"
#include "HitPayload.glsl"

// Cell c's blocks are [starts[c], starts[c + 1]) (Scene.h); bit l of the hidden bits: label
// index l is not drawn (visibility 0 or setHiddenLabels), when any is hidden.
SvdagWords gCellStarts;
SvdagWords gHidden;
bool gAnyHidden;
#define SVDAG_GRID_CELL_BLOCKS(cell, first, end)                                                   \
  {                                                                                                \
    first = gCellStarts.w[(cell)];                                                                 \
    end = gCellStarts.w[(cell) + 1u];                                                              \
  }
#define SVDAG_GRID_BLOCK(b, lo, hi, rootRef, label)                                                \
  {                                                                                                \
    SvdagBlockRecord record_ = svdagReadBlock(b);                                                  \
    lo = record_.lo;                                                                               \
    hi = record_.hi;                                                                               \
    rootRef = record_.rootRef;                                                                     \
    label = record_.label;                                                                         \
  }
#define SVDAG_GRID_SKIP(label) (gAnyHidden && ((gHidden.w[(label) >> 5u] >> ((label) & 31u)) & 1u) != 0u)
// The preview walks block boxes only: the DAG's descent is compiled out with it.
#define SVDAG_GRID_LOD(lod, lo, hi, rootRef, origin, dir, tmin, tmax, s)                           \
  (SVDAG_FEATURE_PREVIEW ? SVDAG_LOD_BLOCK : svdagChooseLod(lo, hi, rootRef, origin, dir, tmin, tmax, s))
#include "svdag/GridTraversal.h"

// World (relative to the scene's reference point) -> volume index space (GpuLayout.h).
vec3 indexPoint(vec3 p)
{
  return vec3(dot(frame.worldToIndexX.xyz, p) + frame.worldToIndexX.w,
    dot(frame.worldToIndexY.xyz, p) + frame.worldToIndexY.w,
    dot(frame.worldToIndexZ.xyz, p) + frame.worldToIndexZ.w);
}

vec3 indexVector(vec3 d)
{
  return vec3(dot(frame.worldToIndexX.xyz, d), dot(frame.worldToIndexY.xyz, d),
    dot(frame.worldToIndexZ.xyz, d));
}

SvdagGridHit castGrid(vec3 origin, vec3 direction, float tmin, float tmax, bool entryOnly,
  bool anyHit)
{
  return svdagCastGrid(indexPoint(origin), indexVector(direction), tmin, tmax,
    ivec3(frame.volumeDims.xyz), ivec3(frame.grid.xy, frame.volumeDims.w), frame.widths.w,
    frame.widths2.x, SVDAG_FEATURE_PREVIEW ? SVDAG_LOD_BLOCK : frame.image.z, entryOnly, anyHit);
}

// The world direction has unit length and the index-space one is not renormalised, so the walk
// parameter is the world distance, as in the ray tracing backend. Shadow rays (anyHit) go through
// the same walk, stopping at the first hit: the walk is inlined once.
void svdagTraceInterval(vec3 origin, vec3 direction, float tmin, float tmax, uint hitGroup,
  bool anyHit)
{
  SvdagGridHit h = castGrid(origin, direction, tmin, tmax, hitGroup == 1u, anyHit);
  if (!h.hit)
  {
    payload = svdagMissPayload();
    return;
  }
  if (anyHit)
  {
    payload.label = 1u;
    return;
  }
  vec3 o = indexPoint(origin);
  vec3 d = indexVector(direction);
  // Relative to the hit cell's corner before the parameter is added, as the walk anchors it.
  vec3 local = (o - vec3(h.cell * ivec3(CELL_SIZE))) + h.s * d;
  mat3 worldToIndex = transpose(
    mat3(frame.worldToIndexX.xyz, frame.worldToIndexY.xyz, frame.worldToIndexZ.xyz));
  payload = svdagHitPayload(h.label, h.s, vec3(h.normal),
    h.lod == SVDAG_LOD_VOXEL ? h.block : SVDAG_NO_BLOCK, local, d, worldToIndex);
}

// The coverage dispatch shares a subgroup's sub-pixel rays among its invocations (PathTrace.glsl):
// subgroup operations, not workgroup barriers and shared memory, whose mere presence in the
// program cost lavapipe's frames 6-10%.
#define SVDAG_COVERAGE_SUBGROUP 1
#include "PathTrace.glsl"

void main()
{
  svdagBindStreams();
  gCellStarts = SvdagWords(frame.cellGrid.xy);
  gAnyHidden = frame.cellGrid.z != 0u || frame.cellGrid.w != 0u;
  gHidden = SvdagWords(frame.cellGrid.zw);
  if (featureStepStatistics)
  {
    for (uint c = 0u; c < SVDAG_STAT_COUNT; ++c)
      gStepCounts[c] = 0u;
  }
  uvec2 pixel = pixelOfInvocation();
  svdagRenderPixel(pixel);
  if (featureStepStatistics && pixel.x < frame.image.x && pixel.y < frame.image.y &&
    (frame.stepStatistics.x != 0u || frame.stepStatistics.y != 0u))
  {
    SvdagUintOutput counts = SvdagUintOutput(frame.stepStatistics.xy);
    uint base = SVDAG_STAT_COUNT * (pixel.x + frame.image.x * pixel.y);
    for (uint c = 0u; c < SVDAG_STAT_COUNT; ++c)
      counts.v[base + c] = gStepCounts[c];
  }
}
