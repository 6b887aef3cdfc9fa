#include "vtkSegmentationSVDAGRenderer.h"

#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedCharArray.h"

#include <svdag_render/ImageFiles.h>
#include <svdag_render/Renderer.h>

#include <cstring>
#include <exception>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

struct vtkSegmentationSVDAGRenderer::Internals
{
  vtkSmartPointer<vtkSegmentationSVDAG> Input;
  std::unique_ptr<svdag::render::Renderer> Renderer;
  // The volume the renderer holds (uploaded), to re-upload only when the input's volume changes.
  std::shared_ptr<const svdag::Volume> Uploaded;
  std::set<vtkIdType> Hidden;
  // Edited materials by label index (the others keep the renderer's defaults); after
  // ResetLabelMaterials the next Render() returns every label to its default first.
  std::map<vtkIdType, svdag::render::Material> Materials;
  bool MaterialsReset = false;
  vtkNew<vtkImageData> Output;
  bool CameraSet = false;

  svdag::render::Material& edit(vtkIdType index)
  {
    auto it = this->Materials.find(index);
    if (it == this->Materials.end())
    {
      const uint32_t defaultIndex = index >= 0 && index <= vtkIdType(UINT32_MAX) ? uint32_t(index) : 0;
      it = this->Materials.emplace(index, svdag::render::Renderer::defaultMaterial(defaultIndex)).first;
    }
    return it->second;
  }
};

vtkStandardNewMacro(vtkSegmentationSVDAGRenderer);

vtkSegmentationSVDAGRenderer::vtkSegmentationSVDAGRenderer()
  : Internal(new Internals)
{
}

vtkSegmentationSVDAGRenderer::~vtkSegmentationSVDAGRenderer()
{
  this->SetEnvironmentMap(nullptr);
}

void vtkSegmentationSVDAGRenderer::SetLabelColor(vtkIdType index, double r, double g, double b)
{
  glm::vec4& c = this->Internal->edit(index).baseColorVisibility;
  c = glm::vec4(float(r), float(g), float(b), c.a);
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::SetLabelRoughness(vtkIdType index, double roughness)
{
  this->Internal->edit(index).params.x = float(roughness);
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::SetLabelMetallic(vtkIdType index, double metallic)
{
  this->Internal->edit(index).params.y = float(metallic);
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::SetLabelTransmission(vtkIdType index, double transmission)
{
  this->Internal->edit(index).params.z = float(transmission);
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::SetLabelIOR(vtkIdType index, double ior)
{
  this->Internal->edit(index).params.w = float(ior);
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::SetLabelSpecular(vtkIdType index, double specular)
{
  this->Internal->edit(index).extra.x = float(specular);
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::SetLabelEmission(vtkIdType index, double r, double g, double b)
{
  this->Internal->edit(index).emission = glm::vec4(float(r), float(g), float(b), 0.0f);
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::SetLabelVisibility(vtkIdType index, bool visible)
{
  this->Internal->edit(index).baseColorVisibility.a = visible ? 1.0f : 0.0f;
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::ResetLabelMaterials()
{
  this->Internal->Materials.clear();
  this->Internal->MaterialsReset = true;
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::ResetAccumulation()
{
  if (this->Internal->Renderer)
    this->Internal->Renderer->resetAccumulation();
}

void vtkSegmentationSVDAGRenderer::SetInputData(vtkSegmentationSVDAG* volume)
{
  if (this->Internal->Input != volume)
  {
    this->Internal->Input = volume;
    this->Modified();
  }
}

vtkSegmentationSVDAG* vtkSegmentationSVDAGRenderer::GetInput()
{
  return this->Internal->Input;
}

void vtkSegmentationSVDAGRenderer::SetCameraPosition(double x, double y, double z)
{
  this->CameraPosition[0] = x;
  this->CameraPosition[1] = y;
  this->CameraPosition[2] = z;
  this->Internal->CameraSet = true;
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::SetCameraFocalPoint(double x, double y, double z)
{
  this->CameraFocalPoint[0] = x;
  this->CameraFocalPoint[1] = y;
  this->CameraFocalPoint[2] = z;
  this->Internal->CameraSet = true;
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::SetCameraViewUp(double x, double y, double z)
{
  this->CameraViewUp[0] = x;
  this->CameraViewUp[1] = y;
  this->CameraViewUp[2] = z;
  this->Internal->CameraSet = true;
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::SetCameraViewAngle(double degrees)
{
  // Open interval (0, 180): clamp like vtkCamera::SetViewAngle does to [0.00000001, 179].
  degrees = degrees < 1e-8 ? 1e-8 : (degrees > 179 ? 179 : degrees);
  if (this->CameraViewAngle != degrees)
  {
    this->CameraViewAngle = degrees;
    this->Modified();
  }
}

int vtkSegmentationSVDAGRenderer::ResetCamera(double azimuth, double elevation, double zoom)
{
  vtkSegmentationSVDAG* input = this->Internal->Input;
  if (!input || !input->HasVolume())
  {
    vtkErrorMacro("ResetCamera needs an input volume (SetInputData)");
    return 0;
  }
  try
  {
    const svdag::render::Camera c = svdag::render::frameVolume(
      input->GetVolume()->geometry, azimuth, elevation, zoom, this->CameraViewAngle);
    for (int a = 0; a < 3; ++a)
    {
      this->CameraPosition[a] = c.position[a];
      this->CameraFocalPoint[a] = c.focalPoint[a];
      this->CameraViewUp[a] = c.viewUp[a];
    }
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("ResetCamera: " << e.what());
    return 0;
  }
  this->Internal->CameraSet = true;
  this->Modified();
  return 1;
}

void vtkSegmentationSVDAGRenderer::HideLabel(vtkIdType index)
{
  if (this->Internal->Hidden.insert(index).second)
    this->Modified();
}

void vtkSegmentationSVDAGRenderer::ShowLabel(vtkIdType index)
{
  if (this->Internal->Hidden.erase(index))
    this->Modified();
}

void vtkSegmentationSVDAGRenderer::ShowAllLabels()
{
  if (!this->Internal->Hidden.empty())
  {
    this->Internal->Hidden.clear();
    this->Modified();
  }
}

bool vtkSegmentationSVDAGRenderer::IsLabelHidden(vtkIdType index) const
{
  return this->Internal->Hidden.count(index) != 0;
}

int vtkSegmentationSVDAGRenderer::Render()
{
  Internals& in = *this->Internal;
  if (!in.Input || !in.Input->HasVolume())
  {
    vtkErrorMacro("Render needs an input volume (SetInputData)");
    return 0;
  }
  if (!in.CameraSet && !this->ResetCamera())
    return 0;
  try
  {
    if (!in.Renderer)
    {
      in.Renderer = std::make_unique<svdag::render::Renderer>();
      in.Uploaded.reset();
    }
    svdag::render::Renderer& r = *in.Renderer;
    r.setPrimitivesPerBlasLimit(uint32_t(this->MaximumBlocksPerBLAS));
    if (in.Uploaded != in.Input->GetVolume())
    {
      r.setVolume(in.Input->GetVolume());
      in.Uploaded = in.Input->GetVolume();
    }
    std::vector<uint32_t> hidden;
    for (vtkIdType index : in.Hidden)
    {
      if (index >= 0 && index <= vtkIdType(UINT32_MAX))
        hidden.push_back(uint32_t(index));
    }
    r.setHiddenLabels(hidden);
    svdag::render::Camera camera;
    for (int a = 0; a < 3; ++a)
    {
      camera.position[a] = this->CameraPosition[a];
      camera.focalPoint[a] = this->CameraFocalPoint[a];
      camera.viewUp[a] = this->CameraViewUp[a];
    }
    camera.viewAngle = this->CameraViewAngle;
    r.setCamera(camera);
    r.setImageSize(uint32_t(this->Width), uint32_t(this->Height));
    r.setLod(static_cast<svdag::render::Lod>(this->LOD));
    r.setAutoLodPixels(float(this->AutoLODPixels));
    r.setBackground({ { float(this->Background[0]), float(this->Background[1]),
      float(this->Background[2]), float(this->Background[3]) } });
    r.setSamplesPerPixel(uint32_t(this->SamplesPerPixel));
    r.setMaxBounces(uint32_t(this->MaximumBounces));
    r.setSeed(this->Seed);
    r.setNextEventEstimation(this->NextEventEstimation);
    r.setExposure(float(this->Exposure));
    r.setEnvironmentColor({ { float(this->EnvironmentColor[0]), float(this->EnvironmentColor[1]),
      float(this->EnvironmentColor[2]) } });
    r.setEnvironmentMap(this->EnvironmentMap ? this->EnvironmentMap : "");
    svdag::render::SunLight sun;
    sun.on = this->Sun;
    for (int a = 0; a < 3; ++a)
    {
      sun.direction[a] = this->SunDirection[a];
      sun.irradiance[a] = float(this->SunIrradiance[a]);
    }
    sun.angularRadiusDegrees = this->SunAngularRadius;
    r.setSun(sun);
    if (in.MaterialsReset)
    {
      for (size_t i = 0; i < r.materialCount(); ++i)
        r.setMaterial(uint32_t(i), svdag::render::Renderer::defaultMaterial(uint32_t(i)));
      in.MaterialsReset = false;
    }
    for (const auto& entry : in.Materials)
    {
      if (entry.first < 0 || uint64_t(entry.first) >= r.materialCount())
      {
        throw std::invalid_argument("a material is set for label index " +
          std::to_string(entry.first) + ", outside the volume's label table (" +
          std::to_string(r.materialCount()) + " labels)");
      }
      r.setMaterial(uint32_t(entry.first), entry.second);
    }
    r.render();
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Render failed: " << e.what());
    return 0;
  }

  const svdag::render::Image& image = in.Renderer->image();
  const vtkIdType pixels = vtkIdType(image.width) * image.height;
  vtkNew<vtkImageData> output;
  output->SetDimensions(int(image.width), int(image.height), 1);
  vtkNew<vtkUnsignedCharArray> color;
  color->SetName("Color");
  color->SetNumberOfComponents(4);
  color->SetNumberOfTuples(pixels);
  // Packed RGBA8 with R in the lowest byte: bytes R, G, B, A on a little-endian host; unpack
  // explicitly so the order does not depend on the host.
  for (vtkIdType i = 0; i < pixels; ++i)
  {
    for (int c = 0; c < 4; ++c)
      color->SetValue(4 * i + c, static_cast<unsigned char>(image.color[i] >> (8 * c)));
  }
  auto floats = [pixels](const char* name, int components, const std::vector<float>& values) {
    vtkNew<vtkFloatArray> a;
    a->SetName(name);
    a->SetNumberOfComponents(components);
    a->SetNumberOfTuples(pixels);
    std::memcpy(a->GetPointer(0), values.data(), values.size() * sizeof(float));
    return vtkSmartPointer<vtkFloatArray>(a.GetPointer());
  };
  vtkNew<vtkIntArray> label;
  label->SetName("Label");
  label->SetNumberOfTuples(pixels);
  for (vtkIdType i = 0; i < pixels; ++i)
    label->SetValue(i, int(image.label[i]));
  vtkPointData* pd = output->GetPointData();
  pd->SetScalars(color);
  pd->AddArray(floats("HDR", 4, image.hdr));
  pd->AddArray(floats("Depth", 1, image.depth));
  pd->AddArray(label);
  pd->AddArray(floats("Normal", 3, image.normal));
  in.Output->ShallowCopy(output);
  return 1;
}

int vtkSegmentationSVDAGRenderer::WriteImage(const char* path)
{
  const std::string name = path ? path : "";
  auto endsWith = [&name](const char* suffix) {
    const size_t n = std::strlen(suffix);
    return name.size() >= n && name.compare(name.size() - n, n, suffix) == 0;
  };
  if (!endsWith(".png") && !endsWith(".exr"))
  {
    vtkErrorMacro("WriteImage: the file name must end in .png or .exr, got '" << name << "'");
    return 0;
  }
  if (!this->Internal->Renderer || this->Internal->Renderer->image().width == 0)
  {
    vtkErrorMacro("WriteImage: nothing rendered yet (call Render first)");
    return 0;
  }
  try
  {
    if (endsWith(".png"))
      svdag::render::writePng(this->Internal->Renderer->image(), name);
    else
      svdag::render::writeExr(this->Internal->Renderer->image(), name);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("WriteImage: " << e.what());
    return 0;
  }
  return 1;
}

int vtkSegmentationSVDAGRenderer::GetAccumulatedSamples() const
{
  return this->Internal->Renderer ? int(this->Internal->Renderer->accumulatedSamples()) : 0;
}

double vtkSegmentationSVDAGRenderer::GetRenderSeconds() const
{
  return this->Internal->Renderer ? this->Internal->Renderer->renderSeconds() : 0.0;
}

vtkTypeInt64 vtkSegmentationSVDAGRenderer::GetNumberOfBVHBuilds() const
{
  return this->Internal->Renderer ? vtkTypeInt64(this->Internal->Renderer->bvhBuilds()) : 0;
}

vtkTypeInt64 vtkSegmentationSVDAGRenderer::GetNumberOfPipelineBuilds() const
{
  return this->Internal->Renderer ? vtkTypeInt64(this->Internal->Renderer->pipelineBuilds()) : 0;
}

vtkImageData* vtkSegmentationSVDAGRenderer::GetOutput()
{
  return this->Internal->Output;
}

const char* vtkSegmentationSVDAGRenderer::GetDeviceName() const
{
  return this->Internal->Renderer ? this->Internal->Renderer->deviceName().c_str() : "";
}

double vtkSegmentationSVDAGRenderer::GetSetupSeconds() const
{
  return this->Internal->Renderer ? this->Internal->Renderer->setupSeconds() : 0.0;
}

double vtkSegmentationSVDAGRenderer::GetLastFrameMilliseconds() const
{
  return this->Internal->Renderer ? this->Internal->Renderer->lastFrameMilliseconds() : 0.0;
}

vtkTypeInt64 vtkSegmentationSVDAGRenderer::GetBLASBytes() const
{
  return this->Internal->Renderer ? vtkTypeInt64(this->Internal->Renderer->blasBytes()) : 0;
}

int vtkSegmentationSVDAGRenderer::GetNumberOfBLAS() const
{
  return this->Internal->Renderer ? int(this->Internal->Renderer->blasCount()) : 0;
}

vtkTypeInt64 vtkSegmentationSVDAGRenderer::GetTLASBytes() const
{
  return this->Internal->Renderer ? vtkTypeInt64(this->Internal->Renderer->tlasBytes()) : 0;
}

void vtkSegmentationSVDAGRenderer::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Input: " << this->Internal->Input.GetPointer() << "\n";
  os << indent << "Width: " << this->Width << "\n";
  os << indent << "Height: " << this->Height << "\n";
  os << indent << "LOD: " << this->LOD << "\n";
  os << indent << "AutoLODPixels: " << this->AutoLODPixels << "\n";
  os << indent << "CameraPosition: " << this->CameraPosition[0] << " " << this->CameraPosition[1]
     << " " << this->CameraPosition[2] << "\n";
  os << indent << "CameraFocalPoint: " << this->CameraFocalPoint[0] << " "
     << this->CameraFocalPoint[1] << " " << this->CameraFocalPoint[2] << "\n";
  os << indent << "CameraViewUp: " << this->CameraViewUp[0] << " " << this->CameraViewUp[1] << " "
     << this->CameraViewUp[2] << "\n";
  os << indent << "CameraViewAngle: " << this->CameraViewAngle << "\n";
  os << indent << "Background: " << this->Background[0] << " " << this->Background[1] << " "
     << this->Background[2] << " " << this->Background[3] << "\n";
  os << indent << "HiddenLabels:";
  for (vtkIdType index : this->Internal->Hidden)
    os << " " << index;
  os << "\n";
  os << indent << "DeviceName: " << this->GetDeviceName() << "\n";
  os << indent << "SetupSeconds: " << this->GetSetupSeconds() << "\n";
  os << indent << "LastFrameMilliseconds: " << this->GetLastFrameMilliseconds() << "\n";
  os << indent << "BLASBytes: " << this->GetBLASBytes() << "\n";
  os << indent << "TLASBytes: " << this->GetTLASBytes() << "\n";
  os << indent << "MaximumBlocksPerBLAS: " << this->MaximumBlocksPerBLAS << "\n";
  os << indent << "NumberOfBLAS: " << this->GetNumberOfBLAS() << "\n";
  os << indent << "SamplesPerPixel: " << this->SamplesPerPixel << "\n";
  os << indent << "MaximumBounces: " << this->MaximumBounces << "\n";
  os << indent << "Seed: " << this->Seed << "\n";
  os << indent << "NextEventEstimation: " << this->NextEventEstimation << "\n";
  os << indent << "Exposure: " << this->Exposure << "\n";
  os << indent << "EnvironmentColor: " << this->EnvironmentColor[0] << " "
     << this->EnvironmentColor[1] << " " << this->EnvironmentColor[2] << "\n";
  os << indent << "EnvironmentMap: " << (this->EnvironmentMap ? this->EnvironmentMap : "(none)")
     << "\n";
  os << indent << "Sun: " << this->Sun << "\n";
  os << indent << "SunDirection: " << this->SunDirection[0] << " " << this->SunDirection[1] << " "
     << this->SunDirection[2] << "\n";
  os << indent << "SunIrradiance: " << this->SunIrradiance[0] << " " << this->SunIrradiance[1]
     << " " << this->SunIrradiance[2] << "\n";
  os << indent << "SunAngularRadius: " << this->SunAngularRadius << "\n";
  os << indent << "EditedLabelMaterials: " << this->Internal->Materials.size() << "\n";
  os << indent << "AccumulatedSamples: " << this->GetAccumulatedSamples() << "\n";
  os << indent << "RenderSeconds: " << this->GetRenderSeconds() << "\n";
  os << indent << "NumberOfBVHBuilds: " << this->GetNumberOfBVHBuilds() << "\n";
  os << indent << "NumberOfPipelineBuilds: " << this->GetNumberOfPipelineBuilds() << "\n";
}
