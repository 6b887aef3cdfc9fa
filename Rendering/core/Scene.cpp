#include "svdag_render/Scene.h"

#include "svdag_render/WorldFrame.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace svdag
{
namespace render
{
namespace
{
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// A visible block's box in index space (hi exclusive) and its block index.
struct BlockBox
{
  std::array<int64_t, 3> lo;
  std::array<int64_t, 3> hi;
  uint32_t block;
};

// Orders boxes by recursive longest-axis median split of their centers (iteratively, with an
// explicit stack: depth is log2(n), but an explicit stack needs no recursion limit argument).
void medianSplitOrder(std::vector<BlockBox>& boxes)
{
  std::vector<std::pair<size_t, size_t>> stack{ { 0, boxes.size() } };
  while (!stack.empty())
  {
    const auto [begin, end] = stack.back();
    stack.pop_back();
    if (end - begin <= 2)
      continue;
    // Twice the center (lo + hi) keeps everything in integers.
    std::array<int64_t, 3> cmin{ { INT64_MAX, INT64_MAX, INT64_MAX } };
    std::array<int64_t, 3> cmax{ { INT64_MIN, INT64_MIN, INT64_MIN } };
    for (size_t i = begin; i < end; ++i)
    {
      for (int a = 0; a < 3; ++a)
      {
        const int64_t c = boxes[i].lo[a] + boxes[i].hi[a];
        cmin[a] = std::min(cmin[a], c);
        cmax[a] = std::max(cmax[a], c);
      }
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
    {
      if (cmax[a] - cmin[a] > cmax[axis] - cmin[axis])
        axis = a;
    }
    const size_t mid = begin + (end - begin) / 2;
    std::nth_element(boxes.begin() + begin, boxes.begin() + mid, boxes.begin() + end,
      [axis](const BlockBox& x, const BlockBox& y) {
        const int64_t cx = x.lo[axis] + x.hi[axis], cy = y.lo[axis] + y.hi[axis];
        return cx != cy ? cx < cy : x.block < y.block; // total order: deterministic
      });
    stack.emplace_back(begin, mid);
    stack.emplace_back(mid, end);
  }
}

void checkAddressable(uint64_t words, const char* what)
{
  // The shaders address bits with 32-bit offsets (Layout.h's SVDAG_OFFSET_T in GLSL).
  if (words > (uint64_t(1) << 27))
  {
    throw std::runtime_error(std::string("the volume's ") + what +
      " stream exceeds 2^32 bits, more than the GPU traversal addresses");
  }
}
} // namespace

Scene::Scene(Context& context, std::shared_ptr<const Volume> volume, Backend backend,
  uint32_t blockChunkShift)
  : Ctx(context)
  , Kind(backend)
  , Source(std::move(volume))
  , BlockChunkShift(std::min(std::max(blockChunkShift, 4u), MaxBlockChunkShift))
{
  if (!this->Source)
    throw std::invalid_argument("Scene needs a volume");
  if (backend != Backend::RayTracing && backend != Backend::Compute)
    throw std::invalid_argument("a Scene is built for the rt or the compute backend");
  const Volume& v = *this->Source;
  if (v.form != DagForm::Compact)
    throw std::invalid_argument("a Scene renders the compact form of a volume (svdag::compacted)");
  const auto bounds = worldBounds(v.geometry);
  for (int a = 0; a < 3; ++a)
    this->Reference[a] = (bounds[2 * a] + bounds[2 * a + 1]) / 2;
  checkAddressable(v.roots.size(), "root node");
  checkAddressable(v.mids.size(), "mid node");
  // Refused as a whole before any upload: the error names what the volume needs.
  const uint64_t chunkWords = uint64_t(1) << this->BlockChunkShift;
  const uint64_t chunkCount = (v.blocks.size() + chunkWords - 1) / chunkWords;
  const uint64_t blockBytes = (v.blocks.size() + 4 * chunkCount) * 4 + chunkCount * 8;
  const uint64_t leafBytes = std::max<uint64_t>(v.leaves.size(), 1) * 8;
  this->Ctx.checkFits(blockBytes + (v.roots.size() + v.mids.size()) * 4 + leafBytes,
    "The volume's streams (blocks and DAG)",
    std::max({ std::min(v.blocks.size(), chunkWords + 4) * 4, v.roots.size() * 4,
      v.mids.size() * 4, leafBytes }));
  const auto start = Clock::now();
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  auto upload = [&](const auto& words) {
    return uploadBuffer(this->Ctx, words.data(), words.size() * sizeof(words[0]), usage);
  };
  // Chunks of the block stream (see Scene.h), each with the 4 words after it.
  std::vector<VkDeviceAddress> chunkAddresses;
  for (uint64_t first = 0; first < v.blocks.size(); first += chunkWords)
  {
    const uint64_t end = std::min<uint64_t>(v.blocks.size(), first + chunkWords + 4);
    this->BlockChunks.push_back(uploadBuffer(this->Ctx, v.blocks.data() + first,
      size_t(end - first) * sizeof(uint32_t), usage));
    chunkAddresses.push_back(this->BlockChunks.back().address());
  }
  this->BlockChunkTable = upload(chunkAddresses);
  this->Roots = upload(v.roots);
  this->Mids = upload(v.mids);
  // A volume without leaves still gets a (never read) one-leaf buffer: buffers cannot be empty.
  const std::vector<uint64_t> noLeaf(1, 0);
  this->Leaves = upload(v.leaves.empty() ? noLeaf : v.leaves);
  this->UploadSeconds = secondsSince(start);
  this->build();
}

void Scene::setBackend(Backend backend)
{
  if (backend != Backend::RayTracing && backend != Backend::Compute)
    throw std::invalid_argument("a Scene is built for the rt or the compute backend");
  if (backend == this->Kind && this->Built)
    return;
  this->release();
  this->Kind = backend;
  this->build();
}

void Scene::release()
{
  this->Built = false;
  this->Tlas.reset();
  this->Blas.clear();
  this->Instances.reset();
  this->PrimitiveBlocks.reset();
  this->CellStarts.reset();
  this->HiddenBits.reset();
  this->VisibleBlocks = 0;
}

Scene::~Scene() = default;

bool Scene::setHiddenLabels(const std::vector<uint32_t>& labelIndices)
{
  std::vector<uint32_t> hidden;
  for (uint32_t l : labelIndices)
  {
    if (l < this->Source->labels.size())
      hidden.push_back(l);
  }
  std::sort(hidden.begin(), hidden.end());
  hidden.erase(std::unique(hidden.begin(), hidden.end()), hidden.end());
  if (hidden == this->Hidden && this->Built)
    return false;
  this->Hidden = std::move(hidden);
  if (this->Kind == Backend::Compute && this->Built)
    this->writeHiddenBits();
  else
    this->build();
  return true;
}

bool Scene::setPrimitivesPerBlasLimit(uint32_t limit)
{
  if (limit == this->PrimitivesPerBlasLimit && this->Built)
    return false;
  this->PrimitivesPerBlasLimit = limit;
  if (this->Kind != Backend::RayTracing && this->Built)
    return false;
  this->build();
  return true;
}

uint64_t Scene::blasBytes() const
{
  uint64_t total = 0;
  for (const auto& b : this->Blas)
    total += b.bytes();
  return total;
}

std::array<double, 12> Scene::worldToIndex() const
{
  const auto m = indexToWorld(this->Source->geometry);
  glm::dmat3 a; // column-major: a[c][r]
  glm::dvec3 b;
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
      a[c][r] = m[4 * r + c];
    b[r] = m[4 * r + 3] - this->Reference[r];
  }
  const glm::dmat3 inverse = glm::inverse(a);
  const glm::dvec3 t = -(inverse * b);
  std::array<double, 12> out;
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
      out[4 * r + c] = inverse[c][r];
    out[4 * r + 3] = t[r];
  }
  return out;
}

uint64_t Scene::accelerationBytes() const
{
  return this->blasBytes() + this->Tlas.bytes() + this->Instances.size() +
    this->PrimitiveBlocks.size() + this->CellStarts.size() + this->HiddenBits.size();
}

uint64_t Scene::streamBytes() const
{
  uint64_t blocks = this->BlockChunkTable.size();
  for (const Buffer& chunk : this->BlockChunks)
    blocks += chunk.size();
  return blocks + this->Roots.size() + this->Mids.size() + this->Leaves.size();
}

void Scene::buildCellGrid()
{
  const auto start = Clock::now();
  const Volume& v = *this->Source;
  const auto n = v.geometry.cellCounts();
  const uint64_t cells = uint64_t(n[0]) * uint64_t(n[1]) * uint64_t(n[2]);
  if (v.blockCount > std::numeric_limits<uint32_t>::max())
    throw std::runtime_error("the compute backend indexes at most 2^32 - 1 blocks");
  const uint64_t words = (v.labels.size() + 31) / 32;
  this->Ctx.checkFits((cells + 1) * 4 + std::max<uint64_t>(words, 1) * 4,
    "The compute backend's cell grid", (cells + 1) * 4);
  this->release();
  // starts[c] = the first block whose cell is >= c (blocks are sorted by cell); and the blocks
  // of each label, from which writeHiddenBits counts the visible ones.
  std::vector<uint32_t> starts(size_t(cells + 1), 0);
  this->LabelBlocks.assign(v.labels.size(), 0);
  uint64_t c = 0;
  for (uint64_t b = 0; b < v.blockCount; ++b)
  {
    const Block block = v.block(b);
    while (c <= block.cell)
      starts[size_t(c++)] = uint32_t(b);
    ++this->LabelBlocks[block.label];
  }
  while (c <= cells)
    starts[size_t(c++)] = uint32_t(v.blockCount);
  this->CellStarts = uploadBuffer(this->Ctx, starts.data(), starts.size() * sizeof(uint32_t),
    VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  this->HiddenBits = Buffer(this->Ctx, std::max<uint64_t>(words, 1) * 4,
    VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::Upload);
  this->writeHiddenBits();
  this->BuildSeconds = secondsSince(start);
  this->Built = true;
}

void Scene::writeHiddenBits()
{
  // The GPU is idle between frames (the renderer waits for every frame): written in place.
  uint32_t* bits = static_cast<uint32_t*>(this->HiddenBits.mapped());
  std::memset(bits, 0, size_t(this->HiddenBits.size()));
  uint64_t hiddenBlocks = 0;
  for (uint32_t l : this->Hidden)
  {
    bits[l / 32] |= 1u << (l % 32);
    hiddenBlocks += this->LabelBlocks[l];
  }
  this->VisibleBlocks = this->Source->blockCount - hiddenBlocks;
}

void Scene::build()
{
  if (this->Kind == Backend::Compute)
  {
    this->buildCellGrid();
    return;
  }
  const auto start = Clock::now();
  const Volume& v = *this->Source;
  std::vector<char> visibleLabel(v.labels.size(), 1);
  for (uint32_t l : this->Hidden)
    visibleLabel[l] = 0;

  const auto cells = v.geometry.cellCounts();
  std::vector<BlockBox> boxes;
  for (uint64_t i = 0; i < v.blockCount; ++i)
  {
    const Block b = v.block(i);
    if (!visibleLabel[b.label])
      continue;
    const int64_t c[3] = { int64_t(b.cell % uint32_t(cells[0])),
      int64_t(b.cell / uint32_t(cells[0]) % uint32_t(cells[1])),
      int64_t(b.cell / (uint64_t(cells[0]) * uint64_t(cells[1]))) };
    BlockBox box;
    for (int a = 0; a < 3; ++a)
    {
      box.lo[a] = int64_t(layout::CELL_SIZE) * c[a] + b.lo[a];
      box.hi[a] = int64_t(layout::CELL_SIZE) * c[a] + b.hi[a] + 1;
    }
    box.block = uint32_t(i);
    boxes.push_back(box);
  }
  medianSplitOrder(boxes);

  // Release the old BVH before building the new one (peak memory). Until the end of this
  // function the scene is not ready: a failure leaves it so, and the next call rebuilds.
  this->release();

  const uint64_t count = boxes.size();
  this->VisibleBlocks = count;
  this->PrimitivesPerBlas = uint32_t(std::min<uint64_t>(this->Ctx.limits().maxPrimitiveCount,
    uint64_t(std::numeric_limits<uint32_t>::max())));
  if (this->PrimitivesPerBlasLimit > 0)
    this->PrimitivesPerBlas = std::min(this->PrimitivesPerBlas, this->PrimitivesPerBlasLimit);
  if (this->PrimitivesPerBlas == 0)
    throw std::runtime_error("the Vulkan device reports maxPrimitiveCount 0");

  std::vector<uint32_t> primitiveBlocks(std::max<uint64_t>(count, 1), 0);
  std::vector<VkAabbPositionsKHR> aabbs(count);
  for (uint64_t i = 0; i < count; ++i)
  {
    primitiveBlocks[i] = boxes[i].block;
    aabbs[i] = VkAabbPositionsKHR{ float(boxes[i].lo[0]), float(boxes[i].lo[1]),
      float(boxes[i].lo[2]), float(boxes[i].hi[0]), float(boxes[i].hi[1]), float(boxes[i].hi[2]) };
  }
  boxes = {};
  this->PrimitiveBlocks = uploadBuffer(this->Ctx, primitiveBlocks.data(),
    primitiveBlocks.size() * sizeof(uint32_t), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);

  // Index -> world - Reference (the shift is applied in double, see Scene.h).
  auto transform = indexToWorld(v.geometry);
  for (int r = 0; r < 3; ++r)
    transform[4 * r + 3] -= this->Reference[r];
  std::vector<VkAccelerationStructureInstanceKHR> instances;
  if (count > 0)
  {
    for (uint64_t first = 0; first < count; first += this->PrimitivesPerBlas)
    {
      const uint32_t n = uint32_t(std::min<uint64_t>(this->PrimitivesPerBlas, count - first));
      // Each BLAS's boxes in their own buffer, freed after its build: the device never holds
      // more than one BLAS's input (24 bytes a block: 400 MB at lavapipe's 16.7M primitives).
      const Buffer aabbBuffer = uploadBuffer(this->Ctx, aabbs.data() + first,
        n * sizeof(VkAabbPositionsKHR),
        VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR);
      this->Blas.push_back(AccelerationStructure::bottomLevel(this->Ctx, aabbBuffer.address(), n));
      VkAccelerationStructureInstanceKHR instance{};
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c)
          instance.transform.matrix[r][c] = float(transform[4 * r + c]);
      instance.instanceCustomIndex = uint32_t(this->Blas.size() - 1);
      instance.mask = 0xFF;
      instance.instanceShaderBindingTableRecordOffset = 0;
      instance.flags = VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR;
      instance.accelerationStructureReference = this->Blas.back().address();
      instances.push_back(instance);
    }
  }
  aabbs = {};
  if (instances.size() > this->Ctx.limits().maxInstanceCount ||
    instances.size() >= (size_t(1) << 24))
    throw std::runtime_error("the volume needs more BLAS than one TLAS can hold");
  // An empty scene still gets a one-entry (unused) instance buffer: buffers cannot be empty.
  const VkAccelerationStructureInstanceKHR none{};
  this->Instances = uploadBuffer(this->Ctx, instances.empty() ? &none : instances.data(),
    std::max<size_t>(instances.size(), 1) * sizeof(VkAccelerationStructureInstanceKHR),
    VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR);
  this->Tlas = AccelerationStructure::topLevel(
    this->Ctx, this->Instances.address(), uint32_t(instances.size()));
  this->BuildSeconds = secondsSince(start);
  this->Built = true;
}

} // namespace render
} // namespace svdag
