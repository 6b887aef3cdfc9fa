#include "vtkSegmentationSVDAGRenderer.h"

#include "vtkAlgorithmOutput.h"
#include "vtkDataObject.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPlane.h"
#include "vtkPlaneCollection.h"
#include "vtkPointData.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkSegmentationSVDAGLabelProperties.h"
#include "vtkSegmentationSVDAGRenderSettings.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnsignedIntArray.h"

#include <svdag/Layout.h>
#include <svdag/Traversal.h>
#include <svdag_render/ImageFiles.h>
#include <svdag_render/Renderer.h>

#include "svdagClipping.h"
#include "svdagRenderSession.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

struct vtkSegmentationSVDAGRenderer::Internals
{
  svdag::vtkglue::RenderSession Session;
  vtkSmartPointer<vtkPlaneCollection> ClippingPlanes;
  bool CameraSet = false;
  // Whether the last execution succeeded (Render()'s result), and its passes' frame times.
  bool Succeeded = false;
  std::vector<double> PassMilliseconds;
  vtkNew<vtkUnsignedIntArray> StepCounts;
};

vtkStandardNewMacro(vtkSegmentationSVDAGRenderer);

vtkSegmentationSVDAGRenderer::vtkSegmentationSVDAGRenderer()
  : Internal(new Internals)
{
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(1);
}

vtkSegmentationSVDAGRenderer::~vtkSegmentationSVDAGRenderer() = default;

int vtkSegmentationSVDAGRenderer::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkSegmentationSVDAG");
  return 1;
}

vtkSegmentationSVDAG* vtkSegmentationSVDAGRenderer::GetInput()
{
  return vtkSegmentationSVDAG::SafeDownCast(this->GetInputDataObject(0, 0));
}

vtkMTimeType vtkSegmentationSVDAGRenderer::GetMTime()
{
  vtkMTimeType t = std::max(this->Superclass::GetMTime(), this->Internal->Session.mtime());
  // A plane moved after it was added re-executes the pass, like any other change.
  if (vtkPlaneCollection* planes = this->Internal->ClippingPlanes)
  {
    t = std::max(t, planes->GetMTime());
    vtkCollectionSimpleIterator it;
    planes->InitTraversal(it);
    while (vtkPlane* plane = planes->GetNextPlane(it))
      t = std::max(t, plane->GetMTime());
  }
  return t;
}

void vtkSegmentationSVDAGRenderer::AddClippingPlane(vtkPlane* plane)
{
  if (!plane)
    return;
  if (!this->Internal->ClippingPlanes)
    this->Internal->ClippingPlanes = vtkSmartPointer<vtkPlaneCollection>::New();
  this->Internal->ClippingPlanes->AddItem(plane);
  this->Modified();
}

void vtkSegmentationSVDAGRenderer::RemoveClippingPlane(vtkPlane* plane)
{
  if (plane && this->Internal->ClippingPlanes &&
    this->Internal->ClippingPlanes->IsItemPresent(plane))
  {
    this->Internal->ClippingPlanes->RemoveItem(plane);
    this->Modified();
  }
}

void vtkSegmentationSVDAGRenderer::RemoveAllClippingPlanes()
{
  if (this->Internal->ClippingPlanes && this->Internal->ClippingPlanes->GetNumberOfItems() > 0)
  {
    this->Internal->ClippingPlanes->RemoveAllItems();
    this->Modified();
  }
}

void vtkSegmentationSVDAGRenderer::SetClippingPlanes(vtkPlaneCollection* planes)
{
  if (this->Internal->ClippingPlanes != planes)
  {
    this->Internal->ClippingPlanes = planes;
    this->Modified();
  }
}

vtkPlaneCollection* vtkSegmentationSVDAGRenderer::GetClippingPlanes()
{
  return this->Internal->ClippingPlanes;
}

int vtkSegmentationSVDAGRenderer::GetMaximumNumberOfClippingPlanes()
{
  return int(svdag::render::MaximumClipPlanes);
}

void vtkSegmentationSVDAGRenderer::SetCroppingRegionPlanes(
  double xmin, double xmax, double ymin, double ymax, double zmin, double zmax)
{
  const double planes[6] = { xmin, xmax, ymin, ymax, zmin, zmax };
  if (svdag::vtkglue::setCroppingRegionPlanes(this, this->CroppingRegionPlanes, planes))
    this->Modified();
}

vtkSegmentationSVDAGRenderSettings* vtkSegmentationSVDAGRenderer::GetSettings()
{
  return this->Internal->Session.settings();
}

void vtkSegmentationSVDAGRenderer::SetSettings(vtkSegmentationSVDAGRenderSettings* settings)
{
  if (this->Internal->Session.setSettings(settings))
    this->Modified();
}

vtkSegmentationSVDAGLabelProperties* vtkSegmentationSVDAGRenderer::GetLabelProperties()
{
  return this->Internal->Session.labels();
}

void vtkSegmentationSVDAGRenderer::SetLabelProperties(
  vtkSegmentationSVDAGLabelProperties* properties)
{
  if (this->Internal->Session.setLabels(properties))
    this->Modified();
}

void vtkSegmentationSVDAGRenderer::ResetAccumulation()
{
  if (svdag::render::Renderer* r = this->Internal->Session.renderer())
    r->resetAccumulation();
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

int vtkSegmentationSVDAGRenderer::FrameVolume(
  vtkSegmentationSVDAG* input, double azimuth, double elevation, double zoom)
{
  if (!input || !input->HasVolume())
  {
    vtkErrorMacro("ResetCamera needs an input volume (SetInputConnection or SetInputData)");
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
  return 1;
}

int vtkSegmentationSVDAGRenderer::ResetCamera(double azimuth, double elevation, double zoom)
{
  // A connected input is brought up to date first (its volume is what is framed).
  if (this->GetNumberOfInputConnections(0) > 0)
  {
    vtkAlgorithmOutput* connection = this->GetInputConnection(0, 0);
    connection->GetProducer()->Update(connection->GetIndex());
  }
  if (!this->FrameVolume(this->GetInput(), azimuth, elevation, zoom))
    return 0;
  this->Modified();
  return 1;
}

int vtkSegmentationSVDAGRenderer::Render()
{
  if (this->GetNumberOfInputConnections(0) == 0)
  {
    vtkErrorMacro("Render needs an input volume (SetInputConnection or SetInputData)");
    return 0;
  }
  this->Internal->Succeeded = false;
  this->Modified();
  this->Update();
  return this->Internal->Succeeded ? 1 : 0;
}

int vtkSegmentationSVDAGRenderer::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  const int extent[6] = { 0, this->Width - 1, 0, this->Height - 1, 0, 0 };
  outInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), extent, 6);
  const double origin[3] = { 0, 0, 0 };
  const double spacing[3] = { 1, 1, 1 };
  outInfo->Set(vtkDataObject::ORIGIN(), origin, 3);
  outInfo->Set(vtkDataObject::SPACING(), spacing, 3);
  vtkDataObject::SetPointDataActiveScalarInfo(outInfo, VTK_UNSIGNED_CHAR, 4);
  return 1;
}

namespace
{
// The core image as point data of a vtkImageData of its size.
void fillOutput(const svdag::render::Image& image, vtkImageData* output)
{
  const vtkIdType pixels = vtkIdType(image.width) * image.height;
  output->Initialize();
  output->SetExtent(0, int(image.width) - 1, 0, int(image.height) - 1, 0, 0);
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
  pd->AddArray(floats("FaceNormal", 3, image.faceNormal));
}
} // namespace

int vtkSegmentationSVDAGRenderer::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  Internals& in = *this->Internal;
  in.Succeeded = false;
  vtkSegmentationSVDAG* input = vtkSegmentationSVDAG::GetData(inputVector[0], 0);
  vtkImageData* output = vtkImageData::GetData(outputVector, 0);
  if (!output)
  {
    vtkErrorMacro("the output is not a vtkImageData");
    return 0;
  }
  output->Initialize();
  if (!input || !input->HasVolume())
  {
    vtkErrorMacro("Render needs an input volume (SetInputConnection or SetInputData)");
    return 0;
  }
  if (!in.CameraSet && !this->FrameVolume(input, 0.0, 0.0, 1.0))
    return 0;
  try
  {
    if (!in.Session.initialize())
      throw std::runtime_error(in.Session.error());
    svdag::render::Renderer& r = in.Session.prepare(input->GetVolume());
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
    r.setTraceReduction(uint32_t(this->TraceReduction));
    svdag::render::RenderSettings settings = in.Session.settings()->GetCoreSettings();
    const std::array<double, 16> identity = svdag::vtkglue::identityMatrix();
    svdag::vtkglue::setClipping(settings, this->Internal->ClippingPlanes, identity, identity,
      this->Cropping != 0, this->CroppingRegionPlanes);
    r.setSettings(settings);
    r.setStepStatistics(this->StepStatistics != 0);
    in.PassMilliseconds.clear();
    using PassUse = svdag::render::Renderer::PassUse;
    for (int pass = 0; pass < this->PassesPerRender; ++pass)
    {
      r.render(pass + 1 < this->PassesPerRender ? PassUse::Accumulating : PassUse::Shown);
      in.PassMilliseconds.push_back(r.lastFrameMilliseconds());
    }
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Render failed: " << e.what());
    return 0;
  }
  fillOutput(in.Session.renderer()->image(), output);
  in.Succeeded = true;
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
  const svdag::render::Renderer* renderer = this->Internal->Session.renderer();
  if (!renderer || renderer->image().width == 0)
  {
    vtkErrorMacro("WriteImage: nothing rendered yet (call Render or Update first)");
    return 0;
  }
  try
  {
    if (endsWith(".png"))
      svdag::render::writePng(renderer->image(), name);
    else
      svdag::render::writeExr(renderer->image(), name);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("WriteImage: " << e.what());
    return 0;
  }
  return 1;
}

// The statistics: the core renderer's, 0 (or "") before the first pass.
#define SVDAG_RENDERER_STATISTIC(Type, Name, expression)                                           \
  Type vtkSegmentationSVDAGRenderer::Get##Name() const                                             \
  {                                                                                                \
    const svdag::render::Renderer* r = this->Internal->Session.renderer();                             \
    return r ? Type(expression) : Type(0);                                                         \
  }
SVDAG_RENDERER_STATISTIC(int, AccumulatedSamples, r->accumulatedSamples())
SVDAG_RENDERER_STATISTIC(double, RenderSeconds, r->renderSeconds())
SVDAG_RENDERER_STATISTIC(double, ErrorEstimate, r->errorEstimate())
SVDAG_RENDERER_STATISTIC(vtkTypeInt64, NumberOfBVHBuilds, r->bvhBuilds())
SVDAG_RENDERER_STATISTIC(vtkTypeInt64, NumberOfPipelineBuilds, r->pipelineBuilds())
SVDAG_RENDERER_STATISTIC(double, SetupSeconds, r->setupSeconds())
SVDAG_RENDERER_STATISTIC(double, LastFrameMilliseconds, r->lastFrameMilliseconds())
SVDAG_RENDERER_STATISTIC(vtkTypeInt64, BLASBytes, r->blasBytes())
SVDAG_RENDERER_STATISTIC(vtkTypeInt64, TLASBytes, r->tlasBytes())
SVDAG_RENDERER_STATISTIC(vtkTypeInt64, NeighbourTableBytes, r->neighbourTableBytes())
SVDAG_RENDERER_STATISTIC(int, NumberOfBLAS, r->blasCount())
#undef SVDAG_RENDERER_STATISTIC

// The header's clamp of TraceReduction is the core's range.
static_assert(svdag::render::Renderer::MaximumTraceReduction == 8, "TraceReduction's clamp");

vtkUnsignedIntArray* vtkSegmentationSVDAGRenderer::GetStepCounts()
{
  static const char* const names[] = { "rays", "cells", "cells_with_blocks", "blocks",
    "dag_walks", "dag_steps", "shadow_rays", "hits" };
  static_assert(sizeof(names) / sizeof(names[0]) == svdag::traversal::SVDAG_STAT_COUNT,
    "one name per step counter");
  vtkUnsignedIntArray* a = this->Internal->StepCounts;
  const svdag::render::Renderer* r = this->Internal->Session.renderer();
  const std::vector<uint32_t> empty;
  const std::vector<uint32_t>& counts = r ? r->stepCounts() : empty;
  a->SetName("StepCounts");
  a->SetNumberOfComponents(int(svdag::traversal::SVDAG_STAT_COUNT));
  for (int c = 0; c < int(svdag::traversal::SVDAG_STAT_COUNT); ++c)
    a->SetComponentName(c, names[c]);
  a->SetNumberOfTuples(vtkIdType(counts.size() / svdag::traversal::SVDAG_STAT_COUNT));
  if (!counts.empty())
    std::memcpy(a->GetPointer(0), counts.data(), counts.size() * sizeof(uint32_t));
  return a;
}

double vtkSegmentationSVDAGRenderer::GetPassMilliseconds(int pass) const
{
  const std::vector<double>& times = this->Internal->PassMilliseconds;
  return pass >= 0 && size_t(pass) < times.size() ? times[size_t(pass)] : 0.0;
}

const char* vtkSegmentationSVDAGRenderer::GetBackendInUse() const
{
  return this->Internal->Session.backendInUse();
}

vtkTypeInt64 vtkSegmentationSVDAGRenderer::GetDeviceBytes() const
{
  return this->Internal->Session.deviceBytes("total");
}

vtkTypeInt64 vtkSegmentationSVDAGRenderer::GetEncodingBytes() const
{
  return this->Internal->Session.deviceBytes("encoding");
}

vtkTypeInt64 vtkSegmentationSVDAGRenderer::GetAccelerationBytes() const
{
  return this->Internal->Session.deviceBytes("acceleration");
}

vtkTypeInt64 vtkSegmentationSVDAGRenderer::GetMaterialBytes() const
{
  return this->Internal->Session.deviceBytes("materials");
}

vtkTypeInt64 vtkSegmentationSVDAGRenderer::GetImageBytes() const
{
  return this->Internal->Session.deviceBytes("images");
}

int vtkSegmentationSVDAGRenderer::GetDeviceUsers()
{
  return svdag::vtkglue::RenderSession::deviceUsers();
}

vtkTypeInt64 vtkSegmentationSVDAGRenderer::GetDeviceId() const
{
  return this->Internal->Session.deviceId();
}

const char* vtkSegmentationSVDAGRenderer::GetDeviceName() const
{
  const svdag::render::Renderer* r = this->Internal->Session.renderer();
  return r ? r->deviceName().c_str() : "";
}

void vtkSegmentationSVDAGRenderer::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  auto triple = [&os](const double* v) { os << v[0] << " " << v[1] << " " << v[2] << "\n"; };
  os << indent << "Width: " << this->Width << "\n";
  os << indent << "Height: " << this->Height << "\n";
  os << indent << "PassesPerRender: " << this->PassesPerRender << "\n";
  os << indent << "TraceReduction: " << this->TraceReduction << "\n";
  os << indent << "StepStatistics: " << this->StepStatistics << "\n";
  os << indent << "CameraPosition: ";
  triple(this->CameraPosition);
  os << indent << "CameraFocalPoint: ";
  triple(this->CameraFocalPoint);
  os << indent << "CameraViewUp: ";
  triple(this->CameraViewUp);
  os << indent << "CameraViewAngle: " << this->CameraViewAngle << "\n";
  os << indent << "ClippingPlanes: "
     << (this->Internal->ClippingPlanes ? this->Internal->ClippingPlanes->GetNumberOfItems() : 0)
     << "\n";
  os << indent << "Cropping: " << this->Cropping << "\n" << indent << "CroppingRegionPlanes:";
  for (double b : this->CroppingRegionPlanes)
    os << " " << b;
  os << "\n";
  os << indent << "Settings:\n";
  this->Internal->Session.settings()->PrintSelf(os, indent.GetNextIndent());
  os << indent << "LabelProperties:\n";
  this->Internal->Session.labels()->PrintSelf(os, indent.GetNextIndent());
  os << indent << "DeviceName: " << this->GetDeviceName() << "\n";
  os << indent << "SetupSeconds: " << this->GetSetupSeconds() << "\n";
  os << indent << "LastFrameMilliseconds: " << this->GetLastFrameMilliseconds() << "\n";
  os << indent << "BackendInUse: " << this->GetBackendInUse() << "\n";
  os << indent << "DeviceBytes: " << this->GetDeviceBytes() << " (encoding " << this->GetEncodingBytes()
     << ", acceleration " << this->GetAccelerationBytes() << ", materials " << this->GetMaterialBytes()
     << ", images " << this->GetImageBytes() << ")\n";
  os << indent << "BLASBytes: " << this->GetBLASBytes() << "\n";
  os << indent << "TLASBytes: " << this->GetTLASBytes() << "\n";
  os << indent << "NeighbourTableBytes: " << this->GetNeighbourTableBytes() << "\n";
  os << indent << "NumberOfBLAS: " << this->GetNumberOfBLAS() << "\n";
  os << indent << "AccumulatedSamples: " << this->GetAccumulatedSamples() << "\n";
  os << indent << "RenderSeconds: " << this->GetRenderSeconds() << "\n";
  os << indent << "ErrorEstimate: " << this->GetErrorEstimate() << "\n";
  os << indent << "NumberOfBVHBuilds: " << this->GetNumberOfBVHBuilds() << "\n";
  os << indent << "NumberOfPipelineBuilds: " << this->GetNumberOfPipelineBuilds() << "\n";
}
