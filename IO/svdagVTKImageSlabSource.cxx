#include "svdagVTKImageSlabSource.h"

#include "vtkAlgorithm.h"
#include "vtkCallbackCommand.h"
#include "vtkDataArray.h"
#include "vtkDataObject.h"
#include "vtkDataSetAttributes.h"
#include "vtkErrorCode.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkPointData.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include <algorithm>
#include <cstring>
#include <utility>

namespace
{
void storeErrorText(vtkObject*, unsigned long, void* clientData, void* callData)
{
  auto* text = static_cast<std::string*>(clientData);
  if (text->empty() && callData)
    *text = static_cast<const char*>(callData);
}

// VTK's error text starts with "ERROR: In file, line N\nvtkClass (0x..): message": keep the
// message.
std::string messageOf(const std::string& text)
{
  const size_t colon = text.find("): ");
  std::string m = colon == std::string::npos ? text : text.substr(colon + 3);
  while (!m.empty() && (m.back() == '\n' || m.back() == ' '))
    m.pop_back();
  return m;
}
}

svdagVTKImageSlabSource::svdagVTKImageSlabSource(
  vtkSmartPointer<vtkAlgorithm> reader, const std::string& fileName)
  : Reader(std::move(reader))
  , FileName(fileName)
{
  this->ErrorObserver = vtkSmartPointer<vtkCallbackCommand>::New();
  this->ErrorObserver->SetCallback(storeErrorText);
  this->ErrorObserver->SetClientData(&this->ErrorText);
  this->Reader->AddObserver(vtkCommand::ErrorEvent, this->ErrorObserver);
  // The executive reports the reader's failures on itself, as errors too.
  this->Reader->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, this->ErrorObserver);
}

svdagVTKImageSlabSource::~svdagVTKImageSlabSource()
{
  this->Reader->GetExecutive()->RemoveObserver(this->ErrorObserver);
  this->Reader->RemoveObserver(this->ErrorObserver);
}

void svdagVTKImageSlabSource::throwReaderError(const char* during)
{
  const unsigned long code = this->Reader->GetErrorCode();
  if (this->ErrorText.empty() && code == vtkErrorCode::NoError)
    return;
  std::string message = this->FileName + ": " + during;
  if (!this->ErrorText.empty())
    message += ": " + messageOf(this->ErrorText);
  else
    message += std::string(": ") + vtkErrorCode::GetStringFromErrorCode(code);
  this->ErrorText.clear();
  throw svdagReadError(code != vtkErrorCode::NoError ? code : vtkErrorCode::FileFormatError,
    message);
}

void svdagVTKImageSlabSource::open()
{
  this->Reader->UpdateInformation();
  this->throwReaderError("cannot read the header");
  vtkInformation* info = this->Reader->GetOutputInformation(0);
  if (!info || !info->Has(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()))
    throw svdagReadError(vtkErrorCode::FileFormatError, this->FileName + ": no image extent");
  info->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), this->WholeExtent);
  for (int a = 0; a < 3; ++a)
  {
    // Extents are int: the difference of two extreme values would overflow.
    const long long n =
      (long long)this->WholeExtent[2 * a + 1] - (long long)this->WholeExtent[2 * a] + 1;
    if (n < 1 || n > INT32_MAX)
      throw svdagReadError(vtkErrorCode::FileFormatError,
        this->FileName + ": empty or absurd image extent along axis " + std::to_string(a));
    this->Geometry.dims[a] = static_cast<int32_t>(n);
  }
  if (info->Has(vtkDataObject::SPACING()))
    info->Get(vtkDataObject::SPACING(), this->Geometry.spacing.data());
  if (info->Has(vtkDataObject::ORIGIN()))
  {
    double origin[3];
    info->Get(vtkDataObject::ORIGIN(), origin);
    for (int a = 0; a < 3; ++a)
      this->Geometry.origin[a] = origin[a];
  }
  if (info->Has(vtkDataObject::DIRECTION()))
    info->Get(vtkDataObject::DIRECTION(), this->Geometry.direction.data());
  // The origin VTK reports is that of index 0; the volume starts at the extent's first voxel.
  for (int r = 0; r < 3; ++r)
  {
    for (int a = 0; a < 3; ++a)
      this->Geometry.origin[r] += this->Geometry.direction[3 * r + a] *
        this->Geometry.spacing[a] * this->WholeExtent[2 * a];
  }

  vtkInformation* scalars = vtkDataObject::GetActiveFieldInformation(
    info, vtkDataObject::FIELD_ASSOCIATION_POINTS, vtkDataSetAttributes::SCALARS);
  if (!scalars || !scalars->Has(vtkDataObject::FIELD_ARRAY_TYPE()))
    throw svdagReadError(vtkErrorCode::FileFormatError,
      this->FileName + ": the image has no point scalars");
  this->VTKScalarType = scalars->Get(vtkDataObject::FIELD_ARRAY_TYPE());
  const int components = scalars->Has(vtkDataObject::FIELD_NUMBER_OF_COMPONENTS())
    ? scalars->Get(vtkDataObject::FIELD_NUMBER_OF_COMPONENTS())
    : 1;
  const int coreType = vtkSegmentationSVDAG::FromVTKScalarType(this->VTKScalarType);
  if (coreType < 0)
    svdagThrowNotIntegerLabels(this->FileName, vtkImageScalarTypeNameMacro(this->VTKScalarType));
  if (components != 1)
    throw svdagReadError(vtkErrorCode::FileFormatError,
      "label volumes need one component per voxel; " + this->FileName + " has " +
        std::to_string(components));
  this->Type = static_cast<svdag::ScalarType>(coreType);
}

void svdagVTKImageSlabSource::readWhole()
{
  // The wrapped reader allocates the whole image: refuse what cannot fit in memory.
  const uint64_t bytes = this->Geometry.voxelCount() * uint64_t(svdag::scalarSize(this->Type));
  const uint64_t memory = svdagPhysicalMemoryBytes();
  if (memory > 0 && bytes > memory)
    throw svdagReadError(vtkErrorCode::OutOfDiskSpaceError,
      this->FileName + ": the image takes " + std::to_string(bytes) +
        " bytes, more than this machine's memory (it must be read whole)");
  this->WholeRead = true;
}

void svdagVTKImageSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  const int32_t first = this->readerSlice(z0);
  const int32_t last = this->readerSlice(z0 + nz - 1);
  const int* whole = this->WholeExtent;
  if (!this->WholeRead)
  {
    int extent[6] = { whole[0], whole[1], whole[2], whole[3],
      whole[4] + std::min(first, last), whole[4] + std::max(first, last) };
    this->Reader->UpdateExtent(extent);
  }
  else if (!this->WholeReadDone)
  {
    this->Reader->Update();
    this->WholeReadDone = true;
  }
  this->throwReaderError("cannot read the voxels");

  vtkImageData* image = vtkImageData::SafeDownCast(this->Reader->GetOutputDataObject(0));
  vtkDataArray* array = image ? image->GetPointData()->GetScalars() : nullptr;
  int extent[6] = { 0, -1, 0, -1, 0, -1 };
  if (image)
    image->GetExtent(extent);
  const int sliceLow = whole[4] + std::min(first, last);
  const int sliceHigh = whole[4] + std::max(first, last);
  if (!array || array->GetDataType() != this->VTKScalarType ||
    array->GetNumberOfComponents() != 1 || extent[0] != whole[0] || extent[1] != whole[1] ||
    extent[2] != whole[2] || extent[3] != whole[3] || extent[4] > sliceLow ||
    extent[5] < sliceHigh ||
    array->GetNumberOfTuples() != vtkIdType(extent[1] - extent[0] + 1) *
        vtkIdType(extent[3] - extent[2] + 1) * vtkIdType(extent[5] - extent[4] + 1))
    throw svdagReadError(vtkErrorCode::FileFormatError,
      this->FileName + ": the reader did not deliver z-slices " + std::to_string(z0) + ".." +
        std::to_string(z0 + nz - 1) + " as its header describes them");

  const size_t sliceBytes = size_t(this->Geometry.dims[0]) * size_t(this->Geometry.dims[1]) *
    size_t(svdag::scalarSize(this->Type));
  const auto* source = static_cast<const uint8_t*>(array->GetVoidPointer(0));
  auto* out = static_cast<uint8_t*>(dst);
  for (int32_t z = 0; z < nz; ++z)
  {
    const int slice = whole[4] + this->readerSlice(z0 + z) - extent[4];
    std::memcpy(out + size_t(z) * sliceBytes, source + size_t(slice) * sliceBytes, sliceBytes);
  }
}
