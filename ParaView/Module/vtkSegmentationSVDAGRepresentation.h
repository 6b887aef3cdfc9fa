/**
 * @class   vtkSegmentationSVDAGRepresentation
 * @brief   ParaView representation 'Segmentation Path Tracing' of a vtkSegmentationSVDAG
 *
 * Draws its input with vtkSegmentationSVDAGVolumeMapper (the Vulkan path tracer) in a
 * vtkPVRenderView. The properties forward to the mapper's render settings (LOD, Backend,
 * Shading, SamplesPerPixel, MaximumBounces, Exposure), to the mapper (TargetSamplesPerPixel,
 * RefineStillRenders, clipping planes) and to its label properties (LookupTable: label colors,
 * annotated values of a categorical table; Opacity: every label's; HiddenLabels).
 *
 * Rendering: the compressed volume is never moved between processes (ParaView cannot serialize
 * it): the representation requires distributed rendering, so in a client-server session the
 * server renders and sends the image, and on several ranks each rank traces its own piece and
 * writes depth, which IceT composites. The render window's DesiredUpdateRate (set by ParaView's
 * interactor while the user interacts) gives the mapper its time budget; still renders refine
 * to TargetSamplesPerPixel when RefineStillRenders is on (the default).
 *
 * Pieces (MPI ranks): the reader gives each rank a z-range of whole slabs (its piece), and each
 * rank's labels take the default colors of their indices in the whole volume's label table
 * (gathered from the ranks in RequestData), so the composited image has the colors of the
 * undivided volume. A pick is made on every rank and the nearest hit wins. Shadow and bounce
 * rays end at the rank's piece: light that crosses a piece boundary is not traced (see the
 * README's ParaView section).
 *
 * Picking: SetPickPixel(x, y) (display pixels of the view, origin bottom left, like VTK's)
 * picks on the last traced frame; GetPickedHit and GetPickedLabel report the result. Sessions
 * reach them through vtkSegmentationSVDAGPicker (proxy misc/SegmentationPicker), which runs
 * them where the frame was traced.
 */
#ifndef vtkSegmentationSVDAGRepresentation_h
#define vtkSegmentationSVDAGRepresentation_h

#include "vtkNew.h"                    // for vtkNew
#include "vtkPVDataRepresentation.h"
#include "vtkSVDAGParaViewModule.h"     // for export macro
#include "vtkSmartPointer.h"           // for vtkSmartPointer

#include <vector> // for std::vector

class vtkPlane;
class vtkRenderer;
class vtkScalarsToColors;
class vtkSegmentationSVDAG;
class vtkSegmentationSVDAGVolumeMapper;
class vtkStringArray;
class vtkVolume;

class VTKSVDAGPARAVIEW_EXPORT vtkSegmentationSVDAGRepresentation : public vtkPVDataRepresentation
{
public:
  static vtkSegmentationSVDAGRepresentation* New();
  vtkTypeMacro(vtkSegmentationSVDAGRepresentation, vtkPVDataRepresentation);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  int ProcessViewRequest(vtkInformationRequestKey* request_type, vtkInformation* inInfo,
    vtkInformation* outInfo) override;
  void SetVisibility(bool visible) override;

  /** ParaView's representation type; only "Segmentation Path Tracing" is drawn. */
  void SetRepresentation(const char* type);

  ///@{
  /** Render settings (vtkSegmentationSVDAGRenderSettings), by name for the enumerations. */
  void SetLOD(const char* name);
  void SetBackend(const char* name);
  void SetShading(const char* name);
  void SetSamplesPerPixel(int samples);
  void SetMaximumBounces(int bounces);
  void SetExposure(double exposure);
  /** The names the settings class defines, for the properties' domains. */
  vtkStringArray* GetLODNames();
  vtkStringArray* GetBackendNames();
  vtkStringArray* GetShadingNames();
  ///@}

  ///@{
  /** The mapper's refinement: samples per pixel a still view refines to, and whether still
   * renders refine within the render (on) or by one pass each (off). */
  void SetTargetSamplesPerPixel(int samples);
  void SetRefineStillRenders(bool refine);
  void SetRefineTimeLimit(double seconds);
  ///@}

  ///@{
  /** Label appearance: colors from a lookup table, one opacity for every label, labels never
   * drawn (nor picked). A categorical table (IndexedLookup, as ParaView's color map editor
   * makes with "Interpret Values As Categories") colors its annotated values only: the other
   * labels keep their default colors. Any other table colors every label by its value. */
  void SetLookupTable(vtkScalarsToColors* table);
  void SetOpacity(double opacity);
  void AddHiddenLabel(vtkTypeInt64 label);
  void RemoveAllHiddenLabels();
  ///@}

  ///@{
  /** Clipping planes in world coordinates, each keeping the side its normal points to. */
  void AddClippingPlane(vtkPlane* plane);
  void RemoveAllClippingPlanes();
  ///@}

  ///@{
  /** Picks the label under display pixel (x, y) of the last traced frame. */
  void SetPickPixel(double x, double y);
  vtkGetMacro(PickedHit, int);
  vtkGetMacro(PickedLabel, vtkTypeInt64);
  ///@}

  /** Samples per pixel accumulated by the last frame (0 before the first). */
  int GetAccumulatedSamples();

  /** The mapper (for tests and applications in the same process). */
  vtkSegmentationSVDAGVolumeMapper* GetMapper() { return this->Mapper; }

protected:
  vtkSegmentationSVDAGRepresentation();
  ~vtkSegmentationSVDAGRepresentation() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  bool AddToView(vtkView* view) override;
  bool RemoveFromView(vtkView* view) override;

private:
  vtkSegmentationSVDAGRepresentation(const vtkSegmentationSVDAGRepresentation&) = delete;
  void operator=(const vtkSegmentationSVDAGRepresentation&) = delete;

  // Applies Opacity and HiddenLabels to the labels of the volume being drawn.
  void UpdateLabelProperties(vtkSegmentationSVDAG* volume);

  vtkNew<vtkSegmentationSVDAGVolumeMapper> Mapper;
  vtkNew<vtkVolume> Actor;
  vtkSmartPointer<vtkSegmentationSVDAG> Cache; // this process's piece
  vtkRenderer* Renderer = nullptr;              // of the view this is in (not owned)
  bool DrawnType = true;                        // the representation type is ours
  double Opacity = 1.0;
  std::vector<vtkTypeInt64> HiddenLabels;
  vtkSmartPointer<vtkScalarsToColors> LookupTable;
  std::vector<vtkTypeInt64> ColoredLabels; // given colors (annotations, whole-table defaults)
  vtkSegmentationSVDAG* LabelsAppliedTo = nullptr; // the volume UpdateLabelProperties last saw
  vtkMTimeType LabelsAppliedTime = 0;
  vtkTimeStamp LabelsModified;
  // The index in the whole volume's label table of each of Cache's labels, when the volume is
  // split across ranks (else empty: the piece is the whole volume).
  std::vector<vtkIdType> WholeTableIndices;
  int PickedHit = 0;
  vtkTypeInt64 PickedLabel = 0;
};

#endif
