// MetaImage (.mha with the data inline, .mhd with a separate data file; raw or zlib-compressed)
// through vtkMetaImageReader. Not streamed: VTK 9.1's reader writes the whole image into its
// output whatever update extent is asked for (a slab extent overruns the output buffer), so the
// image is read once, whole, and slabs are copied out of it.
#ifndef svdagMetaImageSlabSource_h
#define svdagMetaImageSlabSource_h

#include "svdagVTKImageSlabSource.h"

class svdagMetaImageSlabSource : public svdagVTKImageSlabSource
{
public:
  explicit svdagMetaImageSlabSource(const std::string& fileName);
  const char* formatName() const override { return "MetaImage"; }
  // True if the file's text header holds the MetaImage keys NDims and DimSize.
  static bool canRead(const std::string& fileName);
};

#endif
