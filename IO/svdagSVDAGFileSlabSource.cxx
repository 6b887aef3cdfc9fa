#include "svdagSVDAGFileSlabSource.h"

#include "vtkErrorCode.h"
#include "vtkSVDAGParallel.h"

#include "svdag/Decoder.h"
#include "svdag/File.h"

#include <cstring>

struct svdagSVDAGFileSlabSource::Impl
{
  std::shared_ptr<const svdag::Volume> volume;
};

svdagSVDAGFileSlabSource::svdagSVDAGFileSlabSource(const std::string& fileName)
  : impl(new Impl)
{
  try
  {
    impl->volume =
      std::make_shared<const svdag::Volume>(svdag::readFile(fileName, vtkSVDAGParallelFor()));
  }
  catch (const svdag::FileError& e)
  {
    throw svdagReadError(vtkErrorCode::FileFormatError, fileName + ": " + e.what());
  }
  this->Geometry = impl->volume->geometry;
  this->Type = impl->volume->scalarType;
  this->checkGeometry(fileName);
}

svdagSVDAGFileSlabSource::svdagSVDAGFileSlabSource(
  const uint8_t* data, size_t size, const std::string& name)
  : impl(new Impl)
{
  try
  {
    impl->volume =
      std::make_shared<const svdag::Volume>(svdag::deserialize(data, size, vtkSVDAGParallelFor()));
  }
  catch (const svdag::FileError& e)
  {
    throw svdagReadError(vtkErrorCode::FileFormatError, name + ": " + e.what());
  }
  this->Geometry = impl->volume->geometry;
  this->Type = impl->volume->scalarType;
  this->checkGeometry(name);
}

svdagSVDAGFileSlabSource::~svdagSVDAGFileSlabSource() = default;

std::shared_ptr<const svdag::Volume> svdagSVDAGFileSlabSource::compressedVolume() const
{
  return impl->volume;
}

void svdagSVDAGFileSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  svdag::decodeSlab(*impl->volume, z0, nz, dst);
}

bool svdagSVDAGFileSlabSource::hasSignature(const uint8_t* head, size_t size)
{
  return size >= svdag::FileMagicSize &&
    std::memcmp(head, svdag::FileMagic, svdag::FileMagicSize) == 0;
}
