#include "svdagNiftiSlabSource.h"

#include "vtkErrorCode.h"
#include "vtkNIFTIImageHeader.h"
#include "vtkNIFTIImageReader.h"
#include "vtk_zlib.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

svdagNiftiSlabSource::svdagNiftiSlabSource(const std::string& fileName)
  : svdagVTKImageSlabSource(vtkSmartPointer<vtkNIFTIImageReader>::New(), fileName)
{
  auto* reader = vtkNIFTIImageReader::SafeDownCast(this->Reader);
  reader->SetFileName(fileName.c_str());
  this->open();
  vtkNIFTIImageHeader* header = reader->GetNIFTIHeader();
  if (!header)
    throw svdagReadError(vtkErrorCode::FileFormatError, fileName + ": no NIfTI header");

  // Only 3D volumes: a 4th or 5th dimension (time, vector components) must be 1.
  for (int d = 4; d <= header->GetDim(0) && d <= 7; ++d)
  {
    if (header->GetDim(d) > 1)
      throw svdagReadError(vtkErrorCode::FileFormatError,
        fileName + " has " + std::to_string(header->GetDim(0)) +
          " dimensions (dim[" + std::to_string(d) + "] = " + std::to_string(header->GetDim(d)) +
          "); label volumes need 3");
  }
  // Scaled values are not labels. A slope of 0 (or NaN, as nibabel writes) means no scaling.
  const double slope = header->GetSclSlope();
  const double inter = header->GetSclInter();
  const bool scaled = std::isfinite(slope) && slope != 0 &&
    (slope != 1 || (std::isfinite(inter) && inter != 0));
  if (scaled)
    throw svdagReadError(vtkErrorCode::FileFormatError,
      fileName + " scales its values (scl_slope " + std::to_string(slope) + ", scl_inter " +
        std::to_string(inter) + "); label volumes need unscaled integers");

  // With qfac = -1, vtkNIFTIImageReader reverses the slices. VTK 9.1 does that correctly for
  // the whole image only: with a sub-extent it reads the file's slices of that extent and
  // reverses them within the slab. Such files are read whole (and the reversal undone).
  this->SlicesReversed = reader->GetQFac() < 0;
  if (this->SlicesReversed)
    this->readWhole();

  // The index-to-world affine (3x4, row-major), as nibabel's img.affine.
  double m[3][4] = { { 0 } };
  if (header->GetSFormCode() > 0)
  {
    header->GetSRowX(m[0]);
    header->GetSRowY(m[1]);
    header->GetSRowZ(m[2]);
  }
  else if (header->GetQFormCode() > 0)
  {
    const double b = header->GetQuaternB(), c = header->GetQuaternC(), d = header->GetQuaternD();
    const double a = std::sqrt(std::max(0.0, 1.0 - (b * b + c * c + d * d)));
    const double r[3][3] = {
      { a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c) },
      { 2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b) },
      { 2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - b * b - c * c },
    };
    const double qfac = header->GetPixDim(0) < 0 ? -1.0 : 1.0;
    const double zoom[3] = { header->GetPixDim(1), header->GetPixDim(2),
      qfac * header->GetPixDim(3) };
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        m[i][j] = r[i][j] * zoom[j];
    m[0][3] = header->GetQOffsetX();
    m[1][3] = header->GetQOffsetY();
    m[2][3] = header->GetQOffsetZ();
  }
  else
  {
    for (int i = 0; i < 3; ++i)
      m[i][i] = header->GetPixDim(i + 1);
  }
  for (int j = 0; j < 3; ++j)
  {
    const double norm = std::sqrt(m[0][j] * m[0][j] + m[1][j] * m[1][j] + m[2][j] * m[2][j]);
    if (!(norm > 0) || !std::isfinite(norm))
      throw svdagReadError(vtkErrorCode::FileFormatError,
        fileName + ": the voxel size along axis " + std::to_string(j) + " is zero or invalid");
    this->Geometry.spacing[j] = norm;
    for (int i = 0; i < 3; ++i)
      this->Geometry.direction[3 * i + j] = m[i][j] / norm;
  }
  for (int i = 0; i < 3; ++i)
    this->Geometry.origin[i] = m[i][3];
  this->checkGeometry(fileName);
}

bool svdagNiftiSlabSource::canRead(const std::string& fileName)
{
  // gzread reads uncompressed files as they are, so one path serves .nii and .nii.gz.
  gzFile f = gzopen(fileName.c_str(), "rb");
  if (!f)
    return false;
  unsigned char h[352] = {};
  const int n = gzread(f, h, sizeof(h));
  gzclose(f);
  if (n < 348)
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
