// Float label files read as integer labels, value for value: what vtkSegmentationVolumeReader's
// CastFloatLabels (and so vtksvdag.read(..., cast="exact")) does for every format. The rule is
// cast_labels' in Python/vtksvdag/_labels.py: every value must be finite and a whole number, and
// the labels get the narrowest integer type holding all of them (unsigned when none is negative:
// uint8, uint16, uint32, uint64; else int8 .. int64).
//
// A wrapper around any source of float samples, in two streaming passes, so that memory stays
// one slab whatever the volume's size:
// - pass 1, when this source is constructed, reads every slab of the inner source: it finds the
//   minimum and maximum and the first value that is not finite or not whole, or that no integer
//   type holds together with the others (below -2^63; from 2^64 on; from 2^63 on when a value is
//   negative). "First" is cast_labels' first, in C order of the [x, y, z] array that to_numpy()
//   returns (the least x, then y, then z), so that every format names the same voxel;
// - pass 2 reopens the file (sources that decompress a stream cannot rewind) and converts each
//   slab the reader asks for.
// A failure throws a FileFormatError naming the file, the value (as Python's repr writes it), its
// (x, y, z) index and why; vtksvdag raises it as FloatLabelsError.
#ifndef svdagExactCastSlabSource_h
#define svdagExactCastSlabSource_h

#include "svdagSlabSource.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

class svdagExactCastSlabSource : public svdagSlabSource
{
public:
  using Opener = std::function<std::unique_ptr<svdagSlabSource>()>;
  // `source`: just opened, with float samples. `reopen` opens the same file again the same way
  // (for pass 2). Runs pass 1; throws svdagReadError.
  svdagExactCastSlabSource(
    std::unique_ptr<svdagSlabSource> source, Opener reopen, const std::string& fileName);
  ~svdagExactCastSlabSource() override;
  const char* formatName() const override { return this->FormatName.c_str(); }
  // Writes labels of scalarType(); throws a FileFormatError if a value is not what pass 1 saw
  // (the file changed in between).
  void readSlab(int32_t z0, int32_t nz, void* dst) override;

  // The message ending of a value refused (vtksvdag's Python code recognises it, as it is the
  // ending of cast_labels' messages).
  static constexpr const char* RefusalEnding =
    "only whole numbers that an integer type holds are accepted";

private:
  Opener Reopen;
  std::string FileName;
  std::string FormatName;
  svdagSampleKind FloatKind;
  double Low = 0, High = 0; // the values' range, for the check of pass 2
  std::unique_ptr<svdagSlabSource> Inner; // pass 2's source, opened at its first slab
  std::vector<uint8_t> Floats;            // one slab of the inner source's samples
};

#endif
