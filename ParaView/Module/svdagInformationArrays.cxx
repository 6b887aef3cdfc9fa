#include "svdagInformationArrays.h"

#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkNew.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkTypeInt64Array.h"

namespace
{
template <class ArrayT, class T>
void SetOneValue(vtkFieldData* fields, const char* name, T value)
{
  vtkNew<ArrayT> array;
  array->SetName(name);
  array->InsertNextValue(value);
  fields->AddArray(array); // replaces an array of the same name
}
}

void svdag::paraview::AddInformationArrays(vtkSegmentationSVDAG* volume)
{
  if (!volume || !volume->HasVolume())
  {
    return; // an empty piece (more ranks than slabs) adds nothing to the ranks' ranges
  }
  vtkFieldData* fields = volume->GetFieldData();
  const vtkTypeInt64 voxels = volume->GetNumberOfVoxels();
  const vtkTypeInt64 bytes = volume->GetCompressedSize();
  SetOneValue<vtkTypeInt64Array>(fields, "LabelCount", vtkTypeInt64(volume->GetNumberOfLabels()));
  SetOneValue<vtkTypeInt64Array>(fields, "CompressedBytes", bytes);
  SetOneValue<vtkDoubleArray>(
    fields, "BitsPerVoxel", voxels > 0 ? 8.0 * double(bytes) / double(voxels) : 0.0);
  int dims[3];
  volume->GetDimensions(dims);
  vtkNew<vtkTypeInt64Array> dimensions;
  dimensions->SetName("Dimensions");
  dimensions->SetNumberOfComponents(3);
  dimensions->InsertNextTuple3(dims[0], dims[1], dims[2]);
  fields->AddArray(dimensions);
}
