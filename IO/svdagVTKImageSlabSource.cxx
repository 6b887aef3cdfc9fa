#include "svdagVTKImageSlabSource.h"

#include "vtkAlgorithm.h"
#include "vtkCallbackCommand.h"
#include "vtkDataArray.h"
#include "vtkDataCompressor.h"
#include "vtkDataObject.h"
#include "vtkDataSetAttributes.h"
#include "vtkErrorCode.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkPointData.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkXMLDataParser.h"
#include "vtkXMLReader.h"

#include <algorithm>
#include <cstring>
#include <utility>
#include <vector>

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

struct svdagVTKImageSlabSource::Impl
{
  vtkSmartPointer<vtkAlgorithm> reader;
  std::string fileName;
  vtkSmartPointer<vtkCallbackCommand> errorObserver;
  std::string errorText;
  int wholeExtent[6] = { 0, -1, 0, -1, 0, -1 };
  int vtkScalarType = 0;

  // Throws the error the wrapped reader reported since the last call, if any.
  void throwReaderError(const char* during);

  // The VTK objects that report a read's failures: the reader, its executive and, for VTK's XML
  // readers, the XML parser and the compressor the reader gives it while reading the header.
  // vtkErrorMacro prints only when nothing observes the ErrorEvent: observed, the first error
  // is folded into the project's message instead of printed before it.
  std::vector<vtkObject*> reporters() const;
  // Observes the reporters not observed yet (the parser and compressor exist only once the
  // reader has read the header, and a new header read replaces them).
  void observeReporters();
};

std::vector<vtkObject*> svdagVTKImageSlabSource::Impl::reporters() const
{
  std::vector<vtkObject*> objects{ this->reader, this->reader->GetExecutive() };
  vtkXMLReader* xml = vtkXMLReader::SafeDownCast(this->reader);
  vtkXMLDataParser* parser = xml ? xml->GetXMLParser() : nullptr;
  if (parser)
  {
    objects.push_back(parser);
    if (parser->GetCompressor())
      objects.push_back(parser->GetCompressor());
  }
  return objects;
}

void svdagVTKImageSlabSource::Impl::observeReporters()
{
  for (vtkObject* object : this->reporters())
  {
    if (!object->HasObserver(vtkCommand::ErrorEvent, this->errorObserver))
      object->AddObserver(vtkCommand::ErrorEvent, this->errorObserver);
  }
}

svdagVTKImageSlabSource::svdagVTKImageSlabSource(
  vtkSmartPointer<vtkAlgorithm> reader, const std::string& fileName)
  : impl(new Impl)
{
  impl->reader = std::move(reader);
  impl->fileName = fileName;
  impl->errorObserver = vtkSmartPointer<vtkCallbackCommand>::New();
  impl->errorObserver->SetCallback(storeErrorText);
  impl->errorObserver->SetClientData(&impl->errorText);
  // The reader and its executive, which reports the reader's failures on itself as errors too.
  impl->observeReporters();
  // The XML parser is created inside the header read, where its errors (malformed XML) arise:
  // the reader hands it this observer as it creates it.
  if (vtkXMLReader* xml = vtkXMLReader::SafeDownCast(impl->reader))
    xml->SetParserErrorObserver(impl->errorObserver);
}

svdagVTKImageSlabSource::~svdagVTKImageSlabSource()
{
  // The observer's client data dies with impl: nothing may call it afterwards.
  if (vtkXMLReader* xml = vtkXMLReader::SafeDownCast(impl->reader))
    xml->SetParserErrorObserver(nullptr);
  for (vtkObject* object : impl->reporters())
    object->RemoveObserver(impl->errorObserver);
}

void svdagVTKImageSlabSource::Impl::throwReaderError(const char* during)
{
  const unsigned long code = this->reader->GetErrorCode();
  if (this->errorText.empty() && code == vtkErrorCode::NoError)
    return;
  std::string message = this->fileName + ": " + during;
  if (!this->errorText.empty())
    message += ": " + messageOf(this->errorText);
  else
    message += std::string(": ") + vtkErrorCode::GetStringFromErrorCode(code);
  this->errorText.clear();
  throw svdagReadError(code != vtkErrorCode::NoError ? code : vtkErrorCode::FileFormatError,
    message);
}

void svdagVTKImageSlabSource::open(bool allowFloat)
{
  impl->reader->UpdateInformation();
  impl->observeReporters();
  impl->throwReaderError("cannot read the header");
  vtkInformation* info = impl->reader->GetOutputInformation(0);
  if (!info || !info->Has(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()))
    throw svdagReadError(vtkErrorCode::FileFormatError, impl->fileName + ": no image extent");
  info->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), impl->wholeExtent);
  for (int a = 0; a < 3; ++a)
  {
    // Extents are int: the difference of two extreme values would overflow.
    const long long n =
      (long long)impl->wholeExtent[2 * a + 1] - (long long)impl->wholeExtent[2 * a] + 1;
    if (n < 1 || n > INT32_MAX)
      throw svdagReadError(vtkErrorCode::FileFormatError,
        impl->fileName + ": empty or absurd image extent along axis " + std::to_string(a));
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
        this->Geometry.spacing[a] * impl->wholeExtent[2 * a];
  }

  vtkInformation* scalars = vtkDataObject::GetActiveFieldInformation(
    info, vtkDataObject::FIELD_ASSOCIATION_POINTS, vtkDataSetAttributes::SCALARS);
  if (!scalars || !scalars->Has(vtkDataObject::FIELD_ARRAY_TYPE()))
    throw svdagReadError(vtkErrorCode::FileFormatError,
      impl->fileName + ": the image has no point scalars");
  impl->vtkScalarType = scalars->Get(vtkDataObject::FIELD_ARRAY_TYPE());
  const int components = scalars->Has(vtkDataObject::FIELD_NUMBER_OF_COMPONENTS())
    ? scalars->Get(vtkDataObject::FIELD_NUMBER_OF_COMPONENTS())
    : 1;
  const int coreType = vtkSegmentationSVDAG::FromVTKScalarType(impl->vtkScalarType);
  const bool isFloat = impl->vtkScalarType == VTK_FLOAT || impl->vtkScalarType == VTK_DOUBLE;
  if (isFloat)
    this->setFloatSamples(allowFloat, impl->vtkScalarType == VTK_FLOAT ? 32 : 64, impl->fileName);
  else if (coreType < 0)
    svdagThrowNotIntegerLabels(impl->fileName, vtkImageScalarTypeNameMacro(impl->vtkScalarType));
  if (components != 1)
    throw svdagReadError(vtkErrorCode::FileFormatError,
      "label volumes need one component per voxel; " + impl->fileName + " has " +
        std::to_string(components));
  if (!isFloat)
    this->Type = static_cast<svdag::ScalarType>(coreType);
}

vtkAlgorithm* svdagVTKImageSlabSource::reader() const
{
  return impl->reader;
}

void svdagVTKImageSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  const int* whole = impl->wholeExtent;
  int update[6] = { whole[0], whole[1], whole[2], whole[3], whole[4] + z0, whole[4] + z0 + nz - 1 };
  impl->observeReporters();
  impl->reader->UpdateExtent(update);
  impl->throwReaderError("cannot read the voxels");

  vtkImageData* image = vtkImageData::SafeDownCast(impl->reader->GetOutputDataObject(0));
  vtkDataArray* array = image ? image->GetPointData()->GetScalars() : nullptr;
  int extent[6] = { 0, -1, 0, -1, 0, -1 };
  if (image)
    image->GetExtent(extent);
  const int sliceLow = update[4];
  const int sliceHigh = update[5];
  if (!array || array->GetDataType() != impl->vtkScalarType ||
    array->GetNumberOfComponents() != 1 || extent[0] != whole[0] || extent[1] != whole[1] ||
    extent[2] != whole[2] || extent[3] != whole[3] || extent[4] > sliceLow ||
    extent[5] < sliceHigh ||
    array->GetNumberOfTuples() != vtkIdType(extent[1] - extent[0] + 1) *
        vtkIdType(extent[3] - extent[2] + 1) * vtkIdType(extent[5] - extent[4] + 1))
    throw svdagReadError(vtkErrorCode::FileFormatError,
      impl->fileName + ": the reader did not deliver z-slices " + std::to_string(z0) + ".." +
        std::to_string(z0 + nz - 1) + " as its header describes them");

  const size_t sliceBytes = size_t(this->Geometry.dims[0]) * size_t(this->Geometry.dims[1]) *
    size_t(this->sampleSize());
  const auto* source = static_cast<const uint8_t*>(array->GetVoidPointer(0));
  auto* out = static_cast<uint8_t*>(dst);
  for (int32_t z = 0; z < nz; ++z)
  {
    const int slice = sliceLow + z - extent[4];
    std::memcpy(out + size_t(z) * sliceBytes, source + size_t(slice) * sliceBytes, sliceBytes);
  }
}
