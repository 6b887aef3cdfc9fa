#include "svdag_render/AccelerationStructure.h"

#include <stdexcept>
#include <utility>

namespace svdag
{
namespace render
{

AccelerationStructure::~AccelerationStructure()
{
  this->reset();
}

AccelerationStructure::AccelerationStructure(AccelerationStructure&& other) noexcept
{
  *this = std::move(other);
}

AccelerationStructure& AccelerationStructure::operator=(AccelerationStructure&& other) noexcept
{
  if (this != &other)
  {
    this->reset();
    std::swap(this->Owner, other.Owner);
    std::swap(this->Storage, other.Storage);
    std::swap(this->Handle, other.Handle);
    std::swap(this->Address, other.Address);
  }
  return *this;
}

void AccelerationStructure::reset()
{
  if (this->Handle)
    this->Owner->fn().destroyAccelerationStructure(this->Owner->device(), this->Handle, nullptr);
  this->Handle = VK_NULL_HANDLE;
  this->Address = 0;
  this->Storage.reset();
}

AccelerationStructure AccelerationStructure::create(
  Context& context, VkAccelerationStructureTypeKHR type, VkDeviceSize size)
{
  AccelerationStructure as;
  as.Owner = &context;
  as.Storage = Buffer(
    context, size, VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR, MemoryUse::Device);
  VkAccelerationStructureCreateInfoKHR info{
    VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR
  };
  info.buffer = as.Storage.handle();
  info.size = size;
  info.type = type;
  check(context.fn().createAccelerationStructure(context.device(), &info, nullptr, &as.Handle),
    "vkCreateAccelerationStructureKHR");
  VkAccelerationStructureDeviceAddressInfoKHR addressInfo{
    VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_DEVICE_ADDRESS_INFO_KHR
  };
  addressInfo.accelerationStructure = as.Handle;
  as.Address = context.fn().getAccelerationStructureDeviceAddress(context.device(), &addressInfo);
  return as;
}

AccelerationStructure AccelerationStructure::build(Context& context,
  VkAccelerationStructureTypeKHR type, const VkAccelerationStructureGeometryKHR& geometry,
  uint32_t count, VkBuildAccelerationStructureFlagsKHR flags)
{
  VkAccelerationStructureBuildGeometryInfoKHR buildInfo{
    VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR
  };
  buildInfo.type = type;
  buildInfo.flags = flags;
  buildInfo.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
  buildInfo.geometryCount = 1;
  buildInfo.pGeometries = &geometry;
  VkAccelerationStructureBuildSizesInfoKHR sizes{
    VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR
  };
  context.fn().getAccelerationStructureBuildSizes(context.device(),
    VK_ACCELERATION_STRUCTURE_BUILD_TYPE_DEVICE_KHR, &buildInfo, &count, &sizes);

  AccelerationStructure as = create(context, type, sizes.accelerationStructureSize);
  // The scratch address must be aligned to minAccelerationStructureScratchOffsetAlignment.
  const VkDeviceSize alignment = context.limits().minScratchOffsetAlignment;
  Buffer scratch(context, sizes.buildScratchSize + alignment,
    VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::Device);
  buildInfo.dstAccelerationStructure = as.Handle;
  buildInfo.scratchData.deviceAddress =
    (scratch.address() + alignment - 1) / alignment * alignment;
  VkAccelerationStructureBuildRangeInfoKHR range{};
  range.primitiveCount = count;
  const VkAccelerationStructureBuildRangeInfoKHR* ranges = &range;
  context.submitAndWait([&](VkCommandBuffer cmd) {
    context.fn().cmdBuildAccelerationStructures(cmd, 1, &buildInfo, &ranges);
  });
  return as;
}

AccelerationStructure AccelerationStructure::compacted(Context& context) const
{
  VkQueryPoolCreateInfo poolInfo{ VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO };
  poolInfo.queryType = VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR;
  poolInfo.queryCount = 1;
  VkQueryPool pool = VK_NULL_HANDLE;
  check(vkCreateQueryPool(context.device(), &poolInfo, nullptr, &pool), "vkCreateQueryPool");
  VkDeviceSize size = 0;
  VkResult result = VK_SUCCESS;
  try
  {
    context.submitAndWait([&](VkCommandBuffer cmd) {
      vkCmdResetQueryPool(cmd, pool, 0, 1);
      context.fn().cmdWriteAccelerationStructuresProperties(cmd, 1, &this->Handle,
        VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR, pool, 0);
    });
    result = vkGetQueryPoolResults(context.device(), pool, 0, 1, sizeof(size), &size,
      sizeof(size), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
  }
  catch (...)
  {
    vkDestroyQueryPool(context.device(), pool, nullptr);
    throw;
  }
  vkDestroyQueryPool(context.device(), pool, nullptr);
  check(result, "vkGetQueryPoolResults (compacted size)");
  if (size == 0 || size >= this->bytes())
    return AccelerationStructure(); // nothing to gain
  AccelerationStructure small =
    create(context, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, size);
  context.submitAndWait([&](VkCommandBuffer cmd) {
    VkCopyAccelerationStructureInfoKHR copy{ VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR };
    copy.src = this->Handle;
    copy.dst = small.Handle;
    copy.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR;
    context.fn().cmdCopyAccelerationStructure(cmd, &copy);
  });
  return small;
}

AccelerationStructure AccelerationStructure::bottomLevel(
  Context& context, VkDeviceAddress aabbs, uint32_t count)
{
  if (count == 0 || count > context.limits().maxPrimitiveCount)
    throw std::invalid_argument("BLAS primitive count outside 1..maxPrimitiveCount");
  VkAccelerationStructureGeometryKHR geometry{ VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR };
  geometry.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
  // Opaque: no any-hit shader; the intersection shader reports only real (nearest) hits.
  geometry.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
  geometry.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
  geometry.geometry.aabbs.data.deviceAddress = aabbs;
  geometry.geometry.aabbs.stride = sizeof(VkAabbPositionsKHR);
  AccelerationStructure full = build(context, VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR,
    geometry, count,
    VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR |
      VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR);
  AccelerationStructure small = full.compacted(context);
  return small.Handle ? std::move(small) : std::move(full);
}

AccelerationStructure AccelerationStructure::topLevel(
  Context& context, VkDeviceAddress instances, uint32_t count)
{
  VkAccelerationStructureGeometryKHR geometry{ VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR };
  geometry.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
  geometry.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
  geometry.geometry.instances.sType =
    VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
  geometry.geometry.instances.arrayOfPointers = VK_FALSE;
  geometry.geometry.instances.data.deviceAddress = instances;
  return build(context, VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, geometry, count,
    VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR);
}

} // namespace render
} // namespace svdag
