/**
 * @class   vtkSegmentationSVDAGToImageData
 * @brief   decodes a vtkSegmentationSVDAG losslessly back into a label image
 *
 * The output has the original dimensions, spacing, origin, direction and scalar type; its point
 * scalars are named "Labels". Voxels of no block hold the background label.
 */
#ifndef vtkSegmentationSVDAGToImageData_h
#define vtkSegmentationSVDAGToImageData_h

#include "vtkImageAlgorithm.h"
#include "vtkSVDAGCoreModule.h" // for export macro

class VTKSVDAGCORE_EXPORT vtkSegmentationSVDAGToImageData : public vtkImageAlgorithm
{
public:
  static vtkSegmentationSVDAGToImageData* New();
  vtkTypeMacro(vtkSegmentationSVDAGToImageData, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

protected:
  vtkSegmentationSVDAGToImageData();
  ~vtkSegmentationSVDAGToImageData() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

private:
  vtkSegmentationSVDAGToImageData(const vtkSegmentationSVDAGToImageData&) = delete;
  void operator=(const vtkSegmentationSVDAGToImageData&) = delete;
};

#endif
