#include "svdag_render/Camera.h"

#include "svdag_render/Scene.h"

#include <cmath>
#include <stdexcept>

namespace svdag
{
namespace render
{
namespace
{
using Vec = std::array<double, 3>;
constexpr double Pi = 3.14159265358979323846;

Vec sub(const Vec& a, const Vec& b)
{
  return { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
}
Vec cross(const Vec& a, const Vec& b)
{
  return { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
}
double length(const Vec& a)
{
  return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}
Vec scale(const Vec& a, double s)
{
  return { a[0] * s, a[1] * s, a[2] * s };
}
bool finite(const Vec& a)
{
  return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]);
}
} // namespace

RayBasis rayBasis(const Camera& camera, uint32_t width, uint32_t height)
{
  if (width == 0 || height == 0)
    throw std::invalid_argument("image size must be at least 1 x 1");
  if (!finite(camera.position) || !finite(camera.focalPoint) || !finite(camera.viewUp) ||
    !(camera.viewAngle > 0 && camera.viewAngle < 180))
    throw std::invalid_argument("camera values must be finite, view angle in (0, 180) degrees");
  const Vec toFocal = sub(camera.focalPoint, camera.position);
  const double distance = length(toFocal);
  if (!(distance > 0))
    throw std::invalid_argument("camera position equals its focal point");
  const Vec forward = scale(toFocal, 1 / distance);
  const Vec side = cross(forward, camera.viewUp);
  const double sideLength = length(side);
  if (!(sideLength > 1e-12 * length(camera.viewUp)) || !(sideLength > 0))
    throw std::invalid_argument("camera view up is zero or parallel to the view direction");
  const Vec right = scale(side, 1 / sideLength);
  const Vec up = cross(right, forward);
  const double h = std::tan(camera.viewAngle * Pi / 360);
  RayBasis b;
  b.forward = forward;
  b.right = scale(right, h * double(width) / double(height));
  b.up = scale(up, h);
  return b;
}

std::array<double, 6> worldBounds(const Geometry& g)
{
  // Voxel boxes span index space [0, dims]; transform the 8 corners.
  const auto m = indexToWorld(g);
  std::array<double, 6> b{ { INFINITY, -INFINITY, INFINITY, -INFINITY, INFINITY, -INFINITY } };
  for (int corner = 0; corner < 8; ++corner)
  {
    const double p[3] = { (corner & 1) ? double(g.dims[0]) : 0.0,
      (corner & 2) ? double(g.dims[1]) : 0.0, (corner & 4) ? double(g.dims[2]) : 0.0 };
    for (int r = 0; r < 3; ++r)
    {
      const double w = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
      b[2 * r] = std::min(b[2 * r], w);
      b[2 * r + 1] = std::max(b[2 * r + 1], w);
    }
  }
  return b;
}

Camera frameVolume(
  const Geometry& geometry, double azimuth, double elevation, double zoom, double viewAngle)
{
  if (!(zoom > 0) || !std::isfinite(zoom) || !std::isfinite(azimuth) || !std::isfinite(elevation))
    throw std::invalid_argument("zoom must be > 0 and angles finite");
  if (!(viewAngle > 0 && viewAngle < 180))
    throw std::invalid_argument("view angle must be in (0, 180) degrees");
  const auto b = worldBounds(geometry);
  const Vec center = { (b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2 };
  double radius = length(Vec{ b[1] - b[0], b[3] - b[2], b[5] - b[4] }) / 2;
  if (!(radius > 0))
    radius = 0.5; // an empty volume: any finite framing will do
  const double distance = radius / std::sin(viewAngle * Pi / 360) / zoom;
  // Orbit: from +z, azimuth about +y, then elevation about the camera's right axis; view up
  // rotates with the elevation, so it stays orthogonal to the view direction.
  const double az = azimuth * Pi / 180, el = elevation * Pi / 180;
  const Vec back = { std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az) };
  // (+ 0.0 turns -0 into 0, for tidy printing.)
  const Vec up = { -std::sin(el) * std::sin(az) + 0.0, std::cos(el) + 0.0,
    -std::sin(el) * std::cos(az) + 0.0 };
  Camera camera;
  camera.focalPoint = center;
  camera.position = { center[0] + distance * back[0], center[1] + distance * back[1],
    center[2] + distance * back[2] };
  camera.viewUp = up;
  camera.viewAngle = viewAngle;
  return camera;
}

} // namespace render
} // namespace svdag
