// Picks the slab source for a file from its content (magic numbers, header keys), not from its
// extension, and opens it.
#ifndef svdagSlabSourceFactory_h
#define svdagSlabSourceFactory_h

#include "svdagSlabSource.h"

#include <memory>
#include <string>

struct svdagSlabSourceOptions
{
  std::string datasetName; // HDF5: the dataset to read; empty: the only 3D integer dataset
  // Float data (float32, float64) is read as integer labels, value for value, when every value
  // is a whole number (svdagExactCastSlabSource); off, it is refused. Integer files read the same
  // either way.
  bool castFloatLabels = false;
};

// The format a file holds ("NRRD", "MetaImage", "VTKImageData", "NIfTI", "TIFF", "HDF5",
// "SVDAG"), or an empty string when it is none of them or cannot be read. Never throws.
std::string svdagDetectFileFormat(const std::string& fileName);

// Opens the file with the source for its format and reads its header (with castFloatLabels and
// float data, the whole file: the check pass). The source returned always hands out integer
// labels. Throws svdagReadError: FileNotFoundError, UnrecognizedFileTypeError,
// FileFormatError, PrematureEndOfFileError, ...
std::unique_ptr<svdagSlabSource> svdagOpenSlabSource(
  const std::string& fileName, const svdagSlabSourceOptions& options);

#endif
