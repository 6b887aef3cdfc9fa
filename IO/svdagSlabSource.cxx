#include "svdagSlabSource.h"

#include "vtkErrorCode.h"

#include "svdag/Volume.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
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

int svdagSlabSource::sampleSize() const
{
  switch (this->Kind)
  {
    case svdagSampleKind::Float32:
      return 4;
    case svdagSampleKind::Float64:
      return 8;
    case svdagSampleKind::Integer:
      break;
  }
  return svdag::scalarSize(this->Type);
}

void svdagSlabSource::setFloatSamples(bool allowFloat, int bits, const std::string& fileName)
{
  if (allowFloat && (bits == 32 || bits == 64))
  {
    this->Kind = bits == 32 ? svdagSampleKind::Float32 : svdagSampleKind::Float64;
    return;
  }
  svdagThrowNotIntegerLabels(fileName, "float" + std::to_string(bits));
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

std::string svdagFloatRepr(double value, bool single)
{
  if (std::isnan(value))
    return "nan";
  if (std::isinf(value))
    return value < 0 ? "-inf" : "inf";
  // The shortest round-trip digits, as d.ddde+X; then laid out by repr's rule.
  char text[64];
  const std::to_chars_result written = single
    ? std::to_chars(text, text + sizeof text, float(value), std::chars_format::scientific)
    : std::to_chars(text, text + sizeof text, value, std::chars_format::scientific);
  std::string s(text, written.ptr);
  std::string sign;
  if (s[0] == '-')
  {
    sign = "-";
    s.erase(0, 1);
  }
  const size_t e = s.find('e');
  const int exponent = std::stoi(s.substr(e + 1));
  std::string digits = s.substr(0, e);
  digits.erase(std::remove(digits.begin(), digits.end(), '.'), digits.end());
  const int n = int(digits.size());
  if (exponent < -4 || exponent >= 16)
  {
    const std::string power = std::to_string(std::abs(exponent));
    return sign + digits[0] + (n > 1 ? "." + digits.substr(1) : "") + "e" +
      (exponent < 0 ? "-" : "+") + (power.size() < 2 ? "0" : "") + power;
  }
  if (exponent < 0)
    return sign + "0." + std::string(size_t(-exponent - 1), '0') + digits;
  if (n <= exponent + 1)
    return sign + digits + std::string(size_t(exponent + 1 - n), '0') + ".0";
  return sign + digits.substr(0, size_t(exponent + 1)) + "." + digits.substr(size_t(exponent + 1));
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
