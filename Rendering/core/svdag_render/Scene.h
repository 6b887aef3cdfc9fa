// The GPU scene of one volume: its streams (blocks, roots, mids, leaves) in device buffers read by
// the shaders through device addresses, and what the backend in use finds blocks with: for the
// ray tracing backend the BVH over its VISIBLE blocks (below), for the compute backend the cell
// grid: per cell of the volume's 16^3 grid, the index of its first block (blocks are sorted by
// cell; cells + 1 uint32 entries, 4 bytes a cell), and the hidden labels as bits (one uint32 per
// 32 labels, host-visible: hiding a label is a write, never a rebuild). Each backend's structure
// exists only while that backend is in use: the compute backend holds no BLAS.
//
// Each visible block is one AABB primitive in volume INDEX space, where voxel (i, j, k) occupies
// [i, i+1)^3 (Traversal.h); the AABB is the block's tight bounds box. Primitives are ordered by a
// recursive longest-axis median split of the box centers before the build (lavapipe's builder
// keeps the input order, and this order traces several times faster than a random or Morton order;
// GPU drivers build their own hierarchy). A primitive -> block index buffer maps the ray-tracing
// primitive back to the block record. The primitives are cut into BLAS of at most the driver's
// maxPrimitiveCount (16,777,215 on lavapipe); the TLAS holds one instance per BLAS, all with the
// volume's index-to-world transform (world = origin + D * diag(spacing) * (p - 0.5)) and the BLAS
// number as instance custom index. The AABB buffer is freed right after the build.
//
// The block stream is held in chunks of 2^blockChunkShift words, each its own allocation (a
// driver caps one allocation: lavapipe at 2 GiB), reached through a table of their addresses.
// Chunk k holds words [k << shift, (k + 1) << shift) and the next 4 words, so that a block record
// (at most 120 bits, 5 words) starting in chunk k is read from it whole; bit offsets inside a
// chunk stay below 2^32 for the shaders' 32-bit arithmetic (shift <= 26: 256 MiB chunks).
//
// Precision: the GPU works in float. World coordinates are shifted by a reference point (the
// center of the volume's world bounds) in double precision on the host, both in the instance
// transform and in the camera position the renderer uploads, so a volume far from the world
// origin loses no precision; only the camera's distance to the volume and the volume's size
// matter.
#pragma once

#include "svdag_render/AccelerationStructure.h"
#include "svdag_render/Buffer.h"
#include "svdag_render/Context.h"
#include "svdag_render/RenderSettings.h"
#include "svdag_render/WorldFrame.h"

#include <svdag/Volume.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace svdag
{
namespace render
{

class Scene
{
public:
  // Largest (and default) chunk of the block stream, as log2 of its words.
  static constexpr uint32_t MaxBlockChunkShift = 26;
  // Uploads the streams and builds the BVH with every label visible. Throws std::runtime_error
  // when Vulkan fails or a node stream exceeds what the shaders address (2^32 bits). The block
  // stream is cut into chunks of 2^blockChunkShift words (clamped to 4..MaxBlockChunkShift;
  // smaller chunks exist to test the chunked path on small volumes).
  // backend: Backend::RayTracing or Backend::Compute (resolved, not Auto).
  Scene(Context& context, std::shared_ptr<const Volume> volume, Backend backend,
    uint32_t blockChunkShift = MaxBlockChunkShift);
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // Switches to the structure of another backend (building it; the other one is freed).
  void setBackend(Backend backend);
  Backend backend() const { return this->Kind; }
  // Leaves out the blocks of these label indices (out-of-range indices are ignored); returns
  // whether the set changed. Ray tracing: the BVH is rebuilt without them (cheap: no stream is
  // uploaded again); compute: their bits are set.
  bool setHiddenLabels(const std::vector<uint32_t>& labelIndices);
  const std::vector<uint32_t>& hiddenLabels() const { return this->Hidden; }
  // Caps the primitives per BLAS below the driver's maxPrimitiveCount (0: no cap) and rebuilds
  // if that changes the split (ray tracing backend); returns whether it rebuilt. More, smaller
  // BLAS trace slower: this exists to exercise the multi-BLAS path on small volumes (tests).
  bool setPrimitivesPerBlasLimit(uint32_t limit);

  const Volume& volume() const { return *this->Source; }
  // The point subtracted from world coordinates on the GPU (see Precision above).
  const std::array<double, 3>& worldReference() const { return this->Reference; }
  // The map from world coordinates minus worldReference() to index space, 3 rows of 4: the
  // inverse of the instance transform (the compute backend transforms its rays with it).
  std::array<double, 12> worldToIndex() const;
  // False after a failed (re)build (out of memory, say) until a later one succeeds.
  bool ready() const { return this->Built; }
  VkAccelerationStructureKHR tlas() const { return this->Tlas.handle(); }
  // The table of the block stream chunks' addresses (uint64 each) and log2 of words per chunk.
  VkDeviceAddress blocksAddress() const { return this->BlockChunkTable.address(); }
  uint32_t blockChunkShift() const { return this->BlockChunkShift; }
  size_t blockChunkCount() const { return this->BlockChunks.size(); }
  VkDeviceAddress rootsAddress() const { return this->Roots.address(); }
  VkDeviceAddress midsAddress() const { return this->Mids.address(); }
  VkDeviceAddress leavesAddress() const { return this->Leaves.address(); }
  VkDeviceAddress primitiveBlocksAddress() const { return this->PrimitiveBlocks.address(); }
  // Primitives per BLAS: instance i's primitive p is entry i * this + p of the primitive -> block
  // buffer.
  uint32_t primitivesPerBlas() const { return this->PrimitivesPerBlas; }
  // The compute backend's cell grid: each cell's first block (uint32, cells + 1 entries), and the
  // hidden label bits (0 when no label is hidden).
  VkDeviceAddress cellStartsAddress() const { return this->CellStarts.address(); }
  VkDeviceAddress hiddenBitsAddress() const
  {
    return this->Hidden.empty() ? VkDeviceAddress(0) : this->HiddenBits.address();
  }

  uint64_t visibleBlocks() const { return this->VisibleBlocks; }
  size_t blasCount() const { return this->Blas.size(); }
  uint64_t blasBytes() const;
  uint64_t tlasBytes() const { return this->Tlas.bytes(); }
  // Bytes of the volume's streams on the device.
  uint64_t streamBytes() const;
  // Bytes of what the backend finds blocks with: BLAS, TLAS, instances and the primitive -> block
  // map (ray tracing), or the cell grid and the hidden label bits (compute).
  uint64_t accelerationBytes() const;
  double uploadSeconds() const { return this->UploadSeconds; }
  double buildSeconds() const { return this->BuildSeconds; }

private:
  void build();
  void buildCellGrid();
  void writeHiddenBits();
  void release();

  Context& Ctx;
  Backend Kind;
  std::shared_ptr<const Volume> Source;
  std::vector<uint32_t> Hidden;
  std::array<double, 3> Reference{ { 0, 0, 0 } };
  std::vector<Buffer> BlockChunks;
  Buffer BlockChunkTable;
  uint32_t BlockChunkShift = MaxBlockChunkShift;
  Buffer Roots, Mids, Leaves;
  Buffer PrimitiveBlocks;
  Buffer CellStarts;
  Buffer HiddenBits;
  std::vector<uint64_t> LabelBlocks; // blocks per label index (compute: the visible count)
  Buffer Instances;
  std::vector<AccelerationStructure> Blas;
  AccelerationStructure Tlas;
  uint32_t PrimitivesPerBlas = 1;
  uint32_t PrimitivesPerBlasLimit = 0;
  bool Built = false;
  uint64_t VisibleBlocks = 0;
  double UploadSeconds = 0;
  double BuildSeconds = 0;
};

} // namespace render
} // namespace svdag
