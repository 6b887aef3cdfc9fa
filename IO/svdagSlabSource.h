// A label volume file seen as a sequence of z-slabs: the reader asks a source for its geometry
// and scalar type (read from the header when the source is opened) and then for slabs of
// z-slices in increasing order, one call at a time, so that a slab or two are in memory at a
// time (the reader reads the next while it compresses one).
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

// What readSlab writes: integer labels of scalarType(), or floats. Sources report floats only
// when they are opened with floats allowed (svdagSlabSourceOptions::castFloatLabels), and the
// factory then wraps them in svdagExactCastSlabSource: the reader always receives labels.
enum class svdagSampleKind : uint8_t
{
  Integer,
  Float32,
  Float64
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
  // The label type; meaningless while sampleKind() is not Integer.
  svdag::ScalarType scalarType() const { return this->Type; }
  svdagSampleKind sampleKind() const { return this->Kind; }
  // Bytes of one sample: scalarSize(scalarType()) for labels, 4 or 8 for floats.
  int sampleSize() const;

  // Writes z-slices [z0, z0 + nz) into dst: dims[0] * dims[1] * nz samples (sampleKind(),
  // sampleSize()), x fastest, native byte order. Slabs are requested in increasing z without gaps (sources
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
  // For a file of floats of `bits` bits: sets Kind to Float32 or Float64 when `allowFloat`,
  // else (and for other widths: float16, float128) throws svdagThrowNotIntegerLabels naming
  // `fileName` and the type ("float32").
  void setFloatSamples(bool allowFloat, int bits, const std::string& fileName);

  svdag::Geometry Geometry;
  svdag::ScalarType Type = svdag::ScalarType::UInt8;
  svdagSampleKind Kind = svdagSampleKind::Integer;
  std::vector<std::string> Warnings;
};

// The most voxels a volume may have (2^40); checkGeometry refuses more.
constexpr uint64_t svdagMaxVoxels = uint64_t(1) << 40;

// The label type with this signedness and size in bytes (1, 2, 4 or 8); throws a
// FileFormatError naming `what` (for example "FILE has float32") for anything else.
svdag::ScalarType svdagIntegerScalarType(bool isSigned, int bytes, const std::string& what);
// "label volumes need integer scalars; FILE has TYPE".
[[noreturn]] void svdagThrowNotIntegerLabels(const std::string& fileName, const std::string& type);
// `value` as Python's repr() writes a float (numpy's for a float32 when `single`): the shortest
// digits that read back as the value, positional from 1e-4 to 1e16, else with an exponent
// ("0.5", "70000.0", "1.8446744073709552e+19", "nan", "-inf"), so that C++ messages name a
// value as vtksvdag's Python messages do.
std::string svdagFloatRepr(double value, bool single);
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
