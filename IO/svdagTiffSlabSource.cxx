#include "svdagTiffSlabSource.h"

#include "svdagInflateStream.h"
#include "svdagVoxelStream.h"

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
// Warnings are kept (not printed): the one saying that libtiff replaced a page's byte counts
// by its own estimate is an error here (the file does not say where its pixels end).
int storeTiffWarning(TIFF*, void* userData, const char*, const char* fmt, va_list ap)
{
  auto* text = static_cast<std::string*>(userData);
  char buffer[512];
  std::vsnprintf(buffer, sizeof(buffer), fmt, ap);
  if (text->empty() && std::strstr(buffer, "ByteCounts"))
    *text = buffer;
  return 1;
}

template <typename T>
void accumulate(uint8_t* data, size_t bytes, uint32_t rowSamples)
{
  const size_t samples = bytes / sizeof(T);
  for (size_t row = 0; row + rowSamples <= samples; row += rowSamples)
  {
    T previous;
    std::memcpy(&previous, data + row * sizeof(T), sizeof(T));
    for (size_t i = 1; i < rowSamples; ++i)
    {
      T v;
      std::memcpy(&v, data + (row + i) * sizeof(T), sizeof(T));
      previous = T(previous + v);
      std::memcpy(data + (row + i) * sizeof(T), &previous, sizeof(T));
    }
  }
}

// TIFF predictor 2 (horizontal differencing), on native-order samples of `size` bytes.
void undoHorizontalPredictor(uint8_t* data, size_t bytes, uint32_t rowSamples, int size)
{
  switch (size)
  {
    case 1: accumulate<uint8_t>(data, bytes, rowSamples); break;
    case 2: accumulate<uint16_t>(data, bytes, rowSamples); break;
    case 4: accumulate<uint32_t>(data, bytes, rowSamples); break;
    default: accumulate<uint64_t>(data, bytes, rowSamples); break;
  }
}
}

struct svdagTiffSlabSource::Impl
{
  std::string fileName;
  TIFF* tiff = nullptr;
  std::string errorText;
  std::string byteCountWarning;
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

  uint64_t fileSize = 0;
  std::vector<uint8_t> raw; // one compressed strip or tile

  // Decodes strip or tile `index` of the current page (`page`) into out: exactly `bytes` bytes,
  // in native byte order. Checks that the chunk lies inside the file; an uncompressed chunk must
  // hold exactly `bytes` bytes (or `paddedBytes`, a last strip stored at full height); deflate
  // chunks are inflated here and verified (Adler-32, exact length); other codecs go through
  // libtiff, which must deliver exactly `bytes` bytes. `rowSamples` is the samples per row (for
  // the horizontal predictor).
  void decode(bool tile, uint32_t index, uint8_t* out, size_t bytes, size_t paddedBytes,
    uint32_t rowSamples, int32_t page)
  {
    const std::string what = std::string(tile ? "tile " : "strip ") + std::to_string(index) +
      " of page " + std::to_string(page);
    const uint32_t count = tile ? TIFFNumberOfTiles(this->tiff) : TIFFNumberOfStrips(this->tiff);
    uint64_t* offsets = nullptr;
    uint64_t* sizes = nullptr;
    if (index >= count ||
      !TIFFGetField(this->tiff, tile ? TIFFTAG_TILEOFFSETS : TIFFTAG_STRIPOFFSETS, &offsets) ||
      !TIFFGetField(this->tiff, tile ? TIFFTAG_TILEBYTECOUNTS : TIFFTAG_STRIPBYTECOUNTS, &sizes) ||
      !offsets || !sizes)
      this->fail(vtkErrorCode::FileFormatError, "no offset or byte count for " + what);
    const uint64_t offset = offsets[index], stored = sizes[index];
    if (offset > this->fileSize || stored > this->fileSize - offset)
      this->fail(vtkErrorCode::PrematureEndOfFileError,
        what + " (" + std::to_string(stored) + " bytes at byte " + std::to_string(offset) +
          ") runs past the end of the file (" + std::to_string(this->fileSize) +
          " bytes; truncated file?)");
    uint16_t compression = COMPRESSION_NONE, predictor = PREDICTOR_NONE, fillOrder = FILLORDER_MSB2LSB;
    TIFFGetFieldDefaulted(this->tiff, TIFFTAG_COMPRESSION, &compression);
    TIFFGetFieldDefaulted(this->tiff, TIFFTAG_FILLORDER, &fillOrder);
    if (compression != COMPRESSION_NONE)
      TIFFGetFieldDefaulted(this->tiff, TIFFTAG_PREDICTOR, &predictor);
    if (compression == COMPRESSION_NONE && stored != bytes && stored != paddedBytes)
      this->fail(stored < bytes ? vtkErrorCode::PrematureEndOfFileError : vtkErrorCode::FileFormatError,
        what + " holds " + std::to_string(stored) + " bytes, its pixels take " +
          std::to_string(bytes));
    const bool deflate = compression == COMPRESSION_ADOBE_DEFLATE || compression == COMPRESSION_DEFLATE;
    if (deflate && fillOrder == FILLORDER_MSB2LSB &&
      (predictor == PREDICTOR_NONE || predictor == PREDICTOR_HORIZONTAL))
    {
      this->raw.resize(size_t(stored));
      const tmsize_t got = tile ? TIFFReadRawTile(this->tiff, index, this->raw.data(), tmsize_t(stored))
                                : TIFFReadRawStrip(this->tiff, index, this->raw.data(), tmsize_t(stored));
      if (got != tmsize_t(stored))
        this->fail(vtkErrorCode::PrematureEndOfFileError, "cannot read " + what);
      svdagInflateStream::inflateAll(this->raw.data(), this->raw.size(), out, bytes,
        this->fileName + ": " + what);
      const int size = this->sampleBytes;
      if (size > 1 && TIFFIsByteSwapped(this->tiff))
        svdagSwapBytes(out, bytes / size_t(size), size);
      if (predictor == PREDICTOR_HORIZONTAL)
        undoHorizontalPredictor(out, bytes, rowSamples, size);
      return;
    }
    const tmsize_t got = tile ? TIFFReadEncodedTile(this->tiff, index, out, tmsize_t(bytes))
                              : TIFFReadEncodedStrip(this->tiff, index, out, tmsize_t(bytes));
    if (got != tmsize_t(bytes))
      this->fail(vtkErrorCode::PrematureEndOfFileError, "cannot read " + what);
  }

  int sampleBytes = 1;

  void goTo(int32_t page)
  {
    if (page == this->directory)
      return;
    const int ok = page == this->directory + 1 ? TIFFReadDirectory(this->tiff)
                                                : TIFFSetDirectory(this->tiff, tdir_t(page));
    if (!ok)
      this->fail(vtkErrorCode::PrematureEndOfFileError, "cannot read page " + std::to_string(page));
    this->directory = page;
    this->checkByteCounts();
  }

  void checkByteCounts()
  {
    if (!this->byteCountWarning.empty())
      this->fail(vtkErrorCode::FileFormatError,
        "the strip or tile byte counts of page " + std::to_string(this->directory) +
          " do not match its pixels (libtiff: " + this->byteCountWarning + ")");
  }
};

bool svdagTiffSlabSource::hasSignature(const uint8_t* m, size_t size)
{
  if (size < 4)
    return false;
  // "II" little-endian or "MM" big-endian, then 42 (classic) or 43 (BigTIFF).
  return (m[0] == 'I' && m[1] == 'I' && (m[2] == 42 || m[2] == 43) && m[3] == 0) ||
    (m[0] == 'M' && m[1] == 'M' && m[2] == 0 && (m[3] == 42 || m[3] == 43));
}

svdagTiffSlabSource::svdagTiffSlabSource(const std::string& fileName, bool allowFloat)
  : impl(new Impl)
{
  impl->fileName = fileName;
  TIFFOpenOptions* options = TIFFOpenOptionsAlloc();
  TIFFOpenOptionsSetErrorHandlerExtR(options, storeTiffError, &impl->errorText);
  TIFFOpenOptionsSetWarningHandlerExtR(options, storeTiffWarning, &impl->byteCountWarning);
  impl->tiff = TIFFOpenExt(fileName.c_str(), "r", options);
  TIFFOpenOptionsFree(options);
  if (!impl->tiff)
    impl->fail(vtkErrorCode::FileFormatError, "cannot open as TIFF");
  impl->checkByteCounts();

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
      if (format == SAMPLEFORMAT_COMPLEXIEEEFP || format == SAMPLEFORMAT_COMPLEXINT)
        svdagThrowNotIntegerLabels(fileName, "complex" + std::to_string(bits));
      if (format == SAMPLEFORMAT_IEEEFP)
        this->setFloatSamples(allowFloat, bits, fileName);
      else if (format != SAMPLEFORMAT_UINT && format != SAMPLEFORMAT_INT &&
        format != SAMPLEFORMAT_VOID)
        impl->fail(vtkErrorCode::FileFormatError, "unknown sample format " + std::to_string(format));
      if (samples != 1)
        impl->fail(vtkErrorCode::FileFormatError,
          "label volumes need one sample per pixel; the file has " + std::to_string(samples));
      if (format != SAMPLEFORMAT_IEEEFP)
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
  impl->sampleBytes = this->sampleSize();
  impl->fileSize = svdagVoxelStream::fileSize(fileName);
}

svdagTiffSlabSource::~svdagTiffSlabSource() = default;

void svdagTiffSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  const size_t size = size_t(this->sampleSize());
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
      if (tw == 0 || th == 0 || tileBytes != tmsize_t(size_t(tw) * th * size))
        impl->fail(vtkErrorCode::FileFormatError, "bad tile size on page " + std::to_string(z));
      // No codec TIFF uses expands data more than 4096-fold (LZW's longest string per 9-bit
      // code; deflate's limit is about 1032), and an uncompressed tile is stored whole: a tile
      // larger than that cannot come from this file, and is refused before it is allocated.
      if (uint64_t(tileBytes) > 4096 * impl->fileSize + 65536)
        impl->fail(vtkErrorCode::FileFormatError,
          "tiles of " + std::to_string(tw) + " x " + std::to_string(th) + " pixels (" +
            std::to_string(uint64_t(tileBytes)) + " bytes) on page " + std::to_string(z) +
            " cannot be stored in a file of " + std::to_string(impl->fileSize) + " bytes");
      impl->chunk.resize(size_t(tileBytes));
      for (uint32_t y = 0; y < height; y += th)
      {
        for (uint32_t x = 0; x < width; x += tw)
        {
          impl->decode(true, TIFFComputeTile(tiff, x, y, 0, 0), impl->chunk.data(),
            size_t(tileBytes), size_t(tileBytes), tw, z);
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
        // Decode straight into the slice: a strip is whole rows. An uncompressed last strip
        // may be stored padded to the full strip height.
        impl->decode(false, TIFFComputeStrip(tiff, s * rowsPerStrip, 0),
          slice + size_t(s) * rowsPerStrip * rowBytes, rows * rowBytes,
          size_t(rowsPerStrip) * rowBytes, uint32_t(width), z);
      }
    }
  }
}
