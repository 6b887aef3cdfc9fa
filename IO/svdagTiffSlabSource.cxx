#include "svdagTiffSlabSource.h"

#include "vtkErrorCode.h"
#include "vtk_tiff.h"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <vector>

namespace
{
// libtiff reports through handlers; keep the first error message for the exception (and keep
// libtiff from printing to stderr).
int storeTiffError(TIFF*, void* userData, const char* module, const char* fmt, va_list ap)
{
  auto* text = static_cast<std::string*>(userData);
  if (text->empty())
  {
    char buffer[512];
    std::vsnprintf(buffer, sizeof(buffer), fmt, ap);
    *text = std::string(module ? module : "libtiff") + ": " + buffer;
  }
  return 1;
}
int ignoreTiffWarning(TIFF*, void*, const char*, const char*, va_list)
{
  return 1;
}
}

struct svdagTiffSlabSource::Impl
{
  std::string fileName;
  TIFF* tiff = nullptr;
  std::string errorText;
  int32_t directory = 0; // page libtiff is on
  std::vector<uint8_t> chunk; // one decoded strip or tile

  ~Impl()
  {
    if (this->tiff)
      TIFFClose(this->tiff);
  }

  [[noreturn]] void fail(unsigned long code, const std::string& what)
  {
    std::string message = this->fileName + ": " + what;
    if (!this->errorText.empty())
      message += " (" + this->errorText + ")";
    this->errorText.clear();
    throw svdagReadError(code, message);
  }

  void goTo(int32_t page)
  {
    if (page == this->directory)
      return;
    const int ok = page == this->directory + 1 ? TIFFReadDirectory(this->tiff)
                                                : TIFFSetDirectory(this->tiff, tdir_t(page));
    if (!ok)
      this->fail(vtkErrorCode::PrematureEndOfFileError, "cannot read page " + std::to_string(page));
    this->directory = page;
  }
};

bool svdagTiffSlabSource::hasMagic(const std::string& fileName)
{
  std::FILE* f = std::fopen(fileName.c_str(), "rb");
  if (!f)
    return false;
  unsigned char m[4] = {};
  const size_t n = std::fread(m, 1, 4, f);
  std::fclose(f);
  if (n != 4)
    return false;
  // "II" little-endian or "MM" big-endian, then 42 (classic) or 43 (BigTIFF).
  return (m[0] == 'I' && m[1] == 'I' && (m[2] == 42 || m[2] == 43) && m[3] == 0) ||
    (m[0] == 'M' && m[1] == 'M' && m[2] == 0 && (m[3] == 42 || m[3] == 43));
}

svdagTiffSlabSource::svdagTiffSlabSource(const std::string& fileName)
  : impl(new Impl)
{
  impl->fileName = fileName;
  TIFFOpenOptions* options = TIFFOpenOptionsAlloc();
  TIFFOpenOptionsSetErrorHandlerExtR(options, storeTiffError, &impl->errorText);
  TIFFOpenOptionsSetWarningHandlerExtR(options, ignoreTiffWarning, nullptr);
  impl->tiff = TIFFOpenExt(fileName.c_str(), "r", options);
  TIFFOpenOptionsFree(options);
  if (!impl->tiff)
    impl->fail(vtkErrorCode::FileFormatError, "cannot open as TIFF");

  // Every page must agree on size and sample layout.
  // libtiff counts pages by following the chain of directory offsets; in a truncated file the
  // chain breaks, which it reports as an error while still returning the pages it found.
  const tdir_t pages = TIFFNumberOfDirectories(impl->tiff);
  if (!impl->errorText.empty())
    impl->fail(vtkErrorCode::PrematureEndOfFileError, "broken chain of pages (truncated file?)");
  if (pages < 1 || pages > INT32_MAX)
    impl->fail(vtkErrorCode::FileFormatError, "no readable page");
  uint32_t width0 = 0, height0 = 0;
  uint16_t bits0 = 0, format0 = 0;
  for (tdir_t page = 0; page < pages; ++page)
  {
    impl->goTo(int32_t(page));
    uint32_t width = 0, height = 0;
    uint16_t samples = 1, bits = 1, format = SAMPLEFORMAT_UINT;
    if (!TIFFGetField(impl->tiff, TIFFTAG_IMAGEWIDTH, &width) ||
      !TIFFGetField(impl->tiff, TIFFTAG_IMAGELENGTH, &height))
      impl->fail(vtkErrorCode::FileFormatError, "page " + std::to_string(page) + " has no size");
    TIFFGetFieldDefaulted(impl->tiff, TIFFTAG_SAMPLESPERPIXEL, &samples);
    TIFFGetFieldDefaulted(impl->tiff, TIFFTAG_BITSPERSAMPLE, &bits);
    TIFFGetFieldDefaulted(impl->tiff, TIFFTAG_SAMPLEFORMAT, &format);
    if (page == 0)
    {
      if (format == SAMPLEFORMAT_IEEEFP || format == SAMPLEFORMAT_COMPLEXIEEEFP ||
        format == SAMPLEFORMAT_COMPLEXINT)
        svdagThrowNotIntegerLabels(fileName,
          (format == SAMPLEFORMAT_IEEEFP ? "float" : "complex") + std::to_string(bits));
      if (format != SAMPLEFORMAT_UINT && format != SAMPLEFORMAT_INT &&
        format != SAMPLEFORMAT_VOID)
        impl->fail(vtkErrorCode::FileFormatError, "unknown sample format " + std::to_string(format));
      if (samples != 1)
        impl->fail(vtkErrorCode::FileFormatError,
          "label volumes need one sample per pixel; the file has " + std::to_string(samples));
      this->Type = svdagIntegerScalarType(format == SAMPLEFORMAT_INT, bits / 8,
        fileName + " has " + std::to_string(bits) + "-bit samples");
      if (bits % 8 != 0)
        impl->fail(vtkErrorCode::FileFormatError,
          std::to_string(bits) + "-bit samples are not supported");
      width0 = width;
      height0 = height;
      bits0 = bits;
      format0 = format;
    }
    else if (width != width0 || height != height0 || samples != 1 || bits != bits0 ||
      format != format0)
      impl->fail(vtkErrorCode::FileFormatError,
        "page " + std::to_string(page) + " differs from page 0 in size or sample type");
  }
  if (width0 > uint32_t(INT32_MAX) || height0 > uint32_t(INT32_MAX))
    impl->fail(vtkErrorCode::FileFormatError, "absurd page size");
  this->Geometry.dims = { { int32_t(width0), int32_t(height0), int32_t(pages) } };
  this->checkGeometry(fileName);
}

svdagTiffSlabSource::~svdagTiffSlabSource() = default;

void svdagTiffSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  const size_t size = size_t(svdag::scalarSize(this->Type));
  const size_t width = size_t(this->Geometry.dims[0]);
  const size_t height = size_t(this->Geometry.dims[1]);
  TIFF* tiff = impl->tiff;
  for (int32_t z = z0; z < z0 + nz; ++z)
  {
    impl->goTo(z);
    auto* slice = static_cast<uint8_t*>(dst) + size_t(z - z0) * width * height * size;
    if (TIFFIsTiled(tiff))
    {
      uint32_t tw = 0, th = 0;
      TIFFGetField(tiff, TIFFTAG_TILEWIDTH, &tw);
      TIFFGetField(tiff, TIFFTAG_TILELENGTH, &th);
      const tmsize_t tileBytes = TIFFTileSize(tiff);
      if (tw == 0 || th == 0 || tileBytes < tmsize_t(size_t(tw) * th * size))
        impl->fail(vtkErrorCode::FileFormatError, "bad tile size on page " + std::to_string(z));
      impl->chunk.resize(size_t(tileBytes));
      for (uint32_t y = 0; y < height; y += th)
      {
        for (uint32_t x = 0; x < width; x += tw)
        {
          if (TIFFReadTile(tiff, impl->chunk.data(), x, y, 0, 0) < 0)
            impl->fail(vtkErrorCode::PrematureEndOfFileError,
              "cannot read a tile of page " + std::to_string(z));
          const size_t w = std::min<size_t>(tw, width - x);
          const size_t h = std::min<size_t>(th, height - y);
          for (size_t row = 0; row < h; ++row)
            std::memcpy(slice + ((y + row) * width + x) * size,
              impl->chunk.data() + row * tw * size, w * size);
        }
      }
    }
    else
    {
      uint32_t rowsPerStrip = 0;
      TIFFGetFieldDefaulted(tiff, TIFFTAG_ROWSPERSTRIP, &rowsPerStrip);
      rowsPerStrip = std::max<uint32_t>(1, std::min<uint32_t>(rowsPerStrip, uint32_t(height)));
      const size_t rowBytes = width * size;
      const uint32_t strips = uint32_t((height + rowsPerStrip - 1) / rowsPerStrip);
      for (uint32_t s = 0; s < strips; ++s)
      {
        const size_t rows = std::min<size_t>(rowsPerStrip, height - size_t(s) * rowsPerStrip);
        const tmsize_t want = tmsize_t(rows * rowBytes);
        // Decode straight into the slice: a strip is whole rows.
        const tmsize_t got = TIFFReadEncodedStrip(
          tiff, TIFFComputeStrip(tiff, s * rowsPerStrip, 0), slice + size_t(s) * rowsPerStrip * rowBytes, want);
        if (got != want)
          impl->fail(vtkErrorCode::PrematureEndOfFileError,
            "cannot read strip " + std::to_string(s) + " of page " + std::to_string(z));
      }
    }
  }
}
