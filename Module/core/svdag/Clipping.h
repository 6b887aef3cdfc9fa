/* Clipping of a ray's parameter interval to a convex region (clipping planes and a crop box),
 * written once for C++ (with GLM) and GLSL 4.60, in the common subset of both like Traversal.h.
 *
 * The region kept is the intersection of half-spaces, each a plane vec4 (n.xyz, w) that keeps the
 * points p with dot(n, p) + w >= 0 (VTK's convention: the side the normal points to). A crop box
 * is six such planes. The ray origin + t * dir keeps [tmin, tmax] intersected with the region;
 * a parallel ray (dot(n, dir) == 0) keeps all or nothing of a plane. Every kept interval is one
 * interval: the region is convex.
 *
 * Precision: C++ computes in double (the CPU reference), GLSL in float.
 *
 * Conventions the hosts (svdag::RayCaster, the GPU renderer) follow:
 *   - The planes are in the space the rays are traced in, with n of unit length in WORLD units, so
 *     that dot(n, p) + w is a world distance; at most SVDAG_CLIP_MAX_SLOTS planes: up to
 *     SVDAG_CLIP_MAX_PLANES user planes first, then the crop box's six faces.
 *   - Each plane is moved into the kept side by a margin (w - margin; a fraction of a voxel, see
 *     the hosts), so that the point where a ray enters the region lies strictly inside it even
 *     after rounding: a plane exactly on voxel faces then never shows the voxels just outside it
 *     (no speckle). The margin is far below the ray epsilon of secondary rays, so a ray leaving a
 *     cut face starts outside the region and is clipped away entirely where it moves away from it.
 *   - Cut faces: the traversal reports a ray that starts inside a solid as a hit at t = tmin with
 *     a zero normal. When tmin was moved by plane i (enterPlane = i), that hit is the cut face of
 *     plane i: its normal is -n (the region's outward normal, facing the ray). At block and leaf
 *     LOD the solid is the block box or leaf box, so the cut shows their cross-sections.
 */
#ifndef SVDAG_CLIPPING_CONSTANTS_H
#define SVDAG_CLIPPING_CONSTANTS_H
/* User clipping planes (VTK's usual limit) and all plane slots (the crop box adds six). */
#define SVDAG_CLIP_MAX_PLANES 6
#define SVDAG_CLIP_MAX_SLOTS 12
#endif

/* GLSL: the function needs the includer's plane accessor SVDAG_CLIP_PLANE(i), so a file that only
 * needs the constants (GpuLayout.h, before the uniform block exists) gets only those. */
#if !defined(SVDAG_CLIPPING_H) && (defined(__cplusplus) || defined(SVDAG_CLIP_PLANE))
#define SVDAG_CLIPPING_H

#ifdef __cplusplus
#include <glm/glm.hpp>
namespace svdag
{
namespace clipping
{
typedef unsigned int uint;
typedef double SvdagClipReal;
typedef glm::dvec3 SvdagClipVec3;
typedef glm::dvec4 SvdagClipVec4;
#define SVDAG_CLIP_FN inline
// C++ passes the planes as an array; GLSL reads them with SVDAG_CLIP_PLANE(i) (the includer's
// uniform array).
#define SVDAG_CLIP_PLANES_PARAM const ::svdag::clipping::SvdagClipVec4 *svdagClipPlanes,
#define SVDAG_CLIP_PLANE(i) svdagClipPlanes[(i)]
using glm::dot;
#else
#define SvdagClipReal float
#define SvdagClipVec3 vec3
#define SvdagClipVec4 vec4
#define SVDAG_CLIP_FN
#define SVDAG_CLIP_PLANES_PARAM
#endif

struct SvdagClipInterval
{
  bool kept;       // false: no part of [tmin, tmax] is inside the region
  SvdagClipReal tmin;
  SvdagClipReal tmax;
  int enterPlane;  // the plane that moved tmin (where the ray enters the region), else -1
};

/* [tmin, tmax] of the ray origin + t * dir intersected with the region of planeCount planes. */
SVDAG_CLIP_FN SvdagClipInterval svdagClipInterval(SVDAG_CLIP_PLANES_PARAM uint planeCount,
  SvdagClipVec3 origin, SvdagClipVec3 dir, SvdagClipReal tmin, SvdagClipReal tmax)
{
  SvdagClipInterval r;
  r.tmin = tmin;
  r.tmax = tmax;
  r.enterPlane = -1;
  bool outside = false;
  for (uint i = 0u; i < uint(SVDAG_CLIP_MAX_SLOTS); ++i)
  {
    if (i >= planeCount)
      break;
    SvdagClipVec4 plane = SVDAG_CLIP_PLANE(i);
    SvdagClipVec3 n = SvdagClipVec3(plane);
    SvdagClipReal f = dot(n, origin) + plane.w; // the plane function at t = 0
    SvdagClipReal d = dot(n, dir);              // its change per unit t
    if (d > SvdagClipReal(0))
    {
      // Entering: kept from t = -f / d on. Ties keep the first plane (user planes before crop).
      SvdagClipReal t = -f / d;
      if (t > r.tmin)
      {
        r.tmin = t;
        r.enterPlane = int(i);
      }
    }
    else if (d < SvdagClipReal(0))
    {
      SvdagClipReal t = -f / d; // leaving
      if (t < r.tmax)
        r.tmax = t;
    }
    else if (!(f >= SvdagClipReal(0)))
      outside = true; // parallel and on the removed side
  }
  r.kept = !outside && r.tmin <= r.tmax;
  return r;
}

#ifdef __cplusplus
} // namespace clipping
} // namespace svdag
#endif

#endif
