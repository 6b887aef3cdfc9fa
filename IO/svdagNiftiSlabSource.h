// NIfTI-1 and NIfTI-2 (.nii, .nii.gz, .hdr/.img pairs) through vtkNIFTIImageReader, one update
// extent per slab. Voxels come out in the file's order, which is nibabel's array order (x
// fastest): where vtkNIFTIImageReader reverses the slices (qfac = -1) the reversal is undone;
// such files are read whole, not by slab (see the .cxx).
// Geometry is the file's affine as nibabel reads it: the sform if its code is set, else the
// qform, else the voxel sizes alone; spacing is the length of each column, direction the
// normalised columns, origin the translation (world = RAS+ as NIfTI defines it).
#ifndef svdagNiftiSlabSource_h
#define svdagNiftiSlabSource_h

#include "svdagVTKImageSlabSource.h"

class svdagNiftiSlabSource : public svdagVTKImageSlabSource
{
public:
  explicit svdagNiftiSlabSource(const std::string& fileName);
  const char* formatName() const override { return "NIfTI"; }
  // True if the file (gzip-compressed or not) starts with a NIfTI-1 or NIfTI-2 header.
  static bool canRead(const std::string& fileName);

protected:
  int32_t readerSlice(int32_t z) const override
  {
    return this->SlicesReversed ? this->Geometry.dims[2] - 1 - z : z;
  }

private:
  bool SlicesReversed = false;
};

#endif
