#include "vtkPVSegmentationVolumeReader.h"

#include "svdagInformationArrays.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkSegmentationSVDAG.h"

vtkStandardNewMacro(vtkPVSegmentationVolumeReader);

int vtkPVSegmentationVolumeReader::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  if (!this->Superclass::RequestData(request, inputVector, outputVector))
  {
    return 0;
  }
  svdag::paraview::AddInformationArrays(vtkSegmentationSVDAG::GetData(outputVector));
  return 1;
}
