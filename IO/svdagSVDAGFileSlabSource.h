// The project's own .svdag files (svdag::readFile). The reader passes the loaded volume through
// when its background and excluded labels leave it unchanged; otherwise the volume is decoded
// slab by slab and compressed again with the reader's labels.
#ifndef svdagSVDAGFileSlabSource_h
#define svdagSVDAGFileSlabSource_h

#include "svdagSlabSource.h"

#include <memory>

class svdagSVDAGFileSlabSource : public svdagSlabSource
{
public:
  explicit svdagSVDAGFileSlabSource(const std::string& fileName);
  // The bytes of a whole file held in memory; `name` is what error messages call them.
  svdagSVDAGFileSlabSource(const uint8_t* data, size_t size, const std::string& name);
  ~svdagSVDAGFileSlabSource() override;
  const char* formatName() const override { return "SVDAG"; }
  void readSlab(int32_t z0, int32_t nz, void* dst) override;
  std::shared_ptr<const svdag::Volume> compressedVolume() const override;
  // True if a file's first `size` bytes start with the .svdag magic.
  static bool hasSignature(const uint8_t* head, size_t size);

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
};

#endif
