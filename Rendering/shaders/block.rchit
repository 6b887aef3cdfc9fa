#version 460
// The nearest block hit: label index + 1, world distance, world-space face normal and shading
// normal (with smooth shading the estimate of Module/core/svdag/SmoothNormal.h, the code the CPU
// ray caster runs, from the hit label's occupancy around the hit point).
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
#include "Common.glsl"
#include "svdag/Layout.h"

// Stream access for Traversal.h / SmoothNormal.h (set in main() when smooth shading needs them).
SvdagWords gRoots;
SvdagWords gMids;
SvdagLeafMasks gLeaves;
SvdagWords gNeighbours;
#define SVDAG_WORD(stream, i) (stream).w[(i)]
#define SVDAG_ROOT_STREAM gRoots
#define SVDAG_MID_STREAM gMids
#define SVDAG_LEAF(i) gLeaves.m[(i)]
#include "svdag/Traversal.h"
// The hit block's 27 neighbour root references start at word 27 * block of the table.
#define SVDAG_NEIGHBOURS_PARAM uint svdagNeighbourBase,
#define SVDAG_NEIGHBOURS_ARG svdagNeighbourBase,
#define SVDAG_NEIGHBOUR_ROOT(n) gNeighbours.w[svdagNeighbourBase + (n)]
#include "svdag/SmoothNormal.h"

layout(location = SVDAG_PAYLOAD_CLOSEST) rayPayloadInEXT SvdagPayload payload;
hitAttributeEXT SvdagHitAttributes attributes;

void main()
{
  payload.label = attributes.label + 1u;
  // The world ray's direction has unit length and t is shared by the object-space ray (the
  // instance transform is affine and the direction is not renormalised): t is the distance.
  payload.t = gl_HitTEXT;
  // Normals transform with the inverse transpose of object-to-world, i.e. the transpose of
  // world-to-object: n_world = transpose(W) * n = n * W.
  vec3 n = attributes.normal * mat3(gl_WorldToObjectEXT);
  payload.normal = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0);
  payload.shading = vec4(payload.normal, 0.0);
  if (frame.image.w == SVDAG_SHADING_SMOOTH && attributes.block != SVDAG_NO_BLOCK &&
    dot(n, n) > 0.0)
  {
    gRoots = SvdagWords(frame.volumeStreams.zw);
    gMids = SvdagWords(frame.volumeStreams2.xy);
    gLeaves = SvdagLeafMasks(frame.volumeStreams2.zw);
    gNeighbours = SvdagWords(frame.widths2.zw);
    // The hit point in the block's cell-local coordinates, as block.rint anchors the ray.
    uint nx = frame.grid.x;
    uint ny = frame.grid.y;
    uint cell = attributes.cell;
    uvec3 cellCoord = uvec3(cell % nx, (cell / nx) % ny, cell / (nx * ny));
    vec3 origin = gl_ObjectRayOriginEXT - vec3(cellCoord * CELL_SIZE);
    vec3 p = origin + gl_HitTEXT * gl_ObjectRayDirectionEXT;
    vec4 s = svdagSmoothNormalLift(27u * attributes.block, frame.widths.w, frame.widths2.x, p,
      attributes.normal, gl_ObjectRayDirectionEXT);
    vec3 w = s.xyz * mat3(gl_WorldToObjectEXT);
    // The lift is in voxels: world units by the smallest voxel side (frame.autoLod.x).
    payload.shading = dot(w, w) > 0.0 ? vec4(normalize(w), s.w * frame.autoLod.x)
                                      : vec4(payload.normal, 0.0);
  }
}
