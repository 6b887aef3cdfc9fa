#include "svdag_render/RenderSettings.h"

// The shaders' constants (headers shared by C++ and GLSL) are the enumerations' values.
#include "svdag/RayCaster.h"
#include "svdag/Traversal.h"
#include "svdag_render/GpuLayout.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace svdag
{
namespace render
{

static_assert(uint32_t(Lod::Block) == gpu::SVDAG_RENDER_LOD_BLOCK && uint32_t(Lod::Leaf) == gpu::SVDAG_RENDER_LOD_LEAF &&
    uint32_t(Lod::Voxel) == gpu::SVDAG_RENDER_LOD_VOXEL && uint32_t(Lod::Auto) == gpu::SVDAG_RENDER_LOD_AUTO,
  "GpuLayout.h's LOD constants");
static_assert(uint32_t(Lod::Block) == traversal::SVDAG_LOD_BLOCK && uint32_t(Lod::Leaf) == traversal::SVDAG_LOD_LEAF &&
    uint32_t(Lod::Voxel) == traversal::SVDAG_LOD_VOXEL,
  "Traversal.h's LOD constants (the traversal takes Lod values below Auto as they are)");
static_assert(uint32_t(Lod::Block) == uint32_t(svdag::Lod::Block) &&
    uint32_t(Lod::Leaf) == uint32_t(svdag::Lod::Leaf) &&
    uint32_t(Lod::Voxel) == uint32_t(svdag::Lod::Voxel),
  "the CPU ray caster's LODs");
static_assert(uint32_t(Shading::Voxel) == gpu::SVDAG_SHADING_VOXEL &&
    uint32_t(Shading::Smooth) == gpu::SVDAG_SHADING_SMOOTH,
  "GpuLayout.h's shading constants");
// Each list holds every value once, in order: value i at index i (validate relies on it).
template <typename E, size_t N>
constexpr bool inOrder(const std::array<E, N>& values)
{
  for (size_t i = 0; i < N; ++i)
  {
    if (uint32_t(values[i]) != i)
      return false;
  }
  return true;
}
static_assert(inOrder(Lods) && inOrder(Backends) && inOrder(Shadings), "the value lists");

namespace
{
// "a, b, c or d": the names of `values`, for error messages.
template <typename E, size_t N>
std::string spokenList(const std::array<E, N>& values, const char* (*name)(E))
{
  std::string list;
  for (size_t i = 0; i < N; ++i)
    list += (i == 0 ? "" : (i + 1 == N ? " or " : ", ")) + std::string(name(values[i]));
  return list;
}

template <typename E, size_t N>
std::string joined(const std::array<E, N>& values, const char* (*name)(E), const std::string& sep)
{
  std::string list;
  for (size_t i = 0; i < N; ++i)
    list += (i == 0 ? "" : sep) + std::string(name(values[i]));
  return list;
}

// The value named `name`; otherwise std::invalid_argument "unknown <what> '<name>' (a, b or c)".
template <typename E, size_t N>
E parse(const std::array<E, N>& values, const char* (*name)(E), const std::string& text,
  const char* what)
{
  for (E value : values)
  {
    if (text == name(value))
      return value;
  }
  throw std::invalid_argument(
    "unknown " + std::string(what) + " '" + text + "' (" + spokenList(values, name) + ")");
}
} // namespace

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
  return parse(Lods, lodName, name, "LOD");
}

std::string lodNames(const std::string& separator)
{
  return joined(Lods, lodName, separator);
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
  return parse(Backends, backendName, name, "backend");
}

std::string backendNames(const std::string& separator)
{
  return joined(Backends, backendName, separator);
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
  return parse(Shadings, shadingName, name, "shading");
}

std::string shadingNames(const std::string& separator)
{
  return joined(Shadings, shadingName, separator);
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
    a.clipPlanes == b.clipPlanes && a.crop == b.crop && a.backend == b.backend &&
    a.denoise == b.denoise;
}

void validate(const RenderSettings& s)
{
  require(uint32_t(s.lod) < Lods.size(), "LOD must be block, leaf, voxel or auto");
  require(uint32_t(s.shading) < Shadings.size(), "shading must be voxel or smooth");
  require(uint32_t(s.backend) < Backends.size(), "backend must be auto, rt or compute");
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
