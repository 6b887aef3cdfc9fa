/**
 * @class   vtkSegmentationSVDAGAlgorithm
 * @brief   superclass for algorithms that produce a vtkSegmentationSVDAG
 *
 * VTK 9.1's executive cannot create data objects of types it does not know by name, so this
 * class creates the vtkSegmentationSVDAG output itself in RequestDataObject. Subclasses
 * implement RequestInformation and RequestData as usual. Input ports default to none; a filter
 * sets its own number of input ports and overrides FillInputPortInformation.
 *
 * It also holds what every compressing algorithm is asked: the background label and the labels
 * to leave out. Label values are 64-bit integers interpreted in the input's scalar type (for
 * example -1 means 255 for unsigned char input).
 */
#ifndef vtkSegmentationSVDAGAlgorithm_h
#define vtkSegmentationSVDAGAlgorithm_h

#include "vtkAlgorithm.h"
#include "vtkSVDAGCoreModule.h" // for export macro

#include <vector> // for std::vector

#ifndef __VTK_WRAP__
namespace svdag
{
struct BuildOptions;
}
#endif

class vtkSegmentationSVDAG;

class VTKSVDAGCORE_EXPORT vtkSegmentationSVDAGAlgorithm : public vtkAlgorithm
{
public:
  static vtkSegmentationSVDAGAlgorithm* New();
  vtkTypeMacro(vtkSegmentationSVDAGAlgorithm, vtkAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /** The output of port 0, after an update. */
  vtkSegmentationSVDAG* GetOutput();

  ///@{
  /** Label value not stored (default 0). */
  vtkSetMacro(BackgroundLabel, vtkTypeInt64);
  vtkGetMacro(BackgroundLabel, vtkTypeInt64);
  ///@}

  ///@{
  /** Labels left out of the compressed volume (they decode as background). */
  void AddExcludedLabel(vtkTypeInt64 label);
  void RemoveAllExcludedLabels();
  vtkIdType GetNumberOfExcludedLabels() const;
  vtkTypeInt64 GetExcludedLabel(vtkIdType i) const;
  ///@}

  vtkTypeBool ProcessRequest(
    vtkInformation* request, vtkInformationVector** in, vtkInformationVector* out) override;

#ifndef __VTK_WRAP__
  /**
   * The piece an output request asks for (UPDATE_PIECE_NUMBER of UPDATE_NUMBER_OF_PIECES; 0 of
   * 1 without them) and its z-slices [z0, z1) of a volume `depth` slices deep
   * (svdag::Builder::pieceZRange: whole slabs; z0 == z1 for a piece beyond the slab count).
   * False, with piece and pieces set, when the piece does not exist (z0, z1 untouched).
   */
  static bool GetRequestedPiece(
    vtkInformation* outInfo, int depth, int& piece, int& pieces, int& z0, int& z1);
#endif

protected:
  vtkSegmentationSVDAGAlgorithm();
  ~vtkSegmentationSVDAGAlgorithm() override;

  virtual int RequestDataObject(vtkInformation*, vtkInformationVector**, vtkInformationVector*);
  virtual int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*);
  virtual int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*);
  virtual int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*);

  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int FillInputPortInformation(int port, vtkInformation* info) override;

#ifndef __VTK_WRAP__
  /** The builder's options from BackgroundLabel and the excluded labels. */
  svdag::BuildOptions GetBuildOptions() const;
#endif


  vtkTypeInt64 BackgroundLabel = 0;
  std::vector<vtkTypeInt64> ExcludedLabels;

private:
  vtkSegmentationSVDAGAlgorithm(const vtkSegmentationSVDAGAlgorithm&) = delete;
  void operator=(const vtkSegmentationSVDAGAlgorithm&) = delete;
};

#endif
