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
  // `reader` gets its file name from the subclass, which then calls open().
  svdagVTKImageSlabSource(vtkSmartPointer<vtkAlgorithm> reader, const std::string& fileName);
  // Runs the information pass and fills Geometry and Type. Subclasses call it from their
  // constructor, adjust the geometry if their format needs to, then call checkGeometry().
  void open();
  // Slice of the reader's output (counted from its whole extent's first slice) that holds
  // slice z of the volume; NIfTI overrides it where vtkNIFTIImageReader reverses the slices.
  virtual int32_t readerSlice(int32_t z) const { return z; }
  // Switches to whole-image reads (call after open()); throws if the image cannot fit in memory.
  void readWhole();
  // Throws the error the wrapped reader reported since the last call, if any.
  void throwReaderError(const char* during);

  vtkSmartPointer<vtkAlgorithm> Reader;
  std::string FileName;

private:
  vtkSmartPointer<vtkCallbackCommand> ErrorObserver;
  std::string ErrorText;
  bool WholeRead = false; // update the whole image once and copy slabs out of it
  bool WholeReadDone = false;
  int WholeExtent[6] = { 0, -1, 0, -1, 0, -1 };
  int VTKScalarType = 0;
};

#endif
