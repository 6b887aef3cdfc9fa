/**
 * @class   vtkSegmentationSVDAGSlice
 * @brief   one slice of a vtkSegmentationSVDAG, decoded straight from the compressed form
 *
 * Only the 16^3 cells the slice crosses are decoded (svdag/RandomAccess.h), so a slice costs a
 * small fraction of a full decode. The output is a vtkImageData one voxel thick whose point
 * scalars "Labels" hold the original label values (original scalar type), placed in the
 * volume's world geometry, ready for vtkImageSlice or a pyvista plotter.
 *
 * Two modes:
 * - AxisAligned (default): the slice Index (0 .. dims[Axis] - 1) along Axis (0 = x, 1 = y,
 *   2 = z). The output has the volume's spacing, origin and direction and the extent of that
 *   slice within the volume's whole extent (e.g. 0..nx-1, 0..ny-1, k..k for Axis 2), so it lies
 *   exactly where the voxels are.
 * - Oblique: the plane through PlaneOrigin (world) with normal PlaneNormal (world), sampled on a
 *   regular grid and resampled nearest: each sample takes the label of the voxel whose center is
 *   nearest (floor(index + 0.5) per index coordinate); samples outside the volume get the
 *   background label. The grid's first axis u is PlaneXAxis projected on the plane, or, when
 *   PlaneXAxis is (0, 0, 0), the volume's index axis (world direction) most nearly in the plane
 *   (the first one on ties: x for a z normal, y for an x normal), projected on the plane; the
 *   second is v = normal x u. OutputSpacing (u, v) in world units defaults (0) to the smallest
 *   voxel spacing. With OutputDimensions (nu, nv) set, the grid is centered on PlaneOrigin;
 *   with (0, 0) it is sized to cover the projection of the volume's voxel centers on the plane,
 *   starting at the smallest projection. The output image has extent 0..nu-1, 0..nv-1, 0..0,
 *   the spacing (su, sv, 1), the grid's first sample as origin and the direction matrix with
 *   columns u, v, normal.
 *
 * Errors (no volume, a bad axis, an index outside the volume, a zero normal, a plane x axis
 * along the normal, an output too large for memory) are reported with vtkErrorMacro and leave
 * the output empty.
 */
#ifndef vtkSegmentationSVDAGSlice_h
#define vtkSegmentationSVDAGSlice_h

#include "vtkImageAlgorithm.h"
#include "vtkSVDAGCoreModule.h" // for export macro

#include <string> // for std::string

class vtkSegmentationSVDAG;

class VTKSVDAGCORE_EXPORT vtkSegmentationSVDAGSlice : public vtkImageAlgorithm
{
public:
  static vtkSegmentationSVDAGSlice* New();
  vtkTypeMacro(vtkSegmentationSVDAGSlice, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum Modes
  {
    AXIS_ALIGNED = 0,
    OBLIQUE = 1
  };

  ///@{
  /** AXIS_ALIGNED (default) or OBLIQUE. */
  vtkSetClampMacro(Mode, int, AXIS_ALIGNED, OBLIQUE);
  vtkGetMacro(Mode, int);
  void SetModeToAxisAligned() { this->SetMode(AXIS_ALIGNED); }
  void SetModeToOblique() { this->SetMode(OBLIQUE); }
  ///@}

  ///@{
  /** Axis (0 = x, 1 = y, 2 = z; default 2) and voxel index of an axis-aligned slice (default 0).
   * Not clamped: a value outside the volume is an error when the filter runs. */
  vtkSetMacro(Axis, int);
  vtkGetMacro(Axis, int);
  vtkSetMacro(Index, int);
  vtkGetMacro(Index, int);
  ///@}

  ///@{
  /** The oblique plane, in world coordinates: a point on it and its normal (default: the
   * origin and +z). */
  vtkSetVector3Macro(PlaneOrigin, double);
  vtkGetVector3Macro(PlaneOrigin, double);
  vtkSetVector3Macro(PlaneNormal, double);
  vtkGetVector3Macro(PlaneNormal, double);
  /** Direction of the output's first axis (projected on the plane); (0, 0, 0): automatic. */
  vtkSetVector3Macro(PlaneXAxis, double);
  vtkGetVector3Macro(PlaneXAxis, double);
  ///@}

  ///@{
  /** Samples along u and v of the oblique grid; (0, 0) (default): cover the volume. */
  vtkSetVector2Macro(OutputDimensions, int);
  vtkGetVector2Macro(OutputDimensions, int);
  /** World distance between samples along u and v; 0 (default): the smallest voxel spacing. */
  vtkSetVector2Macro(OutputSpacing, double);
  vtkGetVector2Macro(OutputSpacing, double);
  ///@}

protected:
  vtkSegmentationSVDAGSlice();
  ~vtkSegmentationSVDAGSlice() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int Mode = AXIS_ALIGNED;
  int Axis = 2;
  int Index = 0;
  double PlaneOrigin[3] = { 0, 0, 0 };
  double PlaneNormal[3] = { 0, 0, 1 };
  double PlaneXAxis[3] = { 0, 0, 0 };
  int OutputDimensions[2] = { 0, 0 };
  double OutputSpacing[2] = { 0, 0 };

private:
  vtkSegmentationSVDAGSlice(const vtkSegmentationSVDAGSlice&) = delete;
  void operator=(const vtkSegmentationSVDAGSlice&) = delete;

#ifndef __VTK_WRAP__
  struct OutputGeometry;
  // The output's extent, spacing, origin, direction (and the sampling of an oblique plane) for
  // the input's volume; false with `error` set when the settings do not fit it.
  bool ComputeOutputGeometry(vtkSegmentationSVDAG* input, OutputGeometry& g, std::string& error);
#endif
};

#endif
