#include "vtkImageDataToSegmentationSVDAG.h"

#include "vtkDataArray.h"
#include "vtkDataSetAttributes.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMatrix3x3.h"
#include "vtkObjectFactory.h"
#include "vtkSVDAGParallel.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include "svdag/Builder.h"

#include <algorithm>
#include <exception>
#include <memory>

vtkStandardNewMacro(vtkImageDataToSegmentationSVDAG);

vtkImageDataToSegmentationSVDAG::vtkImageDataToSegmentationSVDAG()
{
  this->SetNumberOfInputPorts(1);
  this->SetInputArrayToProcess(
    0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_POINTS, vtkDataSetAttributes::SCALARS);
}

vtkImageDataToSegmentationSVDAG::~vtkImageDataToSegmentationSVDAG() = default;

int vtkImageDataToSegmentationSVDAG::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  return 1;
}

int vtkImageDataToSegmentationSVDAG::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector** in, vtkInformationVector*)
{
  vtkInformation* info = in[0]->GetInformationObject(0);
  if (info && info->Has(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()))
  {
    info->Set(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT(),
      info->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()), 6);
  }
  return 1;
}

int vtkImageDataToSegmentationSVDAG::RequestData(
  vtkInformation*, vtkInformationVector** in, vtkInformationVector* out)
{
  vtkImageData* image = vtkImageData::GetData(in[0]);
  vtkSegmentationSVDAG* output = vtkSegmentationSVDAG::GetData(out);
  if (!image || !output)
  {
    vtkErrorMacro("Missing input image or output.");
    return 0;
  }
  vtkDataArray* labels = this->GetInputArrayToProcess(0, in);
  if (!labels)
  {
    vtkErrorMacro("The input image has no point scalars to compress.");
    return 0;
  }
  const int coreType = vtkSegmentationSVDAG::FromVTKScalarType(labels->GetDataType());
  if (coreType < 0 || labels->GetNumberOfComponents() != 1)
  {
    vtkErrorMacro("Label volumes need one integer component; array '"
      << (labels->GetName() ? labels->GetName() : "") << "' has "
      << labels->GetNumberOfComponents() << " component(s) of type " << labels->GetDataTypeAsString()
      << ".");
    return 0;
  }
  int extent[6];
  image->GetExtent(extent);
  svdag::Geometry geometry;
  for (int a = 0; a < 3; ++a)
  {
    geometry.dims[a] = extent[2 * a + 1] - extent[2 * a] + 1;
  }
  if (labels->GetNumberOfTuples() != static_cast<vtkIdType>(geometry.voxelCount()))
  {
    vtkErrorMacro("The label array has " << labels->GetNumberOfTuples() << " values for "
                                         << geometry.voxelCount() << " voxels.");
    return 0;
  }
  double origin[3];
  image->TransformIndexToPhysicalPoint(extent[0], extent[2], extent[4], origin);
  const double* spacing = image->GetSpacing();
  for (int a = 0; a < 3; ++a)
  {
    geometry.spacing[a] = spacing[a];
    geometry.origin[a] = origin[a];
  }
  const double* direction = image->GetDirectionMatrix()->GetData();
  std::copy(direction, direction + 9, geometry.direction.begin());

  const svdag::BuildOptions options = this->GetBuildOptions();

  try
  {
    const auto type = static_cast<svdag::ScalarType>(coreType);
    svdag::Builder builder(geometry, type, options, vtkSVDAGParallelFor());
    const size_t slice = size_t(geometry.dims[0]) * size_t(geometry.dims[1]) *
      size_t(svdag::scalarSize(type));
    const auto* data = static_cast<const uint8_t*>(labels->GetVoidPointer(0));
    for (int32_t z0 = 0; z0 < geometry.dims[2]; z0 += svdag::Builder::SlabDepth)
    {
      if (this->GetAbortExecute())
        return 0;
      const int32_t nz = std::min(svdag::Builder::SlabDepth, geometry.dims[2] - z0);
      builder.addSlab(z0, nz, data + size_t(z0) * slice);
      this->UpdateProgress(double(z0 + nz) / geometry.dims[2]);
    }
    output->SetVolume(std::make_shared<const svdag::Volume>(builder.finish()));
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Cannot compress the label image: " << e.what());
    return 0;
  }
  return 1;
}

void vtkImageDataToSegmentationSVDAG::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
}
