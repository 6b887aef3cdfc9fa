/**
 * @class   vtkPVImageDataToSegmentationSVDAG
 * @brief   compresses an integer vtkImageData (vtkImageDataToSegmentationSVDAG) for ParaView
 *
 * vtkImageDataToSegmentationSVDAG with the output's label count, compressed bytes and bits per voxel as field data
 * arrays (LabelCount, CompressedBytes, BitsPerVoxel), which ParaView's Information panel lists:
 * vtkPVDataInformation gathers nothing else from a vtkSegmentationSVDAG.
 */
#ifndef vtkPVImageDataToSegmentationSVDAG_h
#define vtkPVImageDataToSegmentationSVDAG_h

#include "vtkImageDataToSegmentationSVDAG.h"
#include "vtkSVDAGParaViewModule.h" // for export macro

class VTKSVDAGPARAVIEW_EXPORT vtkPVImageDataToSegmentationSVDAG : public vtkImageDataToSegmentationSVDAG
{
public:
  static vtkPVImageDataToSegmentationSVDAG* New();
  vtkTypeMacro(vtkPVImageDataToSegmentationSVDAG, vtkImageDataToSegmentationSVDAG);

protected:
  vtkPVImageDataToSegmentationSVDAG() = default;
  ~vtkPVImageDataToSegmentationSVDAG() override = default;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

private:
  vtkPVImageDataToSegmentationSVDAG(const vtkPVImageDataToSegmentationSVDAG&) = delete;
  void operator=(const vtkPVImageDataToSegmentationSVDAG&) = delete;
};

#endif
