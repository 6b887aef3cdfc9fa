// Common part of the sources that read through a VTK image reader (vtkXMLImageDataReader,
// vtkNIFTIImageReader, vtkMetaImageReader): geometry and scalar type from the reader's
// information pass, then one update per slab with an update extent covering that slab's slices.
// The wrapped reader's errors are caught with an ErrorEvent observer and rethrown as
// svdagReadError, so they reach the user through vtkSegmentationVolumeReader.
#ifndef svdagVTKImageSlabSource_h
#define svdagVTKImageSlabSource_h

#include "svdagSlabSource.h"

#include "vtkSmartPointer.h"

#include <string>

class vtkAlgorithm;
class vtkCallbackCommand;

class svdagVTKImageSlabSource : public svdagSlabSource
{
public:
  ~svdagVTKImageSlabSource() override;
  void readSlab(int32_t z0, int32_t nz, void* dst) override;

protected:
  // `reader` has its file name set. With wholeRead the reader is updated once for the whole
  // image (for readers that cannot produce a sub-extent) and slabs are copied out of it.
  svdagVTKImageSlabSource(
    vtkSmartPointer<vtkAlgorithm> reader, const std::string& fileName, bool wholeRead);
  // Runs the information pass and fills Geometry and Type. Subclasses call it from their
  // constructor (then adjust the geometry if their format needs to).
  void open();
  // Slice of the reader's output (counted from its whole extent's first slice) that holds
  // slice z of the volume; NIfTI overrides it where vtkNIFTIImageReader reverses the slices.
  virtual int32_t readerSlice(int32_t z) const { return z; }
  // Throws the error the wrapped reader reported since the last call, if any.
  void throwReaderError(const char* during);

  vtkSmartPointer<vtkAlgorithm> Reader;
  std::string FileName;
  // Update the whole image once and copy slabs out of it (set before the first readSlab).
  bool WholeRead = false;

private:
  vtkSmartPointer<vtkCallbackCommand> ErrorObserver;
  std::string ErrorText;
  bool WholeReadDone = false;
  int WholeExtent[6] = { 0, -1, 0, -1, 0, -1 };
  int VTKScalarType = 0;
};

#endif
