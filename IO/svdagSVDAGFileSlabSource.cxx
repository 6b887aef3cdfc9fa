#include "svdagSVDAGFileSlabSource.h"

#include "vtkErrorCode.h"

#include "svdag/Builder.h"
#include "svdag/File.h"

svdagSVDAGFileSlabSource::svdagSVDAGFileSlabSource(const std::string& fileName)
{
  try
  {
    this->Volume = std::make_shared<const svdag::Volume>(svdag::readFile(fileName));
  }
  catch (const svdag::FileError& e)
  {
    throw svdagReadError(vtkErrorCode::FileFormatError, fileName + ": " + e.what());
  }
  this->Geometry = this->Volume->geometry;
  this->Type = this->Volume->scalarType;
  this->checkGeometry(fileName);
}

void svdagSVDAGFileSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  svdag::decodeSlab(*this->Volume, z0, nz, dst);
}

bool svdagSVDAGFileSlabSource::hasMagic(const std::string& fileName)
{
  try
  {
    return svdag::isSVDAGFile(fileName);
  }
  catch (const std::exception&)
  {
    return false;
  }
}
