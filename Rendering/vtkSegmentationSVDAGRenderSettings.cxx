#include "vtkSegmentationSVDAGRenderSettings.h"

#include "vtkObjectFactory.h"

#include <svdag_render/RenderSettings.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

vtkStandardNewMacro(vtkSegmentationSVDAGRenderSettings);

namespace
{
namespace core = svdag::render;

double clampTo(double v, double lo, double hi)
{
  return std::isnan(v) ? lo : std::min(std::max(v, lo), hi);
}

// Colors and irradiances: finite, >= 0 (infinity clamps to the largest float).
float colorComponent(double v)
{
  return float(clampTo(v, 0.0, 3.0e38));
}

// Assigns and bumps the MTime only when the value changes.
template <typename T>
void assign(vtkObject* owner, T& member, const T& value)
{
  if (!(member == value))
  {
    member = value;
    owner->Modified();
  }
}

// The name of value i of an enumeration's list; nullptr outside it.
template <typename E, size_t N>
const char* nameOf(const std::array<E, N>& values, int i, const char* (*name)(E))
{
  return i >= 0 && size_t(i) < N ? name(values[size_t(i)]) : nullptr;
}

// An enumeration set by number, clamped to [first, last] like VTK's clamped setters ...
template <typename E>
void assignClamped(vtkObject* owner, E& member, int value, E first, E last)
{
  assign(owner, member, static_cast<E>(std::min(std::max(value, int(first)), int(last))));
}

// ... or by name: a name `parse` rejects is reported (as "<setter>: <why>") and changes nothing.
template <typename E, typename Parse>
void assignNamed(vtkObject* owner, E& member, const char* name, Parse parse, const char* setter)
{
  try
  {
    assign(owner, member, parse(name ? name : ""));
  }
  catch (const std::invalid_argument& e)
  {
    vtkErrorWithObjectMacro(owner, << setter << ": " << e.what());
  }
}
} // namespace

// The VTK enumerations are the core's values (the setters pass them through).
using Self = vtkSegmentationSVDAGRenderSettings;
static_assert(int(core::Lod::Block) == Self::LOD_BLOCK && int(core::Lod::Leaf) == Self::LOD_LEAF &&
    int(core::Lod::Voxel) == Self::LOD_VOXEL && int(core::Lod::Auto) == Self::LOD_AUTO,
  "LOD values");
static_assert(int(core::Shading::Voxel) == Self::SHADING_VOXEL &&
    int(core::Shading::Smooth) == Self::SHADING_SMOOTH,
  "shading values");
static_assert(int(core::Backend::Auto) == Self::BACKEND_AUTO &&
    int(core::Backend::RayTracing) == Self::BACKEND_RT &&
    int(core::Backend::Compute) == Self::BACKEND_COMPUTE,
  "backend values");

vtkSegmentationSVDAGRenderSettings::vtkSegmentationSVDAGRenderSettings()
  : Settings(new core::RenderSettings)
{
}

vtkSegmentationSVDAGRenderSettings::~vtkSegmentationSVDAGRenderSettings() = default;

void vtkSegmentationSVDAGRenderSettings::SetLOD(int lod)
{
  assignClamped(this, this->Settings->lod, lod, core::Lods.front(), core::Lods.back());
}

void vtkSegmentationSVDAGRenderSettings::SetLOD(const char* name)
{
  assignNamed(this, this->Settings->lod, name, core::parseLod, "SetLOD");
}

int vtkSegmentationSVDAGRenderSettings::GetLOD() const
{
  return int(this->Settings->lod);
}

const char* vtkSegmentationSVDAGRenderSettings::GetLODAsString() const
{
  return core::lodName(this->Settings->lod);
}

int vtkSegmentationSVDAGRenderSettings::GetNumberOfLODs()
{
  return int(core::Lods.size());
}

const char* vtkSegmentationSVDAGRenderSettings::GetLODName(int lod)
{
  return nameOf(core::Lods, lod, core::lodName);
}

void vtkSegmentationSVDAGRenderSettings::SetAutoLODPixels(double pixels)
{
  assign(this, this->Settings->autoLodPixels, float(clampTo(pixels, 1e-6, 1e6)));
}

double vtkSegmentationSVDAGRenderSettings::GetAutoLODPixels() const
{
  return this->Settings->autoLodPixels;
}

void vtkSegmentationSVDAGRenderSettings::SetSamplesPerPixel(int samples)
{
  assign(this, this->Settings->samplesPerPixel,
    uint32_t(std::min<int64_t>(std::max(samples, 1), core::MaximumSamplesPerPixel)));
}

int vtkSegmentationSVDAGRenderSettings::GetSamplesPerPixel() const
{
  return int(this->Settings->samplesPerPixel);
}

void vtkSegmentationSVDAGRenderSettings::SetMaximumBounces(int bounces)
{
  assign(this, this->Settings->maximumBounces,
    uint32_t(std::min<int64_t>(std::max(bounces, 0), core::MaximumBounces)));
}

int vtkSegmentationSVDAGRenderSettings::GetMaximumBounces() const
{
  return int(this->Settings->maximumBounces);
}

void vtkSegmentationSVDAGRenderSettings::SetSeed(vtkTypeUInt32 seed)
{
  assign(this, this->Settings->seed, uint32_t(seed));
}

vtkTypeUInt32 vtkSegmentationSVDAGRenderSettings::GetSeed() const
{
  return this->Settings->seed;
}

void vtkSegmentationSVDAGRenderSettings::SetNextEventEstimation(bool on)
{
  assign(this, this->Settings->nextEventEstimation, on);
}

bool vtkSegmentationSVDAGRenderSettings::GetNextEventEstimation() const
{
  return this->Settings->nextEventEstimation;
}

void vtkSegmentationSVDAGRenderSettings::SetDenoise(bool on)
{
  assign(this, this->Settings->denoise, on);
}

bool vtkSegmentationSVDAGRenderSettings::GetDenoise() const
{
  return this->Settings->denoise;
}

void vtkSegmentationSVDAGRenderSettings::SetExposure(double exposure)
{
  assign(this, this->Settings->exposure, float(clampTo(exposure, 1e-6, 1e6)));
}

double vtkSegmentationSVDAGRenderSettings::GetExposure() const
{
  return this->Settings->exposure;
}

void vtkSegmentationSVDAGRenderSettings::SetBackground(double r, double g, double b, double a)
{
  assign(this, this->Settings->background,
    std::array<float, 4>{ { colorComponent(r), colorComponent(g), colorComponent(b),
      float(clampTo(a, 0.0, 1.0)) } });
}

void vtkSegmentationSVDAGRenderSettings::GetBackground(double rgba[4]) const
{
  std::copy(this->Settings->background.begin(), this->Settings->background.end(), rgba);
}

void vtkSegmentationSVDAGRenderSettings::SetEnvironmentColor(double r, double g, double b)
{
  assign(this, this->Settings->environmentColor,
    std::array<float, 3>{ { colorComponent(r), colorComponent(g), colorComponent(b) } });
}

void vtkSegmentationSVDAGRenderSettings::GetEnvironmentColor(double rgb[3]) const
{
  std::copy(this->Settings->environmentColor.begin(), this->Settings->environmentColor.end(), rgb);
}

void vtkSegmentationSVDAGRenderSettings::SetEnvironmentMap(const char* path)
{
  assign(this, this->Settings->environmentMap, std::string(path ? path : ""));
}

const char* vtkSegmentationSVDAGRenderSettings::GetEnvironmentMap() const
{
  return this->Settings->environmentMap.c_str();
}

void vtkSegmentationSVDAGRenderSettings::SetSun(bool on)
{
  assign(this, this->Settings->sun.on, on);
}

bool vtkSegmentationSVDAGRenderSettings::GetSun() const
{
  return this->Settings->sun.on;
}

void vtkSegmentationSVDAGRenderSettings::SetSunDirection(double x, double y, double z)
{
  const double length = std::sqrt(x * x + y * y + z * z);
  if (!(length > 0) || !std::isfinite(length))
  {
    vtkErrorMacro("SetSunDirection: the direction must be a finite, non-zero vector, got ("
      << x << ", " << y << ", " << z << ")");
    return;
  }
  assign(this, this->Settings->sun.direction, std::array<double, 3>{ { x, y, z } });
}

void vtkSegmentationSVDAGRenderSettings::GetSunDirection(double d[3]) const
{
  std::copy(this->Settings->sun.direction.begin(), this->Settings->sun.direction.end(), d);
}

void vtkSegmentationSVDAGRenderSettings::SetSunIrradiance(double r, double g, double b)
{
  assign(this, this->Settings->sun.irradiance,
    std::array<float, 3>{ { colorComponent(r), colorComponent(g), colorComponent(b) } });
}

void vtkSegmentationSVDAGRenderSettings::GetSunIrradiance(double e[3]) const
{
  std::copy(this->Settings->sun.irradiance.begin(), this->Settings->sun.irradiance.end(), e);
}

void vtkSegmentationSVDAGRenderSettings::SetSunAngularRadius(double degrees)
{
  assign(this, this->Settings->sun.angularRadiusDegrees,
    clampTo(degrees, 0.0, core::MaximumSunAngularRadius));
}

double vtkSegmentationSVDAGRenderSettings::GetSunAngularRadius() const
{
  return this->Settings->sun.angularRadiusDegrees;
}

void vtkSegmentationSVDAGRenderSettings::SetMaximumBlocksPerBLAS(vtkTypeInt64 blocks)
{
  assign(this, this->Settings->maximumBlocksPerBlas,
    uint32_t(std::min<vtkTypeInt64>(std::max<vtkTypeInt64>(blocks, 0), VTK_INT_MAX)));
}

vtkTypeInt64 vtkSegmentationSVDAGRenderSettings::GetMaximumBlocksPerBLAS() const
{
  return this->Settings->maximumBlocksPerBlas;
}

void vtkSegmentationSVDAGRenderSettings::SetDeviceMemoryLimit(vtkTypeInt64 bytes)
{
  assign(this, this->Settings->deviceMemoryLimit, uint64_t(std::max<vtkTypeInt64>(bytes, 0)));
}

vtkTypeInt64 vtkSegmentationSVDAGRenderSettings::GetDeviceMemoryLimit() const
{
  return vtkTypeInt64(this->Settings->deviceMemoryLimit);
}

void vtkSegmentationSVDAGRenderSettings::SetShading(int shading)
{
  assignClamped(this, this->Settings->shading, shading, core::Shadings.front(), core::Shadings.back());
}

void vtkSegmentationSVDAGRenderSettings::SetShading(const char* name)
{
  assignNamed(this, this->Settings->shading, name, core::parseShading, "SetShading");
}

int vtkSegmentationSVDAGRenderSettings::GetShading() const
{
  return int(this->Settings->shading);
}

const char* vtkSegmentationSVDAGRenderSettings::GetShadingAsString() const
{
  return core::shadingName(this->Settings->shading);
}

int vtkSegmentationSVDAGRenderSettings::GetNumberOfShadings()
{
  return int(core::Shadings.size());
}

const char* vtkSegmentationSVDAGRenderSettings::GetShadingName(int shading)
{
  return nameOf(core::Shadings, shading, core::shadingName);
}

void vtkSegmentationSVDAGRenderSettings::SetBackend(int backend)
{
  assignClamped(
    this, this->Settings->backend, backend, core::Backends.front(), core::Backends.back());
}

void vtkSegmentationSVDAGRenderSettings::SetBackend(const char* name)
{
  assignNamed(this, this->Settings->backend, name, core::parseBackend, "SetBackend");
}

int vtkSegmentationSVDAGRenderSettings::GetBackend() const
{
  return int(this->Settings->backend);
}

const char* vtkSegmentationSVDAGRenderSettings::GetBackendAsString() const
{
  return core::backendName(this->Settings->backend);
}

int vtkSegmentationSVDAGRenderSettings::GetNumberOfBackends()
{
  return int(core::Backends.size());
}

const char* vtkSegmentationSVDAGRenderSettings::GetBackendName(int backend)
{
  return nameOf(core::Backends, backend, core::backendName);
}

void vtkSegmentationSVDAGRenderSettings::DeepCopy(vtkSegmentationSVDAGRenderSettings* other)
{
  if (other && other != this)
  {
    *this->Settings = *other->Settings;
    this->Modified();
  }
}

void vtkSegmentationSVDAGRenderSettings::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  const core::RenderSettings& s = *this->Settings;
  auto triple = [&os](const auto& v) { os << v[0] << " " << v[1] << " " << v[2]; };
  os << indent << "LOD: " << core::lodName(s.lod) << "\n";
  os << indent << "AutoLODPixels: " << s.autoLodPixels << "\n";
  os << indent << "SamplesPerPixel: " << s.samplesPerPixel << "\n";
  os << indent << "MaximumBounces: " << s.maximumBounces << "\n";
  os << indent << "Seed: " << s.seed << "\n";
  os << indent << "NextEventEstimation: " << s.nextEventEstimation << "\n";
  os << indent << "Denoise: " << s.denoise << "\n";
  os << indent << "Exposure: " << s.exposure << "\n";
  os << indent << "Background: ";
  triple(s.background);
  os << " " << s.background[3] << "\n";
  os << indent << "EnvironmentColor: ";
  triple(s.environmentColor);
  os << "\n" << indent << "EnvironmentMap: "
     << (s.environmentMap.empty() ? "(none)" : s.environmentMap) << "\n";
  os << indent << "Sun: " << s.sun.on << "\n" << indent << "SunDirection: ";
  triple(s.sun.direction);
  os << "\n" << indent << "SunIrradiance: ";
  triple(s.sun.irradiance);
  os << "\n" << indent << "SunAngularRadius: " << s.sun.angularRadiusDegrees << "\n";
  os << indent << "MaximumBlocksPerBLAS: " << s.maximumBlocksPerBlas << "\n";
  os << indent << "DeviceMemoryLimit: " << s.deviceMemoryLimit << "\n";
  os << indent << "Shading: " << core::shadingName(s.shading) << "\n";
  os << indent << "Backend: " << core::backendName(s.backend) << "\n";
}
