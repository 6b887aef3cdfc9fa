/**
 * @class   vtkSegmentationSVDAG
 * @brief   a segmentation (label) volume compressed losslessly into blocks and a shared SVDAG
 *
 * Each 16^3 cell of the volume holds one block per label present, with tight voxel bounds and
 * the label's index; the binary occupancy of every block is a tree of 8^3 nodes and 4^3 leaf
 * masks, deduplicated across all blocks and labels (with complement sharing). The original
 * label values, of any integer type up to 64 bits, are kept in a sorted label table.
 *
 * The object is immutable once built: ShallowCopy shares the compressed volume, DeepCopy
 * duplicates it. Build one with vtkImageDataToSegmentationSVDAG or vtkSegmentationVolumeReader,
 * decode it with vtkSegmentationSVDAGToImageData.
 */
#ifndef vtkSegmentationSVDAG_h
#define vtkSegmentationSVDAG_h

#include "vtkDataObject.h"
#include "vtkSVDAGCoreModule.h" // for export macro

#include <memory> // for std::shared_ptr
#include <string> // for std::string

class vtkDataArray;
class vtkDoubleArray;
class vtkIdTypeArray;
class vtkImageData;
class vtkInformation;
class vtkInformationVector;
class vtkMatrix3x3;
class vtkTable;
#ifndef __VTK_WRAP__
namespace svdag
{
class Volume;
}
#endif

class VTKSVDAGCORE_EXPORT vtkSegmentationSVDAG : public vtkDataObject
{
public:
  static vtkSegmentationSVDAG* New();
  vtkTypeMacro(vtkSegmentationSVDAG, vtkDataObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void Initialize() override;
  void ShallowCopy(vtkDataObject* src) override;
  void DeepCopy(vtkDataObject* src) override;
  /** Kibibytes held (the compressed volume plus this object), as VTK counts memory. */
  unsigned long GetActualMemorySize() override;

  /** True when a compressed volume is present. */
  bool HasVolume() const { return this->Volume != nullptr; }

  ///@{
  /** Geometry of the original image. */
  void GetDimensions(int dims[3]) const;
  void GetSpacing(double spacing[3]) const;
  void GetOrigin(double origin[3]) const;
  /** Row-major 3x3 index-to-physical direction, as vtkImageData::GetDirectionMatrix. */
  void GetDirection(double direction[9]) const;
  vtkIdType GetNumberOfVoxels() const;
  ///@}

  ///@{
  /** Label table: original values sorted ascending, their voxel counts and inclusive bounds. */
  /** VTK scalar type of the original labels (VTK_UNSIGNED_CHAR, VTK_LONG_LONG, ...). */
  int GetLabelScalarType() const;
  vtkIdType GetNumberOfLabels() const;
  /** A new array of the original scalar type holding the label values in table order. */
  vtkDataArray* NewLabelValues() const;
  vtkIdType GetLabelVoxelCount(vtkIdType index) const;
  void GetLabelBounds(vtkIdType index, int bounds[6]) const;
  /** Background label (not stored) as a one-value array of the original scalar type. */
  vtkDataArray* NewBackgroundValue() const;
  /** Index of the label stored at voxel (i, j, k), or -1 for background. */
  vtkIdType GetLabelIndexAt(int i, int j, int k) const;
  ///@}

  ///@{
  /**
   * Sizes of the parts, as held in memory (the compact form, svdag/Compact.h). Counts of nodes
   * are unique (deduplicated) nodes; GetNumberOfLeaves counts the leaves stored apart, those
   * that several mid nodes share (a leaf used once is inline in its mid node).
   */
  vtkIdType GetNumberOfBlocks() const;
  vtkIdType GetNumberOfRootNodes() const;
  vtkIdType GetNumberOfMidNodes() const;
  vtkIdType GetNumberOfLeaves() const;
  vtkIdType GetNumberOfDAGNodes() const;
  vtkTypeInt64 GetBlocksMemorySize() const;
  vtkTypeInt64 GetDAGMemorySize() const;
  vtkTypeInt64 GetLabelTableMemorySize() const;
  /** Bytes a renderer holds besides its BVH: blocks + DAG + label table. */
  vtkTypeInt64 GetCompressedSize() const;
  ///@}

  /** Decodes losslessly into an image of the original scalar type ("Labels" point scalars). */
  bool DecodeTo(vtkImageData* image) const;
#ifndef __VTK_WRAP__
  /** The same, handing the reason of a failure to the caller (no error event on this object). */
  bool DecodeTo(vtkImageData* image, std::string& error) const;
#endif

  ///@{
  /**
   * Random access from the compressed form (svdag/RandomAccess.h): only the 16^3 cells that
   * meet the extent are decoded. `extent` is an inclusive VTK extent (xmin, xmax, ymin, ymax,
   * zmin, zmax) of voxel indices inside the volume. The image gets that extent, the volume's
   * spacing, origin and direction, and point scalars "Labels" of the original type.
   */
  bool DecodeExtentTo(const int extent[6], vtkImageData* image) const;
  /**
   * Unsigned char point scalars "Mask" over `extent`: 1 where the voxel holds the label of table
   * index `labelIndex` (see GetLabelIndexAt / NewLabelValues), else 0. Only that label's blocks
   * are decoded.
   */
  bool DecodeLabelMaskTo(vtkIdType labelIndex, const int extent[6], vtkImageData* image) const;
  /**
   * Per-label statistics without a dense decode (svdag/LabelStatistics.h), in table order:
   * `centroids` gets 3 components per label, the mean voxel index (i, j, k); `surfaceVoxels`
   * the number of the label's voxels with at least one of their 6 face neighbours of another
   * label (background included) or outside the volume. Either array may be null.
   */
  bool ComputeLabelStatistics(vtkDoubleArray* centroids, vtkIdTypeArray* surfaceVoxels) const;
  /**
   * The label pairs that touch across a voxel face (6-neighbourhood), from the compressed form
   * one layer of cells at a time (svdag/LabelAdjacency.h): `pairs` gets 2 components per pair,
   * the table indices a < b of the two labels, sorted. The background is no label.
   */
  bool ComputeLabelAdjacency(vtkIdTypeArray* pairs) const;
  /**
   * Where the bytes go (svdag/EncodingAnalysis.h): one row per level ("blocks", "roots",
   * "mids", "leaves"; column "level") with "compact_bytes" (the level in the compact form held
   * in memory) and, of the pooled form files store, in bits or counts: "nodes", "bits", "header_bits",
   * "reference_bits", "references", "reference_width" (into the next level); of the references
   * into the level: "incoming_references", "referenced_once", "max_incoming",
   * "top1_percent_share", "top10_percent_share", "reference_entropy_bits"; and what sharing
   * nodes equal up to a mirror (a cube symmetry) would store: "mirror_classes", "mirror_bits",
   * "symmetry_classes", "symmetry_bits". The table's previous columns are removed.
   */
  bool ComputeEncodingStatistics(vtkTable* table) const;
  /**
   * The default categorical colors (svdag/LabelColoring.h), display sRGB, 3 components per
   * label in table order: palette colors assigned over the label adjacency so that touching
   * labels get clearly different ones.
   */
  bool ComputeDistinctLabelColors(vtkDoubleArray* colors) const;
  /**
   * The first `n` colors of the categorical palette (svdag/Palette.h), display sRGB, 3
   * components each; past its size the palette repeats.
   */
  static void GetCategoricalPalette(vtkIdType n, vtkDoubleArray* colors);
  ///@}

#ifndef __VTK_WRAP__
  /** The same, handing the reason of a failure to the caller (no error event on this object). */
  bool DecodeExtentTo(const int extent[6], vtkImageData* image, std::string& error) const;
  bool DecodeLabelMaskTo(
    vtkIdType labelIndex, const int extent[6], vtkImageData* image, std::string& error) const;
#endif

#ifndef __VTK_WRAP__
  /** The compressed volume (shared, immutable). */
  const std::shared_ptr<const svdag::Volume>& GetVolume() const { return this->Volume; }
  void SetVolume(std::shared_ptr<const svdag::Volume> volume);
#endif

  static vtkSegmentationSVDAG* GetData(vtkInformation* info);
  static vtkSegmentationSVDAG* GetData(vtkInformationVector* v, int i = 0);

  /** Maps between VTK scalar type ids and the core's label types; -1 when not an integer type. */
  static int ToVTKScalarType(int coreType);
  static int FromVTKScalarType(int vtkType);

protected:
  vtkSegmentationSVDAG();
  ~vtkSegmentationSVDAG() override;

private:
  vtkSegmentationSVDAG(const vtkSegmentationSVDAG&) = delete;
  void operator=(const vtkSegmentationSVDAG&) = delete;

#ifndef __VTK_WRAP__
  std::shared_ptr<const svdag::Volume> Volume;
#endif
};

#endif
