#include "vtkSegmentationSVDAGRepresentation.h"

#include "vtkDataArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkPVRenderView.h"
#include "vtkPlane.h"
#include "vtkRenderer.h"
#include "vtkScalarsToColors.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkSegmentationSVDAGLabelProperties.h"
#include "vtkSegmentationSVDAGRenderSettings.h"
#include "vtkSegmentationSVDAGVolumeMapper.h"
#include "vtkStringArray.h"
#include "vtkVariant.h"
#include "vtkVolume.h"

#include <algorithm>
#include <cstring>

vtkStandardNewMacro(vtkSegmentationSVDAGRepresentation);

namespace
{
// The representation type this class draws (ParaView's Representation property).
constexpr const char* PathTracingType = "Segmentation Path Tracing";

// A new array of the names count() and name(i) give.
vtkStringArray* NamesArray(vtkStringArray* array, int count, const char* (*name)(int))
{
  array->Initialize();
  for (int i = 0; i < count; ++i)
  {
    array->InsertNextValue(name(i));
  }
  return array;
}
}

vtkSegmentationSVDAGRepresentation::vtkSegmentationSVDAGRepresentation()
{
  this->Actor->SetMapper(this->Mapper);
  // pvbatch screenshots and the GUI's still renders show the refined image.
  this->Mapper->RefineStillRendersOn();
}

vtkSegmentationSVDAGRepresentation::~vtkSegmentationSVDAGRepresentation() = default;

void vtkSegmentationSVDAGRepresentation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Opacity: " << this->Opacity << "\n";
  os << indent << "HiddenLabels: " << this->HiddenLabels.size() << "\n";
  os << indent << "PickedHit: " << this->PickedHit << " PickedLabel: " << this->PickedLabel
     << "\n";
}

int vtkSegmentationSVDAGRepresentation::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkSegmentationSVDAG");
  info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

int vtkSegmentationSVDAGRepresentation::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  this->Cache = nullptr;
  if (inputVector[0]->GetNumberOfInformationObjects() == 1)
  {
    if (vtkSegmentationSVDAG* input = vtkSegmentationSVDAG::GetData(inputVector[0], 0))
    {
      this->Cache = vtkSmartPointer<vtkSegmentationSVDAG>::New();
      this->Cache->ShallowCopy(input);
    }
  }
  return this->Superclass::RequestData(request, inputVector, outputVector);
}

int vtkSegmentationSVDAGRepresentation::ProcessViewRequest(
  vtkInformationRequestKey* request_type, vtkInformation* inInfo, vtkInformation* outInfo)
{
  if (!this->Superclass::ProcessViewRequest(request_type, inInfo, outInfo))
  {
    return 0; // not visible
  }
  if (request_type == vtkPVView::REQUEST_UPDATE())
  {
    vtkPVView::SetPiece(inInfo, this, this->Cache);
    // The compressed volume cannot travel: render where the data is (server, every rank).
    vtkPVRenderView::SetRequiresDistributedRendering(inInfo, this, true);
    if (this->Cache && this->Cache->HasVolume())
    {
      // The mapper knows the voxels' world bounds (direction matrix included).
      this->Mapper->SetInputData(this->Cache);
      vtkPVRenderView::SetGeometryBounds(inInfo, this, this->Mapper->GetBounds());
    }
  }
  else if (request_type == vtkPVView::REQUEST_RENDER())
  {
    auto* volume = vtkSegmentationSVDAG::SafeDownCast(vtkPVView::GetPiece(inInfo, this));
    if (volume && !volume->HasVolume())
    {
      volume = nullptr; // an empty piece (this rank read nothing)
    }
    if (this->Mapper->GetInput() != volume)
    {
      this->Mapper->SetInputData(volume);
    }
    this->UpdateLabelProperties(volume);
    this->Actor->SetVisibility(volume != nullptr && this->GetVisibility() && this->DrawnType);
  }
  return 1;
}

bool vtkSegmentationSVDAGRepresentation::AddToView(vtkView* view)
{
  if (auto* rview = vtkPVRenderView::SafeDownCast(view))
  {
    this->Renderer = rview->GetRenderer();
    this->Renderer->AddVolume(this->Actor);
    return this->Superclass::AddToView(view);
  }
  return false;
}

bool vtkSegmentationSVDAGRepresentation::RemoveFromView(vtkView* view)
{
  if (auto* rview = vtkPVRenderView::SafeDownCast(view))
  {
    rview->GetRenderer()->RemoveVolume(this->Actor);
    this->Renderer = nullptr;
    return this->Superclass::RemoveFromView(view);
  }
  return false;
}

void vtkSegmentationSVDAGRepresentation::SetVisibility(bool visible)
{
  this->Superclass::SetVisibility(visible);
  this->Actor->SetVisibility(visible && this->DrawnType);
}

void vtkSegmentationSVDAGRepresentation::SetRepresentation(const char* type)
{
  this->DrawnType = type && std::strcmp(type, PathTracingType) == 0;
  this->Actor->SetVisibility(this->GetVisibility() && this->DrawnType);
  this->Modified();
}

void vtkSegmentationSVDAGRepresentation::SetLOD(const char* name)
{
  this->Mapper->GetSettings()->SetLOD(name);
}

void vtkSegmentationSVDAGRepresentation::SetBackend(const char* name)
{
  this->Mapper->GetSettings()->SetBackend(name);
}

void vtkSegmentationSVDAGRepresentation::SetShading(const char* name)
{
  this->Mapper->GetSettings()->SetShading(name);
}

void vtkSegmentationSVDAGRepresentation::SetSamplesPerPixel(int samples)
{
  this->Mapper->GetSettings()->SetSamplesPerPixel(samples);
}

void vtkSegmentationSVDAGRepresentation::SetMaximumBounces(int bounces)
{
  this->Mapper->GetSettings()->SetMaximumBounces(bounces);
}

void vtkSegmentationSVDAGRepresentation::SetExposure(double exposure)
{
  this->Mapper->GetSettings()->SetExposure(exposure);
}

vtkStringArray* vtkSegmentationSVDAGRepresentation::GetLODNames()
{
  static vtkNew<vtkStringArray> names;
  return NamesArray(names, vtkSegmentationSVDAGRenderSettings::GetNumberOfLODs(),
    &vtkSegmentationSVDAGRenderSettings::GetLODName);
}

vtkStringArray* vtkSegmentationSVDAGRepresentation::GetBackendNames()
{
  static vtkNew<vtkStringArray> names;
  return NamesArray(names, vtkSegmentationSVDAGRenderSettings::GetNumberOfBackends(),
    &vtkSegmentationSVDAGRenderSettings::GetBackendName);
}

vtkStringArray* vtkSegmentationSVDAGRepresentation::GetShadingNames()
{
  static vtkNew<vtkStringArray> names;
  return NamesArray(names, vtkSegmentationSVDAGRenderSettings::GetNumberOfShadings(),
    &vtkSegmentationSVDAGRenderSettings::GetShadingName);
}

void vtkSegmentationSVDAGRepresentation::SetTargetSamplesPerPixel(int samples)
{
  this->Mapper->SetTargetSamplesPerPixel(samples);
}

void vtkSegmentationSVDAGRepresentation::SetRefineStillRenders(bool refine)
{
  this->Mapper->SetRefineStillRenders(refine);
}

void vtkSegmentationSVDAGRepresentation::SetRefineTimeLimit(double seconds)
{
  this->Mapper->SetRefineTimeLimit(seconds);
}

void vtkSegmentationSVDAGRepresentation::SetLookupTable(vtkScalarsToColors* table)
{
  if (this->LookupTable != table)
  {
    this->LookupTable = table;
    this->LabelsModified.Modified();
  }
}

void vtkSegmentationSVDAGRepresentation::SetOpacity(double opacity)
{
  if (this->Opacity != opacity)
  {
    this->Opacity = opacity;
    this->LabelsModified.Modified();
  }
}

void vtkSegmentationSVDAGRepresentation::AddHiddenLabel(vtkTypeInt64 label)
{
  this->HiddenLabels.push_back(label);
  this->LabelsModified.Modified();
}

void vtkSegmentationSVDAGRepresentation::RemoveAllHiddenLabels()
{
  this->HiddenLabels.clear();
  this->LabelsModified.Modified();
}

void vtkSegmentationSVDAGRepresentation::UpdateLabelProperties(vtkSegmentationSVDAG* volume)
{
  const vtkMTimeType tableTime = this->LookupTable ? this->LookupTable->GetMTime() : 0;
  if (!volume ||
    (volume == this->LabelsAppliedTo && this->LabelsAppliedTime >= this->LabelsModified &&
      this->LabelsAppliedTime >= volume->GetMTime() && this->LabelsAppliedTime >= tableTime))
  {
    return;
  }
  vtkSegmentationSVDAGLabelProperties* labels = this->Mapper->GetLabelProperties();
  for (vtkTypeInt64 label : this->AnnotatedLabels)
  {
    labels->RemoveColor(label);
  }
  this->AnnotatedLabels.clear();
  vtkScalarsToColors* table = this->LookupTable;
  if (table && table->GetIndexedLookup())
  {
    labels->SetLookupTable(nullptr);
    for (vtkIdType i = 0; i < table->GetNumberOfAnnotatedValues(); ++i)
    {
      bool valid = false;
      const vtkTypeInt64 label = table->GetAnnotatedValue(i).ToTypeInt64(&valid);
      if (valid)
      {
        double rgba[4];
        table->GetAnnotationColor(table->GetAnnotatedValue(i), rgba);
        labels->SetColor(label, rgba[0], rgba[1], rgba[2]);
        this->AnnotatedLabels.push_back(label);
      }
    }
  }
  else
  {
    labels->SetLookupTable(table);
  }
  labels->ShowAllLabels();
  vtkSmartPointer<vtkDataArray> values;
  values.TakeReference(volume->NewLabelValues());
  for (vtkIdType i = 0; i < values->GetNumberOfTuples(); ++i)
  {
    labels->SetOpacity(values->GetVariantValue(i).ToTypeInt64(), this->Opacity);
  }
  for (vtkTypeInt64 label : this->HiddenLabels)
  {
    labels->SetVisibility(label, false);
  }
  this->LabelsAppliedTo = volume;
  this->LabelsAppliedTime =
    std::max({ this->LabelsModified.GetMTime(), volume->GetMTime(), tableTime });
}

void vtkSegmentationSVDAGRepresentation::AddClippingPlane(vtkPlane* plane)
{
  if (plane)
  {
    this->Mapper->AddClippingPlane(plane);
  }
}

void vtkSegmentationSVDAGRepresentation::RemoveAllClippingPlanes()
{
  this->Mapper->RemoveAllClippingPlanes();
}

int vtkSegmentationSVDAGRepresentation::GetAccumulatedSamples()
{
  return this->Mapper->GetInput() ? this->Mapper->GetAccumulatedSamples() : 0;
}

void vtkSegmentationSVDAGRepresentation::SetPickPixel(double x, double y)
{
  this->PickedHit = 0;
  this->PickedLabel = 0;
  if (this->Renderer && this->Mapper->GetInput() && this->Mapper->Pick(this->Renderer, x, y))
  {
    this->PickedHit = 1;
    this->PickedLabel = this->Mapper->GetPickedLabel();
  }
}
