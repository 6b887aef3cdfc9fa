// A label volume file seen as a sequence of z-slabs: the reader asks a source for its geometry
// and scalar type (read from the header when the source is opened) and then for slabs of
// z-slices in increasing order, so that only one slab is in memory at a time.
//
// One subclass per file format (svdag<Format>SlabSource). Sources are not VTK objects: they
// report failures by throwing svdagReadError, which carries the vtkErrorCode the reader sets.
#ifndef svdagSlabSource_h
#define svdagSlabSource_h

#include "svdag/Volume.h"

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

// A failure to read a file, with the vtkErrorCode::ErrorIds value that describes it.
class svdagReadError : public std::runtime_error
{
public:
  svdagReadError(unsigned long code, const std::string& message)
    : std::runtime_error(message)
    , Code(code)
  {
  }
  unsigned long code() const { return this->Code; }

private:
  unsigned long Code;
};

class svdagSlabSource
{
public:
  virtual ~svdagSlabSource() = default;
  svdagSlabSource(const svdagSlabSource&) = delete;
  svdagSlabSource& operator=(const svdagSlabSource&) = delete;

  // Short name of the format ("NRRD", "NIfTI", ...).
  virtual const char* formatName() const = 0;
  const svdag::Geometry& geometry() const { return this->Geometry; }
  svdag::ScalarType scalarType() const { return this->Type; }

  // Writes z-slices [z0, z0 + nz) into dst: dims[0] * dims[1] * nz values of scalarType(),
  // x fastest, native byte order. Slabs are requested in increasing z without gaps (sources
  // that decompress a stream rely on it). Throws svdagReadError.
  virtual void readSlab(int32_t z0, int32_t nz, void* dst) = 0;

  // Sources of already compressed files (.svdag) return their volume, so the reader can pass
  // it through when no label needs to change; every other source returns null.
  virtual std::shared_ptr<const svdag::Volume> compressedVolume() const { return nullptr; }

  // Remarks about a file that is read all the same (an HDF5 dataset whose unwritten chunks
  // read as its fill value, a VTK reader's warning), in the order found; the list grows while
  // the source is opened and read. vtkSegmentationVolumeReader passes each on as a VTK warning.
  const std::vector<std::string>& warnings() const { return this->Warnings; }

protected:
  svdagSlabSource() = default;

  // Throws a FileFormatError naming the file when the geometry cannot be compressed (absurd
  // dimensions: more than svdagMaxVoxels, zero spacing, ...). Every source calls it before it
  // allocates anything or multiplies the dimensions.
  void checkGeometry(const std::string& fileName) const;
  // Throws a FileFormatError when (z0, nz) is not a slab inside the volume.
  void checkSlab(int32_t z0, int32_t nz) const;

  svdag::Geometry Geometry;
  svdag::ScalarType Type = svdag::ScalarType::UInt8;
  std::vector<std::string> Warnings;
};

// The most voxels a volume may have (2^40); checkGeometry refuses more.
constexpr uint64_t svdagMaxVoxels = uint64_t(1) << 40;

// The label type with this signedness and size in bytes (1, 2, 4 or 8); throws a
// FileFormatError naming `what` (for example "FILE has float32") for anything else.
svdag::ScalarType svdagIntegerScalarType(bool isSigned, int bytes, const std::string& what);
// "label volumes need integer scalars; FILE has TYPE".
[[noreturn]] void svdagThrowNotIntegerLabels(const std::string& fileName, const std::string& type);
// Header-text helpers of the text-header formats (NRRD, MetaImage): `s` without leading and
// trailing blanks (space, tab, CR), and `s` in lower case (ASCII).
std::string svdagTrim(const std::string& s);
std::string svdagLower(std::string s);
// Reverses the byte order of `count` values of `size` bytes in place.
void svdagSwapBytes(void* data, size_t count, int size);
// Bytes of physical memory on this machine (0 if unknown): the bound for any one buffer.
uint64_t svdagPhysicalMemoryBytes();
// True on little-endian hosts.
bool svdagHostIsLittleEndian();

#endif
