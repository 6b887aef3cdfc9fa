// NRRD label volumes: attached (.nrrd) or detached (.nhdr + data file) headers, raw or gzip
// encoding, any integer type under any NRRD spelling, either byte order. Geometry comes from
// "space directions" + "space origin" (or "spacings"), in the file's own space (no LPS/RAS
// conversion). 3D Slicer .seg.nrrd files are read when they hold one 3D labelmap layer; a 4D
// multi-layer segmentation is rejected with a message saying so.
//
// VTK 9.1's vtkNrrdReader decodes no gzip, so the header is parsed here (small and strict) and
// the data is streamed slab by slab (gzip through zlib's inflate).
#ifndef svdagNrrdSlabSource_h
#define svdagNrrdSlabSource_h

#include "svdagSlabSource.h"

#include <memory>

class svdagNrrdSlabSource : public svdagSlabSource
{
public:
  // Parses the header; throws svdagReadError on a missing file or a bad header, and on float
  // data unless `allowFloat` (then the samples are floats, see svdagSampleKind).
  explicit svdagNrrdSlabSource(const std::string& fileName, bool allowFloat = false);
  ~svdagNrrdSlabSource() override;
  const char* formatName() const override { return "NRRD"; }
  void readSlab(int32_t z0, int32_t nz, void* dst) override;

  // True if a file's first `size` bytes start with the NRRD magic ("NRRD000").
  static bool hasSignature(const uint8_t* head, size_t size);

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
};

#endif
