/**
 * @class   vtkSegmentationSVDAGPicker
 * @brief   Picks a label of a 'Segmentation Path Tracing' representation where it renders
 *
 * The server manager proxy `misc/SegmentationPicker` of this class lives on the render server
 * only (processes="renderserver"), so that setting PickPixel runs the representation's pick on
 * every rank that traced a piece, and reading PickedHit, PickedLabel and AccumulatedSamples
 * (information properties) pulls the values from the rank that holds them: the render server's
 * root in a client-server session, this process in a built-in session or pvbatch. (The
 * representation's own proxy also lives on the client, which has no data to pick on, and an
 * information property is read from the client first.)
 */
#ifndef vtkSegmentationSVDAGPicker_h
#define vtkSegmentationSVDAGPicker_h

#include "vtkObject.h"
#include "vtkSVDAGParaViewModule.h" // for export macro
#include "vtkWeakPointer.h"         // for Representation

class vtkSegmentationSVDAGRepresentation;

class VTKSVDAGPARAVIEW_EXPORT vtkSegmentationSVDAGPicker : public vtkObject
{
public:
  static vtkSegmentationSVDAGPicker* New();
  vtkTypeMacro(vtkSegmentationSVDAGPicker, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /** The representation to pick on (not owned). */
  void SetRepresentation(vtkSegmentationSVDAGRepresentation* representation);

  /**
   * Picks the label under display pixel (x, y) of the representation's last traced frame
   * (origin bottom left, like VTK's); negative coordinates only clear the result.
   */
  void SetPickPixel(double x, double y);
  /** 1 if the last pick hit a label, else 0. */
  int GetPickedHit();
  /** The label value the last pick hit (0 without a hit). */
  vtkTypeInt64 GetPickedLabel();
  /** Samples per pixel the representation's last frame accumulated (0 before the first). */
  int GetAccumulatedSamples();

protected:
  vtkSegmentationSVDAGPicker();
  ~vtkSegmentationSVDAGPicker() override;

private:
  vtkSegmentationSVDAGPicker(const vtkSegmentationSVDAGPicker&) = delete;
  void operator=(const vtkSegmentationSVDAGPicker&) = delete;

  vtkWeakPointer<vtkSegmentationSVDAGRepresentation> Representation;
};

#endif
