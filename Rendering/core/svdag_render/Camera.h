// A perspective camera with VTK's semantics (position, focal point, view up, vertical view angle
// in degrees) and the primary-ray basis the shaders use (the pixel-center convention is in
// GpuLayout.h).
#pragma once

#include <svdag/Volume.h>

#include <array>

namespace svdag
{
namespace render
{

struct Camera
{
  std::array<double, 3> position{ { 0, 0, 1 } };
  std::array<double, 3> focalPoint{ { 0, 0, 0 } };
  std::array<double, 3> viewUp{ { 0, 1, 0 } };
  double viewAngle = 30; // vertical, degrees, in (0, 180)
};

// The vectors of GpuLayout.h's primary ray: direction(u, v) = normalize(forward + u * right +
// v * up) for u, v in [-1, 1] across the image. Throws std::invalid_argument for a degenerate
// camera (position == focal point, view up parallel to the view direction, angle outside (0,180),
// non-finite values) or an empty image.
struct RayBasis
{
  std::array<double, 3> forward;
  std::array<double, 3> right; // scaled by tan(viewAngle / 2) * width / height
  std::array<double, 3> up;    // scaled by tan(viewAngle / 2)
};
RayBasis rayBasis(const Camera& camera, uint32_t width, uint32_t height);

// The primary rays of an image, as affine functions of the image coordinates u, v in [-1, 1]
// (GpuLayout.h: u = 2 (x + 0.5) / width - 1, v likewise with height):
//   origin(u, v) = origin + u * originU + v * originV
//   span(u, v)   = direction + u * directionU + v * directionV   (not unit length)
// The ray through (u, v) starts at origin(u, v) with the unit direction span / |span|; when
// `bounded`, it ends at origin + span (a far clipping plane), else it is unbounded. Both the
// pinhole Camera and any projective camera whose homogeneous w does not depend on u, v (VTK's
// perspective, off-axis and parallel projections, tiles of them) are exactly of this form.
struct ViewRays
{
  std::array<double, 3> origin{ { 0, 0, 1 } };
  std::array<double, 3> originU{ { 0, 0, 0 } };
  std::array<double, 3> originV{ { 0, 0, 0 } };
  std::array<double, 3> direction{ { 0, 0, -1 } };
  std::array<double, 3> directionU{ { 0, 0, 0 } };
  std::array<double, 3> directionV{ { 0, 0, 0 } };
  bool bounded = false;
};

// The rays of a pinhole camera (origin: the camera position, unbounded); throws like rayBasis.
ViewRays viewRays(const Camera& camera, uint32_t width, uint32_t height);

// The rays between the near (z = -1) and far (z = +1) planes of a projection, from the inverse
// of a world-to-clip matrix (row-major 4 x 4, clip = M * (x, y, z, 1)): origin on the near plane,
// far end on the far plane. Throws std::invalid_argument for a singular or non-finite matrix and
// for one whose w varies across the image (not a projection of this form).
ViewRays viewRaysFromClipToWorld(const std::array<double, 16>& clipToWorld);

// The same rays started `s` (in units of their span) further along: origin + s * span, ending
// where they ended if bounded (0 <= s < 1 then). Tracing from near the volume keeps float
// precision when the camera is far away: a float direction's rounding times the distance
// travelled is what moves a ray.
ViewRays advanceRays(const ViewRays& rays, double s);
// How far (in units of span) the rays may be advanced and still start in front of a sphere of
// `radius` around `center` (every ray checked at the image's corners, edge midpoints and center,
// with a margin of one more radius); 0 when the camera is close or inside.
double approachParameter(const ViewRays& rays, const std::array<double, 3>& center, double radius);
// Length of span(u, v) (the distance to the far plane of bounded rays).
double spanLength(const ViewRays& rays, double u, double v);

// World size of one image pixel (along v) at the ray origin, and its growth per unit of distance
// along the ray: a pixel at distance t covers footprint0 + t * footprintSlope world units.
struct PixelFootprint
{
  double footprint0;
  double footprintSlope;
};
PixelFootprint pixelFootprint(const ViewRays& rays, uint32_t height);

// A camera that frames the whole volume like vtkRenderer::ResetCamera followed by
// vtkCamera::Azimuth(azimuth), Elevation(elevation) (degrees) and a dolly by `zoom` (> 0; 2 halves
// the distance): it looks at the bounds' center from +z with +y up, at the distance where the
// bounding sphere fits the vertical view angle, then orbits.
Camera frameVolume(const Geometry& geometry, double azimuth = 0, double elevation = 0,
  double zoom = 1, double viewAngle = 30);

} // namespace render
} // namespace svdag
