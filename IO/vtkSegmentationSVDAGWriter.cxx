#include "vtkSegmentationSVDAGWriter.h"
#include "vtkObjectFactory.h"
vtkStandardNewMacro(vtkSegmentationSVDAGWriter);
