// A slab source run in a child process. Some formats are parsed by third-party C libraries that
// are not hardened against corrupt files (HDF5 1.10 reads out of bounds on a damaged B-tree or
// heap address); a crash there must become an error for that file, not the end of the
// application. The child opens the real source and sends its geometry, scalar type, sample kind
// (integer labels or floats, svdagSampleKind) and slabs back over a socket; the parent reports
// a crash, an early exit or a silent child (no byte for a long time) as svdagReadError naming
// the file.
//
// The slabs cross the socket once (a copy at memory speed) and the child holds one slab of its
// own while it sends it. POSIX only (fork); elsewhere the source runs in the process.
#ifndef svdagIsolatedSlabSource_h
#define svdagIsolatedSlabSource_h

#include "svdagSlabSource.h"

#include <functional>
#include <memory>
#include <string>

class svdagIsolatedSlabSource : public svdagSlabSource
{
public:
  using Opener = std::function<std::unique_ptr<svdagSlabSource>()>;
  // Runs `open` in a child process; `formatName` must outlive the source (a literal).
  svdagIsolatedSlabSource(const std::string& fileName, const char* formatName, Opener open);
  ~svdagIsolatedSlabSource() override;
  const char* formatName() const override { return this->FormatName; }
  void readSlab(int32_t z0, int32_t nz, void* dst) override;

  // Seconds the parent waits for the next byte from the child before it gives up (a hang).
  static constexpr int SilenceTimeoutSeconds = 300;

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
  const char* FormatName;
};

#endif
