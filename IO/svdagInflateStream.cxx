#include "svdagInflateStream.h"

#include "svdagSlabSource.h"

#include "vtkErrorCode.h"
#include "vtk_zlib.h"

#include <algorithm>

struct svdagInflateStream::Impl
{
  std::FILE* file = nullptr;
  std::string fileName;
  z_stream z{};
  std::vector<uint8_t> input = std::vector<uint8_t>(size_t(1) << 18);
  bool ended = false; // the last member ended and the file holds nothing more

  // Refills the input buffer; false at the end of the file.
  bool refill()
  {
    const size_t got = std::fread(this->input.data(), 1, this->input.size(), this->file);
    if (got == 0 && std::ferror(this->file))
    {
      throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
        this->fileName + ": read error in the compressed data");
    }
    this->z.next_in = this->input.data();
    this->z.avail_in = static_cast<uInt>(got);
    return got > 0;
  }

  [[noreturn]] void truncated(uint64_t missing) const
  {
    throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
      this->fileName + ": the compressed data ends " + std::to_string(missing) +
        " bytes before the volume does (truncated file?)");
  }
};

svdagInflateStream::svdagInflateStream(std::FILE* file, const std::string& fileName)
  : impl(new Impl)
{
  impl->file = file;
  impl->fileName = fileName;
  // 32 + MAX_WBITS: accept a gzip or a zlib header (detected from the first bytes).
  if (inflateInit2(&impl->z, 32 + MAX_WBITS) != Z_OK)
  {
    throw svdagReadError(vtkErrorCode::OutOfDiskSpaceError, "cannot initialise zlib");
  }
}

svdagInflateStream::~svdagInflateStream()
{
  inflateEnd(&impl->z);
}

void svdagInflateStream::read(void* dst, uint64_t n)
{
  auto* out = static_cast<uint8_t*>(dst);
  while (n > 0)
  {
    if (impl->ended)
    {
      impl->truncated(n);
    }
    if (impl->z.avail_in == 0 && !impl->refill())
    {
      impl->truncated(n);
    }
    // avail_out is 32-bit: hand zlib at most 1 GiB per call.
    const uInt chunk = static_cast<uInt>(std::min<uint64_t>(n, uint64_t(1) << 30));
    impl->z.next_out = out;
    impl->z.avail_out = chunk;
    const int status = inflate(&impl->z, Z_NO_FLUSH);
    const uInt produced = chunk - impl->z.avail_out;
    out += produced;
    n -= produced;
    if (status == Z_STREAM_END)
    {
      // gzip files may hold several members back to back; anything else after the end is ignored
      // unless more data is needed, in which case it must be another valid member.
      if (n > 0)
      {
        if (impl->z.avail_in == 0 && !impl->refill())
        {
          impl->ended = true;
          continue;
        }
        inflateReset(&impl->z);
      }
    }
    else if (status == Z_BUF_ERROR)
    {
      // No progress possible: zlib needs input we do not have.
      if (impl->z.avail_in == 0 && !impl->refill())
      {
        impl->truncated(n);
      }
    }
    else if (status != Z_OK)
    {
      throw svdagReadError(vtkErrorCode::FileFormatError,
        impl->fileName + ": corrupt compressed data (zlib: " +
          (impl->z.msg ? impl->z.msg : "error " + std::to_string(status)) + ")");
    }
  }
}

void svdagInflateStream::skip(uint64_t n)
{
  std::vector<uint8_t> scratch(size_t(std::min<uint64_t>(n, uint64_t(1) << 20)));
  while (n > 0)
  {
    const uint64_t chunk = std::min<uint64_t>(n, scratch.size());
    this->read(scratch.data(), chunk);
    n -= chunk;
  }
}
