/**
 * @class   vtkSegmentationSVDAGWriter
 * @brief   writes a vtkSegmentationSVDAG to a .svdag file
 *
 * The .svdag format (documented in IO/README.md and svdag/File.h) comes in three versions, all
 * protected by crc32s (FormatVersion):
 * - 4 (the default): the shared DAG as byte streams (node headers, reference flags, the indices
 *   of shared nodes, leaf masks, block cells and labels) under zstd: smaller than CSGV's files,
 *   and read back in a fraction of a build's time, bounds and label totals derived on load.
 * - 3: the volume's labels and occupancy arithmetic-coded, the smallest file (about half of 4's).
 *   Reading it back (vtkSegmentationVolumeReader) rebuilds the blocks and the shared DAG from the
 *   occupancy, without a voxel scan: the volume a build from the same labels gives.
 * - 2: the compressed volume as it is in memory, blocks, the shared DAG and the label table, each
 *   section compressed with zstd (or stored, with CompressionLevel 0). Reading it back gives a
 *   bit-identical volume at once, and readers older than format 3 read it.
 *
 * The file is written under a temporary name next to FileName and renamed when complete, so a
 * failed write never leaves a partial file under FileName. Errors are reported with
 * vtkErrorMacro and GetErrorCode(): NoFileNameError, CannotOpenFileError, OutOfDiskSpaceError
 * (any failed write), UnknownError (an input without a volume, an inconsistent volume).
 *
 * Give the input with SetInputData(svdag) (inherited from vtkWriter) or SetInputConnection.
 */
#ifndef vtkSegmentationSVDAGWriter_h
#define vtkSegmentationSVDAGWriter_h

#include "vtkSVDAGIOModule.h" // for export macro
#include "vtkNew.h"               // for vtkNew
#include "vtkUnsignedCharArray.h" // for vtkNew<vtkUnsignedCharArray>
#include "vtkWriter.h"

class VTKSVDAGIO_EXPORT vtkSegmentationSVDAGWriter : public vtkWriter
{
public:
  static vtkSegmentationSVDAGWriter* New();
  vtkTypeMacro(vtkSegmentationSVDAGWriter, vtkWriter);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /** Name of the file to write. */
  vtkSetFilePathMacro(FileName);
  vtkGetFilePathMacro(FileName);
  ///@}

  ///@{
  /**
   * Format version 2 only: zstd level of the sections, 1 (fastest) to 22 (smallest); 0 stores
   * them uncompressed. Default 3. Sections that do not shrink are stored uncompressed whatever
   * the level.
   */
  vtkSetClampMacro(CompressionLevel, int, 0, 22);
  vtkGetMacro(CompressionLevel, int);
  ///@}

  ///@{
  /**
   * The .svdag format version written: 4 (default: small, and fast to load), 3 (the smallest
   * file, about a build's time to load) or 2 (readers older than format 3 read it).
   */
  vtkSetClampMacro(FormatVersion, int, 2, 4);
  vtkGetMacro(FormatVersion, int);
  ///@}

  ///@{
  /**
   * When on, Write() produces the file's bytes in memory (GetOutputBytes) instead of writing
   * FileName: to send a volume to another process (pickling, Dask) or to store it elsewhere.
   * Default off.
   */
  vtkSetMacro(WriteToOutputString, bool);
  vtkGetMacro(WriteToOutputString, bool);
  vtkBooleanMacro(WriteToOutputString, bool);
  ///@}

  /**
   * The bytes of the last Write() with WriteToOutputString on (one component per byte), or an
   * empty array. Read them back with vtkSegmentationVolumeReader's ReadFromInputString.
   */
  vtkUnsignedCharArray* GetOutputBytes();

protected:
  vtkSegmentationSVDAGWriter();
  ~vtkSegmentationSVDAGWriter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  void WriteData() override;

  char* FileName = nullptr;
  int CompressionLevel;
  int FormatVersion;
  bool WriteToOutputString = false;
  vtkNew<vtkUnsignedCharArray> OutputBytes;

private:
  vtkSegmentationSVDAGWriter(const vtkSegmentationSVDAGWriter&) = delete;
  void operator=(const vtkSegmentationSVDAGWriter&) = delete;
};

#endif
