#include "svdagInflateStream.h"

#include "svdagSlabSource.h"

#include "vtkErrorCode.h"
#include "vtk_zlib.h"

#include <algorithm>
#include <cstdio>
#include <sys/stat.h>
#include <vector>

namespace
{
// Output handed to inflate per call: small enough that the checksum runs on bytes still in
// cache, large enough that zlib's copy of the last 32 KiB into its window after each call
// (updatewindow) stays negligible.
constexpr uInt OutputChunk = uInt(1) << 20;

std::string hex32(uint32_t v)
{
  char text[16];
  std::snprintf(text, sizeof(text), "0x%08x", unsigned(v));
  return text;
}
}

struct svdagInflateStream::Impl
{
  enum class Wrapper
  {
    Gzip,
    Zlib
  };
  enum class State
  {
    Header, // at the start of a member
    Body,   // inside a member's deflate data
    Done    // the last member ended and nothing follows
  };

  std::string name; // for messages
  std::FILE* file = nullptr;
  const uint8_t* memory = nullptr;
  size_t memorySize = 0;
  std::vector<uint8_t> input;
  uint64_t available = 0; // compressed bytes from the start position to the end of the input
  uint64_t fed = 0;       // compressed bytes handed to z so far
  bool eof = false;       // every input byte has been handed to z
  z_stream z{};
  bool zInitialised = false;
  Wrapper wrapper = Wrapper::Gzip;
  State state = State::Header;
  int members = 0;
  uint32_t check = 0;       // CRC-32 (gzip) or Adler-32 (zlib) of the member's data so far
  uint64_t memberBytes = 0; // decompressed bytes of the current member
  uint64_t totalBytes = 0;  // decompressed bytes of the whole stream so far

  ~Impl()
  {
    if (this->zInitialised)
      inflateEnd(&this->z);
  }

  void init()
  {
    // Raw deflate: the wrappers and their checksums are handled here.
    if (inflateInit2(&this->z, -MAX_WBITS) != Z_OK)
      throw svdagReadError(vtkErrorCode::OutOfDiskSpaceError, "cannot initialise zlib");
    this->zInitialised = true;
  }

  [[noreturn]] void corrupt(const std::string& what) const
  {
    throw svdagReadError(vtkErrorCode::FileFormatError, this->name + ": " + what);
  }
  [[noreturn]] void cutShort(const std::string& what) const
  {
    throw svdagReadError(
      vtkErrorCode::PrematureEndOfFileError, this->name + ": " + what + " (truncated file?)");
  }

  // Hands z more input; false when there is none left.
  bool refill()
  {
    if (this->eof)
      return false;
    size_t got = 0;
    if (this->memory)
    {
      this->z.next_in = const_cast<Bytef*>(this->memory);
      got = this->memorySize;
    }
    else
    {
      if (this->input.empty())
        this->input.resize(size_t(1) << 18);
      got = std::fread(this->input.data(), 1, this->input.size(), this->file);
      if (got == 0 && std::ferror(this->file))
        throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
          this->name + ": read error in the compressed data");
      this->z.next_in = this->input.data();
    }
    this->z.avail_in = static_cast<uInt>(got);
    this->fed += got;
    if (got == 0 || this->memory || this->fed >= this->available)
      this->eof = true;
    return got > 0;
  }

  // The next compressed byte, or -1 at the end of the input.
  int nextByte()
  {
    if (this->z.avail_in == 0 && !this->refill())
      return -1;
    --this->z.avail_in;
    return *this->z.next_in++;
  }
  // True if no compressed byte is left.
  bool atEnd()
  {
    return this->z.avail_in == 0 && !this->refill();
  }
  uint64_t remaining() const { return this->available - (this->fed - this->z.avail_in); }

  int headerByte(uint32_t& crc)
  {
    const int c = this->nextByte();
    if (c < 0)
      this->cutShort(this->members == 0 ? "the compressed data ends inside its gzip/zlib header"
                                        : "the gzip stream ends inside a member's header");
    const Bytef b = Bytef(c);
    crc = uint32_t(crc32(crc, &b, 1));
    return c;
  }

  // Parses a member's header (the first member decides gzip or zlib) and starts inflating it.
  void beginMember()
  {
    uint32_t crc = uint32_t(crc32(0, Z_NULL, 0));
    const int b0 = this->headerByte(crc);
    if (this->members > 0 && this->atEnd())
      this->corrupt("1 byte of data after the end of the gzip stream");
    const int b1 = this->headerByte(crc);
    if (b0 == 0x1f && b1 == 0x8b)
    {
      this->wrapper = Wrapper::Gzip;
      if (this->headerByte(crc) != 8)
        this->corrupt("gzip member with an unknown compression method (not deflate)");
      const int flags = this->headerByte(crc);
      if (flags & 0xe0)
        this->corrupt("gzip member header has reserved flag bits set (corrupt header)");
      for (int i = 0; i < 6; ++i) // MTIME, XFL, OS
        this->headerByte(crc);
      if (flags & 0x04) // FEXTRA
      {
        const int lo = this->headerByte(crc);
        const int length = lo | (this->headerByte(crc) << 8);
        for (int i = 0; i < length; ++i)
          this->headerByte(crc);
      }
      for (int bit : { 0x08, 0x10 }) // FNAME, FCOMMENT: zero-terminated
      {
        if (flags & bit)
        {
          while (this->headerByte(crc) != 0)
          {
          }
        }
      }
      if (flags & 0x02) // FHCRC: the low 16 bits of the CRC-32 of the header so far
      {
        const uint32_t expected = crc & 0xffff;
        uint32_t ignored = 0;
        const int lo = this->headerByte(ignored);
        const uint32_t stored = uint32_t(lo | (this->headerByte(ignored) << 8));
        if (stored != expected)
          this->corrupt("gzip header CRC-16 mismatch: stored " + hex32(stored) + ", computed " +
            hex32(expected));
      }
      this->check = uint32_t(crc32(0, Z_NULL, 0));
    }
    else
    {
      if (this->members > 0)
        this->corrupt(std::to_string(this->remaining() + 2) +
          " bytes of data after the end of the gzip stream that are not a gzip member");
      const int cmf = b0, flg = b1;
      if (((cmf << 8) | flg) % 31 != 0 || (cmf & 0x0f) != 8 || (cmf >> 4) > 7)
        this->corrupt("corrupt compressed data (neither a gzip nor a zlib header)");
      if (flg & 0x20)
        this->corrupt("the zlib stream needs a preset dictionary (not supported)");
      this->wrapper = Wrapper::Zlib;
      this->check = uint32_t(adler32(0, Z_NULL, 0));
    }
    if (inflateReset(&this->z) != Z_OK)
      this->corrupt("cannot reset zlib");
    this->memberBytes = 0;
    ++this->members;
    this->state = State::Body;
  }

  uint32_t trailerByte()
  {
    const int c = this->nextByte();
    if (c < 0)
      this->cutShort(this->wrapper == Wrapper::Gzip
          ? "the gzip stream ends inside its trailer (CRC-32, ISIZE)"
          : "the zlib stream ends inside its Adler-32 trailer");
    return uint32_t(c);
  }

  // After a member's deflate data: checks its trailer and what follows.
  void endMember()
  {
    if (this->wrapper == Wrapper::Gzip)
    {
      uint32_t stored = 0, size = 0;
      for (int i = 0; i < 4; ++i)
        stored |= this->trailerByte() << (8 * i);
      for (int i = 0; i < 4; ++i)
        size |= this->trailerByte() << (8 * i);
      if (stored != this->check)
        this->corrupt(
          "gzip CRC-32 mismatch: stored " + hex32(stored) + ", computed " + hex32(this->check));
      if (size != uint32_t(this->memberBytes))
        this->corrupt("gzip ISIZE mismatch: stored " + std::to_string(size) +
          ", decompressed " + std::to_string(uint32_t(this->memberBytes)) + " (mod 2^32) bytes");
      // Another member may follow (beginMember checks that it is one).
      this->state = this->atEnd() ? State::Done : State::Header;
    }
    else
    {
      uint32_t stored = 0;
      for (int i = 0; i < 4; ++i)
        stored = (stored << 8) | this->trailerByte();
      if (stored != this->check)
        this->corrupt(
          "zlib Adler-32 mismatch: stored " + hex32(stored) + ", computed " + hex32(this->check));
      if (!this->atEnd())
        this->corrupt(std::to_string(this->remaining()) +
          " bytes of data after the end of the zlib stream");
      this->state = State::Done;
    }
  }

  // Inflates up to `capacity` bytes into out; returns how many (0 only when the stream is
  // done). `missing` is what the caller still needs, for the truncation message.
  size_t pump(uint8_t* out, size_t capacity, uint64_t missing)
  {
    while (true)
    {
      if (this->state == State::Done)
        return 0;
      if (this->state == State::Header)
      {
        this->beginMember();
        continue;
      }
      if (this->z.avail_in == 0)
        this->refill();
      const uInt room = static_cast<uInt>(std::min<size_t>(capacity, OutputChunk));
      this->z.next_out = out;
      this->z.avail_out = room;
      const int status = inflate(&this->z, Z_NO_FLUSH);
      const uInt produced = room - this->z.avail_out;
      if (produced > 0)
      {
        this->check = this->wrapper == Wrapper::Gzip ? uint32_t(crc32(this->check, out, produced))
                                                     : uint32_t(adler32(this->check, out, produced));
        this->memberBytes += produced;
        this->totalBytes += produced;
      }
      if (status == Z_STREAM_END)
        this->endMember();
      else if (status == Z_BUF_ERROR)
      {
        if (this->z.avail_in == 0 && this->eof)
        {
          if (missing > 0)
            this->cutShort("the compressed data ends " + std::to_string(missing - produced) +
              " bytes before the volume does");
          this->cutShort("the compressed stream ends before its end marker and trailer");
        }
      }
      else if (status != Z_OK)
        this->corrupt(std::string("corrupt compressed data (zlib: ") +
          (this->z.msg ? this->z.msg : "error " + std::to_string(status)) + ")");
      if (produced > 0)
        return produced;
    }
  }
};

svdagInflateStream::svdagInflateStream(std::FILE* file, const std::string& fileName)
  : impl(new Impl)
{
  impl->file = file;
  impl->name = fileName;
  struct stat st;
  const off_t here = ftello(file);
  if (fstat(fileno(file), &st) != 0 || here < 0)
    throw svdagReadError(vtkErrorCode::CannotOpenFileError, "cannot read " + fileName);
  impl->available = uint64_t(st.st_size) > uint64_t(here) ? uint64_t(st.st_size - here) : 0;
  impl->init();
}

svdagInflateStream::svdagInflateStream(const void* data, size_t size, const std::string& what)
  : impl(new Impl)
{
  impl->memory = static_cast<const uint8_t*>(data);
  impl->memorySize = size;
  impl->available = size;
  impl->name = what;
  impl->init();
}

svdagInflateStream::~svdagInflateStream() = default;

void svdagInflateStream::read(void* dst, uint64_t n)
{
  auto* out = static_cast<uint8_t*>(dst);
  while (n > 0)
  {
    const size_t produced = impl->pump(out, size_t(std::min<uint64_t>(n, OutputChunk)), n);
    if (produced == 0)
      impl->cutShort("the compressed data ends " + std::to_string(n) +
        " bytes before the volume does");
    out += produced;
    n -= produced;
  }
}

void svdagInflateStream::skip(uint64_t n)
{
  std::vector<uint8_t> scratch(size_t(std::min<uint64_t>(n, OutputChunk)));
  while (n > 0)
  {
    const uint64_t chunk = std::min<uint64_t>(n, scratch.size());
    this->read(scratch.data(), chunk);
    n -= chunk;
  }
}

void svdagInflateStream::finish()
{
  uint8_t scratch[4096];
  const uint64_t expected = impl->totalBytes;
  uint64_t extra = 0;
  while (size_t produced = impl->pump(scratch, sizeof(scratch), 0))
  {
    // Count the excess (up to a bound, so a bomb costs no time) for the message.
    extra += produced;
    if (extra >= (uint64_t(1) << 20))
      break;
  }
  if (extra > 0)
    impl->corrupt("the compressed data holds " + std::string(extra >= (uint64_t(1) << 20) ? "at least " : "") +
      std::to_string(extra) + " more bytes than the " + std::to_string(expected) +
      " the header describes");
}

void svdagInflateStream::inflateAll(
  const void* in, size_t inSize, void* out, size_t outSize, const std::string& what)
{
  svdagInflateStream stream(in, inSize, what);
  stream.read(out, outSize);
  stream.finish();
}
