// Decompresses a gzip or zlib stream on demand, verifying it, so a slab source can hand out one
// slab of a compressed volume at a time (NRRD "encoding: gzip", MetaImage CompressedData,
// .nii.gz) or inflate one compressed chunk (TIFF deflate strips and tiles).
//
// The gzip and zlib wrappers are parsed here and the deflate data is inflated raw, with the
// checksum computed on the output as it is produced (no second pass): at the end of each member
// the trailer is checked (gzip: CRC-32 and ISIZE; zlib: Adler-32), and the stream must end
// where the file (or buffer) ends. A gzip stream may hold several members back to back (RFC
// 1952), their data concatenated; a zlib stream is one stream, nothing may follow it.
#ifndef svdagInflateStream_h
#define svdagInflateStream_h

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

class svdagInflateStream
{
public:
  // Reads compressed bytes from the current position of `file` to its end (`file` is not owned;
  // it must outlive the stream). `fileName` is only used in error messages.
  svdagInflateStream(std::FILE* file, const std::string& fileName);
  // Reads compressed bytes from memory (not copied; it must outlive the stream). `what` names
  // the data in error messages ("FILE: strip 3 of page 7").
  svdagInflateStream(const void* data, size_t size, const std::string& what);
  ~svdagInflateStream();
  svdagInflateStream(const svdagInflateStream&) = delete;
  svdagInflateStream& operator=(const svdagInflateStream&) = delete;

  // Fills dst with exactly n decompressed bytes. Throws svdagReadError: PrematureEndOfFileError
  // when the stream ends first, FileFormatError when the compressed data is corrupt or a
  // member's trailer does not match its data.
  void read(void* dst, uint64_t n);
  // Discards n decompressed bytes (same errors as read).
  void skip(uint64_t n);
  // Reads the rest of the stream, which must hold no more decompressed data: verifies the last
  // trailer and that nothing but further (empty) gzip members follows. Throws FileFormatError
  // when there is more data, PrematureEndOfFileError when the stream is cut short.
  void finish();

  // Inflates a whole zlib or gzip stream of `inSize` bytes into exactly `outSize` bytes, with
  // the same checks as read() + finish().
  static void inflateAll(const void* in, size_t inSize, void* out, size_t outSize,
    const std::string& what);

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
};

#endif
