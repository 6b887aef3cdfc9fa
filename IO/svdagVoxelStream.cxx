#include "svdagVoxelStream.h"

#include "svdagInflateStream.h"
#include "svdagSlabSource.h"

#include "vtkErrorCode.h"

#include <sys/stat.h>

namespace
{
// Deflate's best ratio is 1032:1 (a run of zeros); twice that leaves margin for any encoder.
constexpr uint64_t MaxDeflateRatio = 2048;
}

struct svdagVoxelStream::Impl
{
  std::string fileName;
  std::FILE* file = nullptr;
  std::unique_ptr<svdagInflateStream> inflater; // Compressed only
  uint64_t dataOffset = 0;
  uint64_t sliceValues = 0;
  int32_t depth = 0;
  int size = 1;
  bool swap = false;
  int32_t nextZ = 0; // Compressed: the slab the stream is positioned at

  ~Impl()
  {
    this->inflater.reset();
    if (this->file)
      std::fclose(this->file);
  }
};

uint64_t svdagVoxelStream::fileSize(const std::string& fileName)
{
  struct stat st;
  return stat(fileName.c_str(), &st) == 0 ? uint64_t(st.st_size) : 0;
}

svdagVoxelStream::svdagVoxelStream(const std::string& fileName, Encoding encoding,
  uint64_t dataOffset, const svdag::Geometry& geometry, int valueSize, bool bigEndian,
  uint64_t skipAfterInflate)
  : impl(new Impl)
{
  impl->fileName = fileName;
  impl->dataOffset = dataOffset;
  impl->sliceValues = uint64_t(geometry.dims[0]) * uint64_t(geometry.dims[1]);
  impl->depth = geometry.dims[2];
  impl->size = valueSize;
  impl->swap = impl->size > 1 && bigEndian == svdagHostIsLittleEndian();
  impl->file = std::fopen(fileName.c_str(), "rb");
  if (!impl->file)
    throw svdagReadError(vtkErrorCode::CannotOpenFileError, "cannot open " + fileName);

  const uint64_t total = impl->sliceValues * uint64_t(impl->depth) * uint64_t(impl->size);
  const uint64_t size = fileSize(fileName);
  if (encoding == Encoding::Raw)
  {
    // The body must be exactly the voxels: a shorter one is truncated, a longer one is not
    // what its header says (wrong sizes or type, or another file's data appended).
    const uint64_t held = size > dataOffset ? size - dataOffset : 0;
    if (held < total)
      throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
        fileName + " holds " + std::to_string(held) + " data bytes, the header describes " +
          std::to_string(total) + " (truncated file?)");
    if (held > total)
      throw svdagReadError(vtkErrorCode::FileFormatError,
        fileName + " holds " + std::to_string(held) + " data bytes, " +
          std::to_string(held - total) + " more than the " + std::to_string(total) +
          " the header describes");
  }
  else
  {
    if (dataOffset >= size || fseeko(impl->file, off_t(dataOffset), SEEK_SET) != 0)
      throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
        fileName + ": no compressed data after the header (truncated file?)");
    // Deflate cannot compress better than about 1032:1, so a header that claims far more voxels
    // than the compressed bytes can hold is wrong; say so before anything is allocated.
    if ((size - dataOffset) * MaxDeflateRatio < total)
      throw svdagReadError(vtkErrorCode::FileFormatError,
        fileName + ": the header describes " + std::to_string(total) + " bytes of voxels, more "
          "than its " + std::to_string(size - dataOffset) + " compressed bytes can hold");
    impl->inflater.reset(new svdagInflateStream(impl->file, fileName));
    impl->inflater->skip(skipAfterInflate);
  }
}

svdagVoxelStream::~svdagVoxelStream() = default;

void svdagVoxelStream::readSlab(int32_t z0, int32_t nz, void* dst)
{
  if (z0 < 0 || nz < 1 || nz > impl->depth - z0)
    throw svdagReadError(vtkErrorCode::FileFormatError, "slab outside the volume");
  const uint64_t values = impl->sliceValues * uint64_t(nz);
  const uint64_t bytes = values * uint64_t(impl->size);
  if (impl->inflater)
  {
    if (z0 != impl->nextZ)
      throw svdagReadError(vtkErrorCode::FileFormatError,
        impl->fileName + ": compressed slabs must be read in order");
    impl->inflater->read(dst, bytes);
    impl->nextZ = z0 + nz;
    // After the last slab the stream must end: trailer checksums, no data left over.
    if (impl->nextZ == impl->depth)
      impl->inflater->finish();
  }
  else
  {
    const uint64_t at = impl->dataOffset + impl->sliceValues * uint64_t(z0) * uint64_t(impl->size);
    if (fseeko(impl->file, off_t(at), SEEK_SET) != 0 ||
      std::fread(dst, 1, bytes, impl->file) != bytes)
      throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
        impl->fileName + ": cannot read z-slices " + std::to_string(z0) + ".." +
          std::to_string(z0 + nz - 1) + " (file truncated while reading?)");
  }
  if (impl->swap)
    svdagSwapBytes(dst, values, impl->size);
}
