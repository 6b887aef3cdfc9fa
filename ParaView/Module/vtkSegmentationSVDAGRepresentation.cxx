#include "vtkSegmentationSVDAGRepresentation.h"

#include "vtkCamera.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiProcessController.h"
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
#include "vtkTypeInt64Array.h"
#include "vtkTypeUInt64Array.h"
#include "vtkVariant.h"
#include "vtkVolume.h"

#include <algorithm>
#include <cstring>

#include "svdag/Volume.h"

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

// The controller of the ranks the data is split across, or null in a single process.
vtkMultiProcessController* RanksController()
{
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  return controller && controller->GetNumberOfProcesses() > 1 ? controller : nullptr;
}

// Collective over the ranks: the index of each of `piece`'s labels in the table of the whole
// volume, the union of every rank's labels sorted by value (the order of a label table), or
// empty in a single process.
std::vector<vtkIdType> GatherWholeTableIndices(vtkSegmentationSVDAG* piece)
{
  vtkMultiProcessController* controller = RanksController();
  if (!controller)
  {
    return {};
  }
  const svdag::Volume* volume = piece && piece->HasVolume() ? piece->GetVolume().get() : nullptr;
  vtkNew<vtkTypeUInt64Array> mine;
  vtkNew<vtkTypeUInt64Array> everyones;
  if (volume)
  {
    mine->SetNumberOfValues(vtkIdType(volume->labels.size()));
    for (size_t i = 0; i < volume->labels.size(); ++i)
    {
      mine->SetValue(vtkIdType(i), volume->labels[i].value);
    }
  }
  controller->AllGatherV(mine, everyones);
  if (!volume)
  {
    return {};
  }
  const svdag::ScalarType type = volume->scalarType;
  const auto less = [type](uint64_t a, uint64_t b) { return svdag::scalarLess(type, a, b); };
  std::vector<uint64_t> whole(everyones->GetPointer(0),
    everyones->GetPointer(0) + everyones->GetNumberOfValues());
  std::sort(whole.begin(), whole.end(), less);
  whole.erase(std::unique(whole.begin(), whole.end()), whole.end());
  std::vector<vtkIdType> indices;
  for (const svdag::LabelInfo& label : volume->labels)
  {
    indices.push_back(
      std::lower_bound(whole.begin(), whole.end(), label.value, less) - whole.begin());
  }
  return indices;
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
  this->WholeTableIndices = GatherWholeTableIndices(this->Cache);
  this->LabelsModified.Modified();
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
  for (vtkTypeInt64 label : this->ColoredLabels)
  {
    labels->RemoveColor(label);
  }
  this->ColoredLabels.clear();
  vtkSmartPointer<vtkDataArray> values;
  values.TakeReference(volume->NewLabelValues());
  vtkScalarsToColors* table = this->LookupTable;
  const bool categorical = table && table->GetIndexedLookup();
  labels->SetLookupTable(categorical ? nullptr : table);
  if (categorical)
  {
    for (vtkIdType i = 0; i < table->GetNumberOfAnnotatedValues(); ++i)
    {
      bool valid = false;
      const vtkTypeInt64 label = table->GetAnnotatedValue(i).ToTypeInt64(&valid);
      if (valid)
      {
        double rgba[4];
        table->GetAnnotationColor(table->GetAnnotatedValue(i), rgba);
        labels->SetColor(label, rgba[0], rgba[1], rgba[2]);
        this->ColoredLabels.push_back(label);
      }
    }
  }
  if ((!table || categorical) &&
    this->WholeTableIndices.size() == size_t(values->GetNumberOfTuples()))
  {
    // A piece: the labels the lookup table leaves to their defaults take the whole volume's.
    for (vtkIdType i = 0; i < values->GetNumberOfTuples(); ++i)
    {
      const vtkTypeInt64 label = values->GetVariantValue(i).ToTypeInt64();
      double rgb[3];
      if (!labels->GetColor(label, rgb))
      {
        vtkSegmentationSVDAGLabelProperties::GetDefaultColor(this->WholeTableIndices[i], rgb);
        labels->SetColor(label, rgb[0], rgb[1], rgb[2]);
        this->ColoredLabels.push_back(label);
      }
    }
  }
  labels->ShowAllLabels();
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
  if (x < 0 || y < 0)
  {
    return; // the property's default (pushed when the proxy is made): no pick, on every rank
  }
  double depth = 0;
  if (this->Renderer && this->Mapper->GetInput() && this->Mapper->Pick(this->Renderer, x, y))
  {
    this->PickedHit = 1;
    this->PickedLabel = this->Mapper->GetPickedLabel();
    double position[3], eye[3], forward[3];
    this->Mapper->GetPickedPosition(position);
    vtkCamera* camera = this->Renderer->GetActiveCamera();
    camera->GetPosition(eye);
    camera->GetDirectionOfProjection(forward);
    for (int a = 0; a < 3; ++a)
    {
      depth += (position[a] - eye[a]) * forward[a];
    }
  }
  // Collective over the ranks (every rank runs this property's update): the nearest of their
  // hits is the hit of the undivided volume, since each rank traced the same ray.
  if (vtkMultiProcessController* controller = RanksController())
  {
    vtkNew<vtkTypeInt64Array> hitLabel, hitLabels;
    vtkNew<vtkDoubleArray> hitDepth, hitDepths;
    hitLabel->InsertNextValue(this->PickedHit);
    hitLabel->InsertNextValue(this->PickedLabel);
    hitDepth->InsertNextValue(depth);
    controller->AllGatherV(hitLabel, hitLabels);
    controller->AllGatherV(hitDepth, hitDepths);
    this->PickedHit = 0;
    this->PickedLabel = 0;
    for (vtkIdType r = 0; r < hitDepths->GetNumberOfValues(); ++r)
    {
      if (hitLabels->GetValue(2 * r) && (!this->PickedHit || hitDepths->GetValue(r) < depth))
      {
        this->PickedHit = 1;
        this->PickedLabel = hitLabels->GetValue(2 * r + 1);
        depth = hitDepths->GetValue(r);
      }
    }
  }
}
