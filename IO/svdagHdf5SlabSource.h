// HDF5 through the HDF5 C library: a 3D integer dataset stored (z, y, x) in C order, the way
// h5py writes a numpy array (the last axis is x). Each slab is one hyperslab read. The dataset
// is the one named with SetDatasetName, or the only 3D integer dataset in the file (where there
// is none, the only 3D float dataset, which only a source allowing floats reads). Spacing is 1 and origin 0. A
// chunked dataset's chunk index is checked when the source is opened (every chunk HDF5 would
// read found, chunks never written reported as fill value warnings).
#ifndef svdagHdf5SlabSource_h
#define svdagHdf5SlabSource_h

#include "svdagSlabSource.h"

#include <memory>

class svdagHdf5SlabSource : public svdagSlabSource
{
public:
  // With `allowFloat`, float datasets are read too (as native float or double samples, see
  // svdagSampleKind).
  svdagHdf5SlabSource(
    const std::string& fileName, const std::string& datasetName, bool allowFloat = false);
  ~svdagHdf5SlabSource() override;
  const char* formatName() const override { return "HDF5"; }
  void readSlab(int32_t z0, int32_t nz, void* dst) override;
  // True if the file starts with the HDF5 signature (at offset 0, or after a user block).
  static bool hasMagic(const std::string& fileName);
  // Up to this many chunks, each chunk of a chunked dataset's index is also listed and checked
  // on its own (see checkChunkIndex; HDF5 1.10 lists them in quadratic time).
  static constexpr uint64_t ListedChunkLimit = 4096;

private:
  // Throws when the chunk index of the (chunked) dataset misses chunks or is corrupt; warns
  // of chunks never written. `plist`: the dataset's creation property list.
  void checkChunkIndex(int64_t plist);

  struct Impl;
  std::unique_ptr<Impl> impl;
};

#endif
