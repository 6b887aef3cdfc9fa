// Common part of the sources that read through a VTK image reader (today vtkXMLImageDataReader): geometry and scalar type from the reader's
// information pass, then one update per slab with an update extent covering that slab's slices.
// The wrapped reader's errors (and those of its executive, XML parser and compressor) are caught
// with an ErrorEvent observer and rethrown as svdagReadError, so they reach the user through
// vtkSegmentationVolumeReader as one message, not also as VTK's own log lines.
#ifndef svdagVTKImageSlabSource_h
#define svdagVTKImageSlabSource_h

#include "svdagSlabSource.h"

#include "vtkSmartPointer.h"

#include <memory>
#include <string>

class vtkAlgorithm;

class svdagVTKImageSlabSource : public svdagSlabSource
{
public:
  ~svdagVTKImageSlabSource() override;
  void readSlab(int32_t z0, int32_t nz, void* dst) override;

protected:
  // `reader` gets its file name from the subclass, which then calls open().
  svdagVTKImageSlabSource(vtkSmartPointer<vtkAlgorithm> reader, const std::string& fileName);
  // Runs the information pass and fills Geometry and Type (Kind for float or double scalars,
  // which throw unless `allowFloat`). Subclasses call it from their constructor, adjust the
  // geometry if their format needs to, then call checkGeometry().
  void open(bool allowFloat);
  // The wrapped reader.
  vtkAlgorithm* reader() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
};

#endif
