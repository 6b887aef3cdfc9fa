#include "svdag_render/Buffer.h"

#include <cstring>
#include <string>
#include <stdexcept>
#include <utility>

namespace svdag
{
namespace render
{

Buffer::Buffer(Context& context, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use)
{
  if (size == 0)
    throw std::invalid_argument("a Vulkan buffer of 0 bytes was requested");
  this->Device = context.device();
  this->Size = size;
  try
  {
    VkBufferCreateInfo info{ VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO };
    info.size = size;
    info.usage = usage | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
      VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    const VkExternalMemoryHandleTypeFlagBits fdType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
    VkExternalMemoryBufferCreateInfo external{
      VK_STRUCTURE_TYPE_EXTERNAL_MEMORY_BUFFER_CREATE_INFO
    };
    const bool exportable = use == MemoryUse::Shared || use == MemoryUse::SharedHost;
    if (exportable)
    {
      if (!context.canExportMemory())
        throw std::logic_error("a shared buffer was requested from a device that cannot export memory");
      VkPhysicalDeviceExternalBufferInfo query{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_EXTERNAL_BUFFER_INFO
      };
      query.usage = info.usage;
      query.handleType = fdType;
      VkExternalBufferProperties properties{ VK_STRUCTURE_TYPE_EXTERNAL_BUFFER_PROPERTIES };
      vkGetPhysicalDeviceExternalBufferProperties(context.physicalDevice(), &query, &properties);
      const VkExternalMemoryFeatureFlags features =
        properties.externalMemoryProperties.externalMemoryFeatures;
      if (!(features & VK_EXTERNAL_MEMORY_FEATURE_EXPORTABLE_BIT))
        throw std::runtime_error("the device cannot export this buffer's memory as a file descriptor");
      this->Dedicated = (features & VK_EXTERNAL_MEMORY_FEATURE_DEDICATED_ONLY_BIT) != 0;
      this->GetMemoryFd = context.fn().getMemoryFd;
      external.handleTypes = fdType;
      info.pNext = &external;
    }
    check(vkCreateBuffer(this->Device, &info, nullptr, &this->Handle), "vkCreateBuffer");

    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(this->Device, this->Handle, &req);
    VkMemoryPropertyFlags required = 0, preferred = 0;
    switch (use)
    {
      case MemoryUse::Device:
      case MemoryUse::Shared:
        preferred = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
        break;
      case MemoryUse::Readback:
        required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        preferred = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
        break;
      case MemoryUse::Upload:
      case MemoryUse::SharedHost:
        required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        break;
    }
    VkMemoryAllocateFlagsInfo flags{ VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO };
    flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkExportMemoryAllocateInfo exported{ VK_STRUCTURE_TYPE_EXPORT_MEMORY_ALLOCATE_INFO };
    VkMemoryDedicatedAllocateInfo dedicated{ VK_STRUCTURE_TYPE_MEMORY_DEDICATED_ALLOCATE_INFO };
    if (exportable)
    {
      exported.handleTypes = fdType;
      flags.pNext = &exported;
      if (this->Dedicated)
      {
        dedicated.buffer = this->Handle;
        exported.pNext = &dedicated;
      }
    }
    VkMemoryAllocateInfo alloc{ VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO };
    alloc.pNext = &flags;
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = context.memoryType(req.memoryTypeBits, required, preferred);
    context.checkFits(req.size, "A buffer", req.size);
    const VkResult allocated = vkAllocateMemory(this->Device, &alloc, nullptr, &this->Memory);
    if (allocated == VK_ERROR_OUT_OF_DEVICE_MEMORY || allocated == VK_ERROR_OUT_OF_HOST_MEMORY)
    {
      throw DeviceMemoryError("The device could not allocate a buffer of " +
        std::to_string(req.size) + " bytes (" + resultName(allocated) + "); " +
        std::to_string(context.availableBytes()) + " bytes were available by the heap sizes, " +
        std::to_string(context.allocatedBytes()) + " in use by this renderer");
    }
    check(allocated, "vkAllocateMemory");
    this->Owner = &context;
    this->Allocated = req.size;
    context.noteAllocation(int64_t(req.size));
    check(vkBindBufferMemory(this->Device, this->Handle, this->Memory, 0), "vkBindBufferMemory");
    if (use == MemoryUse::Readback || use == MemoryUse::Upload || use == MemoryUse::SharedHost)
    {
      check(vkMapMemory(this->Device, this->Memory, 0, VK_WHOLE_SIZE, 0, &this->Mapped),
        "vkMapMemory");
    }
    VkBufferDeviceAddressInfo addressInfo{ VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO };
    addressInfo.buffer = this->Handle;
    this->Address = vkGetBufferDeviceAddress(this->Device, &addressInfo);
  }
  catch (...)
  {
    this->reset();
    throw;
  }
}

Buffer::~Buffer()
{
  this->reset();
}

Buffer::Buffer(Buffer&& other) noexcept
{
  *this = std::move(other);
}

Buffer& Buffer::operator=(Buffer&& other) noexcept
{
  if (this != &other)
  {
    this->reset();
    std::swap(this->Device, other.Device);
    std::swap(this->Owner, other.Owner);
    std::swap(this->Allocated, other.Allocated);
    std::swap(this->Handle, other.Handle);
    std::swap(this->Memory, other.Memory);
    std::swap(this->Size, other.Size);
    std::swap(this->Address, other.Address);
    std::swap(this->Mapped, other.Mapped);
    std::swap(this->GetMemoryFd, other.GetMemoryFd);
    std::swap(this->Dedicated, other.Dedicated);
  }
  return *this;
}

void Buffer::reset()
{
  if (this->Handle)
    vkDestroyBuffer(this->Device, this->Handle, nullptr);
  if (this->Memory)
    vkFreeMemory(this->Device, this->Memory, nullptr); // unmaps implicitly
  if (this->Owner)
    this->Owner->noteAllocation(-int64_t(this->Allocated));
  this->Owner = nullptr;
  this->Allocated = 0;
  this->Handle = VK_NULL_HANDLE;
  this->Memory = VK_NULL_HANDLE;
  this->Size = 0;
  this->Address = 0;
  this->Mapped = nullptr;
  this->GetMemoryFd = nullptr;
  this->Dedicated = false;
}

ExportedMemory Buffer::exportMemory() const
{
  if (!this->GetMemoryFd || !this->Memory)
    throw std::logic_error("only a shared buffer's memory can be exported");
  VkMemoryGetFdInfoKHR info{ VK_STRUCTURE_TYPE_MEMORY_GET_FD_INFO_KHR };
  info.memory = this->Memory;
  info.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
  ExportedMemory out;
  check(this->GetMemoryFd(this->Device, &info, &out.fd), "vkGetMemoryFdKHR");
  out.bytes = this->Allocated;
  out.dedicated = this->Dedicated;
  return out;
}

Buffer uploadBuffer(Context& context, const void* data, size_t bytes, VkBufferUsageFlags usage)
{
  Buffer staging(context, bytes, 0, MemoryUse::Upload);
  std::memcpy(staging.mapped(), data, bytes);
  Buffer target(context, bytes, usage, MemoryUse::Device);
  context.submitAndWait([&](VkCommandBuffer cmd) {
    VkBufferCopy region{ 0, 0, bytes };
    vkCmdCopyBuffer(cmd, staging.handle(), target.handle(), 1, &region);
  });
  return target;
}

} // namespace render
} // namespace svdag
