// Placeholder: replaced by the real class (work in progress).
#ifndef vtkSegmentationVolumeReader_h
#define vtkSegmentationVolumeReader_h
#include "vtkObject.h"
#include "vtkSVDAGIOModule.h"
class VTKSVDAGIO_EXPORT vtkSegmentationVolumeReader : public vtkObject
{
public:
  static vtkSegmentationVolumeReader* New();
  vtkTypeMacro(vtkSegmentationVolumeReader, vtkObject);
protected:
  vtkSegmentationVolumeReader() = default;
  ~vtkSegmentationVolumeReader() override = default;
};
#endif
