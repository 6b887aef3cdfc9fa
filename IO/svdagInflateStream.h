// Decompresses a gzip (or zlib) stream from an open file, on demand, so a slab source can hand
// out one slab of a compressed volume at a time. Used by the NRRD source for "encoding: gzip".
#ifndef svdagInflateStream_h
#define svdagInflateStream_h

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

class svdagInflateStream
{
public:
  // Reads compressed bytes from the current position of `file` (not owned; it must outlive the
  // stream). `fileName` is only used in error messages.
  svdagInflateStream(std::FILE* file, const std::string& fileName);
  ~svdagInflateStream();
  svdagInflateStream(const svdagInflateStream&) = delete;
  svdagInflateStream& operator=(const svdagInflateStream&) = delete;

  // Fills dst with exactly n decompressed bytes. Throws svdagReadError: PrematureEndOfFileError
  // when the stream ends first, FileFormatError when the compressed data is corrupt.
  void read(void* dst, uint64_t n);
  // Discards n decompressed bytes (same errors as read).
  void skip(uint64_t n);

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
};

#endif
