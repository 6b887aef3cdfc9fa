#include "vtkSegmentationSVDAGAlgorithm.h"

#include "vtkDemandDrivenPipeline.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include "svdag/Builder.h"

#include <algorithm>

vtkStandardNewMacro(vtkSegmentationSVDAGAlgorithm);

vtkSegmentationSVDAGAlgorithm::vtkSegmentationSVDAGAlgorithm()
{
  this->SetNumberOfInputPorts(0);
  this->SetNumberOfOutputPorts(1);
}

vtkSegmentationSVDAGAlgorithm::~vtkSegmentationSVDAGAlgorithm() = default;

vtkSegmentationSVDAG* vtkSegmentationSVDAGAlgorithm::GetOutput()
{
  return vtkSegmentationSVDAG::SafeDownCast(this->GetOutputDataObject(0));
}

vtkTypeBool vtkSegmentationSVDAGAlgorithm::ProcessRequest(
  vtkInformation* request, vtkInformationVector** in, vtkInformationVector* out)
{
  if (request->Has(vtkDemandDrivenPipeline::REQUEST_DATA_OBJECT()))
    return this->RequestDataObject(request, in, out);
  if (request->Has(vtkDemandDrivenPipeline::REQUEST_INFORMATION()))
    return this->RequestInformation(request, in, out);
  if (request->Has(vtkStreamingDemandDrivenPipeline::REQUEST_UPDATE_EXTENT()))
    return this->RequestUpdateExtent(request, in, out);
  if (request->Has(vtkDemandDrivenPipeline::REQUEST_DATA()))
    return this->RequestData(request, in, out);
  return this->Superclass::ProcessRequest(request, in, out);
}

int vtkSegmentationSVDAGAlgorithm::RequestDataObject(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* out)
{
  for (int i = 0; i < this->GetNumberOfOutputPorts(); ++i)
  {
    vtkInformation* info = out->GetInformationObject(i);
    if (!vtkSegmentationSVDAG::GetData(info))
    {
      vtkSegmentationSVDAG* output = vtkSegmentationSVDAG::New();
      info->Set(vtkDataObject::DATA_OBJECT(), output);
      output->Delete();
    }
  }
  return 1;
}

int vtkSegmentationSVDAGAlgorithm::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector*)
{
  return 1;
}

int vtkSegmentationSVDAGAlgorithm::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector**, vtkInformationVector*)
{
  return 1;
}

int vtkSegmentationSVDAGAlgorithm::RequestData(
  vtkInformation*, vtkInformationVector**, vtkInformationVector*)
{
  return 1;
}

int vtkSegmentationSVDAGAlgorithm::FillOutputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkSegmentationSVDAG");
  return 1;
}

int vtkSegmentationSVDAGAlgorithm::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkDataObject");
  return 1;
}

void vtkSegmentationSVDAGAlgorithm::AddExcludedLabel(vtkTypeInt64 label)
{
  this->ExcludedLabels.push_back(label);
  this->Modified();
}

void vtkSegmentationSVDAGAlgorithm::RemoveAllExcludedLabels()
{
  if (!this->ExcludedLabels.empty())
  {
    this->ExcludedLabels.clear();
    this->Modified();
  }
}

vtkIdType vtkSegmentationSVDAGAlgorithm::GetNumberOfExcludedLabels() const
{
  return static_cast<vtkIdType>(this->ExcludedLabels.size());
}

vtkTypeInt64 vtkSegmentationSVDAGAlgorithm::GetExcludedLabel(vtkIdType i) const
{
  return (i >= 0 && i < this->GetNumberOfExcludedLabels()) ? this->ExcludedLabels[size_t(i)] : 0;
}

bool vtkSegmentationSVDAGAlgorithm::GetRequestedPiece(
  vtkInformation* outInfo, int depth, int& piece, int& pieces, int& z0, int& z1)
{
  pieces = outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES())
    ? outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES())
    : 1;
  piece = outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER())
    ? outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER())
    : 0;
  if (pieces < 1 || piece < 0 || piece >= pieces)
    return false;
  const auto range = svdag::Builder::pieceZRange(std::max(0, depth), piece, pieces);
  z0 = range[0];
  z1 = range[1];
  return true;
}

svdag::BuildOptions vtkSegmentationSVDAGAlgorithm::GetBuildOptions() const
{
  svdag::BuildOptions options;
  options.background = static_cast<uint64_t>(this->BackgroundLabel);
  for (vtkTypeInt64 label : this->ExcludedLabels)
    options.excluded.push_back(static_cast<uint64_t>(label));
  return options;
}

void vtkSegmentationSVDAGAlgorithm::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "BackgroundLabel: " << this->BackgroundLabel << "\n";
  os << indent << "ExcludedLabels:";
  for (vtkTypeInt64 label : this->ExcludedLabels)
    os << " " << label;
  os << "\n";
}
