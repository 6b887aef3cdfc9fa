// svdagExactCastSlabSource (vtkSegmentationVolumeReader::CastFloatLabels) on in-memory float
// sources, and svdagFloatRepr, which writes the values its messages name. The file formats are
// tested from Python (Testing/Python/test_cast_files.py), with files other libraries wrote.
#include "svdagExactCastSlabSource.h"

#include "vtkErrorCode.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace
{
// A float volume in memory that, like the sources of compressed streams, serves slabs only in
// increasing z without gaps, once.
template <typename F>
class MemorySource : public svdagSlabSource
{
public:
  MemorySource(const std::array<int32_t, 3>& dims, const std::vector<F>& values)
    : Values(values)
  {
    this->Geometry.dims = dims;
    this->Kind = sizeof(F) == 4 ? svdagSampleKind::Float32 : svdagSampleKind::Float64;
  }
  const char* formatName() const override { return "memory"; }
  void readSlab(int32_t z0, int32_t nz, void* dst) override
  {
    this->checkSlab(z0, nz);
    if (z0 != this->Next)
      throw svdagReadError(vtkErrorCode::FileFormatError, "slabs out of order");
    this->Next = z0 + nz;
    const size_t slice = size_t(this->Geometry.dims[0]) * size_t(this->Geometry.dims[1]);
    std::copy_n(this->Values.data() + slice * size_t(z0), slice * size_t(nz), static_cast<F*>(dst));
  }

private:
  std::vector<F> Values;
  int32_t Next = 0;
};

// x, y, z: the index of a value in an x-fastest buffer.
size_t at(const std::array<int32_t, 3>& dims, int x, int y, int z)
{
  return (size_t(z) * size_t(dims[1]) + size_t(y)) * size_t(dims[0]) + size_t(x);
}

// The cast source of `values`, counting how often the file is (re)opened in `opens`.
template <typename F>
std::unique_ptr<svdagSlabSource> cast(
  const std::array<int32_t, 3>& dims, const std::vector<F>& values, int* opens = nullptr)
{
  auto reopen = [=] {
    if (opens)
      ++*opens;
    return std::unique_ptr<svdagSlabSource>(new MemorySource<F>(dims, values));
  };
  return std::unique_ptr<svdagSlabSource>(
    new svdagExactCastSlabSource(reopen(), reopen, "volume.test"));
}

// The labels of a cast source, read in slabs of 16 z-slices as the reader reads them.
std::vector<uint64_t> labels(svdagSlabSource& source)
{
  const auto& dims = source.geometry().dims;
  const size_t slice = size_t(dims[0]) * size_t(dims[1]);
  const int size = source.sampleSize();
  std::vector<uint8_t> slab(slice * 16 * size_t(size));
  std::vector<uint64_t> out;
  for (int32_t z0 = 0; z0 < dims[2]; z0 += 16)
  {
    const int32_t nz = std::min(16, dims[2] - z0);
    source.readSlab(z0, nz, slab.data());
    for (size_t i = 0; i < slice * size_t(nz); ++i)
      out.push_back(svdag::scalarLoad(source.scalarType(), slab.data(), i));
  }
  return out;
}

std::string refusal(const std::array<int32_t, 3>& dims, const std::vector<double>& values)
{
  try
  {
    cast(dims, values);
  }
  catch (const svdagReadError& e)
  {
    EXPECT_EQ(e.code(), vtkErrorCode::FileFormatError);
    return e.what();
  }
  return "";
}

const std::array<int32_t, 3> Dims = { { 13, 7, 37 } }; // odd sizes, three slabs
}

TEST(ExactCast, NarrowestTypeAndExactValues)
{
  struct Case
  {
    std::vector<double> values;
    svdag::ScalarType type;
  };
  const double two63 = std::ldexp(1.0, 63);
  const Case cases[] = {
    { { 0, 200, 7 }, svdag::ScalarType::UInt8 },
    { { -0.0, 255 }, svdag::ScalarType::UInt8 }, // -0.0 is 0
    { { -1, 127 }, svdag::ScalarType::Int8 },
    { { -129, 0 }, svdag::ScalarType::Int16 },
    { { 0, 65536 }, svdag::ScalarType::UInt32 },
    { { -70000, 3 }, svdag::ScalarType::Int32 },
    { { 0, two63 }, svdag::ScalarType::UInt64 },
    { { -two63, 1 }, svdag::ScalarType::Int64 },
  };
  for (const Case& c : cases)
  {
    std::vector<double> values(size_t(Dims[0]) * Dims[1] * Dims[2]);
    for (size_t i = 0; i < values.size(); ++i)
      values[i] = c.values[i % c.values.size()];
    int opens = 0;
    const auto source = cast(Dims, values, &opens);
    EXPECT_EQ(source->scalarType(), c.type) << c.values[1];
    EXPECT_EQ(source->sampleKind(), svdagSampleKind::Integer);
    EXPECT_EQ(opens, 1); // pass 1 only, so far
    const std::vector<uint64_t> got = labels(*source);
    EXPECT_EQ(opens, 2); // pass 2 reopened the file once
    ASSERT_EQ(got.size(), values.size());
    for (size_t i = 0; i < values.size(); ++i)
    {
      const double back = svdag::scalarSigned(c.type) ? double(int64_t(got[i])) : double(got[i]);
      ASSERT_EQ(back, values[i]) << i;
    }
  }
  // float32 values are cast the same way.
  const std::vector<float> singles(size_t(Dims[0]) * Dims[1] * Dims[2], 300.0f);
  EXPECT_EQ(cast(Dims, singles)->scalarType(), svdag::ScalarType::UInt16);
}

TEST(ExactCast, RefusalsNameTheFirstValueInXyzOrder)
{
  std::vector<double> values(size_t(Dims[0]) * Dims[1] * Dims[2], 1.0);
  // (12, 6, 0) comes first in the buffer (z slowest); (11, 4, 36), in the last slab, comes
  // first in C order of the [x, y, z] array: it is the one named, as cast_labels names it.
  values[at(Dims, 12, 6, 0)] = 0.25;
  values[at(Dims, 11, 4, 36)] = 0.5;
  EXPECT_EQ(refusal(Dims, values),
    "volume.test: the label volume (float64) holds 0.5 at index (11, 4, 36), not a whole number; "
    "only whole numbers that an integer type holds are accepted");
  values[at(Dims, 11, 4, 36)] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(refusal(Dims, values).find("holds nan at index (11, 4, 36), not finite"), std::string::npos);
  // Beyond every integer type: 2^64; and 2^63 once a value is negative.
  std::vector<double> big(values.size(), 0.0);
  big[at(Dims, 3, 2, 20)] = std::ldexp(1.0, 64);
  EXPECT_NE(refusal(Dims, big).find("holds 1.8446744073709552e+19 at index (3, 2, 20), outside "
                                    "every integer type (with the other values)"),
    std::string::npos);
  big[at(Dims, 3, 2, 20)] = std::ldexp(1.0, 63);
  EXPECT_EQ(cast(Dims, big)->scalarType(), svdag::ScalarType::UInt64);
  big[at(Dims, 0, 0, 30)] = -1;
  EXPECT_NE(refusal(Dims, big).find("holds 9.223372036854776e+18 at index (3, 2, 20), outside"),
    std::string::npos);
}

TEST(ExactCast, FloatReprIsPythons)
{
  EXPECT_EQ(svdagFloatRepr(0.5, false), "0.5");
  EXPECT_EQ(svdagFloatRepr(70000, false), "70000.0");
  EXPECT_EQ(svdagFloatRepr(-0.0, false), "-0.0");
  EXPECT_EQ(svdagFloatRepr(123.456, false), "123.456");
  EXPECT_EQ(svdagFloatRepr(0.0001, false), "0.0001");
  EXPECT_EQ(svdagFloatRepr(0.00001, false), "1e-05");
  EXPECT_EQ(svdagFloatRepr(1e16, false), "1e+16");
  EXPECT_EQ(svdagFloatRepr(9999999999999998.0, false), "9999999999999998.0");
  EXPECT_EQ(svdagFloatRepr(std::ldexp(1.0, 64), false), "1.8446744073709552e+19");
  EXPECT_EQ(svdagFloatRepr(std::ldexp(1.0, 64), true), "1.8446744e+19"); // numpy's float32
  EXPECT_EQ(svdagFloatRepr(0.1f, true), "0.1");
  EXPECT_EQ(svdagFloatRepr(std::numeric_limits<double>::quiet_NaN(), false), "nan");
  EXPECT_EQ(svdagFloatRepr(-std::numeric_limits<double>::infinity(), true), "-inf");
}
