#include "svdag_render/RenderSettings.h"

#include <cmath>
#include <stdexcept>
#include <string>

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

const char* backendName(Backend backend)
{
  switch (backend)
  {
    case Backend::Auto: return "auto";
    case Backend::RayTracing: return "rt";
    case Backend::Compute: return "compute";
  }
  return "?";
}

Backend parseBackend(const std::string& name)
{
  for (Backend backend : { Backend::Auto, Backend::RayTracing, Backend::Compute })
  {
    if (name == backendName(backend))
      return backend;
  }
  throw std::invalid_argument("unknown backend '" + name + "' (auto, rt or compute)");
}

const char* shadingName(Shading shading)
{
  switch (shading)
  {
    case Shading::Voxel: return "voxel";
    case Shading::Smooth: return "smooth";
  }
  return "?";
}

Shading parseShading(const std::string& name)
{
  for (Shading s : { Shading::Voxel, Shading::Smooth })
  {
    if (name == shadingName(s))
      return s;
  }
  throw std::invalid_argument("unknown shading '" + name + "' (voxel or smooth)");
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
    a.maximumBlocksPerBlas == b.maximumBlocksPerBlas &&
    a.deviceMemoryLimit == b.deviceMemoryLimit && a.shading == b.shading &&
    a.clipPlanes == b.clipPlanes && a.crop == b.crop && a.backend == b.backend;
}

void validate(const RenderSettings& s)
{
  require(uint32_t(s.lod) <= uint32_t(Lod::Auto), "LOD must be block, leaf, voxel or auto");
  require(uint32_t(s.shading) <= uint32_t(Shading::Smooth), "shading must be voxel or smooth");
  require(uint32_t(s.backend) <= uint32_t(Backend::Compute), "backend must be auto, rt or compute");
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
  validateClipping(s.clipPlanes, s.crop);
}

void validateClipping(const std::vector<ClipPlane>& planes, const CropBox& crop)
{
  if (planes.size() > MaximumClipPlanes)
    throw std::invalid_argument("at most " + std::to_string(MaximumClipPlanes) +
      " clipping planes are supported, got " + std::to_string(planes.size()));
  for (size_t i = 0; i < planes.size(); ++i)
  {
    const auto& o = planes[i].origin;
    const auto& n = planes[i].normal;
    const std::string which = "clipping plane " + std::to_string(i);
    require(std::isfinite(o[0]) && std::isfinite(o[1]) && std::isfinite(o[2]),
      (which + ": the origin must be finite").c_str());
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    require(length > 0 && std::isfinite(length),
      (which + ": the normal must be a finite, non-zero vector").c_str());
  }
  if (crop.on)
  {
    const char* axes = "xyz";
    for (int a = 0; a < 3; ++a)
    {
      const double lo = crop.bounds[2 * a], hi = crop.bounds[2 * a + 1];
      require(std::isfinite(lo) && std::isfinite(hi), "the crop box must be finite");
      if (!(lo <= hi))
        throw std::invalid_argument(std::string("the crop box is inverted along ") + axes[a] +
          ": min " + std::to_string(lo) + " > max " + std::to_string(hi));
    }
  }
}

CropBox validCropBox(const std::array<double, 6>& bounds)
{
  CropBox box;
  box.on = true;
  box.bounds = bounds;
  validateClipping({}, box);
  return box;
}

} // namespace render
} // namespace svdag
