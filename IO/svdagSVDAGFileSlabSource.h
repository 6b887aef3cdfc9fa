// The project's own .svdag files (svdag::readFile). The reader passes the loaded volume through
// when its background and excluded labels leave it unchanged; otherwise the volume is decoded
// slab by slab and compressed again with the reader's labels.
#ifndef svdagSVDAGFileSlabSource_h
#define svdagSVDAGFileSlabSource_h

#include "svdagSlabSource.h"

class svdagSVDAGFileSlabSource : public svdagSlabSource
{
public:
  explicit svdagSVDAGFileSlabSource(const std::string& fileName);
  const char* formatName() const override { return "SVDAG"; }
  void readSlab(int32_t z0, int32_t nz, void* dst) override;
  std::shared_ptr<const svdag::Volume> compressedVolume() const override { return this->Volume; }
  static bool hasMagic(const std::string& fileName);

private:
  std::shared_ptr<const svdag::Volume> Volume;
};

#endif
