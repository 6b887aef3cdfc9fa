#include "vtkSegmentationSVDAGLabelProperties.h"

#include "vtkObjectFactory.h"
#include "vtkScalarsToColors.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkSmartPointer.h"

#include <svdag/Volume.h>
#include <svdag_render/Material.h>
#include <svdag_render/Renderer.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <utility>
#include <set>

vtkStandardNewMacro(vtkSegmentationSVDAGLabelProperties);

namespace
{
double clampTo(double v, double lo, double hi)
{
  return std::isnan(v) ? lo : std::min(std::max(v, lo), hi);
}

// sRGB display value -> linear (the path tracer's base colors are linear).
float linearFromSrgb(double c)
{
  c = clampTo(c, 0.0, 1.0);
  return float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
}

// What was set for one label; unset members take the defaults.
struct Appearance
{
  std::optional<std::array<double, 3>> color;
  double opacity = 1;
  std::optional<bool> visible;
  std::optional<double> roughness, metallic, transmission, ior, specular;
  std::optional<std::array<double, 3>> emission;
};

// The volume (null without one) and the index of `label` in its table (-1: none, or no volume).
std::pair<const svdag::Volume*, int64_t> findLabel(vtkSegmentationSVDAG* volume, vtkTypeInt64 label)
{
  if (!volume || !volume->HasVolume())
    return { nullptr, -1 };
  const svdag::Volume* v = volume->GetVolume().get();
  return { v, v->findLabel(uint64_t(label)) };
}

const svdag::render::Material& defaults()
{
  static const svdag::render::Material m = svdag::render::Renderer::defaultMaterial(0);
  return m;
}
} // namespace

struct vtkSegmentationSVDAGLabelProperties::Internals
{
  std::map<vtkTypeInt64, Appearance> Labels;
  std::set<vtkTypeInt64> Highlighted;
  vtkSmartPointer<vtkScalarsToColors> Table;
  bool DefaultVisible = true;

  Appearance* find(vtkTypeInt64 label)
  {
    auto it = this->Labels.find(label);
    return it == this->Labels.end() ? nullptr : &it->second;
  }
};

vtkSegmentationSVDAGLabelProperties::vtkSegmentationSVDAGLabelProperties()
  : Internal(new Internals)
{
}

vtkSegmentationSVDAGLabelProperties::~vtkSegmentationSVDAGLabelProperties() = default;

vtkMTimeType vtkSegmentationSVDAGLabelProperties::GetMTime()
{
  vtkMTimeType t = this->Superclass::GetMTime();
  if (this->Internal->Table)
    t = std::max(t, this->Internal->Table->GetMTime());
  return t;
}

void vtkSegmentationSVDAGLabelProperties::SetColor(vtkTypeInt64 label, double r, double g, double b)
{
  this->Internal->Labels[label].color =
    std::array<double, 3>{ { clampTo(r, 0, 1), clampTo(g, 0, 1), clampTo(b, 0, 1) } };
  this->Modified();
}

bool vtkSegmentationSVDAGLabelProperties::GetColor(vtkTypeInt64 label, double rgb[3])
{
  const Appearance* a = this->Internal->find(label);
  if (!a || !a->color)
    return false;
  std::copy(a->color->begin(), a->color->end(), rgb);
  return true;
}

double* vtkSegmentationSVDAGLabelProperties::GetColor(vtkTypeInt64 label)
{
  return this->GetColor(label, this->ColorReturned) ? this->ColorReturned : nullptr;
}

void vtkSegmentationSVDAGLabelProperties::RemoveColor(vtkTypeInt64 label)
{
  Appearance* a = this->Internal->find(label);
  if (a && a->color)
  {
    a->color.reset();
    this->Modified();
  }
}

void vtkSegmentationSVDAGLabelProperties::SetOpacity(vtkTypeInt64 label, double opacity)
{
  this->Internal->Labels[label].opacity = clampTo(opacity, 0, 1);
  this->Modified();
}

double vtkSegmentationSVDAGLabelProperties::GetOpacity(vtkTypeInt64 label)
{
  const Appearance* a = this->Internal->find(label);
  return a ? a->opacity : 1.0;
}

void vtkSegmentationSVDAGLabelProperties::SetVisibility(vtkTypeInt64 label, bool visible)
{
  this->Internal->Labels[label].visible = visible;
  this->Modified();
}

bool vtkSegmentationSVDAGLabelProperties::GetVisibility(vtkTypeInt64 label)
{
  const Appearance* a = this->Internal->find(label);
  return a && a->visible ? *a->visible : this->Internal->DefaultVisible;
}

#define SVDAG_LABEL_SCALAR(Name, member, lo, hi, fallback)                                         \
  void vtkSegmentationSVDAGLabelProperties::Set##Name(vtkTypeInt64 label, double value)          \
  {                                                                                                \
    this->Internal->Labels[label].member = clampTo(value, lo, hi);                                 \
    this->Modified();                                                                              \
  }                                                                                                \
  double vtkSegmentationSVDAGLabelProperties::Get##Name(vtkTypeInt64 label)                      \
  {                                                                                                \
    const Appearance* a = this->Internal->find(label);                                             \
    return a && a->member ? *a->member : double(fallback);                                         \
  }
SVDAG_LABEL_SCALAR(Roughness, roughness, 0.0, 1.0, defaults().params.x)
SVDAG_LABEL_SCALAR(Metallic, metallic, 0.0, 1.0, defaults().params.y)
SVDAG_LABEL_SCALAR(Transmission, transmission, 0.0, 1.0, defaults().params.z)
SVDAG_LABEL_SCALAR(IOR, ior, 1e-3, 10.0, defaults().params.w)
SVDAG_LABEL_SCALAR(Specular, specular, 0.0, 1.0, defaults().extra.x)
#undef SVDAG_LABEL_SCALAR

void vtkSegmentationSVDAGLabelProperties::SetEmission(
  vtkTypeInt64 label, double r, double g, double b)
{
  this->Internal->Labels[label].emission =
    std::array<double, 3>{ { clampTo(r, 0, 3e38), clampTo(g, 0, 3e38), clampTo(b, 0, 3e38) } };
  this->Modified();
}

bool vtkSegmentationSVDAGLabelProperties::GetEmission(vtkTypeInt64 label, double rgb[3])
{
  const Appearance* a = this->Internal->find(label);
  if (!a || !a->emission)
    return false;
  std::copy(a->emission->begin(), a->emission->end(), rgb);
  return true;
}

void vtkSegmentationSVDAGLabelProperties::AddHighlightedLabel(vtkTypeInt64 label)
{
  if (this->Internal->Highlighted.insert(label).second)
    this->Modified();
}

void vtkSegmentationSVDAGLabelProperties::RemoveHighlightedLabel(vtkTypeInt64 label)
{
  if (this->Internal->Highlighted.erase(label))
    this->Modified();
}

void vtkSegmentationSVDAGLabelProperties::RemoveAllHighlightedLabels()
{
  if (!this->Internal->Highlighted.empty())
  {
    this->Internal->Highlighted.clear();
    this->Modified();
  }
}

bool vtkSegmentationSVDAGLabelProperties::IsHighlighted(vtkTypeInt64 label)
{
  return this->Internal->Highlighted.count(label) != 0;
}

vtkIdType vtkSegmentationSVDAGLabelProperties::GetNumberOfHighlightedLabels()
{
  return vtkIdType(this->Internal->Highlighted.size());
}

vtkTypeInt64 vtkSegmentationSVDAGLabelProperties::GetHighlightedLabel(vtkIdType i)
{
  if (i < 0 || i >= this->GetNumberOfHighlightedLabels())
  {
    vtkErrorMacro("GetHighlightedLabel: index " << i << " is outside 0 .. "
                                                << this->GetNumberOfHighlightedLabels() - 1);
    return 0;
  }
  return *std::next(this->Internal->Highlighted.begin(), i);
}

void vtkSegmentationSVDAGLabelProperties::SetHighlightColor(double r, double g, double b)
{
  const double rgb[3] = { clampTo(r, 0, 1), clampTo(g, 0, 1), clampTo(b, 0, 1) };
  if (std::equal(rgb, rgb + 3, this->HighlightColor))
    return;
  std::copy(rgb, rgb + 3, this->HighlightColor);
  this->Modified();
}

void vtkSegmentationSVDAGLabelProperties::SetLookupTable(vtkScalarsToColors* table)
{
  if (this->Internal->Table != table)
  {
    this->Internal->Table = table;
    this->Modified();
  }
}

vtkScalarsToColors* vtkSegmentationSVDAGLabelProperties::GetLookupTable()
{
  return this->Internal->Table;
}

void vtkSegmentationSVDAGLabelProperties::HideAllLabels()
{
  this->Internal->DefaultVisible = false;
  for (auto& entry : this->Internal->Labels)
    entry.second.visible.reset();
  this->Modified();
}

void vtkSegmentationSVDAGLabelProperties::ShowAllLabels()
{
  this->Internal->DefaultVisible = true;
  for (auto& entry : this->Internal->Labels)
    entry.second.visible.reset();
  this->Modified();
}

void vtkSegmentationSVDAGLabelProperties::RemoveLabel(vtkTypeInt64 label)
{
  if (this->Internal->Labels.erase(label))
    this->Modified();
}

void vtkSegmentationSVDAGLabelProperties::RemoveAllLabels()
{
  this->Internal->Labels.clear();
  this->Internal->DefaultVisible = true;
  this->Modified();
}

vtkIdType vtkSegmentationSVDAGLabelProperties::GetNumberOfLabels()
{
  return vtkIdType(this->Internal->Labels.size());
}

vtkTypeInt64 vtkSegmentationSVDAGLabelProperties::GetLabel(vtkIdType i)
{
  if (i < 0 || i >= this->GetNumberOfLabels())
  {
    vtkErrorMacro("GetLabel: index " << i << " is outside 0 .. " << this->GetNumberOfLabels() - 1);
    return 0;
  }
  return std::next(this->Internal->Labels.begin(), i)->first;
}

std::vector<svdag::shading::Material> vtkSegmentationSVDAGLabelProperties::MaterialsFor(
  const svdag::Volume& volume)
{
  Internals& in = *this->Internal;
  const bool signedLabels = svdag::scalarSigned(volume.scalarType);
  std::vector<svdag::render::Material> materials;
  materials.reserve(volume.labels.size());
  const glm::vec3 tint = glm::vec3(linearFromSrgb(this->HighlightColor[0]),
                           linearFromSrgb(this->HighlightColor[1]),
                           linearFromSrgb(this->HighlightColor[2])) *
    float(this->HighlightIntensity);
  for (size_t i = 0; i < volume.labels.size(); ++i)
  {
    svdag::render::Material m = svdag::render::Renderer::defaultMaterial(uint32_t(i));
    const uint64_t pattern = volume.labels[i].value;
    const vtkTypeInt64 label = vtkTypeInt64(pattern);
    const Appearance* a = in.find(label);
    // The table maps the value itself (exact as a double up to 2^53).
    const double value = signedLabels ? double(vtkTypeInt64(pattern)) : double(pattern);
    std::array<double, 3> color{ { -1, -1, -1 } };
    if (a && a->color)
      color = *a->color;
    else if (in.Table)
    {
      const double* c = in.Table->GetColor(value);
      color = { { c[0], c[1], c[2] } };
    }
    if (color[0] >= 0)
      m.baseColorVisibility = glm::vec4(
        linearFromSrgb(color[0]), linearFromSrgb(color[1]), linearFromSrgb(color[2]), 1.0f);
    const bool visible = a && a->visible ? *a->visible : in.DefaultVisible;
    double opacity = a ? a->opacity : 1.0;
    if (a)
    {
      m.params.x = float(a->roughness.value_or(m.params.x));
      m.params.y = float(a->metallic.value_or(m.params.y));
      m.params.z = float(a->transmission.value_or(m.params.z));
      m.params.w = float(a->ior.value_or(m.params.w));
      m.extra.x = float(a->specular.value_or(m.extra.x));
      if (a->emission)
        m.emission = glm::vec4(float((*a->emission)[0]), float((*a->emission)[1]),
          float((*a->emission)[2]), 0.0f);
    }
    if (!in.Highlighted.empty())
    {
      if (in.Highlighted.count(label))
        m.emission += glm::vec4(tint, 0.0f);
      else
      {
        // Dimming scales the linear albedo: reflected light scales by the same factor.
        m.baseColorVisibility = glm::vec4(
          glm::vec3(m.baseColorVisibility) * float(this->DimOthers), m.baseColorVisibility.a);
        opacity *= this->OthersOpacity;
      }
    }
    if (opacity < 1)
    {
      m.params.z = float(1 - opacity * (1 - m.params.z));
      if (!a || !a->ior)
        m.params.w = 1.0f;
    }
    m.baseColorVisibility.a = visible && opacity > 0 ? 1.0f : 0.0f;
    materials.push_back(m);
  }
  return materials;
}

bool vtkSegmentationSVDAGLabelProperties::GetMaterial(
  vtkSegmentationSVDAG* volume, vtkTypeInt64 label, double material[16])
{
  const auto [found, index] = findLabel(volume, label);
  if (index < 0)
    return false;
  const svdag::Volume& v = *found;
  // The whole table: a label's default color depends on its index.
  const svdag::render::Material m = this->MaterialsFor(v)[size_t(index)];
  const glm::vec4* parts[4] = { &m.baseColorVisibility, &m.emission, &m.params, &m.extra };
  for (int p = 0; p < 4; ++p)
    for (int c = 0; c < 4; ++c)
      material[4 * p + c] = double((*parts[p])[c]);
  return true;
}

bool vtkSegmentationSVDAGLabelProperties::GetDisplayColor(
  vtkSegmentationSVDAG* volume, vtkTypeInt64 label, double rgb[3])
{
  const auto [found, index] = findLabel(volume, label);
  if (index < 0)
    return false;
  const svdag::Volume& v = *found;
  // The precedence of MaterialsFor, without its highlight dimming and the linear conversion
  // (one label: MaterialsFor builds the whole table).
  if (this->GetColor(label, rgb))
    return true;
  if (this->Internal->Table)
  {
    const uint64_t pattern = uint64_t(label);
    const double value = svdag::scalarSigned(v.scalarType) ? double(label) : double(pattern);
    const double* c = this->Internal->Table->GetColor(value);
    std::copy(c, c + 3, rgb);
    return true;
  }
  vtkSegmentationSVDAGLabelProperties::GetDefaultColor(index, rgb);
  return true;
}

void vtkSegmentationSVDAGLabelProperties::GetDefaultColor(vtkIdType labelIndex, double rgb[3])
{
  const glm::vec4 linear =
    svdag::render::Renderer::defaultMaterial(uint32_t(std::max<vtkIdType>(labelIndex, 0)))
      .baseColorVisibility;
  for (int c = 0; c < 3; ++c)
  {
    // linear -> sRGB display value, the inverse of linearFromSrgb.
    const double l = clampTo(double(linear[c]), 0.0, 1.0);
    rgb[c] = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
  }
}

void vtkSegmentationSVDAGLabelProperties::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "LookupTable: " << this->Internal->Table.GetPointer() << "\n";
  os << indent << "DefaultVisibility: " << this->Internal->DefaultVisible << "\n";
  os << indent << "HighlightedLabels: " << this->Internal->Highlighted.size() << "\n";
  os << indent << "HighlightColor: " << this->HighlightColor[0] << " " << this->HighlightColor[1]
     << " " << this->HighlightColor[2] << "\n";
  os << indent << "HighlightIntensity: " << this->HighlightIntensity << "\n";
  os << indent << "DimOthers: " << this->DimOthers << "\n";
  os << indent << "OthersOpacity: " << this->OthersOpacity << "\n";
  os << indent << "Labels: " << this->Internal->Labels.size() << "\n";
  for (const auto& entry : this->Internal->Labels)
  {
    os << indent.GetNextIndent() << entry.first << ": opacity " << entry.second.opacity;
    if (entry.second.color)
      os << ", color " << (*entry.second.color)[0] << " " << (*entry.second.color)[1] << " "
         << (*entry.second.color)[2];
    if (entry.second.visible)
      os << ", visible " << *entry.second.visible;
    os << "\n";
  }
}
