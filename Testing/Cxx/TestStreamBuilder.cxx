// vtkSegmentationSVDAGStreamBuilder against the one-shot vtkImageDataToSegmentationSVDAG filter:
// the same svdag::Volume (operator==: label table, streams, widths, geometry) for every way of
// cutting the volume into slabs, and errors that return false without changing the builder.
#include "vtkCallbackCommand.h"
#include "vtkCommand.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkImageDataToSegmentationSVDAG.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkSegmentationSVDAGStreamBuilder.h"
#include "vtkShortArray.h"

#include "svdag/Volume.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace
{
constexpr int Dims[3] = { 37, 21, 45 };

std::vector<short> makeLabels()
{
  // Blobs of 6 voxels (several blocks per cell, shared nodes) with negative labels and noise.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> label(-3, 4), noise(0, 9);
  std::vector<short> coarse(8 * 8 * 8);
  for (auto& v : coarse)
    v = short(label(rng));
  std::vector<short> labels(size_t(Dims[0]) * Dims[1] * Dims[2]);
  size_t i = 0;
  for (int z = 0; z < Dims[2]; ++z)
    for (int y = 0; y < Dims[1]; ++y)
      for (int x = 0; x < Dims[0]; ++x, ++i)
        labels[i] = noise(rng) == 0 ? short(label(rng))
                                    : coarse[(x / 6) + 8 * ((y / 6) + 8 * (z / 6))];
  return labels;
}

vtkNew<vtkShortArray> slices(const std::vector<short>& labels, int z0, int nz)
{
  vtkNew<vtkShortArray> array;
  const size_t slice = size_t(Dims[0]) * Dims[1];
  array->SetNumberOfTuples(vtkIdType(slice * nz));
  std::copy(labels.begin() + long(slice * z0), labels.begin() + long(slice * (z0 + nz)),
    array->GetPointer(0));
  return array;
}

struct ErrorCounter
{
  int count = 0;
  vtkNew<vtkCallbackCommand> callback;
  explicit ErrorCounter(vtkObject* object)
  {
    callback->SetClientData(this);
    callback->SetCallback([](vtkObject*, unsigned long, void* self, void*) {
      ++static_cast<ErrorCounter*>(self)->count;
    });
    object->AddObserver(vtkCommand::ErrorEvent, callback);
  }
};

const double Spacing[3] = { 0.5, 1.0, 2.5 };
const double Origin[3] = { -3.0, 4.0, 9.0 };
const double Direction[9] = { 0, -1, 0, 1, 0, 0, 0, 0, 1 };
} // namespace

TEST(StreamBuilder, SameVolumeAsTheFilterForEverySlabSize)
{
  const std::vector<short> labels = makeLabels();
  vtkNew<vtkImageData> image;
  image->SetDimensions(Dims);
  image->SetSpacing(Spacing);
  image->SetOrigin(Origin);
  image->SetDirectionMatrix(Direction);
  image->GetPointData()->SetScalars(slices(labels, 0, Dims[2]));
  vtkNew<vtkImageDataToSegmentationSVDAG> filter;
  filter->SetInputData(image);
  filter->SetBackgroundLabel(-3);
  filter->AddExcludedLabel(4);
  filter->Update();
  const auto& expected = *filter->GetOutput()->GetVolume();
  ASSERT_GT(expected.labels.size(), 3u);

  for (int step : { 1, 7, 16, 33, Dims[2] })
  {
    vtkNew<vtkSegmentationSVDAGStreamBuilder> builder;
    builder->SetBackgroundLabel(-3);
    builder->AddExcludedLabel(4);
    ASSERT_TRUE(builder->Initialize(Dims, VTK_SHORT, Spacing, Origin, Direction));
    for (int z0 = 0; z0 < Dims[2]; z0 += step)
    {
      const int nz = std::min(step, Dims[2] - z0);
      ASSERT_TRUE(builder->AddSlab(slices(labels, z0, nz), z0, nz));
      EXPECT_EQ(builder->GetNextSlice(), z0 + nz);
    }
    vtkNew<vtkSegmentationSVDAG> output;
    ASSERT_TRUE(builder->Finish(output));
    EXPECT_TRUE(*output->GetVolume() == expected) << "slabs of " << step;
    EXPECT_NO_THROW(output->GetVolume()->validate());
  }
}

TEST(StreamBuilder, ErrorsReturnFalseAndChangeNothing)
{
  const std::vector<short> labels = makeLabels();
  vtkNew<vtkSegmentationSVDAGStreamBuilder> builder;
  ErrorCounter errors(builder);
  vtkNew<vtkSegmentationSVDAG> output;
  const int absurd[3] = { 2147483647, 2147483647, 2147483647 };
  EXPECT_FALSE(builder->Initialize(absurd, VTK_SHORT));
  EXPECT_FALSE(builder->Initialize(Dims, VTK_FLOAT));
  EXPECT_FALSE(builder->AddSlab(slices(labels, 0, 1)));
  EXPECT_FALSE(builder->Finish(output));
  EXPECT_EQ(errors.count, 4);

  ASSERT_TRUE(builder->Initialize(Dims, VTK_SHORT));
  vtkNew<vtkFloatArray> floats;
  floats->SetNumberOfTuples(vtkIdType(Dims[0]) * Dims[1]);
  EXPECT_FALSE(builder->AddSlab(floats));
  EXPECT_FALSE(builder->AddSlab(slices(labels, 0, 2), 1));      // out of order
  EXPECT_FALSE(builder->AddSlab(slices(labels, 0, 2), 0, 3));   // size mismatch
  EXPECT_FALSE(builder->AddSlab(nullptr));
  ASSERT_TRUE(builder->AddSlab(slices(labels, 0, 40)));
  EXPECT_FALSE(builder->AddSlab(slices(labels, 39, 6)));        // 6 slices, 5 missing
  EXPECT_FALSE(builder->Finish(output));                        // 5 slices missing
  EXPECT_FALSE(output->HasVolume());
  EXPECT_EQ(builder->GetNextSlice(), 40);
  EXPECT_EQ(errors.count, 10);
  ASSERT_TRUE(builder->AddSlab(slices(labels, 40, 5), 40));
  ASSERT_TRUE(builder->Finish(output));
  EXPECT_FALSE(builder->IsInitialized());
  EXPECT_FALSE(builder->AddSlab(slices(labels, 0, 1)));         // after Finish
  EXPECT_EQ(errors.count, 11);
}
