/**
 * @class   vtkPVSegmentationVolumeReader
 * @brief   reads a label volume file (vtkSegmentationVolumeReader) for ParaView
 *
 * vtkSegmentationVolumeReader with the output's label count, compressed bytes and bits per voxel as field data
 * arrays (LabelCount, CompressedBytes, BitsPerVoxel), which ParaView's Information panel lists:
 * vtkPVDataInformation gathers nothing else from a vtkSegmentationSVDAG.
 */
#ifndef vtkPVSegmentationVolumeReader_h
#define vtkPVSegmentationVolumeReader_h

#include "vtkSegmentationVolumeReader.h"
#include "vtkSVDAGParaViewModule.h" // for export macro

class VTKSVDAGPARAVIEW_EXPORT vtkPVSegmentationVolumeReader : public vtkSegmentationVolumeReader
{
public:
  static vtkPVSegmentationVolumeReader* New();
  vtkTypeMacro(vtkPVSegmentationVolumeReader, vtkSegmentationVolumeReader);

protected:
  vtkPVSegmentationVolumeReader() = default;
  ~vtkPVSegmentationVolumeReader() override = default;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

private:
  vtkPVSegmentationVolumeReader(const vtkPVSegmentationVolumeReader&) = delete;
  void operator=(const vtkPVSegmentationVolumeReader&) = delete;
};

#endif
