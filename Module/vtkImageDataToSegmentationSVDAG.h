/**
 * @class   vtkImageDataToSegmentationSVDAG
 * @brief   compresses an integer label image into a vtkSegmentationSVDAG, losslessly
 *
 * The input's point scalars (or the array chosen with SetInputArrayToProcess) must have one
 * integer component of any width, signed or unsigned. The volume is processed in slabs of 16
 * z-slices; cells of a slab are scanned in parallel with vtkSMPTools, and the result does not
 * depend on the number of threads. Voxels equal to BackgroundLabel, or to an excluded label,
 * are not stored and decode as background (see vtkSegmentationSVDAGAlgorithm).
 *
 * Piece requests (UPDATE_PIECE_NUMBER of UPDATE_NUMBER_OF_PIECES, ParaView's MPI ranks): the
 * output is the piece's z-range of whole 16-slice slabs of the input's whole extent
 * (svdag::Builder::pieceZRange), compressed alone, and only that range is requested upstream
 * (an input that brings more is cut to it). A piece beyond the slab count is empty.
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
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

private:
  vtkImageDataToSegmentationSVDAG(const vtkImageDataToSegmentationSVDAG&) = delete;
  void operator=(const vtkImageDataToSegmentationSVDAG&) = delete;
};

#endif
