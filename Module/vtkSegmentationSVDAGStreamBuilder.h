/**
 * @class   vtkSegmentationSVDAGStreamBuilder
 * @brief   compresses a label volume given a few z-slices at a time into a vtkSegmentationSVDAG
 *
 * For volumes that do not fit in memory, or that arrive in pieces (a chunked store, a scanner):
 * Initialize with the geometry and scalar type, hand the z-slices over in increasing order with
 * AddSlab (any number of slices per call, x fastest), then Finish. The result is bit-identical
 * to what vtkImageDataToSegmentationSVDAG produces for the whole volume with the same
 * background and excluded labels: the core builder (svdag::Builder) consumes slabs of 16
 * z-slices; the slices of a call that complete a slab are consumed straight from the caller's
 * array, and only a trailing partial slab is copied, so at most one 16-slice slab is held here.
 *
 * Errors (a wrong scalar type or slice size, slices out of order or beyond the volume, Finish
 * before every slice was added, invalid geometry) are reported with vtkErrorMacro and a false
 * return, and leave the builder as it was. After a successful Finish the builder is empty until
 * the next Initialize. A ProgressEvent (call data: a double in [0, 1], also GetProgress) follows
 * every slab consumed.
 */
#ifndef vtkSegmentationSVDAGStreamBuilder_h
#define vtkSegmentationSVDAGStreamBuilder_h

#include "vtkObject.h"
#include "vtkSVDAGCoreModule.h" // for export macro

#include <memory> // for std::unique_ptr
#include <vector> // for std::vector

class vtkDataArray;
class vtkSegmentationSVDAG;

class VTKSVDAGCORE_EXPORT vtkSegmentationSVDAGStreamBuilder : public vtkObject
{
public:
  static vtkSegmentationSVDAGStreamBuilder* New();
  vtkTypeMacro(vtkSegmentationSVDAGStreamBuilder, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /**
   * Label value not stored (default 0), interpreted in the volume's scalar type (-1 is 255 for
   * unsigned char). Read by Initialize: changes afterwards apply to the next volume.
   */
  vtkSetMacro(BackgroundLabel, vtkTypeInt64);
  vtkGetMacro(BackgroundLabel, vtkTypeInt64);
  ///@}

  ///@{
  /** Labels left out of the compressed volume (they decode as background); read by Initialize. */
  void AddExcludedLabel(vtkTypeInt64 label);
  void RemoveAllExcludedLabels();
  vtkIdType GetNumberOfExcludedLabels() const;
  vtkTypeInt64 GetExcludedLabel(vtkIdType i) const;
  ///@}

  ///@{
  /**
   * Starts a volume of `dims` voxels whose labels have the VTK scalar type `scalarType` (an
   * integer type: VTK_UNSIGNED_CHAR, VTK_LONG_LONG, ...), with the given spacing, origin and
   * row-major 3x3 direction (as vtkImageData::GetDirectionMatrix; identity in the short form).
   * Discards a volume in progress. False (and an error) for an invalid geometry or type.
   */
  bool Initialize(const int dims[3], int scalarType, const double spacing[3],
    const double origin[3], const double direction[9]);
  bool Initialize(const int dims[3], int scalarType, const double spacing[3],
    const double origin[3]);
  bool Initialize(const int dims[3], int scalarType);
  ///@}

  /** True between a successful Initialize and a successful Finish. */
  bool IsInitialized() const;

  ///@{
  /**
   * Adds the next z-slices: `values` holds dims[0] * dims[1] * nz values (one component, the
   * scalar type given to Initialize or one of the same width and signedness, x fastest, then y,
   * then z). The short form takes nz from the array's size; the long forms also check that the
   * slices start at `z0` (GetNextSlice) and, if given, that there are `nz` of them.
   */
  bool AddSlab(vtkDataArray* values);
  bool AddSlab(vtkDataArray* values, int z0);
  bool AddSlab(vtkDataArray* values, int z0, int nz);
  ///@}

  /**
   * Appends `part`, a volume built elsewhere (another process or machine) from the next
   * part->GetDimensions()[2] z-slices, with the same scalar type, background and excluded labels;
   * its spacing, origin and direction are not used. The result is byte-identical to adding
   * those slices with AddSlab, so the volumes of consecutive z-ranges built in parallel merge in
   * z order into the single-machine result. The slices added so far must end on a 16-slice slab
   * (or the volume's end), and a part whose depth is not a multiple of 16 must be the last.
   * False (and an error) otherwise, with the builder unchanged.
   */
  bool AddVolume(vtkSegmentationSVDAG* part);
  /** The index of the next z-slice expected (dims[2] once all were added; 0 when not started). */
  int GetNextSlice() const;

  /** Fraction of the slices consumed by the core builder, in [0, 1]. */
  vtkGetMacro(Progress, double);

  /**
   * Compresses what remains and stores the volume in `output` (which is not changed on
   * failure). False when slices are missing (the builder stays usable: add them and finish
   * again), or when the volume cannot be built.
   */
  bool Finish(vtkSegmentationSVDAG* output);

protected:
  vtkSegmentationSVDAGStreamBuilder();
  ~vtkSegmentationSVDAGStreamBuilder() override;

  vtkTypeInt64 BackgroundLabel = 0;
  std::vector<vtkTypeInt64> ExcludedLabels;
  double Progress = 0.0;

private:
  vtkSegmentationSVDAGStreamBuilder(const vtkSegmentationSVDAGStreamBuilder&) = delete;
  void operator=(const vtkSegmentationSVDAGStreamBuilder&) = delete;

  bool AddSlices(vtkDataArray* values, int z0, int nz);

  struct Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
