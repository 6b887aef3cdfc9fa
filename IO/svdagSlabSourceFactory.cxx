#include "svdagSlabSourceFactory.h"

#include "svdagExactCastSlabSource.h"
#include "svdagHdf5SlabSource.h"
#include "svdagIsolatedSlabSource.h"
#include "svdagMetaImageSlabSource.h"
#include "svdagNiftiSlabSource.h"
#include "svdagNrrdSlabSource.h"
#include "svdagSVDAGFileSlabSource.h"
#include "svdagTiffSlabSource.h"
#include "svdagVTIImageSlabSource.h"

#include "vtkErrorCode.h"

#include <cerrno>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace
{
// One entry per format: its name (GetFileFormat()), how its files are recognised from their
// content, and how they are opened. Detection tries the entries in this order: binary
// signatures first, text headers last. To add a format, add its source and one line here.
// A format is recognised by `hasSignature`, from the file's first bytes (read once for all of
// them), or else by `detect`, which reads the file itself. `open` opens the format's own source:
// with options.castFloatLabels, one that may hand out floats (svdagOpenSlabSource then casts
// them).
struct Format
{
  const char* name;
  bool (*hasSignature)(const uint8_t* head, size_t size);
  bool (*detect)(const std::string& fileName);
  std::unique_ptr<svdagSlabSource> (*open)(
    const std::string& fileName, const svdagSlabSourceOptions& options);
};

template <typename Source>
std::unique_ptr<svdagSlabSource> openPlain(
  const std::string& fileName, const svdagSlabSourceOptions& options)
{
  return std::unique_ptr<svdagSlabSource>(new Source(fileName, options.castFloatLabels));
}

// .svdag files hold integer labels only.
std::unique_ptr<svdagSlabSource> openSvdag(const std::string& fileName, const svdagSlabSourceOptions&)
{
  return std::unique_ptr<svdagSlabSource>(new svdagSVDAGFileSlabSource(fileName));
}

std::unique_ptr<svdagSlabSource> openHdf5(
  const std::string& fileName, const svdagSlabSourceOptions& options)
{
  // In a child process: HDF5 1.10 is not hardened against corrupt metadata (the fuzzer crashes
  // it in its metadata cache), and a crash must be an error for the file.
  const std::string datasetName = options.datasetName;
  const bool allowFloat = options.castFloatLabels;
  return std::unique_ptr<svdagSlabSource>(new svdagIsolatedSlabSource(fileName, "HDF5", [=] {
    return std::unique_ptr<svdagSlabSource>(
      new svdagHdf5SlabSource(fileName, datasetName, allowFloat));
  }));
}

const Format Formats[] = {
  { "NRRD", svdagNrrdSlabSource::hasSignature, nullptr, openPlain<svdagNrrdSlabSource> },
  { "SVDAG", svdagSVDAGFileSlabSource::hasSignature, nullptr, openSvdag },
  { "HDF5", nullptr, svdagHdf5SlabSource::hasMagic, openHdf5 },
  { "TIFF", svdagTiffSlabSource::hasSignature, nullptr, openPlain<svdagTiffSlabSource> },
  { "NIfTI", nullptr, svdagNiftiSlabSource::canRead, openPlain<svdagNiftiSlabSource> },
  { "VTKImageData", nullptr, svdagVTIImageSlabSource::canRead, openPlain<svdagVTIImageSlabSource> },
  { "MetaImage", nullptr, svdagMetaImageSlabSource::canRead, openPlain<svdagMetaImageSlabSource> },
};

// The most bytes a signature needs (.svdag's).
constexpr size_t SignatureBytes = 8;

// The entry for the content of a regular file, or null. Never throws.
const Format* detectRegularFile(const std::string& fileName)
{
  try
  {
    uint8_t head[SignatureBytes] = {};
    size_t size = 0;
    const int fd = ::open(fileName.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
      return nullptr;
    while (size < SignatureBytes)
    {
      const ssize_t got = ::read(fd, head + size, SignatureBytes - size);
      if (got < 0 && errno == EINTR)
        continue;
      if (got <= 0)
        break;
      size += size_t(got);
    }
    ::close(fd);
    for (const Format& format : Formats)
    {
      if (format.hasSignature ? format.hasSignature(head, size) : format.detect(fileName))
        return &format;
    }
  }
  catch (const std::exception&)
  {
  }
  return nullptr;
}

// The entry for the file's content, or null. Never throws.
const Format* detect(const std::string& fileName)
{
  struct stat st;
  if (stat(fileName.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
    return nullptr;
  return detectRegularFile(fileName);
}
}

std::string svdagDetectFileFormat(const std::string& fileName)
{
  const Format* format = detect(fileName);
  return format ? format->name : "";
}

std::unique_ptr<svdagSlabSource> svdagOpenSlabSource(
  const std::string& fileName, const svdagSlabSourceOptions& options)
{
  struct stat st;
  if (fileName.empty() || stat(fileName.c_str(), &st) != 0)
    throw svdagReadError(vtkErrorCode::FileNotFoundError, "file not found: " + fileName);
  if (!S_ISREG(st.st_mode))
    throw svdagReadError(vtkErrorCode::CannotOpenFileError, fileName + " is not a regular file");
  const Format* format = detectRegularFile(fileName);
  if (!format)
    throw svdagReadError(vtkErrorCode::UnrecognizedFileTypeError,
      fileName + " is not a label volume in a known format (NRRD, MetaImage, VTK image data, "
                 "NIfTI, TIFF, HDF5, .svdag)");
  std::unique_ptr<svdagSlabSource> source = format->open(fileName, options);
  if (source->sampleKind() == svdagSampleKind::Integer)
    return source;
  // Floats, which a source hands out only with castFloatLabels: checked and cast here, one
  // wrapper for every format. Its second pass reads the file through a source of its own.
  return std::unique_ptr<svdagSlabSource>(new svdagExactCastSlabSource(
    std::move(source), [=] { return format->open(fileName, options); }, fileName));
}
