// One Vulkan acceleration structure and its storage, built (and, for bottom levels, compacted)
// through a command buffer: lavapipe has no host-side builds.
#pragma once

#include "svdag_render/Buffer.h"
#include "svdag_render/Context.h"

#include <cstdint>

namespace svdag
{
namespace render
{

class AccelerationStructure
{
public:
  AccelerationStructure() = default;
  ~AccelerationStructure();
  AccelerationStructure(AccelerationStructure&& other) noexcept;
  AccelerationStructure& operator=(AccelerationStructure&& other) noexcept;
  AccelerationStructure(const AccelerationStructure&) = delete;
  AccelerationStructure& operator=(const AccelerationStructure&) = delete;

  // A BLAS over `count` (1 .. maxPrimitiveCount) VkAabbPositionsKHR at a device address, built
  // for fast tracing and compacted. The AABB buffer may be freed once this returns.
  static AccelerationStructure bottomLevel(Context& context, VkDeviceAddress aabbs, uint32_t count);
  // A TLAS over `count` VkAccelerationStructureInstanceKHR at a device address (count may be 0).
  static AccelerationStructure topLevel(Context& context, VkDeviceAddress instances, uint32_t count);

  VkAccelerationStructureKHR handle() const { return this->Handle; }
  VkDeviceAddress address() const { return this->Address; }
  // Bytes of the structure's storage.
  uint64_t bytes() const { return this->Storage.size(); }
  void reset();

private:
  static AccelerationStructure create(Context& context, VkAccelerationStructureTypeKHR type,
    VkDeviceSize size);
  static AccelerationStructure build(Context& context, VkAccelerationStructureTypeKHR type,
    const VkAccelerationStructureGeometryKHR& geometry, uint32_t count,
    VkBuildAccelerationStructureFlagsKHR flags);
  AccelerationStructure compacted(Context& context) const;

  const Context* Owner = nullptr;
  Buffer Storage;
  VkAccelerationStructureKHR Handle = VK_NULL_HANDLE;
  VkDeviceAddress Address = 0;
};

} // namespace render
} // namespace svdag
