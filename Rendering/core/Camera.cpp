#include "svdag_render/Camera.h"

#include "svdag_render/WorldFrame.h"

#include <algorithm>
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

ViewRays viewRays(const Camera& camera, uint32_t width, uint32_t height)
{
  const RayBasis b = rayBasis(camera, width, height);
  ViewRays rays;
  rays.origin = camera.position;
  rays.direction = b.forward;
  rays.directionU = b.right;
  rays.directionV = b.up;
  rays.bounded = false;
  return rays;
}

ViewRays viewRaysFromClipToWorld(const std::array<double, 16>& m)
{
  for (double x : m)
  {
    if (!std::isfinite(x))
      throw std::invalid_argument("the clip-to-world matrix has a non-finite entry");
  }
  // The homogeneous point of clip (u, v, z, 1) is affine in u, v; its w must not depend on u, v
  // for the rays to be affine (true of every perspective and parallel projection).
  const double wu = m[12], wv = m[13];
  const double wScale = std::abs(m[14]) + std::abs(m[15]);
  if (!(wScale > 0) || std::abs(wu) > 1e-9 * wScale || std::abs(wv) > 1e-9 * wScale)
    throw std::invalid_argument("the projection's w varies across the image (not supported)");
  auto unproject = [&m](double u, double v, double z) {
    double p[4];
    for (int r = 0; r < 4; ++r)
      p[r] = m[4 * r] * u + m[4 * r + 1] * v + m[4 * r + 2] * z + m[4 * r + 3];
    if (!(std::abs(p[3]) > 0))
      throw std::invalid_argument("the clip-to-world matrix maps a view plane to infinity");
    return Vec{ p[0] / p[3], p[1] / p[3], p[2] / p[3] };
  };
  const Vec n0 = unproject(0, 0, -1), nu = unproject(1, 0, -1), nv = unproject(0, 1, -1);
  const Vec f0 = unproject(0, 0, 1), fu = unproject(1, 0, 1), fv = unproject(0, 1, 1);
  ViewRays rays;
  rays.origin = n0;
  rays.originU = sub(nu, n0);
  rays.originV = sub(nv, n0);
  rays.direction = sub(f0, n0);
  rays.directionU = sub(sub(fu, f0), rays.originU);
  rays.directionV = sub(sub(fv, f0), rays.originV);
  rays.bounded = true;
  if (!(length(rays.direction) > 0) || !finite(rays.direction))
    throw std::invalid_argument("the projection's near and far planes coincide");
  return rays;
}

ViewRays advanceRays(const ViewRays& rays, double s)
{
  ViewRays out = rays;
  for (int a = 0; a < 3; ++a)
  {
    out.origin[a] += s * rays.direction[a];
    out.originU[a] += s * rays.directionU[a];
    out.originV[a] += s * rays.directionV[a];
    if (rays.bounded)
    {
      out.direction[a] *= 1 - s;
      out.directionU[a] *= 1 - s;
      out.directionV[a] *= 1 - s;
    }
  }
  return out;
}

double spanLength(const ViewRays& r, double u, double v)
{
  Vec span;
  for (int a = 0; a < 3; ++a)
    span[a] = r.direction[a] + u * r.directionU[a] + v * r.directionV[a];
  return length(span);
}

double approachParameter(const ViewRays& r, const std::array<double, 3>& center, double radius)
{
  double s = INFINITY;
  for (double u : { -1.0, 0.0, 1.0 })
  {
    for (double v : { -1.0, 0.0, 1.0 })
    {
      Vec origin;
      for (int a = 0; a < 3; ++a)
        origin[a] = r.origin[a] + u * r.originU[a] + v * r.originV[a];
      const double span = spanLength(r, u, v);
      if (!(span > 0))
        return 0;
      Vec direction;
      for (int a = 0; a < 3; ++a)
        direction[a] = (r.direction[a] + u * r.directionU[a] + v * r.directionV[a]) / span;
      const Vec toCenter = sub(center, origin);
      const double along = toCenter[0] * direction[0] + toCenter[1] * direction[1] +
        toCenter[2] * direction[2];
      s = std::min(s, (along - 2 * radius) / span);
    }
  }
  if (!(s > 0) || !std::isfinite(s))
    return 0;
  return r.bounded ? std::min(s, 0.999) : s;
}

PixelFootprint pixelFootprint(const ViewRays& rays, uint32_t height)
{
  const double pixel = 2.0 / std::max<uint32_t>(height, 1);
  const double span = length(rays.direction);
  return { length(rays.originV) * pixel, span > 0 ? length(rays.directionV) / span * pixel : 0.0 };
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
