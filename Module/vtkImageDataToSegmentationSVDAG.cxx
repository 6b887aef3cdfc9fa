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

namespace
{
// The z-range [z0, z1) of the input's whole extent that the output's piece request covers
// (index z, not offsets), or false when the request names no piece.
bool PieceZRange(vtkInformation* outInfo, const int whole[6], int& z0, int& z1)
{
  int piece = 0, pieces = 1;
  if (!vtkSegmentationSVDAGAlgorithm::GetRequestedPiece(
        outInfo, whole[5] - whole[4] + 1, piece, pieces, z0, z1))
    return false;
  z0 += whole[4];
  z1 += whole[4];
  return true;
}
}

int vtkImageDataToSegmentationSVDAG::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* out)
{
  out->GetInformationObject(0)->Set(vtkAlgorithm::CAN_HANDLE_PIECE_REQUEST(), 1);
  return 1;
}

int vtkImageDataToSegmentationSVDAG::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector** in, vtkInformationVector* out)
{
  vtkInformation* info = in[0]->GetInformationObject(0);
  if (info && info->Has(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()))
  {
    int extent[6];
    info->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), extent);
    int z0 = 0, z1 = 0;
    if (PieceZRange(out->GetInformationObject(0), extent, z0, z1))
    {
      if (z0 == z1)
      {
        // An empty piece asks for nothing (VTK's empty extent).
        extent[0] = extent[2] = extent[4] = 0;
        extent[1] = extent[3] = extent[5] = -1;
      }
      else
      {
        extent[4] = z0;
        extent[5] = z1 - 1;
      }
    }
    info->Set(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT(), extent, 6);
    // The extent is the request: upstream readers that split pieces themselves (the XML
    // readers) would otherwise cut their own share instead.
    info->Set(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER(), 0);
    info->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES(), 1);
    info->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_GHOST_LEVELS(), 0);
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
  output->Initialize();
  // The piece's slices [zBegin, zEnd) of the whole extent, when a piece was asked for.
  vtkInformation* inInfo = in[0]->GetInformationObject(0);
  bool piece = false;
  int zBegin = 0, zEnd = 0;
  if (inInfo->Has(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()))
  {
    int whole[6];
    inInfo->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), whole);
    piece = PieceZRange(out->GetInformationObject(0), whole, zBegin, zEnd);
    if (piece && zBegin == zEnd)
      return 1; // more pieces than slabs: this one is empty
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
  // The input may hold more slices than the piece asked for (a source that cannot stream),
  // never fewer.
  if (!piece)
  {
    zBegin = extent[4];
    zEnd = extent[5] + 1;
  }
  else if (zBegin < extent[4] || zEnd > extent[5] + 1)
  {
    vtkErrorMacro("The input image holds slices " << extent[4] << " .. " << extent[5]
                                                  << ", not the piece's " << zBegin << " .. "
                                                  << zEnd - 1 << ".");
    return 0;
  }
  const size_t sliceValues = size_t(geometry.dims[0]) * size_t(geometry.dims[1]);
  const size_t firstValue = size_t(zBegin - extent[4]) * sliceValues;
  geometry.dims[2] = zEnd - zBegin;
  double origin[3];
  image->TransformIndexToPhysicalPoint(extent[0], extent[2], zBegin, origin);
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
    const auto* data = static_cast<const uint8_t*>(labels->GetVoidPointer(vtkIdType(firstValue)));
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
