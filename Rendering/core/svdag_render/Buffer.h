// Vulkan buffers with device addresses and their memory: one dedicated allocation per buffer
// (the renderer holds a handful of large buffers, so a sub-allocator would buy nothing; VMA is
// not available in Debian 12). Memory types are chosen by use:
//   Device   device-local, filled through a staging copy (uploadBuffer) or by the GPU
//   Readback host-visible, coherent, preferably cached: the GPU writes, the host reads in place
//   Upload   host-visible, coherent: the host writes in place (uniforms, staging)
//   Shared   device-local preferred, exportable as a file descriptor (Device::canExportMemory):
//            another API (OpenGL) imports it and reads what the GPU wrote, no host copy
//   SharedHost  exportable like Shared, and host-visible, coherent and mapped: another API
//            writes it, the GPU and the host read it in place (the scene depth OpenGL reads
//            into it, which the host compares between frames)
#pragma once

#include "svdag_render/Context.h"

#include <cstddef>

namespace svdag
{
namespace render
{

enum class MemoryUse
{
  Device,
  Readback,
  Upload,
  Shared,
  SharedHost
};

// A Shared buffer's memory as another API imports it (GL_EXT_memory_object_fd): the importer
// owns `fd` (a new one per export) and must import `bytes` (the allocation's size, not the
// buffer's) as a dedicated allocation when `dedicated` is set.
struct ExportedMemory
{
  int fd = -1;
  uint64_t bytes = 0;
  bool dedicated = false;
};

class Buffer
{
public:
  Buffer() = default;
  // A buffer of `size` bytes (> 0). Transfer and device-address usage are always added.
  // Throws DeviceMemoryError (Context.h) when it does not fit the device's memory, and
  // std::runtime_error when Vulkan refuses otherwise.
  Buffer(Context& context, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use);
  ~Buffer();
  Buffer(Buffer&& other) noexcept;
  Buffer& operator=(Buffer&& other) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  explicit operator bool() const { return this->Handle != VK_NULL_HANDLE; }
  VkBuffer handle() const { return this->Handle; }
  VkDeviceSize size() const { return this->Size; }
  VkDeviceAddress address() const { return this->Address; }
  // Host pointer for Readback, Upload and SharedHost buffers, nullptr for Device and Shared ones.
  void* mapped() const { return this->Mapped; }
  // A new file descriptor of a Shared buffer's memory. Throws std::logic_error for any other
  // buffer, std::runtime_error when Vulkan refuses.
  ExportedMemory exportMemory() const;
  void reset();

private:
  VkDevice Device = VK_NULL_HANDLE;
  Context* Owner = nullptr;     // counts the allocation (Context::allocatedBytes)
  VkDeviceSize Allocated = 0;
  VkBuffer Handle = VK_NULL_HANDLE;
  VkDeviceMemory Memory = VK_NULL_HANDLE;
  VkDeviceSize Size = 0;
  VkDeviceAddress Address = 0;
  void* Mapped = nullptr;
  PFN_vkGetMemoryFdKHR GetMemoryFd = nullptr; // set for Shared buffers
  bool Dedicated = false;
};

// A device-local buffer holding a copy of `bytes` bytes at `data` (through a staging buffer).
Buffer uploadBuffer(Context& context, const void* data, size_t bytes, VkBufferUsageFlags usage);

} // namespace render
} // namespace svdag
