/**
 * @class   vtkSegmentationSVDAGAlgorithm
 * @brief   superclass for algorithms that produce a vtkSegmentationSVDAG
 *
 * VTK 9.1's executive cannot create data objects of types it does not know by name, so this
 * class creates the vtkSegmentationSVDAG output itself in RequestDataObject. Subclasses
 * implement RequestInformation and RequestData as usual. Input ports default to none; a filter
 * sets its own number of input ports and overrides FillInputPortInformation.
 */
#ifndef vtkSegmentationSVDAGAlgorithm_h
#define vtkSegmentationSVDAGAlgorithm_h

#include "vtkAlgorithm.h"
#include "vtkSVDAGCoreModule.h" // for export macro

class vtkSegmentationSVDAG;

class VTKSVDAGCORE_EXPORT vtkSegmentationSVDAGAlgorithm : public vtkAlgorithm
{
public:
  static vtkSegmentationSVDAGAlgorithm* New();
  vtkTypeMacro(vtkSegmentationSVDAGAlgorithm, vtkAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /** The output of port 0, after an update. */
  vtkSegmentationSVDAG* GetOutput();

  vtkTypeBool ProcessRequest(
    vtkInformation* request, vtkInformationVector** in, vtkInformationVector* out) override;

protected:
  vtkSegmentationSVDAGAlgorithm();
  ~vtkSegmentationSVDAGAlgorithm() override;

  virtual int RequestDataObject(vtkInformation*, vtkInformationVector**, vtkInformationVector*);
  virtual int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*);
  virtual int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*);
  virtual int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*);

  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int FillInputPortInformation(int port, vtkInformation* info) override;

private:
  vtkSegmentationSVDAGAlgorithm(const vtkSegmentationSVDAGAlgorithm&) = delete;
  void operator=(const vtkSegmentationSVDAGAlgorithm&) = delete;
};

#endif
