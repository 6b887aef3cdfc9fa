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
  if (!volume)
  {
    return;
  }
  vtkFieldData* fields = volume->GetFieldData();
  const vtkTypeInt64 voxels = volume->GetNumberOfVoxels();
  const vtkTypeInt64 bytes = volume->GetCompressedSize();
  SetOneValue<vtkTypeInt64Array>(fields, "LabelCount", vtkTypeInt64(volume->GetNumberOfLabels()));
  SetOneValue<vtkTypeInt64Array>(fields, "CompressedBytes", bytes);
  SetOneValue<vtkDoubleArray>(
    fields, "BitsPerVoxel", voxels > 0 ? 8.0 * double(bytes) / double(voxels) : 0.0);
}
