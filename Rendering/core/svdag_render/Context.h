// The Vulkan instance, the chosen device, its queue and the extension entry points.
//
// Device choice: among the physical devices that have what every backend needs (Vulkan 1.2,
// VK_KHR_buffer_device_address and its feature, a compute queue), a discrete GPU is preferred,
// then an integrated one, a virtual one, and a CPU implementation (lavapipe) last; among devices
// of one kind, one with ray tracing. Ray tracing (VK_KHR_acceleration_structure,
// VK_KHR_ray_tracing_pipeline, VK_KHR_deferred_host_operations and their features) is enabled
// where the device has it (hasRayTracing()); without it only the compute backend runs.
// Environment:
//   SVDAG_VK_DEVICE=<substring>  only devices whose name contains it (case-insensitive)
//   SVDAG_VK_NO_RAY_TRACING=1    treat every device as one without ray tracing
//   SVDAG_VK_VALIDATION=1        enable VK_LAYER_KHRONOS_validation (messages on stderr)
// When nothing qualifies the constructor throws std::runtime_error naming every device found and
// what it lacks ("no Vulkan driver/loader" when the instance cannot be created); it never crashes
// on a machine without Vulkan (the loader is linked, but an absent driver is an error, not a
// crash).
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace svdag
{
namespace render
{

// Throws std::runtime_error("<what>: <VkResult name>") unless result is VK_SUCCESS.
void check(VkResult result, const char* what);
const char* resultName(VkResult result);

// Entry points of device extensions (not exported by the loader; null without ray tracing).
struct DeviceFunctions
{
  PFN_vkCreateAccelerationStructureKHR createAccelerationStructure = nullptr;
  PFN_vkDestroyAccelerationStructureKHR destroyAccelerationStructure = nullptr;
  PFN_vkGetAccelerationStructureBuildSizesKHR getAccelerationStructureBuildSizes = nullptr;
  PFN_vkGetAccelerationStructureDeviceAddressKHR getAccelerationStructureDeviceAddress = nullptr;
  PFN_vkCmdBuildAccelerationStructuresKHR cmdBuildAccelerationStructures = nullptr;
  PFN_vkCmdWriteAccelerationStructuresPropertiesKHR cmdWriteAccelerationStructuresProperties =
    nullptr;
  PFN_vkCmdCopyAccelerationStructureKHR cmdCopyAccelerationStructure = nullptr;
  PFN_vkCreateRayTracingPipelinesKHR createRayTracingPipelines = nullptr;
  PFN_vkGetRayTracingShaderGroupHandlesKHR getRayTracingShaderGroupHandles = nullptr;
  PFN_vkCmdTraceRaysKHR cmdTraceRays = nullptr;
};

// What does not fit the device's memory: what() names the bytes needed and the bytes available.
struct DeviceMemoryError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

// Driver limits the renderer depends on (read from the driver, never assumed; the ray tracing
// ones are 0 on a device without it).
struct RayTracingLimits
{
  uint64_t maxMemoryAllocationSize = 0; // bytes of one allocation (Vulkan 1.1 maintenance3)
  uint32_t shaderGroupHandleSize = 0;
  uint32_t shaderGroupHandleAlignment = 0;
  uint32_t shaderGroupBaseAlignment = 0;
  uint32_t maxRayRecursionDepth = 0;
  uint64_t maxPrimitiveCount = 0; // per BLAS
  uint64_t maxInstanceCount = 0;  // per TLAS
  uint32_t minScratchOffsetAlignment = 0;
  uint32_t maxRayDispatchInvocationCount = 0;
  uint32_t maxComputeWorkGroupCount[2] = { 0, 0 }; // x, y
};

class Context
{
public:
  // Creates the instance and the device (see the file comment). Throws std::runtime_error.
  Context();
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  VkInstance instance() const { return this->Instance; }
  VkPhysicalDevice physicalDevice() const { return this->PhysicalDevice; }
  VkDevice device() const { return this->Device; }
  VkQueue queue() const { return this->Queue; }
  uint32_t queueFamily() const { return this->QueueFamily; }
  const std::string& deviceName() const { return this->DeviceName; }
  bool isCpuDevice() const { return this->CpuDevice; }
  // Whether the ray tracing backend can run; if not, what the device lacks for it.
  bool hasRayTracing() const { return this->RayTracing; }
  const std::string& rayTracingMissing() const { return this->RayTracingMissing; }
  const DeviceFunctions& fn() const { return this->Functions; }
  const RayTracingLimits& limits() const { return this->Limits; }

  // A memory type allowed by typeBits with all `required` flags, preferring one that also has
  // `preferred`. Throws std::runtime_error when none exists.
  uint32_t memoryType(uint32_t typeBits, VkMemoryPropertyFlags required,
    VkMemoryPropertyFlags preferred = 0) const;

  // Device memory this context holds (every Buffer counts itself) and may hold: the size of
  // the memory heaps, or less if a limit is set (0: none), for a renderer sharing its GPU.
  uint64_t allocatedBytes() const { return this->AllocatedBytes; }
  uint64_t heapBytes() const { return this->HeapBytes; }
  void setMemoryLimit(uint64_t bytes) { this->MemoryLimit = bytes; }
  uint64_t memoryLimit() const { return this->MemoryLimit; }
  // Bytes that can still be allocated: min(heaps, limit) - allocated.
  uint64_t availableBytes() const;
  // Throws DeviceMemoryError naming `bytes` (for `what`) and availableBytes() when they do not
  // fit, or when one allocation of `largestAllocation` bytes exceeds the driver's limit.
  void checkFits(uint64_t bytes, const std::string& what, uint64_t largestAllocation) const;
  void noteAllocation(int64_t bytes) { this->AllocatedBytes += uint64_t(bytes); }

  // Records commands into a one-time command buffer, submits it and waits for completion.
  void submitAndWait(const std::function<void(VkCommandBuffer)>& record);

private:
  void createInstance();
  void pickPhysicalDevice();
  void createDevice();
  void destroy();

  VkInstance Instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT Messenger = VK_NULL_HANDLE; // with SVDAG_VK_VALIDATION only
  VkPhysicalDevice PhysicalDevice = VK_NULL_HANDLE;
  VkDevice Device = VK_NULL_HANDLE;
  VkQueue Queue = VK_NULL_HANDLE;
  uint32_t QueueFamily = 0;
  VkCommandPool CommandPool = VK_NULL_HANDLE;
  VkFence Fence = VK_NULL_HANDLE;
  std::string DeviceName;
  bool CpuDevice = false;
  bool RayTracing = false;
  std::string RayTracingMissing;
  VkPhysicalDeviceMemoryProperties MemoryProperties{};
  uint64_t HeapBytes = 0; // device-local heaps (all heaps if none is device-local)
  uint64_t AllocatedBytes = 0;
  uint64_t MemoryLimit = 0;
  DeviceFunctions Functions;
  RayTracingLimits Limits;
};

} // namespace render
} // namespace svdag
