// What a hit reports to the path tracer (SvdagPayload, Common.glsl), computed the same way by
// both backends (block.rchit, camera.comp): label index + 1, world distance, world entry face
// normal and shading normal (with smooth shading the estimate of Module/core/svdag/SmoothNormal.h,
// the code the CPU ray caster runs, from the hit label's occupancy around the hit point).
// Include after Streams.glsl.
#ifndef SVDAG_RENDER_HIT_PAYLOAD_GLSL
#define SVDAG_RENDER_HIT_PAYLOAD_GLSL

#include "Features.glsl"

SvdagWords gNeighbours;
// The hit block's 27 neighbour root references start at word 27 * block of the table.
#define SVDAG_NEIGHBOURS_PARAM uint svdagNeighbourBase,
#define SVDAG_NEIGHBOURS_ARG svdagNeighbourBase,
#define SVDAG_NEIGHBOUR_ROOT(n) gNeighbours.w[svdagNeighbourBase + (n)]
#include "svdag/SmoothNormal.h"

SvdagPayload svdagMissPayload()
{
  SvdagPayload p;
  p.label = 0u;
  p.t = SVDAG_DEPTH_MISS;
  p.normal = vec3(0.0);
  p.shading = vec4(0.0);
  return p;
}

// label: label index; t: world distance along a unit world direction (shared by the index-space
// ray, whose direction is not renormalised); objectNormal: index-space entry face (zero inside);
// block: the hit block where the hit is at voxel LOD, SVDAG_NO_BLOCK otherwise (shaded with the
// face normal); cellLocalHit: the hit point relative to the block's cell corner; objectDir: the
// index-space direction; worldToObject: the linear part of world -> index space.
SvdagPayload svdagHitPayload(uint label, float t, vec3 objectNormal, uint block, vec3 cellLocalHit,
  vec3 objectDir, mat3 worldToObject)
{
  SvdagPayload p;
  p.label = label + 1u;
  p.t = t;
  // Normals transform with the inverse transpose of object-to-world, i.e. the transpose of
  // world-to-object: n_world = transpose(W) * n = n * W.
  vec3 n = objectNormal * worldToObject;
  p.normal = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0);
  p.shading = vec4(p.normal, 0.0);
  if (SVDAG_FEATURE_SMOOTH_SHADING && block != SVDAG_NO_BLOCK && dot(n, n) > 0.0)
  {
    gNeighbours = SvdagWords(frame.widths2.zw);
    vec4 s = svdagSmoothNormalLift(27u * block, frame.widths.w, frame.widths2.x, cellLocalHit,
      objectNormal, objectDir);
    vec3 w = s.xyz * worldToObject;
    // The lift is in voxels: world units by the smallest voxel side (frame.autoLod.x).
    p.shading = dot(w, w) > 0.0 ? vec4(normalize(w), s.w * frame.autoLod.x) : vec4(p.normal, 0.0);
  }
  return p;
}

#endif
