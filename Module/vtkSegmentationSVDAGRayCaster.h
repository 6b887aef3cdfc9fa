/**
 * @class   vtkSegmentationSVDAGRayCaster
 * @brief   picks the first label a world-space ray hits in a vtkSegmentationSVDAG
 *
 * Casts one ray at a time on the CPU through the compressed volume (no decoding): a DDA over the
 * 16^3 cells and, per cell, the traversal of its blocks' SVDAG that the GPU renderer also runs
 * (svdag/Traversal.h). The ray is given in world coordinates; the volume's origin, spacing and
 * direction matrix map it to index space, where voxel (i, j, k) is the box
 * [i, i+1) x [j, j+1) x [k, k+1) around the VTK point (i, j, k):
 *   world = Origin + Direction * diag(Spacing) * (p - 0.5)   for index-space position p.
 *
 * The level of detail chooses what is hit: the blocks' tight bounding boxes (LOD_BLOCK), the
 * first non-empty 4^3 region of a block (LOD_LEAF) or the first labelled voxel (LOD_VOXEL,
 * exact). After CastRay returns 1, the getters describe the hit; after it returns 0 they hold
 * the miss values (label index -1, no label value array).
 */
#ifndef vtkSegmentationSVDAGRayCaster_h
#define vtkSegmentationSVDAGRayCaster_h

#include "vtkObject.h"
#include "vtkSVDAGCoreModule.h" // for export macro
#include "vtkSmartPointer.h"    // for vtkSmartPointer

#include <array>  // for std::array
#include <vector> // for std::vector

class vtkDataArray;
class vtkSegmentationSVDAG;

class VTKSVDAGCORE_EXPORT vtkSegmentationSVDAGRayCaster : public vtkObject
{
public:
  static vtkSegmentationSVDAGRayCaster* New();
  vtkTypeMacro(vtkSegmentationSVDAGRayCaster, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum LevelOfDetail
  {
    LOD_BLOCK = 0,
    LOD_LEAF = 1,
    LOD_VOXEL = 2
  };

  ///@{
  /** The compressed volume to cast rays into. */
  void SetInputData(vtkSegmentationSVDAG* input);
  vtkSegmentationSVDAG* GetInput();
  ///@}

  ///@{
  /** What a ray hits: LOD_BLOCK, LOD_LEAF or LOD_VOXEL (default, lossless). */
  vtkSetClampMacro(LOD, int, LOD_BLOCK, LOD_VOXEL);
  vtkGetMacro(LOD, int);
  void SetLODToBlock() { this->SetLOD(LOD_BLOCK); }
  void SetLODToLeaf() { this->SetLOD(LOD_LEAF); }
  void SetLODToVoxel() { this->SetLOD(LOD_VOXEL); }
  ///@}

  ///@{
  /** Hits farther than this from the ray origin (world units) are ignored (default: none). */
  vtkSetClampMacro(MaximumDistance, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(MaximumDistance, double);
  ///@}

  ///@{
  /**
   * Clipping planes in world coordinates, as the GPU renderer's (svdag/Clipping.h): each keeps
   * the half-space its normal points to (VTK's convention), at most 6 (VTK's usual limit).
   * AddClippingPlane returns 0 and reports an error for a 7th plane, a zero or non-finite normal
   * or a non-finite origin. A ray that enters the kept region inside a labelled voxel (LOD_BLOCK:
   * block box, LOD_LEAF: leaf box) hits the cut face: the distance where it enters, the label
   * there, the normal -normal (unit, facing the ray); GetHitClippingPlane tells which plane.
   */
  int AddClippingPlane(const double origin[3], const double normal[3]);
  void RemoveAllClippingPlanes();
  int GetNumberOfClippingPlanes();
  ///@}

  ///@{
  /**
   * An axis-aligned crop box (world: xmin, xmax, ymin, ymax, zmin, zmax) applied when Cropping
   * is on (default off): only what lies inside is hit, with cut faces like clipping planes.
   * SetCroppingRegionPlanes reports an error for an inverted (min > max) or non-finite box and
   * keeps the previous one.
   */
  vtkSetMacro(Cropping, bool);
  vtkGetMacro(Cropping, bool);
  vtkBooleanMacro(Cropping, bool);
  void SetCroppingRegionPlanes(
    double xmin, double xmax, double ymin, double ymax, double zmin, double zmax);
  void SetCroppingRegionPlanes(const double planes[6])
  {
    this->SetCroppingRegionPlanes(planes[0], planes[1], planes[2], planes[3], planes[4], planes[5]);
  }
  vtkGetVector6Macro(CroppingRegionPlanes, double);
  ///@}

  /**
   * Casts a ray from `origin` along `direction` (world coordinates; the direction need not be
   * unit length). Returns 1 on a hit, 0 on a miss or an error (no input, zero or non-finite
   * direction, singular index-to-world matrix: reported with vtkErrorMacro). A ray that starts
   * inside a labelled voxel hits it at distance 0 with a zero normal.
   */
  int CastRay(const double origin[3], const double direction[3]);

  ///@{
  /** 1 if the last CastRay hit something. */
  vtkGetMacro(Hit, int);
  /** Index of the label hit in the label table (vtkSegmentationSVDAG::NewLabelValues), or -1. */
  vtkGetMacro(HitLabelIndex, vtkIdType);
  /** The label value hit, as a one-tuple array of the labels' scalar type; nullptr on a miss. */
  vtkDataArray* GetHitLabelValue();
  /** World distance from the ray origin to where it enters the hit box or voxel. */
  vtkGetMacro(HitDistance, double);
  /** World position of that entry point. */
  vtkGetVector3Macro(HitPosition, double);
  /** Unit world normal of the face entered (zero when the ray starts inside). */
  vtkGetVector3Macro(HitNormal, double);
  /** Unit world smooth shading normal (svdag/SmoothNormal.h: the gradient of the hit label's
   * smoothed occupancy around the hit point, facing the ray), what the renderer shades with when
   * its Shading is smooth; the face normal at LOD_BLOCK and LOD_LEAF and where the gradient
   * vanishes; zero when the ray starts inside. */
  vtkGetVector3Macro(HitShadingNormal, double);
  /** Voxel index (i, j, k) where the ray enters the hit box; with LOD_VOXEL the voxel hit. */
  vtkGetVector3Macro(HitVoxel, int);
  /** Index of the block hit in the compressed volume, or -1. */
  vtkGetMacro(HitBlockIndex, vtkIdType);
  /** Where the hit is a cut face: the clipping plane (0 .. 5, in the order added) or crop box
   * face (6 + 2 axis + (0: min, 1: max) after the planes); -1 otherwise. */
  vtkGetMacro(HitClippingPlane, int);
  ///@}

protected:
  vtkSegmentationSVDAGRayCaster();
  ~vtkSegmentationSVDAGRayCaster() override;

  void ClearHit();

  vtkSmartPointer<vtkSegmentationSVDAG> Input;
  int LOD = LOD_VOXEL;
  double MaximumDistance = VTK_DOUBLE_MAX;

  int Hit = 0;
  vtkIdType HitLabelIndex = -1;
  vtkSmartPointer<vtkDataArray> HitLabelValue;
  double HitDistance = 0.0;
  double HitPosition[3] = { 0.0, 0.0, 0.0 };
  double HitNormal[3] = { 0.0, 0.0, 0.0 };
  double HitShadingNormal[3] = { 0.0, 0.0, 0.0 };
  int HitVoxel[3] = { 0, 0, 0 };
  vtkIdType HitBlockIndex = -1;
  int HitClippingPlane = -1;

  // Clipping planes (origin, unit normal; world) and the crop box.
  std::vector<std::array<double, 6>> ClippingPlanes;
  bool Cropping = false;
  double CroppingRegionPlanes[6] = { 0.0, 0.0, 0.0, 0.0, 0.0, 0.0 };

private:
  vtkSegmentationSVDAGRayCaster(const vtkSegmentationSVDAGRayCaster&) = delete;
  void operator=(const vtkSegmentationSVDAGRayCaster&) = delete;
};

#endif
