// The Vulkan instance, the chosen device, its queue and the extension entry points: one Device
// per process, shared by every renderer through its Context.
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
// (read when the device is created). When nothing qualifies Device::acquire throws std::runtime_error naming every device found and
// what it lacks ("no Vulkan driver/loader" when the instance cannot be created); it never crashes
// on a machine without Vulkan (the loader is linked, but an absent driver is an error, not a
// crash).
#pragma once

#include <vulkan/vulkan.h>

#include "svdag_render/ShaderObjectApi.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
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
  // Null where the device cannot export memory (Device::canExportMemory).
  PFN_vkGetMemoryFdKHR getMemoryFd = nullptr;
  // Null where compute shaders are pipelines (Device::hasShaderObjects).
  PFN_vkCreateShadersEXT createShaders = nullptr;
  PFN_vkDestroyShaderEXT destroyShader = nullptr;
  PFN_vkGetShaderBinaryDataEXT getShaderBinaryData = nullptr;
  PFN_vkCmdBindShadersEXT cmdBindShaders = nullptr;
};

// Which device and driver this is, as Vulkan and OpenGL both report them
// (VkPhysicalDeviceIDProperties, GL_EXT_memory_object's GL_DEVICE_UUID_EXT / GL_DRIVER_UUID_EXT):
// memory one exports is importable by the other only where both match.
struct DeviceUuids
{
  std::array<uint8_t, 16> device{};
  std::array<uint8_t, 16> driver{};
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

class Context;
class PipelineLibrary;
class ComputePipeline;
struct PipelineCacheKey;
enum class Backend : uint32_t;

// The process's Vulkan instance, device and queue, shared by every Context (one per renderer):
// the first Context creates it, the last one to go destroys it (a later Context creates a new
// one, reading the environment variables again). A failed creation is not remembered: every
// Context that asks tries again and throws the same error. Besides the device it holds what the
// renderers share: the pipeline cache and, per backend, the pipelines of every feature set asked
// for (Pipeline.h's PipelineLibrary), and the count of device memory all users hold.
// Submissions to the one queue are serialised (Context::submitAndWait); the methods may be
// called from several threads.
class Device
{
public:
  // The device in use, or a new one (see the file comment). Throws std::runtime_error.
  static std::shared_ptr<Device> acquire();
  // Contexts holding the device now (0: no device exists).
  static size_t users();
  // Devices created in this process so far (a new one after the last user went counts again).
  static uint64_t created();

  ~Device();
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  // Which of the process's devices this is: 1 for the first one created, 2 for the next...
  uint64_t serial() const { return this->Serial; }
  VkInstance instance() const { return this->Instance; }
  VkPhysicalDevice physicalDevice() const { return this->PhysicalDevice; }
  VkDevice device() const { return this->Handle; }
  VkQueue queue() const { return this->Queue; }
  uint32_t queueFamily() const { return this->QueueFamily; }
  const std::string& deviceName() const { return this->DeviceName; }
  bool isCpuDevice() const { return this->CpuDevice; }
  bool hasRayTracing() const { return this->RayTracing; }
  const std::string& rayTracingMissing() const { return this->RayTracingMissing; }
  // Whether buffers can be allocated in memory exported as a file descriptor
  // (VK_KHR_external_memory_fd; Buffer's MemoryUse::Shared).
  bool canExportMemory() const { return this->MemoryExport; }
  // Whether shaders may compute in double precision (the shaderFloat64 feature, enabled where
  // the device has it: the depth pass of DepthPass.h needs it).
  bool hasFloat64() const { return this->Float64; }
  const DeviceUuids& uuids() const { return this->Uuids; }
  const DeviceFunctions& fn() const { return this->Functions; }
  const RayTracingLimits& limits() const { return this->Limits; }
  const VkPhysicalDeviceMemoryProperties& memoryProperties() const { return this->MemoryProperties; }
  uint64_t heapBytes() const { return this->HeapBytes; }
  VkPipelineCache pipelineCache() const { return this->PipelineCache; }
  // The persistent pipeline cache (PipelineCacheFile.h): its file ("" when disabled), the bytes
  // of driver data it gave the device when it was created (0: none, or none to trust), and why a
  // file that exists was not used or could not be written ("" when all went well).
  const std::string& pipelineCacheFile() const { return this->PipelineCacheFile; }
  uint64_t pipelineCacheLoadedBytes() const { return this->PipelineCacheLoaded; }
  std::string pipelineCacheProblem() const;
  // Writes the cache's data to its file (after a compilation); a failure is noted, not thrown.
  void savePipelineCache();

  // Whether compute shaders are shader objects (VK_EXT_shader_object, where the device has it and
  // SVDAG_VK_NO_SHADER_OBJECTS is not set; ComputeProgram.h) rather than pipelines: their
  // binaries are kept on disk (PipelineCacheFile.h), so a later process creates them without
  // compiling, which a pipeline cache does not give on lavapipe (it holds no pipeline data).
  bool hasShaderObjects() const { return this->ShaderObjects; }
  // The binary kept on disk for a shader of this hash (ComputeProgram.h's key), or none (empty:
  // no file, no cache directory, or a file not to trust, whose reason shaderBinaryProblem()
  // gives); and the binary of a shader just compiled, written to disk (a failure noted).
  std::vector<uint8_t> loadShaderBinary(uint64_t shaderHash);
  void saveShaderBinary(uint64_t shaderHash, const std::vector<uint8_t>& binary);
  // Whether a binary file is kept for a shader of this hash: what makes creating it a matter of
  // milliseconds (whether the file loads is only known by loading it).
  bool hasShaderBinary(uint64_t shaderHash) const;
  // Counts over the device's life: shaders created from a binary on disk, and compiled from
  // SPIR-V (a binary the driver refused counts as compiled); why the last binary file was not
  // used or written ("" when all went well).
  uint64_t shaderBinariesLoaded() const { return this->ShaderBinariesLoaded.load(); }
  uint64_t shadersCompiled() const { return this->ShadersCompiled.load(); }
  void noteShaderCreated(bool fromBinary, const std::string& problem);
  std::string shaderBinaryProblem() const;

  // Device memory every user holds together, and the part the device holds for all of them
  // (the pipelines' shader binding tables).
  uint64_t allocatedBytes() const { return this->AllocatedBytes.load(); }
  uint64_t sharedBytes() const;
  void noteAllocation(int64_t bytes) { this->AllocatedBytes += uint64_t(bytes); }

  // The pipelines of one backend (created on first use; the backend must be one the device can
  // run). Pipeline compilations so far, over every backend and user.
  PipelineLibrary& pipelines(Backend backend);
  uint64_t pipelineCompilations() const;
  // The compute pipeline of an embedded SPIR-V module (ComputePipeline.h: the depth pass, the
  // denoiser), compiled the first time any user asks for it (the reference stays valid for the
  // device's life). Throws std::runtime_error naming `what`.
  const ComputePipeline& computePipeline(const uint32_t* code, size_t bytes, const char* what);

  // Submits to the queue under the device's lock.
  VkResult submit(const VkSubmitInfo& info, VkFence fence);

private:
  Device();
  void createInstance();
  void pickPhysicalDevice();
  void createDevice();
  void destroy();
  PipelineCacheKey pipelineCacheKey() const;
  PipelineCacheKey shaderBinaryKey(uint64_t shaderHash) const;

  uint64_t Serial = 0;
  VkInstance Instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT Messenger = VK_NULL_HANDLE; // with SVDAG_VK_VALIDATION only
  VkPhysicalDevice PhysicalDevice = VK_NULL_HANDLE;
  VkDevice Handle = VK_NULL_HANDLE;
  VkQueue Queue = VK_NULL_HANDLE;
  uint32_t QueueFamily = 0;
  VkPipelineCache PipelineCache = VK_NULL_HANDLE;
  std::string PipelineCacheFile;
  uint64_t PipelineCacheLoaded = 0;
  std::string PipelineCacheProblem;
  std::array<uint8_t, 16> PipelineCacheUuid{};
  uint32_t VendorId = 0, DeviceId = 0, DriverVersion = 0;
  mutable std::mutex PipelineCacheLock;
  std::string DeviceName;
  bool CpuDevice = false;
  bool RayTracing = false;
  std::string RayTracingMissing;
  bool MemoryExport = false;
  bool Float64 = false;
  bool ShaderObjects = false;
  std::array<uint8_t, 16> ShaderBinaryUuid{};
  uint32_t ShaderBinaryVersion = 0;
  std::string ShaderBinaryDirectory; // "" when the cache is disabled
  std::string ShaderBinaryProblem;   // under PipelineCacheLock
  std::atomic<uint64_t> ShaderBinariesLoaded{ 0 };
  std::atomic<uint64_t> ShadersCompiled{ 0 };
  DeviceUuids Uuids;
  VkPhysicalDeviceMemoryProperties MemoryProperties{};
  uint64_t HeapBytes = 0; // device-local heaps (all heaps if none is device-local)
  std::atomic<uint64_t> AllocatedBytes{ 0 };
  DeviceFunctions Functions;
  RayTracingLimits Limits;
  std::mutex QueueLock;
  std::mutex PipelineLock;
  // The device's own allocations (shader binding tables) are counted on this context.
  std::unique_ptr<Context> Own;
  std::unique_ptr<PipelineLibrary> Libraries[3]; // indexed by Backend
  std::map<const uint32_t*, std::unique_ptr<ComputePipeline>> ComputePipelines; // by SPIR-V
};

// One user's (one renderer's) handle on the shared Device: its own command pool and fence, and
// the count of the device memory it holds, checked against its own limit.
class Context
{
public:
  // Takes the process's device, creating it if there is none (Device::acquire). Throws
  // std::runtime_error naming every device found and what it lacks.
  Context();
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // Contexts sharing the process's device now (Device::users).
  static size_t users() { return Device::users(); }
  Device& shared() const { return *this->Dev; }

  VkInstance instance() const { return this->Dev->instance(); }
  VkPhysicalDevice physicalDevice() const { return this->Dev->physicalDevice(); }
  VkDevice device() const { return this->Dev->device(); }
  VkQueue queue() const { return this->Dev->queue(); }
  uint32_t queueFamily() const { return this->Dev->queueFamily(); }
  const std::string& deviceName() const { return this->Dev->deviceName(); }
  bool isCpuDevice() const { return this->Dev->isCpuDevice(); }
  // Whether the ray tracing backend can run; if not, what the device lacks for it.
  bool hasRayTracing() const { return this->Dev->hasRayTracing(); }
  const std::string& rayTracingMissing() const { return this->Dev->rayTracingMissing(); }
  bool canExportMemory() const { return this->Dev->canExportMemory(); }
  bool hasFloat64() const { return this->Dev->hasFloat64(); }
  const DeviceUuids& uuids() const { return this->Dev->uuids(); }
  const DeviceFunctions& fn() const { return this->Dev->fn(); }
  const RayTracingLimits& limits() const { return this->Dev->limits(); }

  // A memory type allowed by typeBits with all `required` flags, preferring one that also has
  // `preferred`. Throws std::runtime_error when none exists.
  uint32_t memoryType(uint32_t typeBits, VkMemoryPropertyFlags required,
    VkMemoryPropertyFlags preferred = 0) const;

  // Device memory this context holds (every Buffer counts itself on the context it was made
  // with) and may hold. The limit (0: none) is this context's own, for a renderer sharing its
  // GPU: it caps this context's bytes, whatever the other users of the device hold; the heaps
  // cap what all users hold together.
  uint64_t allocatedBytes() const { return this->AllocatedBytes; }
  uint64_t heapBytes() const { return this->Dev->heapBytes(); }
  void setMemoryLimit(uint64_t bytes) { this->MemoryLimit = bytes; }
  uint64_t memoryLimit() const { return this->MemoryLimit; }
  // Bytes that can still be allocated: min(heaps - what every user holds, limit - allocated).
  uint64_t availableBytes() const;
  // Throws DeviceMemoryError naming `bytes` (for `what`) and availableBytes() when they do not
  // fit, or when one allocation of `largestAllocation` bytes exceeds the driver's limit.
  void checkFits(uint64_t bytes, const std::string& what, uint64_t largestAllocation) const;
  void noteAllocation(int64_t bytes);

  // Records commands into a one-time command buffer, submits it (the device serialises
  // submissions) and waits for its completion.
  void submitAndWait(const std::function<void(VkCommandBuffer)>& record);

private:
  friend class Device;
  explicit Context(Device& device); // the device's own context (holds no reference)
  void createCommandObjects();
  void destroy();

  std::shared_ptr<Device> Keep; // null for the device's own context
  Device* Dev = nullptr;
  VkCommandPool CommandPool = VK_NULL_HANDLE;
  VkFence Fence = VK_NULL_HANDLE;
  bool InFlight = false; // submitted, not yet waited for
  uint64_t AllocatedBytes = 0;
  uint64_t MemoryLimit = 0;
};

} // namespace render
} // namespace svdag
