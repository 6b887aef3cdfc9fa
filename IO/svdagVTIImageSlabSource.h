// VTK XML image data (.vti) through vtkXMLImageDataReader, one update extent per slab (the
// reader reads only the pieces and compressed blocks a slab needs). Geometry comes from the
// file's WholeExtent, Origin, Spacing and Direction.
#ifndef svdagVTIImageSlabSource_h
#define svdagVTIImageSlabSource_h

#include "svdagVTKImageSlabSource.h"

class svdagVTIImageSlabSource : public svdagVTKImageSlabSource
{
public:
  // Throws svdagReadError on float or double scalars unless `allowFloat` (see svdagSampleKind).
  explicit svdagVTIImageSlabSource(const std::string& fileName, bool allowFloat = false);
  const char* formatName() const override { return "VTKImageData"; }
  // True if the file is VTK XML with type="ImageData".
  static bool canRead(const std::string& fileName);
};

#endif
