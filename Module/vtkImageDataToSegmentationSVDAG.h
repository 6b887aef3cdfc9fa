/**
 * @class   vtkImageDataToSegmentationSVDAG
 * @brief   compresses an integer label image into a vtkSegmentationSVDAG, losslessly
 *
 * The input's point scalars (or the array chosen with SetInputArrayToProcess) must have one
 * integer component of any width, signed or unsigned. The volume is processed in slabs of 16
 * z-slices; cells of a slab are scanned in parallel with vtkSMPTools, and the result does not
 * depend on the number of threads. Voxels equal to BackgroundLabel, or to an excluded label,
 * are not stored and decode as background (see vtkSegmentationSVDAGAlgorithm).
 */
#ifndef vtkImageDataToSegmentationSVDAG_h
#define vtkImageDataToSegmentationSVDAG_h

#include "vtkSVDAGCoreModule.h" // for export macro
#include "vtkSegmentationSVDAGAlgorithm.h"

class VTKSVDAGCORE_EXPORT vtkImageDataToSegmentationSVDAG : public vtkSegmentationSVDAGAlgorithm
{
public:
  static vtkImageDataToSegmentationSVDAG* New();
  vtkTypeMacro(vtkImageDataToSegmentationSVDAG, vtkSegmentationSVDAGAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /** Sets the label image to compress (for a pipeline connection use SetInputConnection). */
  void SetInputData(vtkDataObject* image) { this->SetInputDataObject(0, image); }


protected:
  vtkImageDataToSegmentationSVDAG();
  ~vtkImageDataToSegmentationSVDAG() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

private:
  vtkImageDataToSegmentationSVDAG(const vtkImageDataToSegmentationSVDAG&) = delete;
  void operator=(const vtkImageDataToSegmentationSVDAG&) = delete;
};

#endif
