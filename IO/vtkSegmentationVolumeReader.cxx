#include "vtkSegmentationVolumeReader.h"
#include "vtkObjectFactory.h"
vtkStandardNewMacro(vtkSegmentationVolumeReader);
