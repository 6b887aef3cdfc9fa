/**
 * @class   vtkSegmentationVolumeReader
 * @brief   reads a label volume file straight into a vtkSegmentationSVDAG
 *
 * The file is never held in memory as a whole: it is read in slabs of 16 z-slices that are fed
 * to the SVDAG builder one after the other, the next read on a thread of its own while the
 * builder compresses this one, so peak memory stays near two slabs plus the compressed output
 * (exception: NIfTI with qfac = -1, see below). Cells of a slab are scanned
 * in parallel with vtkSMPTools; the output does not depend on the thread count.
 *
 * Piece requests (UPDATE_PIECE_NUMBER of UPDATE_NUMBER_OF_PIECES, what ParaView's MPI ranks and
 * UpdatePiece ask for): the output is the piece's z-range of whole slabs
 * (svdag::Builder::pieceZRange), compressed alone, its origin that of its first slice; the
 * slabs before it are read and dropped. A piece beyond the slab count is empty. A .svdag file
 * is passed through whole only when one piece is asked for.
 *
 * The format is detected from the file's content, not its name:
 * - NRRD (.nrrd, detached .nhdr; raw or gzip; 3D Slicer .seg.nrrd with one labelmap layer),
 *   geometry from space directions/space origin or spacings, in the file's own space;
 * - MetaImage (.mha, .mhd; raw or zlib), slab by slab. Its text header is parsed here: VTK 9.1's
 *   vtkMetaImageReader cannot serve a slab extent and accepts truncated data silently;
 * - VTK XML image data (.vti) through vtkXMLImageDataReader, slab by slab;
 * - NIfTI-1/2 (.nii, .nii.gz, .hdr/.img) through vtkNIFTIImageReader, slab by slab, in the
 *   file's voxel order (nibabel's array order, x fastest); origin, spacing and direction come
 *   from the sform (if its code is set) or the qform, as nibabel's affine does. Files with
 *   qfac = -1 are read whole: VTK 9.1's reader reverses their slices correctly only then;
 * - multi-page TIFF (one page per z-slice, one integer sample per pixel) through libtiff;
 * - HDF5 (a 3D integer dataset stored (z, y, x) in C order, the way h5py writes a numpy array);
 * - .svdag files (the project's own format).
 *
 * Label volumes need one integer component (8 to 64 bits, signed or unsigned); other files are
 * rejected with an error naming their type, except float32 and float64 files with
 * CastFloatLabels on. Errors set the error code (FileNotFoundError,
 * UnrecognizedFileTypeError, FileFormatError, PrematureEndOfFileError, ...) and are reported with
 * vtkErrorMacro; RequestInformation already checks the header.
 */
#ifndef vtkSegmentationVolumeReader_h
#define vtkSegmentationVolumeReader_h

#include "vtkSVDAGIOModule.h" // for export macro
#include "vtkSegmentationSVDAGAlgorithm.h"

#include <memory> // for std::unique_ptr
#include <string> // for std::string
#include <vector> // for std::vector

class svdagSlabSource;
class vtkUnsignedCharArray;

class VTKSVDAGIO_EXPORT vtkSegmentationVolumeReader : public vtkSegmentationSVDAGAlgorithm
{
public:
  static vtkSegmentationVolumeReader* New();
  vtkTypeMacro(vtkSegmentationVolumeReader, vtkSegmentationSVDAGAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /** The label volume file to read. */
  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);
  ///@}

  /**
   * 1 if the file's content is in a format this reader knows (magic numbers and header keys
   * are checked; the extension is not), else 0.
   */
  virtual int CanReadFile(const char* fileName);

  /** Extensions of the formats read, space-separated (".nrrd .nhdr .mha ..."). */
  virtual const char* GetFileExtensions();
  /** "Segmentation label volume". */
  virtual const char* GetDescriptiveName();

  ///@{
  /**
   * HDF5 only: path of the dataset to read ("/volumes/labels"). If unset, the file must hold
   * exactly one 3D integer dataset.
   */
  vtkSetStringMacro(DatasetName);
  vtkGetStringMacro(DatasetName);
  ///@}

  ///@{
  /**
   * When on, float labels (float32 or float64 voxels, in any of the formats above) are read as
   * integer labels, value for value, if every value is finite and a whole number: the labels
   * get the narrowest integer type that holds all of them (unsigned when none is negative),
   * the rule of vtksvdag's cast="exact". Otherwise the read fails naming the first offending
   * value and its (x, y, z) index (the least x, then y, then z) and why. The file is read twice,
   * slab by slab (a check pass in RequestInformation, then the conversion in RequestData), so
   * memory stays two slabs. Integer files read the same either way. Default off: float files
   * are refused.
   */
  vtkSetMacro(CastFloatLabels, bool);
  vtkGetMacro(CastFloatLabels, bool);
  vtkBooleanMacro(CastFloatLabels, bool);
  ///@}

  ///@{
  /**
   * When on, the reader parses InputArray (the bytes of a .svdag file, as
   * vtkSegmentationSVDAGWriter gives them with WriteToOutputString) instead of FileName: to
   * receive a volume from another process. Default off. Only the .svdag format is read this way.
   */
  vtkSetMacro(ReadFromInputString, bool);
  vtkGetMacro(ReadFromInputString, bool);
  vtkBooleanMacro(ReadFromInputString, bool);
  virtual void SetInputArray(vtkUnsignedCharArray* bytes);
  vtkGetObjectMacro(InputArray, vtkUnsignedCharArray);
  ///@}
  /**
   * Format detected by the last RequestInformation ("NRRD", "MetaImage", "VTKImageData",
   * "NIfTI", "TIFF", "HDF5", "SVDAG"), or "" before an update or when the file was not read.
   */
  const char* GetFileFormat() const { return this->FileFormat.c_str(); }

protected:
  vtkSegmentationVolumeReader();
  ~vtkSegmentationVolumeReader() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* FileName = nullptr;
  char* DatasetName = nullptr;
  bool CastFloatLabels = false;
  bool ReadFromInputString = false;
  vtkUnsignedCharArray* InputArray = nullptr;
  std::string FileFormat;

private:
  const char* InputName() const;
  bool CheckInputGiven();
  std::unique_ptr<svdagSlabSource> OpenSource();

  // The source opened by RequestInformation, handed to the next RequestData (a file is opened and
  // its header parsed once per update).
  struct Internals;
  Internals* Internal;

  vtkSegmentationVolumeReader(const vtkSegmentationVolumeReader&) = delete;
  void operator=(const vtkSegmentationVolumeReader&) = delete;
};

#endif
