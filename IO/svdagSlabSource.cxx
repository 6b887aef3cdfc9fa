#include "svdagSlabSource.h"

#include "vtkErrorCode.h"

#include "svdag/Volume.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <unistd.h>

void svdagSlabSource::checkGeometry(const std::string& fileName) const
{
  // Before anything multiplies the dimensions: their product must not overflow, and a volume
  // of more than 2^40 voxels is not a label volume anyone can compress here.
  using Wide = unsigned __int128;
  Wide voxels = 1;
  for (int a = 0; a < 3; ++a)
    voxels *= Wide(std::max<int64_t>(this->Geometry.dims[a], 0));
  if (voxels > Wide(svdagMaxVoxels))
  {
    throw svdagReadError(vtkErrorCode::FileFormatError,
      fileName + ": volume too large: " + std::to_string(this->Geometry.dims[0]) + " x " +
        std::to_string(this->Geometry.dims[1]) + " x " + std::to_string(this->Geometry.dims[2]) +
        " voxels, more than 2^40");
  }
  const std::string problem = svdag::checkGeometry(this->Geometry);
  if (!problem.empty())
  {
    throw svdagReadError(vtkErrorCode::FileFormatError, fileName + ": " + problem);
  }
}

void svdagSlabSource::checkSlab(int32_t z0, int32_t nz) const
{
  if (z0 < 0 || nz < 1 || nz > this->Geometry.dims[2] - z0)
  {
    throw svdagReadError(vtkErrorCode::FileFormatError,
      "slab [" + std::to_string(z0) + ", +" + std::to_string(nz) + ") outside the volume");
  }
}

svdag::ScalarType svdagIntegerScalarType(bool isSigned, int bytes, const std::string& what)
{
  switch (bytes)
  {
    case 1:
      return isSigned ? svdag::ScalarType::Int8 : svdag::ScalarType::UInt8;
    case 2:
      return isSigned ? svdag::ScalarType::Int16 : svdag::ScalarType::UInt16;
    case 4:
      return isSigned ? svdag::ScalarType::Int32 : svdag::ScalarType::UInt32;
    case 8:
      return isSigned ? svdag::ScalarType::Int64 : svdag::ScalarType::UInt64;
    default:
      break;
  }
  throw svdagReadError(vtkErrorCode::FileFormatError,
    "label volumes need 8, 16, 32 or 64-bit integer scalars; " + what);
}

void svdagThrowNotIntegerLabels(const std::string& fileName, const std::string& type)
{
  // C type names in numpy's spelling, which says the width.
  const std::string name = type == "float" ? "float32" : type == "double" ? "float64" : type;
  throw svdagReadError(vtkErrorCode::FileFormatError,
    "label volumes need integer scalars; " + fileName + " has " + name);
}

void svdagSwapBytes(void* data, size_t count, int size)
{
  auto* bytes = static_cast<uint8_t*>(data);
  for (size_t i = 0; i < count; ++i, bytes += size)
  {
    std::reverse(bytes, bytes + size);
  }
}

uint64_t svdagPhysicalMemoryBytes()
{
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long pageSize = sysconf(_SC_PAGESIZE);
  return pages > 0 && pageSize > 0 ? uint64_t(pages) * uint64_t(pageSize) : 0;
}

bool svdagHostIsLittleEndian()
{
  const uint16_t one = 1;
  uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

std::string svdagTrim(const std::string& s)
{
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos)
    return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

std::string svdagLower(std::string s)
{
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}
