#include "vtkSegmentationSVDAGToImageData.h"

#include "vtkDataObject.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include <string>

vtkStandardNewMacro(vtkSegmentationSVDAGToImageData);

vtkSegmentationSVDAGToImageData::vtkSegmentationSVDAGToImageData() = default;
vtkSegmentationSVDAGToImageData::~vtkSegmentationSVDAGToImageData() = default;

int vtkSegmentationSVDAGToImageData::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkSegmentationSVDAG");
  return 1;
}

int vtkSegmentationSVDAGToImageData::RequestInformation(
  vtkInformation*, vtkInformationVector** in, vtkInformationVector* out)
{
  vtkSegmentationSVDAG* input = vtkSegmentationSVDAG::GetData(in[0]);
  vtkInformation* info = out->GetInformationObject(0);
  if (!input || !input->HasVolume())
  {
    // The input's data only exists after it executes; information follows in RequestData.
    return 1;
  }
  int dims[3];
  double spacing[3], origin[3], direction[9];
  input->GetDimensions(dims);
  input->GetSpacing(spacing);
  input->GetOrigin(origin);
  input->GetDirection(direction);
  const int extent[6] = { 0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1 };
  info->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), extent, 6);
  info->Set(vtkDataObject::SPACING(), spacing, 3);
  info->Set(vtkDataObject::ORIGIN(), origin, 3);
  info->Set(vtkDataObject::DIRECTION(), direction, 9);
  vtkDataObject::SetPointDataActiveScalarInfo(info, input->GetLabelScalarType(), 1);
  return 1;
}

int vtkSegmentationSVDAGToImageData::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector**, vtkInformationVector*)
{
  return 1;
}

int vtkSegmentationSVDAGToImageData::RequestData(
  vtkInformation*, vtkInformationVector** in, vtkInformationVector* out)
{
  vtkSegmentationSVDAG* input = vtkSegmentationSVDAG::GetData(in[0]);
  vtkImageData* output = vtkImageData::GetData(out);
  if (!input || !input->HasVolume())
  {
    vtkErrorMacro("The input holds no compressed volume.");
    return 0;
  }
  std::string error;
  if (!input->DecodeTo(output, error))
  {
    vtkErrorMacro("Decoding failed: " << error);
    return 0;
  }
  this->UpdateProgress(1.0);
  return 1;
}

void vtkSegmentationSVDAGToImageData::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
}
