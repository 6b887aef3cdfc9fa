// The volume's streams as both backends read them (block.rint, block.rchit, camera.comp): the
// globals Layout.h / Traversal.h read through (set by svdagBindStreams), a block record read from
// the chunked block stream, and the per-block level of detail.
#ifndef SVDAG_RENDER_STREAMS_GLSL
#define SVDAG_RENDER_STREAMS_GLSL

#include "svdag/Layout.h"

SvdagWords gRoots;
SvdagWords gMids;
SvdagLeafMasks gLeaves;
#define SVDAG_WORD(stream, i) (stream).w[(i)]
#define SVDAG_ROOT_STREAM gRoots
#define SVDAG_MID_STREAM gMids
#define SVDAG_LEAF(i) gLeaves.m[(i)]
#include "svdag/Traversal.h"

void svdagBindStreams()
{
  gRoots = SvdagWords(frame.volumeStreams.zw);
  gMids = SvdagWords(frame.volumeStreams2.xy);
  gLeaves = SvdagLeafMasks(frame.volumeStreams2.zw);
}

struct SvdagBlockRecord
{
  uint cell;
  uvec3 lo; // inclusive cell-local bounds
  uvec3 hi;
  uint label;
  uint rootRef;
};

// Block record `block` (Layout.h): its bit offset, block * record bits, takes up to 39 bits: it
// is computed in 64 bits and split into the chunk of the block stream that holds the record whole
// (Scene.h: chunks of 2^grid.w words, overlapping by a record) and the bit offset inside it.
SvdagBlockRecord svdagReadBlock(uint block)
{
  uint cellBits = frame.widths.x;
  uint labelBits = frame.widths.y;
  uint offsetHigh, offsetLow;
  umulExtended(block, frame.widths2.y, offsetHigh, offsetLow);
  uint word = (offsetHigh << 27u) | (offsetLow >> 5u);
  uint chunkShift = frame.grid.w;
  SvdagWords chunk = SvdagWords(SvdagAddresses(frame.volumeStreams.xy).a[word >> chunkShift]);
  uint base = ((word & ((1u << chunkShift) - 1u)) << 5u) | (offsetLow & 31u);
  SvdagBlockRecord r;
  uint box;
  SVDAG_READ_BITS(r.cell, chunk, base, cellBits);
  SVDAG_READ_BITS(box, chunk, base + blockBoundsOffset(cellBits), BLOCK_BOUNDS_BITS);
  SVDAG_READ_BITS(r.label, chunk, base + blockLabelOffset(cellBits), labelBits);
  SVDAG_READ_BITS(r.rootRef, chunk, base + blockRootOffset(cellBits, labelBits), frame.widths.z);
  r.lo = uvec3(box, box >> 4u, box >> 8u) & uvec3(15u);
  r.hi = uvec3(box >> 12u, box >> 16u, box >> 20u) & uvec3(15u);
  return r;
}

// Cell index -> cell coordinates (cell index = cx + nx * (cy + ny * cz)).
uvec3 svdagCellCoord(uint cell)
{
  uint nx = frame.grid.x;
  uint ny = frame.grid.y;
  return uvec3(cell % nx, (cell / nx) % ny, cell / (nx * ny));
}

// The level of detail of a ray in a block (origin relative to the cell's corner; the world
// distance of parameter t is distanceOffset + t). AUTO: the coarsest level whose cells (block: 16
// voxels, leaf: 4) still cover at most frame.autoLod.y pixels at the block's entry distance
// (GpuLayout.h: a pixel's world footprint grows from autoLod.z by autoLod.w per unit distance).
uint svdagChooseLod(uvec3 lo, uvec3 hi, uint rootRef, vec3 origin, vec3 direction, float tmin,
  float tmax, float distanceOffset)
{
  uint lod = frame.image.z;
  if (lod != SVDAG_RENDER_LOD_AUTO)
    return lod;
  SvdagBlockHit box = svdagIntersectBlock(lo, hi, rootRef, frame.widths.w, frame.widths2.x,
    origin, direction, tmin, tmax, SVDAG_LOD_BLOCK, false);
  float distance = distanceOffset + box.t;
  float pixelsPerVoxel = frame.autoLod.x / max(frame.autoLod.z + frame.autoLod.w * distance, 1.0e-30);
  if (16.0 * pixelsPerVoxel <= frame.autoLod.y)
    return SVDAG_LOD_BLOCK;
  if (4.0 * pixelsPerVoxel <= frame.autoLod.y)
    return SVDAG_LOD_LEAF;
  return SVDAG_LOD_VOXEL;
}

#endif
