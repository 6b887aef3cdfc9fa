// MetaImage (.mha with the data inline, .mhd with a separate data file), raw or
// zlib-compressed, streamed slab by slab.
//
// The text header is parsed here and the data streamed like NRRD's (svdagVoxelStream): VTK 9.1's
// vtkMetaImageReader cannot serve slabs (it writes the whole image into an output allocated for
// the requested extent, overrunning it) and accepts a truncated file with only a console message,
// returning partly uninitialised voxels. Geometry: ElementSpacing (or ElementSize), Offset (or
// Origin/Position), TransformMatrix (ITK's convention: row a is the direction of axis a).
#ifndef svdagMetaImageSlabSource_h
#define svdagMetaImageSlabSource_h

#include "svdagSlabSource.h"

#include <memory>

class svdagMetaImageSlabSource : public svdagSlabSource
{
public:
  // Throws svdagReadError on float data unless `allowFloat` (see svdagSampleKind).
  explicit svdagMetaImageSlabSource(const std::string& fileName, bool allowFloat = false);
  ~svdagMetaImageSlabSource() override;
  const char* formatName() const override { return "MetaImage"; }
  void readSlab(int32_t z0, int32_t nz, void* dst) override;
  // True if the file's text header holds the MetaImage keys NDims, DimSize and ElementType.
  static bool canRead(const std::string& fileName);

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
};

#endif
