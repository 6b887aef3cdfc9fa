#include "svdagNiftiSlabSource.h"

#include "svdagVoxelStream.h"

#include "vtkErrorCode.h"
#include "vtk_zlib.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

namespace
{
[[noreturn]] void formatError(const std::string& message)
{
  throw svdagReadError(vtkErrorCode::FileFormatError, message);
}

// The first bytes of a file, decompressed if it is gzip (gzread passes other files through).
size_t readStart(const std::string& fileName, unsigned char* buffer, size_t size)
{
  gzFile f = gzopen(fileName.c_str(), "rb");
  if (!f)
    return 0;
  const int n = gzread(f, buffer, unsigned(size));
  gzclose(f);
  return n > 0 ? size_t(n) : 0;
}

bool isGzip(const std::string& fileName)
{
  std::FILE* f = std::fopen(fileName.c_str(), "rb");
  if (!f)
    return false;
  unsigned char m[2] = { 0, 0 };
  const bool gz = std::fread(m, 1, 2, f) == 2 && m[0] == 0x1f && m[1] == 0x8b;
  std::fclose(f);
  return gz;
}

// Reads little- or big-endian header fields.
struct HeaderBytes
{
  const unsigned char* bytes;
  bool swap;
  template <typename T>
  T get(size_t offset) const
  {
    unsigned char b[sizeof(T)];
    std::memcpy(b, this->bytes + offset, sizeof(T));
    if (this->swap)
      std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }
};

// NIfTI datatype codes -> (signed, bytes) of an integer type, (isFloat, bytes) of float32 and
// float64, or the name of any other type.
bool niftiType(int code, bool& isSigned, int& bytes, bool& isFloat, std::string& other)
{
  switch (code)
  {
    case 16: isFloat = true; bytes = 4; return true;
    case 64: isFloat = true; bytes = 8; return true;
    case 2: isSigned = false; bytes = 1; return true;
    case 4: isSigned = true; bytes = 2; return true;
    case 8: isSigned = true; bytes = 4; return true;
    case 256: isSigned = true; bytes = 1; return true;
    case 512: isSigned = false; bytes = 2; return true;
    case 768: isSigned = false; bytes = 4; return true;
    case 1024: isSigned = true; bytes = 8; return true;
    case 1280: isSigned = false; bytes = 8; return true;
    case 1: other = "1-bit binary"; return false;
    case 1536: other = "float128"; return false;
    case 32: other = "complex64"; return false;
    case 1792: other = "complex128"; return false;
    case 2048: other = "complex256"; return false;
    case 128: other = "RGB (3 x uint8)"; return false;
    case 2304: other = "RGBA (4 x uint8)"; return false;
    default: other.clear(); return false;
  }
}
}

struct svdagNiftiSlabSource::Impl
{
  std::unique_ptr<svdagVoxelStream> voxels;
};

svdagNiftiSlabSource::svdagNiftiSlabSource(const std::string& fileName, bool allowFloat)
  : impl(new Impl)
{
  unsigned char h[544] = {};
  const size_t got = readStart(fileName, h, sizeof(h));
  if (got < 4)
    throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
      fileName + ": too short for a NIfTI header");
  int32_t sizeofHdr = 0;
  std::memcpy(&sizeofHdr, h, 4);
  bool swap = false;
  if (sizeofHdr != 348 && sizeofHdr != 540)
  {
    HeaderBytes swapped{ h, true };
    sizeofHdr = swapped.get<int32_t>(0);
    swap = true;
  }
  if (sizeofHdr != 348 && sizeofHdr != 540)
    formatError(fileName + ": sizeof_hdr is not 348 (NIfTI-1) or 540 (NIfTI-2)");
  const bool nifti2 = sizeofHdr == 540;
  if (got < size_t(sizeofHdr))
    throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
      fileName + ": the file ends inside its " + std::to_string(sizeofHdr) +
        "-byte NIfTI header (truncated file?)");
  const HeaderBytes hb{ h, swap };

  // Magic: data in this file ("n+1", "n+2") or in a separate .img ("ni1", "ni2").
  const unsigned char* magic = nifti2 ? h + 4 : h + 344;
  bool single = false;
  if (std::memcmp(magic, nifti2 ? "n+2" : "n+1", 4) == 0)
    single = true;
  else if (std::memcmp(magic, nifti2 ? "ni2" : "ni1", 4) != 0)
    formatError(fileName + ": bad NIfTI magic (not a NIfTI-1/-2 file)");
  if (nifti2 && std::memcmp(h + 8, "\r\n\032\n", 4) != 0)
    formatError(fileName + ": the NIfTI-2 magic is not followed by \\r\\n\\032\\n (file converted "
                           "as text?)");

  // Dimensions: dim[0] in 1..7; axes past the third must be 1.
  int64_t dim[8] = { 0 };
  for (int i = 0; i < 8; ++i)
    dim[i] = nifti2 ? hb.get<int64_t>(16 + 8 * size_t(i)) : hb.get<int16_t>(40 + 2 * size_t(i));
  if (dim[0] < 1 || dim[0] > 7)
    formatError(fileName + ": NIfTI dim[0] = " + std::to_string(dim[0]) +
      ", must be 1 to 7 (corrupt header or wrong byte order)");
  for (int d = 1; d <= dim[0]; ++d)
  {
    if (dim[d] < 1)
      formatError(fileName + ": NIfTI dim[" + std::to_string(d) + "] = " +
        std::to_string(dim[d]) + ", must be at least 1");
  }
  for (int d = 4; d <= dim[0]; ++d)
  {
    if (dim[d] > 1)
      formatError(fileName + " has " + std::to_string(dim[0]) + " dimensions (dim[" +
        std::to_string(d) + "] = " + std::to_string(dim[d]) + "); label volumes need 3");
  }
  for (int a = 0; a < 3; ++a)
  {
    const int64_t n = a + 1 <= dim[0] ? dim[a + 1] : 1;
    if (n > INT32_MAX)
      formatError(fileName + ": NIfTI dim[" + std::to_string(a + 1) + "] = " +
        std::to_string(n) + " is more than 2^31-1");
    this->Geometry.dims[a] = int32_t(n);
  }

  // Datatype and bitpix.
  const int datatype = nifti2 ? hb.get<int16_t>(12) : hb.get<int16_t>(70);
  const int bitpix = nifti2 ? hb.get<int16_t>(14) : hb.get<int16_t>(72);
  bool isSigned = false, isFloat = false;
  int bytes = 0;
  std::string other;
  if (!niftiType(datatype, isSigned, bytes, isFloat, other))
  {
    if (other.empty())
      formatError(fileName + ": unknown NIfTI datatype " + std::to_string(datatype));
    svdagThrowNotIntegerLabels(fileName, other);
  }
  if (isFloat)
    this->setFloatSamples(allowFloat, 8 * bytes, fileName);
  if (bitpix != 8 * bytes)
    formatError(fileName + ": NIfTI bitpix " + std::to_string(bitpix) + " does not match datatype " +
      std::to_string(datatype) + " (" + std::to_string(8 * bytes) + " bits)");
  if (!isFloat)
    this->Type = svdagIntegerScalarType(isSigned, bytes, fileName);

  // Scaled values are not labels. A slope of 0 (or NaN, as nibabel writes) means no scaling.
  const double slope = nifti2 ? hb.get<double>(176) : hb.get<float>(112);
  const double inter = nifti2 ? hb.get<double>(184) : hb.get<float>(116);
  const bool scaled = std::isfinite(slope) && slope != 0 &&
    (slope != 1 || (std::isfinite(inter) && inter != 0));
  if (scaled)
    formatError(fileName + " scales its values (scl_slope " + std::to_string(slope) +
      ", scl_inter " + std::to_string(inter) + "); label volumes need unscaled integers");

  // vox_offset: where the voxels start in the data file.
  const double voxOffset = nifti2 ? double(hb.get<int64_t>(168)) : double(hb.get<float>(108));
  const int64_t minOffset = single ? sizeofHdr + 4 : 0;
  if (!std::isfinite(voxOffset) || voxOffset != std::floor(voxOffset) ||
    voxOffset < double(minOffset) || voxOffset > 9.0e15)
    formatError(fileName + ": NIfTI vox_offset " + std::to_string(voxOffset) + " is invalid (" +
      (single ? "must be a whole number >= " + std::to_string(minOffset) +
            " in a single-file NIfTI"
              : std::string("must be a whole number >= 0")) +
      ")");

  // The index-to-world affine (3x4, row-major), as nibabel's img.affine.
  double pixdim[8];
  for (int i = 0; i < 8; ++i)
    pixdim[i] = nifti2 ? hb.get<double>(104 + 8 * size_t(i)) : hb.get<float>(76 + 4 * size_t(i));
  const int qformCode = nifti2 ? hb.get<int32_t>(344) : hb.get<int16_t>(252);
  const int sformCode = nifti2 ? hb.get<int32_t>(348) : hb.get<int16_t>(254);
  auto real = [&](size_t offset1, size_t offset2) {
    return nifti2 ? hb.get<double>(offset2) : double(hb.get<float>(offset1));
  };
  double m[3][4] = { { 0 } };
  if (sformCode > 0)
  {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        m[r][c] = real(280 + 16 * size_t(r) + 4 * size_t(c), 400 + 32 * size_t(r) + 8 * size_t(c));
  }
  else if (qformCode > 0)
  {
    const double b = real(256, 352), c = real(260, 360), d = real(264, 368);
    const double a = std::sqrt(std::max(0.0, 1.0 - (b * b + c * c + d * d)));
    const double r[3][3] = {
      { a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c) },
      { 2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b) },
      { 2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - b * b - c * c },
    };
    const double qfac = pixdim[0] < 0 ? -1.0 : 1.0;
    const double zoom[3] = { pixdim[1], pixdim[2], qfac * pixdim[3] };
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        m[i][j] = r[i][j] * zoom[j];
    m[0][3] = real(268, 376);
    m[1][3] = real(272, 384);
    m[2][3] = real(276, 392);
  }
  else
  {
    for (int i = 0; i < 3; ++i)
      m[i][i] = pixdim[i + 1];
  }
  for (int j = 0; j < 3; ++j)
  {
    const double norm = std::sqrt(m[0][j] * m[0][j] + m[1][j] * m[1][j] + m[2][j] * m[2][j]);
    if (!(norm > 0) || !std::isfinite(norm))
      formatError(fileName + ": the voxel size along axis " + std::to_string(j) +
        " is zero or invalid");
    this->Geometry.spacing[j] = norm;
    for (int i = 0; i < 3; ++i)
      this->Geometry.direction[3 * i + j] = m[i][j] / norm;
  }
  for (int i = 0; i < 3; ++i)
    this->Geometry.origin[i] = m[i][3];
  this->checkGeometry(fileName);

  // The data: after the header in a single file, else in the .img next to the .hdr.
  std::string dataFileName = fileName;
  if (!single)
  {
    const std::string lower = svdagLower(fileName);
    size_t at = std::string::npos;
    if (lower.size() >= 4 && lower.compare(lower.size() - 4, 4, ".hdr") == 0)
      at = lower.size() - 3;
    else if (lower.size() >= 7 && lower.compare(lower.size() - 7, 7, ".hdr.gz") == 0)
      at = lower.size() - 6;
    if (at == std::string::npos)
      formatError(fileName + ": a NIfTI header of a .hdr/.img pair must be named .hdr or .hdr.gz");
    dataFileName.replace(at, 3, std::isupper(static_cast<unsigned char>(fileName[at])) ? "IMG" : "img");
    std::FILE* data = std::fopen(dataFileName.c_str(), "rb");
    if (data)
      std::fclose(data);
    else
      throw svdagReadError(vtkErrorCode::FileNotFoundError,
        fileName + ": cannot open its data file " + dataFileName);
  }
  const bool bigEndian = svdagHostIsLittleEndian() == swap;
  if (isGzip(dataFileName))
    impl->voxels.reset(new svdagVoxelStream(dataFileName, svdagVoxelStream::Encoding::Compressed,
      0, this->Geometry, this->sampleSize(), bigEndian, uint64_t(voxOffset)));
  else
    impl->voxels.reset(new svdagVoxelStream(dataFileName, svdagVoxelStream::Encoding::Raw,
      uint64_t(voxOffset), this->Geometry, this->sampleSize(), bigEndian));
}

svdagNiftiSlabSource::~svdagNiftiSlabSource() = default;

void svdagNiftiSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  impl->voxels->readSlab(z0, nz, dst);
}

bool svdagNiftiSlabSource::canRead(const std::string& fileName)
{
  unsigned char h[352] = {};
  if (readStart(fileName, h, sizeof(h)) < 348)
    return false;
  int32_t size = 0;
  std::memcpy(&size, h, 4);
  const int32_t swapped = int32_t((uint32_t(size) >> 24) | ((uint32_t(size) >> 8) & 0xff00) |
    ((uint32_t(size) << 8) & 0xff0000) | (uint32_t(size) << 24));
  auto is = [&](int32_t v) { return size == v || swapped == v; };
  if (is(348))
    return std::memcmp(h + 344, "n+1\0", 4) == 0 || std::memcmp(h + 344, "ni1\0", 4) == 0;
  if (is(540))
    return std::memcmp(h + 4, "n+2\0", 4) == 0 || std::memcmp(h + 4, "ni2\0", 4) == 0;
  return false;
}
