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
};

// The format a file holds ("NRRD", "MetaImage", "VTKImageData", "NIfTI", "TIFF", "HDF5",
// "SVDAG"), or an empty string when it is none of them or cannot be read. Never throws.
std::string svdagDetectFileFormat(const std::string& fileName);

// Opens the file with the source for its format and reads its header. Throws svdagReadError:
// FileNotFoundError, UnrecognizedFileTypeError, FileFormatError, PrematureEndOfFileError, ...
std::unique_ptr<svdagSlabSource> svdagOpenSlabSource(
  const std::string& fileName, const svdagSlabSourceOptions& options);

#endif
