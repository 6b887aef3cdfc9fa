#include "svdagSlabSourceFactory.h"

#include "svdagHdf5SlabSource.h"
#include "svdagMetaImageSlabSource.h"
#include "svdagNiftiSlabSource.h"
#include "svdagNrrdSlabSource.h"
#include "svdagSVDAGFileSlabSource.h"
#include "svdagTiffSlabSource.h"
#include "svdagVTIImageSlabSource.h"

#include "vtkErrorCode.h"

#include <sys/stat.h>

std::string svdagDetectFileFormat(const std::string& fileName)
{
  try
  {
    struct stat st;
    if (stat(fileName.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
      return "";
    // Binary signatures first, text headers last.
    if (svdagNrrdSlabSource::hasMagic(fileName))
      return "NRRD";
    if (svdagSVDAGFileSlabSource::hasMagic(fileName))
      return "SVDAG";
    if (svdagHdf5SlabSource::hasMagic(fileName))
      return "HDF5";
    if (svdagTiffSlabSource::hasMagic(fileName))
      return "TIFF";
    if (svdagNiftiSlabSource::canRead(fileName))
      return "NIfTI";
    if (svdagVTIImageSlabSource::canRead(fileName))
      return "VTKImageData";
    if (svdagMetaImageSlabSource::canRead(fileName))
      return "MetaImage";
  }
  catch (const std::exception&)
  {
  }
  return "";
}

std::unique_ptr<svdagSlabSource> svdagOpenSlabSource(
  const std::string& fileName, const svdagSlabSourceOptions& options)
{
  struct stat st;
  if (fileName.empty() || stat(fileName.c_str(), &st) != 0)
    throw svdagReadError(vtkErrorCode::FileNotFoundError, "file not found: " + fileName);
  if (!S_ISREG(st.st_mode))
    throw svdagReadError(vtkErrorCode::CannotOpenFileError, fileName + " is not a regular file");
  const std::string format = svdagDetectFileFormat(fileName);
  std::unique_ptr<svdagSlabSource> source;
  if (format == "NRRD")
    source.reset(new svdagNrrdSlabSource(fileName));
  else if (format == "SVDAG")
    source.reset(new svdagSVDAGFileSlabSource(fileName));
  else if (format == "HDF5")
    source.reset(new svdagHdf5SlabSource(fileName, options.datasetName));
  else if (format == "TIFF")
    source.reset(new svdagTiffSlabSource(fileName));
  else if (format == "NIfTI")
    source.reset(new svdagNiftiSlabSource(fileName));
  else if (format == "VTKImageData")
    source.reset(new svdagVTIImageSlabSource(fileName));
  else if (format == "MetaImage")
    source.reset(new svdagMetaImageSlabSource(fileName));
  else
    throw svdagReadError(vtkErrorCode::UnrecognizedFileTypeError,
      fileName + " is not a label volume in a known format (NRRD, MetaImage, VTK image data, "
                 "NIfTI, TIFF, HDF5, .svdag)");
  return source;
}
