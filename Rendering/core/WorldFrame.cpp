#include "svdag_render/WorldFrame.h"

#include <algorithm>
#include <cmath>

namespace svdag
{
namespace render
{

std::array<double, 12> indexToWorld(const Geometry& g)
{
  // world = origin + A * (p - 0.5) with A = D * diag(spacing): translation origin - A * 0.5.
  std::array<double, 12> m{};
  for (int r = 0; r < 3; ++r)
  {
    double translation = g.origin[r];
    for (int c = 0; c < 3; ++c)
    {
      const double a = g.direction[3 * r + c] * g.spacing[c];
      m[4 * r + c] = a;
      translation -= 0.5 * a;
    }
    m[4 * r + 3] = translation;
  }
  return m;
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

} // namespace render
} // namespace svdag
