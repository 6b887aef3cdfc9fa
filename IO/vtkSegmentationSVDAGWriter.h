// Placeholder: replaced by the real class (work in progress).
#ifndef vtkSegmentationSVDAGWriter_h
#define vtkSegmentationSVDAGWriter_h
#include "vtkObject.h"
#include "vtkSVDAGIOModule.h"
class VTKSVDAGIO_EXPORT vtkSegmentationSVDAGWriter : public vtkObject
{
public:
  static vtkSegmentationSVDAGWriter* New();
  vtkTypeMacro(vtkSegmentationSVDAGWriter, vtkObject);
protected:
  vtkSegmentationSVDAGWriter() = default;
  ~vtkSegmentationSVDAGWriter() override = default;
};
#endif
