// NIfTI-1 and NIfTI-2 (.nii, .nii.gz, .hdr/.img pairs, either gzipped), with the header parsed
// here and the voxels streamed slab by slab like NRRD's (svdagVoxelStream): raw data must be
// exactly as long as the header says, gzip data is verified to its trailer.
//
// Voxels come out in the file's order, which is nibabel's array order (x fastest). The header
// is checked against the specification: sizeof_hdr 348 (540), the magic, dim[0] in 1..7 with
// every dimension past the third of size 1, dimensions >= 1, a known integer datatype (or
// float32/float64, when allowed) whose bitpix matches, vox_offset >= 352 (544) in single
// files, no scaling (scl_slope).
// Geometry is the file's affine as nibabel reads it: the sform if its code is set, else the
// qform, else the voxel sizes alone; spacing is the length of each column, direction the
// normalised columns, origin the translation (world = RAS+ as NIfTI defines it).
#ifndef svdagNiftiSlabSource_h
#define svdagNiftiSlabSource_h

#include "svdagSlabSource.h"

#include <memory>

class svdagNiftiSlabSource : public svdagSlabSource
{
public:
  // Throws svdagReadError on float32/float64 data unless `allowFloat` (see svdagSampleKind).
  explicit svdagNiftiSlabSource(const std::string& fileName, bool allowFloat = false);
  ~svdagNiftiSlabSource() override;
  const char* formatName() const override { return "NIfTI"; }
  void readSlab(int32_t z0, int32_t nz, void* dst) override;
  // True if the file (gzip-compressed or not) starts with a NIfTI-1 or NIfTI-2 header.
  static bool canRead(const std::string& fileName);

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
};

#endif
