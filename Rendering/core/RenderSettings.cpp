#include "svdag_render/RenderSettings.h"

#include <cmath>
#include <stdexcept>

namespace svdag
{
namespace render
{

const char* lodName(Lod lod)
{
  switch (lod)
  {
    case Lod::Block: return "block";
    case Lod::Leaf: return "leaf";
    case Lod::Voxel: return "voxel";
    case Lod::Auto: return "auto";
  }
  return "?";
}

Lod parseLod(const std::string& name)
{
  for (Lod lod : { Lod::Block, Lod::Leaf, Lod::Voxel, Lod::Auto })
  {
    if (name == lodName(lod))
      return lod;
  }
  throw std::invalid_argument("unknown LOD '" + name + "' (block, leaf, voxel or auto)");
}

namespace
{
void require(bool ok, const char* message)
{
  if (!ok)
    throw std::invalid_argument(message);
}
template <size_t N>
bool nonNegative(const std::array<float, N>& values)
{
  for (float v : values)
  {
    if (!(v >= 0) || !std::isfinite(v))
      return false;
  }
  return true;
}
} // namespace

bool tracesSameImage(const RenderSettings& a, const RenderSettings& b)
{
  return a.lod == b.lod && a.autoLodPixels == b.autoLodPixels &&
    a.maximumBounces == b.maximumBounces && a.seed == b.seed &&
    a.nextEventEstimation == b.nextEventEstimation && a.background == b.background &&
    a.environmentColor == b.environmentColor && a.environmentMap == b.environmentMap &&
    a.sun.on == b.sun.on && a.sun.direction == b.sun.direction &&
    a.sun.irradiance == b.sun.irradiance &&
    a.sun.angularRadiusDegrees == b.sun.angularRadiusDegrees &&
    a.maximumBlocksPerBlas == b.maximumBlocksPerBlas;
}

void validate(const RenderSettings& s)
{
  require(uint32_t(s.lod) <= uint32_t(Lod::Auto), "LOD must be block, leaf, voxel or auto");
  require(s.autoLodPixels > 0 && std::isfinite(s.autoLodPixels),
    "auto LOD pixels must be a finite value > 0");
  require(s.samplesPerPixel >= 1 && s.samplesPerPixel <= MaximumSamplesPerPixel,
    "samples per pixel must be in 1 .. 65536");
  require(s.maximumBounces <= MaximumBounces, "maximum bounces must be in 0 .. 64");
  require(s.exposure > 0 && std::isfinite(s.exposure), "exposure must be a finite value > 0");
  require(nonNegative(s.background), "background must be finite and >= 0");
  require(nonNegative(s.environmentColor), "environment radiance must be finite and >= 0");
  const auto& d = s.sun.direction;
  const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  require(length > 0 && std::isfinite(length),
    "the sun direction must be a finite, non-zero vector");
  require(nonNegative(s.sun.irradiance), "the sun irradiance must be finite and >= 0");
  require(s.sun.angularRadiusDegrees >= 0 && s.sun.angularRadiusDegrees <= MaximumSunAngularRadius,
    "the sun's angular radius must be in [0, 89.9] degrees");
}

} // namespace render
} // namespace svdag
