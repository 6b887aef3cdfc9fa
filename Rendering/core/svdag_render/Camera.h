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

// World-space axis-aligned bounds of the volume's voxels: xmin, xmax, ymin, ymax, zmin, zmax.
std::array<double, 6> worldBounds(const Geometry& geometry);

// A camera that frames the whole volume like vtkRenderer::ResetCamera followed by
// vtkCamera::Azimuth(azimuth), Elevation(elevation) (degrees) and a dolly by `zoom` (> 0; 2 halves
// the distance): it looks at the bounds' center from +z with +y up, at the distance where the
// bounding sphere fits the vertical view angle, then orbits.
Camera frameVolume(const Geometry& geometry, double azimuth = 0, double elevation = 0,
  double zoom = 1, double viewAngle = 30);

} // namespace render
} // namespace svdag
