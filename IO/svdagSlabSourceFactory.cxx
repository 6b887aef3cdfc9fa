#include "svdagSlabSourceFactory.h"

#include "svdagNrrdSlabSource.h"

#include "vtkErrorCode.h"

#include <sys/stat.h>

std::string svdagDetectFileFormat(const std::string& fileName)
{
  try
  {
    if (svdagNrrdSlabSource::hasMagic(fileName))
      return "NRRD";
  }
  catch (const std::exception&)
  {
  }
  return "";
}

std::unique_ptr<svdagSlabSource> svdagOpenSlabSource(
  const std::string& fileName, const svdagSlabSourceOptions& options)
{
  (void)options;
  struct stat st;
  if (fileName.empty() || stat(fileName.c_str(), &st) != 0)
    throw svdagReadError(vtkErrorCode::FileNotFoundError, "file not found: " + fileName);
  if (!S_ISREG(st.st_mode))
    throw svdagReadError(vtkErrorCode::CannotOpenFileError, fileName + " is not a regular file");
  const std::string format = svdagDetectFileFormat(fileName);
  if (format == "NRRD")
    return std::unique_ptr<svdagSlabSource>(new svdagNrrdSlabSource(fileName));
  throw svdagReadError(vtkErrorCode::UnrecognizedFileTypeError,
    fileName + " is not a label volume in a known format (NRRD, MetaImage, VTK image data, "
               "NIfTI, TIFF, HDF5, .svdag)");
}
