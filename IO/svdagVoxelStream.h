// The voxels of a volume stored as one block of binary values in a file, raw or compressed
// (gzip or zlib), in x-fastest order: what NRRD and MetaImage files hold after their text
// header. Hands out slabs of z-slices in native byte order; values are of `valueSize` bytes
// (integers or floats: only their size matters here).
#ifndef svdagVoxelStream_h
#define svdagVoxelStream_h

#include "svdag/Volume.h"

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

class svdagVoxelStream
{
public:
  enum class Encoding
  {
    Raw,       // values start at dataOffset; slabs are read with a seek, in any order
    Compressed // a gzip or zlib stream starts at dataOffset; slabs must come in order
  };

  // Opens `fileName` (the data file: for attached headers the header file itself). For Raw,
  // checks that the file holds exactly the volume after dataOffset (no byte less, no byte
  // more); for Compressed, skips `skipAfterInflate` decompressed bytes, and the slab that
  // reaches the last z-slice also reads the stream to its end and verifies it (checksums,
  // sizes, nothing after it: svdagInflateStream). Throws svdagReadError.
  svdagVoxelStream(const std::string& fileName, Encoding encoding, uint64_t dataOffset,
    const svdag::Geometry& geometry, int valueSize, bool bigEndian,
    uint64_t skipAfterInflate = 0);
  ~svdagVoxelStream();
  svdagVoxelStream(const svdagVoxelStream&) = delete;
  svdagVoxelStream& operator=(const svdagVoxelStream&) = delete;

  void readSlab(int32_t z0, int32_t nz, void* dst);

  // Size of a file in bytes (0 if it cannot be read).
  static uint64_t fileSize(const std::string& fileName);

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
};

#endif
