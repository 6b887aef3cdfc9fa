#include "SegmentationScene.h"

#include "vtkCamera.h"
#include "vtkErrorCode.h"
#include "vtkPolyDataMapper.h"
#include "vtkProperty.h"
#include "vtkSegmentationSVDAGLabelProperties.h"
#include "vtkSegmentationSVDAGRenderSettings.h"

#include <cmath>

SegmentationScene::SegmentationScene()
{
  // The path tracer: sunlight for shape cues, two bounces, 4 samples per pixel added by each
  // render while the view is still, until 32 (a few seconds on a CPU Vulkan device).
  vtkSegmentationSVDAGRenderSettings* settings = this->Mapper->GetSettings();
  settings->SetSun(true);
  settings->SetMaximumBounces(2);
  settings->SetSamplesPerPixel(4);
  this->Mapper->SetTargetSamplesPerPixel(32);
  this->Mapper->SetInputConnection(this->Reader->GetOutputPort());
  this->Volume->SetMapper(this->Mapper);

  // The highlight: the default amber emissive tint on the picked label, the others at 40 %
  // brightness.
  this->Mapper->GetLabelProperties()->SetDimOthers(0.4);

  vtkNew<vtkPolyDataMapper> outlineMapper;
  outlineMapper->SetInputConnection(this->Outline->GetOutputPort());
  this->OutlineActor->SetMapper(outlineMapper);
  this->OutlineActor->GetProperty()->SetColor(0.9, 0.9, 0.9);
  this->OutlineActor->GetProperty()->SetLineWidth(2);

  vtkNew<vtkPolyDataMapper> markerMapper;
  markerMapper->SetInputConnection(this->Marker->GetOutputPort());
  this->Marker->SetThetaResolution(24);
  this->Marker->SetPhiResolution(16);
  this->MarkerActor->SetMapper(markerMapper);
  this->MarkerActor->GetProperty()->SetColor(0.9, 0.15, 0.1);
  this->MarkerActor->VisibilityOff(); // until something is picked

  this->Renderer->SetBackground(0.1, 0.1, 0.12);
  this->Renderer->AddVolume(this->Volume);
  this->Renderer->AddActor(this->OutlineActor);
  this->Renderer->AddActor(this->MarkerActor);
  this->Window->AddRenderer(this->Renderer);
  this->Window->SetSize(480, 360);
}

bool SegmentationScene::Load(const std::string& fileName, std::string& error)
{
  this->Reader->SetFileName(fileName.c_str());
  this->Reader->Update();
  if (this->Reader->GetErrorCode() != vtkErrorCode::NoError)
  {
    error = "cannot read '" + fileName +
      "': " + vtkErrorCode::GetStringFromErrorCode(this->Reader->GetErrorCode());
    return false;
  }
  // Fails without a usable Vulkan device (the mapper's error names the devices found).
  if (!this->Mapper->InitializeDevice())
  {
    error = "no Vulkan device can render the volume";
    return false;
  }

  const double* bounds = this->Mapper->GetBounds();
  this->Outline->SetBounds(bounds[0], bounds[1], bounds[2], bounds[3], bounds[4], bounds[5]);
  const double diagonal = std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
    (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) +
    (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
  this->Marker->SetRadius(0.015 * diagonal);

  // An oblique view of the whole volume (ResetCamera fits its bounding sphere: zoom in a bit).
  this->Renderer->ResetCamera();
  vtkCamera* camera = this->Renderer->GetActiveCamera();
  camera->Azimuth(30);
  camera->Elevation(25);
  camera->OrthogonalizeViewUp();
  this->Renderer->ResetCamera();
  camera->Zoom(1.3);
  this->Renderer->ResetCameraClippingRange();
  return true;
}

bool SegmentationScene::PickAndHighlight(double x, double y)
{
  vtkSegmentationSVDAGLabelProperties* labels = this->Mapper->GetLabelProperties();
  // A highlight change is a material upload: it restarts the refinement, the BVH stays.
  labels->RemoveAllHighlightedLabels();
  this->HasPick = this->Mapper->Pick(this->Renderer, x, y);
  this->MarkerActor->SetVisibility(this->HasPick);
  if (!this->HasPick)
    return false;
  this->PickedLabel = this->Mapper->GetPickedLabel();
  this->Mapper->GetPickedPosition(this->PickedPosition);
  labels->AddHighlightedLabel(this->PickedLabel);
  this->Marker->SetCenter(this->PickedPosition);
  return true;
}

bool SegmentationScene::HidePickedLabel()
{
  if (!this->HasPick)
    return false;
  // A visibility change rebuilds only what finds the blocks (the BVH or the cell grid).
  this->Mapper->GetLabelProperties()->SetVisibility(this->PickedLabel, false);
  this->Mapper->GetLabelProperties()->RemoveHighlightedLabel(this->PickedLabel);
  this->MarkerActor->VisibilityOff();
  this->HasPick = false;
  return true;
}

void SegmentationScene::ShowAllLabels()
{
  this->Mapper->GetLabelProperties()->ShowAllLabels();
  this->Mapper->GetLabelProperties()->RemoveAllHighlightedLabels();
  this->MarkerActor->VisibilityOff();
  this->HasPick = false;
}

const char* SegmentationScene::NextLOD()
{
  vtkSegmentationSVDAGRenderSettings* settings = this->Mapper->GetSettings();
  const int lod = (settings->GetLOD() + 1) % (vtkSegmentationSVDAGRenderSettings::LOD_AUTO + 1);
  settings->SetLOD(lod);
  return LODName(lod);
}

const char* SegmentationScene::LODName(int lod)
{
  switch (lod)
  {
    case vtkSegmentationSVDAGRenderSettings::LOD_BLOCK:
      return "block";
    case vtkSegmentationSVDAGRenderSettings::LOD_LEAF:
      return "leaf";
    case vtkSegmentationSVDAGRenderSettings::LOD_VOXEL:
      return "voxel";
    default:
      return "auto";
  }
}
