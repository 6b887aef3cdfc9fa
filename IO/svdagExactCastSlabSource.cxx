#include "svdagExactCastSlabSource.h"

#include "vtkErrorCode.h"

#include "svdag/Builder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace
{
// Powers of two are exact as doubles (2^63 - 1 is not: it rounds to 2^63).
constexpr double Two63 = 9223372036854775808.0;
constexpr double Two64 = 18446744073709551616.0;

// The first voxel, in C order of the [x, y, z] array, that breaks a rule.
struct Offender
{
  bool found = false;
  std::array<int32_t, 3> at{ { 0, 0, 0 } }; // (x, y, z)
  double value = 0;

  void offer(const std::array<int32_t, 3>& xyz, double v)
  {
    if (!this->found || xyz < this->at)
    {
      this->found = true;
      this->at = xyz;
      this->value = v;
    }
  }
  void offer(const Offender& other)
  {
    if (other.found)
      this->offer(other.at, other.value);
  }
};

// Pass 1's findings. The values outside an integer type are only offenders once the range is
// known (2^63 is a uint64 label unless a value is negative), so each bound has its own.
struct Scan
{
  double low = std::numeric_limits<double>::infinity();
  double high = -std::numeric_limits<double>::infinity();
  Offender notWhole;   // not finite or not a whole number
  Offender belowInt64; // below -2^63
  Offender fromInt64;  // from 2^63 on
  Offender fromUInt64; // from 2^64 on

  template <typename F>
  void add(const F* values, int32_t nx, int32_t ny, int32_t z0, int32_t nz)
  {
    const size_t slice = size_t(nx) * size_t(ny);
    const size_t count = slice * size_t(nz);
    // The index is worked out for offenders only.
    auto index = [&](size_t i) {
      return std::array<int32_t, 3>{ { int32_t(i % size_t(nx)), int32_t(i / size_t(nx) % size_t(ny)),
        z0 + int32_t(i / slice) } };
    };
    for (size_t i = 0; i < count; ++i)
    {
      const double v = double(values[i]); // float to double is exact
      if (!std::isfinite(v) || std::trunc(v) != v)
      {
        this->notWhole.offer(index(i), v);
        continue;
      }
      this->low = std::min(this->low, v);
      this->high = std::max(this->high, v);
      if (v < -Two63)
        this->belowInt64.offer(index(i), v);
      else if (v >= Two64)
        this->fromUInt64.offer(index(i), v);
      if (v >= Two63)
        this->fromInt64.offer(index(i), v);
    }
  }
};

// cast_labels' _smallest_integer_dtype for whole numbers in [low, high]; false if none holds
// them. The bounds compare as powers of two, exact as doubles.
bool narrowestType(double low, double high, svdag::ScalarType& type)
{
  static const svdag::ScalarType unsignedTypes[] = { svdag::ScalarType::UInt8,
    svdag::ScalarType::UInt16, svdag::ScalarType::UInt32, svdag::ScalarType::UInt64 };
  static const svdag::ScalarType signedTypes[] = { svdag::ScalarType::Int8,
    svdag::ScalarType::Int16, svdag::ScalarType::Int32, svdag::ScalarType::Int64 };
  for (int k = 0; k < 4; ++k)
  {
    const int bits = 8 << k;
    // -0.0 counts as 0: unsigned, as int(-0.0) is 0 for cast_labels.
    if (low >= 0 ? high < std::ldexp(1.0, bits)
                 : low >= -std::ldexp(1.0, bits - 1) && high < std::ldexp(1.0, bits - 1))
    {
      type = low >= 0 ? unsignedTypes[k] : signedTypes[k];
      return true;
    }
  }
  return false;
}

// Converts `count` values known to be whole and in [low, high] to labels of type I; false at
// the first one that is not (the file changed since pass 1).
template <typename I, typename F>
bool convert(const F* in, void* out, size_t count, double low, double high)
{
  I* labels = static_cast<I*>(out);
  for (size_t i = 0; i < count; ++i)
  {
    const double v = double(in[i]);
    if (!(v >= low && v <= high) || std::trunc(v) != v)
      return false;
    labels[i] = static_cast<I>(v);
  }
  return true;
}

template <typename F>
bool convertTo(svdag::ScalarType type, const F* in, void* out, size_t count, double low, double high)
{
  switch (type)
  {
    case svdag::ScalarType::Int8: return convert<int8_t>(in, out, count, low, high);
    case svdag::ScalarType::UInt8: return convert<uint8_t>(in, out, count, low, high);
    case svdag::ScalarType::Int16: return convert<int16_t>(in, out, count, low, high);
    case svdag::ScalarType::UInt16: return convert<uint16_t>(in, out, count, low, high);
    case svdag::ScalarType::Int32: return convert<int32_t>(in, out, count, low, high);
    case svdag::ScalarType::UInt32: return convert<uint32_t>(in, out, count, low, high);
    case svdag::ScalarType::Int64: return convert<int64_t>(in, out, count, low, high);
    case svdag::ScalarType::UInt64: return convert<uint64_t>(in, out, count, low, high);
  }
  return false;
}

const char* floatName(svdagSampleKind kind)
{
  return kind == svdagSampleKind::Float32 ? "float32" : "float64";
}
}

svdagExactCastSlabSource::svdagExactCastSlabSource(
  std::unique_ptr<svdagSlabSource> source, Opener reopen, const std::string& fileName)
  : Reopen(std::move(reopen))
  , FileName(fileName)
  , FormatName(source->formatName())
  , FloatKind(source->sampleKind())
{
  if (this->FloatKind == svdagSampleKind::Integer)
    throw svdagReadError(vtkErrorCode::UnknownError,
      fileName + ": svdagExactCastSlabSource needs a source of floats");
  this->Geometry = source->geometry();
  const int32_t nx = this->Geometry.dims[0], ny = this->Geometry.dims[1];
  const int32_t depth = this->Geometry.dims[2];

  // The reader refuses a slab larger than the machine's memory before allocating it; the float
  // slab of pass 1 is allocated here, before the reader sees the geometry.
  const uint64_t slabBytes = uint64_t(nx) * uint64_t(ny) *
    uint64_t(std::min(svdag::Builder::SlabDepth, depth)) * uint64_t(source->sampleSize());
  const uint64_t memory = svdagPhysicalMemoryBytes();
  if (memory > 0 && slabBytes > memory)
    throw svdagReadError(vtkErrorCode::OutOfDiskSpaceError,
      fileName + ": one slab of 16 z-slices takes " + std::to_string(slabBytes) +
        " bytes, more than this machine's memory");

  // Pass 1, slab by slab as the reader reads, in the order the source needs.
  Scan scan;
  for (int32_t z0 = 0; z0 < depth; z0 += svdag::Builder::SlabDepth)
  {
    const int32_t nz = std::min(svdag::Builder::SlabDepth, depth - z0);
    this->Floats.resize(size_t(nx) * size_t(ny) * size_t(nz) * size_t(source->sampleSize()));
    source->readSlab(z0, nz, this->Floats.data());
    if (this->FloatKind == svdagSampleKind::Float32)
      scan.add(reinterpret_cast<const float*>(this->Floats.data()), nx, ny, z0, nz);
    else
      scan.add(reinterpret_cast<const double*>(this->Floats.data()), nx, ny, z0, nz);
  }
  // The remarks of the file are those of its first reading; pass 2 would repeat them.
  this->Warnings = source->warnings();
  source.reset(); // its file (or reader process) is not needed until pass 2
  this->Floats.clear();
  this->Floats.shrink_to_fit();

  // cast_labels' order of checks: values that are no whole number first; then the range.
  Offender refused = scan.notWhole;
  std::string reason = !refused.found ? ""
    : std::isfinite(refused.value)     ? "not a whole number"
                                       : "not finite";
  if (!refused.found && !narrowestType(scan.low, scan.high, this->Type))
  {
    if (scan.low < 0)
    {
      refused.offer(scan.belowInt64);
      refused.offer(scan.fromInt64);
    }
    else
      refused.offer(scan.fromUInt64);
    reason = "outside every integer type (with the other values)";
  }
  if (refused.found)
    throw svdagReadError(vtkErrorCode::FileFormatError,
      fileName + ": the label volume (" + floatName(this->FloatKind) + ") holds " +
        svdagFloatRepr(refused.value, this->FloatKind == svdagSampleKind::Float32) + " at index (" +
        std::to_string(refused.at[0]) + ", " + std::to_string(refused.at[1]) + ", " +
        std::to_string(refused.at[2]) + "), " + reason + "; " + RefusalEnding);
  this->Low = scan.low;
  this->High = scan.high;
  this->Kind = svdagSampleKind::Integer;
}

svdagExactCastSlabSource::~svdagExactCastSlabSource() = default;

void svdagExactCastSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  if (!this->Inner)
  {
    this->Inner = this->Reopen();
    if (!(this->Inner->geometry() == this->Geometry) || this->Inner->sampleKind() != this->FloatKind)
      throw svdagReadError(vtkErrorCode::FileFormatError,
        this->FileName + " changed while it was read (its header differs from the first reading)");
  }
  const size_t count =
    size_t(this->Geometry.dims[0]) * size_t(this->Geometry.dims[1]) * size_t(nz);
  this->Floats.resize(count * size_t(this->Inner->sampleSize()));
  this->Inner->readSlab(z0, nz, this->Floats.data());
  const bool converted = this->FloatKind == svdagSampleKind::Float32
    ? convertTo(this->Type, reinterpret_cast<const float*>(this->Floats.data()), dst, count,
        this->Low, this->High)
    : convertTo(this->Type, reinterpret_cast<const double*>(this->Floats.data()), dst, count,
        this->Low, this->High);
  if (!converted)
    throw svdagReadError(vtkErrorCode::FileFormatError,
      this->FileName + " changed while it was read: z-slices " + std::to_string(z0) + ".." +
        std::to_string(z0 + nz - 1) + " hold values the first reading did not find");
}
