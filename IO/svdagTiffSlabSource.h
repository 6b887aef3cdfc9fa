// Multi-page TIFF through libtiff: page k is z-slice k. Every page must have the same size and
// one integer sample per pixel (8, 16, 32 or 64 bits, signed or unsigned; or float32/float64,
// when allowed); stripped and tiled pages, any compression libtiff decodes. Spacing is 1 and
// origin 0 (TIFF resolution tags are not voxel sizes one can trust).
#ifndef svdagTiffSlabSource_h
#define svdagTiffSlabSource_h

#include "svdagSlabSource.h"

#include <memory>

class svdagTiffSlabSource : public svdagSlabSource
{
public:
  // Throws svdagReadError on float samples unless `allowFloat` (32 or 64 bits then; see
  // svdagSampleKind).
  explicit svdagTiffSlabSource(const std::string& fileName, bool allowFloat = false);
  ~svdagTiffSlabSource() override;
  const char* formatName() const override { return "TIFF"; }
  void readSlab(int32_t z0, int32_t nz, void* dst) override;
  // True if a file's first `size` bytes start with a TIFF or BigTIFF signature.
  static bool hasSignature(const uint8_t* head, size_t size);

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
};

#endif
