#include "svdag_render/Context.h"

#include "svdag_render/ComputePipeline.h"
#include "svdag_render/Pipeline.h"
#include "svdag_render/PipelineCacheFile.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace svdag
{
namespace render
{
namespace
{
// What every backend needs (the compute backend needs nothing else) ...
const char* const RequiredExtensions[] = {
  VK_KHR_BUFFER_DEVICE_ADDRESS_EXTENSION_NAME,
};
// ... and what the ray tracing backend adds, enabled where the device has it.
const char* const RayTracingExtensions[] = {
  VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME,
  VK_KHR_RAY_TRACING_PIPELINE_EXTENSION_NAME,
  VK_KHR_DEFERRED_HOST_OPERATIONS_EXTENSION_NAME,
};
// Exporting device memory as a POSIX file descriptor (OpenGL imports it with
// GL_EXT_memory_object_fd: the volume mapper's image without a host copy); enabled where present.
const char* const MemoryExportExtension = VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME;
// Set (not "0"): every device counts as one without ray tracing (what a GPU without the
// extensions does: the renderer uses its compute backend).
const char* const NoRayTracingVariable = "SVDAG_VK_NO_RAY_TRACING";
// Set (not "0"): compute shaders are pipelines even where the device has shader objects (a
// comparison, or a driver whose shader objects misbehave).
const char* const NoShaderObjectsVariable = "SVDAG_VK_NO_SHADER_OBJECTS";
const char* const ValidationLayer = "VK_LAYER_KHRONOS_validation";

std::string lower(std::string s)
{
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool envFlag(const char* name)
{
  const char* v = std::getenv(name);
  return v && *v && std::strcmp(v, "0") != 0;
}

// Lower is better: discrete, integrated, virtual, CPU, other.
int typeRank(VkPhysicalDeviceType type)
{
  switch (type)
  {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
  }
}

// Feature structures the renderer enables, chained for vkGetPhysicalDeviceFeatures2 and
// vkCreateDevice alike.
struct FeatureChain
{
  VkPhysicalDeviceFeatures2 base{ VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2 };
  VkPhysicalDeviceVulkan12Features v12{ VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES };
  VkPhysicalDeviceAccelerationStructureFeaturesKHR as{
    VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR
  };
  VkPhysicalDeviceRayTracingPipelineFeaturesKHR rt{
    VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_FEATURES_KHR
  };
  FeatureChain()
  {
    base.pNext = &v12;
    v12.pNext = &as;
    as.pNext = &rt;
  }
  FeatureChain(const FeatureChain&) = delete;
};

// What one physical device lacks (empty: it qualifies), what it lacks for ray tracing (empty:
// the ray tracing backend can run) and its compute queue family.
struct Candidate
{
  VkPhysicalDevice device = VK_NULL_HANDLE;
  std::string name;
  VkPhysicalDeviceType type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  std::vector<std::string> missing;
  std::vector<std::string> rayTracingMissing;
  bool memoryExport = false;
  bool float64 = false;
  bool shaderObject = false;
  uint32_t queueFamily = 0;
};

bool hasExtension(const std::vector<VkExtensionProperties>& extensions, const char* name)
{
  return std::any_of(extensions.begin(), extensions.end(),
    [name](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

Candidate inspect(VkPhysicalDevice device)
{
  Candidate c;
  c.device = device;
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(device, &props);
  c.name = props.deviceName;
  c.type = props.deviceType;
  if (props.apiVersion < VK_API_VERSION_1_2)
  {
    c.missing.push_back("Vulkan 1.2");
    return c; // the 1.2 feature query below would be invalid
  }
  uint32_t count = 0;
  vkEnumerateDeviceExtensionProperties(device, nullptr, &count, nullptr);
  std::vector<VkExtensionProperties> extensions(count);
  vkEnumerateDeviceExtensionProperties(device, nullptr, &count, extensions.data());
  for (const char* required : RequiredExtensions)
  {
    if (!hasExtension(extensions, required))
      c.missing.push_back(required);
  }
  if (!c.missing.empty())
    return c;
  c.memoryExport = hasExtension(extensions, MemoryExportExtension);
  for (const char* extension : RayTracingExtensions)
  {
    if (!hasExtension(extensions, extension))
      c.rayTracingMissing.push_back(extension);
  }
  FeatureChain features;
  if (!c.rayTracingMissing.empty())
    features.v12.pNext = nullptr; // the ray tracing feature structs are not known to the device
  vkGetPhysicalDeviceFeatures2(device, &features.base);
  if (!features.v12.bufferDeviceAddress)
    c.missing.push_back("bufferDeviceAddress feature");
  // The compute backend's edge coverage shares rays across a subgroup (PathTrace.glsl).
  VkPhysicalDeviceSubgroupProperties subgroup{ VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES };
  VkPhysicalDeviceProperties2 properties{ VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2 };
  properties.pNext = &subgroup;
  vkGetPhysicalDeviceProperties2(device, &properties);
  const VkSubgroupFeatureFlags wanted = VK_SUBGROUP_FEATURE_BALLOT_BIT | VK_SUBGROUP_FEATURE_SHUFFLE_BIT;
  if (!(subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) ||
    (subgroup.supportedOperations & wanted) != wanted)
    c.missing.push_back("subgroup ballot and shuffle in compute shaders");
  c.float64 = features.base.features.shaderFloat64 == VK_TRUE;
  if (hasExtension(extensions, VK_EXT_SHADER_OBJECT_EXTENSION_NAME) &&
    !envFlag(NoShaderObjectsVariable))
  {
    VkPhysicalDeviceShaderObjectFeaturesEXT shaderObject{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_OBJECT_FEATURES_EXT
    };
    VkPhysicalDeviceFeatures2 query{ VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2 };
    query.pNext = &shaderObject;
    vkGetPhysicalDeviceFeatures2(device, &query);
    c.shaderObject = shaderObject.shaderObject == VK_TRUE;
  }
  if (c.rayTracingMissing.empty())
  {
    if (!features.as.accelerationStructure)
      c.rayTracingMissing.push_back("accelerationStructure feature");
    if (!features.rt.rayTracingPipeline)
      c.rayTracingMissing.push_back("rayTracingPipeline feature");
  }
  if (envFlag(NoRayTracingVariable))
    c.rayTracingMissing.push_back(std::string("ray tracing (") + NoRayTracingVariable + " is set)");
  vkGetPhysicalDeviceQueueFamilyProperties(device, &count, nullptr);
  std::vector<VkQueueFamilyProperties> families(count);
  vkGetPhysicalDeviceQueueFamilyProperties(device, &count, families.data());
  bool compute = false;
  for (uint32_t i = 0; i < count && !compute; ++i)
  {
    if (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT)
    {
      c.queueFamily = i;
      compute = true;
    }
  }
  if (!compute)
    c.missing.push_back("a compute queue");
  return c;
}

// Prints validation warnings and errors on stderr.
VKAPI_ATTR VkBool32 VKAPI_CALL printValidationMessage(
  VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT,
  const VkDebugUtilsMessengerCallbackDataEXT* data, void*)
{
  const char* level =
    (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) ? "error" : "warning";
  std::fprintf(stderr, "svdag::render Vulkan validation %s: %s\n", level,
    data && data->pMessage ? data->pMessage : "");
  return VK_FALSE;
}

std::string describe(const std::vector<Candidate>& candidates)
{
  std::string s;
  for (const Candidate& c : candidates)
  {
    s += "\n  '" + c.name + "': ";
    if (c.missing.empty())
    {
      s += c.rayTracingMissing.empty() ? "usable, with ray tracing" : "usable, compute only";
      continue;
    }
    s += "lacks ";
    for (size_t i = 0; i < c.missing.size(); ++i)
      s += (i ? ", " : "") + c.missing[i];
  }
  return s;
}
} // namespace

const char* resultName(VkResult result)
{
  switch (result)
  {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_INCOMPLETE: return "VK_INCOMPLETE";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
    case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY";
    case VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS: return "VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS";
    default: return "VkResult error";
  }
}

void check(VkResult result, const char* what)
{
  if (result != VK_SUCCESS)
  {
    throw std::runtime_error(std::string(what) + " failed: " + resultName(result) + " (" +
      std::to_string(int(result)) + ")");
  }
}

namespace
{
// The process's device: held by its users (Context::Keep), only observed here.
std::mutex DeviceLock;
std::weak_ptr<Device> CurrentDevice;
uint64_t DevicesCreated = 0;
} // namespace

std::shared_ptr<Device> Device::acquire()
{
  std::lock_guard<std::mutex> lock(DeviceLock);
  if (std::shared_ptr<Device> device = CurrentDevice.lock())
    return device;
  std::shared_ptr<Device> device(new Device());
  device->Serial = ++DevicesCreated;
  CurrentDevice = device;
  return device;
}

size_t Device::users()
{
  std::lock_guard<std::mutex> lock(DeviceLock);
  return size_t(CurrentDevice.use_count());
}

uint64_t Device::created()
{
  std::lock_guard<std::mutex> lock(DeviceLock);
  return DevicesCreated;
}

Device::Device()
{
  try
  {
    this->createInstance();
    this->pickPhysicalDevice();
    this->createDevice();
    this->Own.reset(new Context(*this));
  }
  catch (...)
  {
    this->destroy();
    throw;
  }
}

Device::~Device()
{
  this->destroy();
}

void Device::destroy()
{
  if (this->Handle)
  {
    vkDeviceWaitIdle(this->Handle); // no user is left: nothing else submits
    for (auto& library : this->Libraries)
      library.reset();
    this->ComputePipelines.clear();
    this->Own.reset();
    if (this->PipelineCache)
      vkDestroyPipelineCache(this->Handle, this->PipelineCache, nullptr);
    this->PipelineCache = VK_NULL_HANDLE;
    vkDestroyDevice(this->Handle, nullptr);
    this->Handle = VK_NULL_HANDLE;
  }
  if (this->Messenger)
  {
    auto destroyMessenger = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
      vkGetInstanceProcAddr(this->Instance, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroyMessenger)
      destroyMessenger(this->Instance, this->Messenger, nullptr);
    this->Messenger = VK_NULL_HANDLE;
  }
  if (this->Instance)
  {
    vkDestroyInstance(this->Instance, nullptr);
    this->Instance = VK_NULL_HANDLE;
  }
}

uint64_t Device::sharedBytes() const
{
  return this->Own ? this->Own->allocatedBytes() : 0;
}

PipelineLibrary& Device::pipelines(Backend backend)
{
  std::lock_guard<std::mutex> lock(this->PipelineLock);
  std::unique_ptr<PipelineLibrary>& library = this->Libraries[size_t(backend)];
  if (!library)
    library = std::make_unique<PipelineLibrary>(*this->Own, backend);
  return *library;
}

const ComputePipeline& Device::computePipeline(
  const uint32_t* code, size_t bytes, const char* what)
{
  std::lock_guard<std::mutex> lock(this->PipelineLock);
  std::unique_ptr<ComputePipeline>& pipeline = this->ComputePipelines[code];
  if (!pipeline)
    pipeline = std::make_unique<ComputePipeline>(*this->Own, code, bytes, what);
  return *pipeline;
}

uint64_t Device::pipelineCompilations() const
{
  uint64_t compilations = 0;
  for (const auto& library : this->Libraries)
    compilations += library ? library->compilations() : 0;
  return compilations;
}

VkResult Device::submit(const VkSubmitInfo& info, VkFence fence)
{
  std::lock_guard<std::mutex> lock(this->QueueLock);
  return vkQueueSubmit(this->Queue, 1, &info, fence);
}

Context::Context()
  : Keep(Device::acquire())
  , Dev(Keep.get())
{
  try
  {
    this->createCommandObjects();
  }
  catch (...)
  {
    this->destroy();
    throw;
  }
}

Context::Context(Device& device)
  : Dev(&device)
{
  try
  {
    this->createCommandObjects();
  }
  catch (...)
  {
    this->destroy();
    throw;
  }
}

Context::~Context()
{
  this->destroy();
}

void Context::createCommandObjects()
{
  VkCommandPoolCreateInfo poolInfo{ VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO };
  poolInfo.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
  poolInfo.queueFamilyIndex = this->Dev->queueFamily();
  check(vkCreateCommandPool(this->device(), &poolInfo, nullptr, &this->CommandPool),
    "vkCreateCommandPool");
  VkFenceCreateInfo fenceInfo{ VK_STRUCTURE_TYPE_FENCE_CREATE_INFO };
  check(vkCreateFence(this->device(), &fenceInfo, nullptr, &this->Fence), "vkCreateFence");
}

void Context::destroy()
{
  VkDevice device = this->device();
  if (this->Fence)
  {
    // Every submission waits for its fence; one whose wait failed may still run.
    if (this->InFlight)
      vkWaitForFences(device, 1, &this->Fence, VK_TRUE, UINT64_MAX);
    vkDestroyFence(device, this->Fence, nullptr);
  }
  if (this->CommandPool)
    vkDestroyCommandPool(device, this->CommandPool, nullptr);
  this->Fence = VK_NULL_HANDLE;
  this->CommandPool = VK_NULL_HANDLE;
}

void Context::noteAllocation(int64_t bytes)
{
  this->AllocatedBytes += uint64_t(bytes);
  this->Dev->noteAllocation(bytes);
}

void Device::createInstance()
{
  uint32_t loaderVersion = 0;
  if (vkEnumerateInstanceVersion(&loaderVersion) != VK_SUCCESS ||
    loaderVersion < VK_API_VERSION_1_2)
  {
    throw std::runtime_error("no Vulkan driver/loader with Vulkan 1.2 found");
  }
  std::vector<const char*> layers;
  std::vector<const char*> extensions;
  const bool validation = envFlag("SVDAG_VK_VALIDATION");
  if (validation)
  {
    uint32_t count = 0;
    vkEnumerateInstanceLayerProperties(&count, nullptr);
    std::vector<VkLayerProperties> available(count);
    vkEnumerateInstanceLayerProperties(&count, available.data());
    const bool found = std::any_of(available.begin(), available.end(),
      [](const VkLayerProperties& l) { return std::strcmp(l.layerName, ValidationLayer) == 0; });
    if (!found)
      throw std::runtime_error("SVDAG_VK_VALIDATION is set but the Vulkan validation layer "
                               "VK_LAYER_KHRONOS_validation is not installed");
    layers.push_back(ValidationLayer);
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME); // provided by the layer
  }
  VkApplicationInfo app{ VK_STRUCTURE_TYPE_APPLICATION_INFO };
  app.pApplicationName = "vtkSVDAG";
  app.pEngineName = "svdag::render";
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo info{ VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO };
  info.pApplicationInfo = &app;
  info.enabledLayerCount = uint32_t(layers.size());
  info.ppEnabledLayerNames = layers.data();
  info.enabledExtensionCount = uint32_t(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  const VkResult result = vkCreateInstance(&info, nullptr, &this->Instance);
  if (result != VK_SUCCESS)
  {
    this->Instance = VK_NULL_HANDLE;
    throw std::runtime_error(std::string("no Vulkan driver/loader: vkCreateInstance failed (") +
      resultName(result) + ")");
  }
  if (validation)
  {
    auto createMessenger = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
      vkGetInstanceProcAddr(this->Instance, "vkCreateDebugUtilsMessengerEXT"));
    if (!createMessenger)
      throw std::runtime_error("the validation layer has no VK_EXT_debug_utils");
    VkDebugUtilsMessengerCreateInfoEXT messenger{
      VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT
    };
    messenger.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
      VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
      VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
      VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    messenger.pfnUserCallback = printValidationMessage;
    check(createMessenger(this->Instance, &messenger, nullptr, &this->Messenger),
      "vkCreateDebugUtilsMessengerEXT");
  }
}

void Device::pickPhysicalDevice()
{
  uint32_t count = 0;
  vkEnumeratePhysicalDevices(this->Instance, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  if (count)
    vkEnumeratePhysicalDevices(this->Instance, &count, devices.data());
  if (devices.empty())
    throw std::runtime_error("no Vulkan driver/loader: Vulkan reports no physical device");

  std::vector<Candidate> candidates;
  for (VkPhysicalDevice d : devices)
    candidates.push_back(inspect(d));

  const char* forced = std::getenv("SVDAG_VK_DEVICE");
  const std::string wanted = forced ? lower(forced) : std::string();
  const Candidate* best = nullptr;
  bool nameMatched = false;
  for (const Candidate& c : candidates)
  {
    if (!wanted.empty() && lower(c.name).find(wanted) == std::string::npos)
      continue;
    nameMatched = true;
    if (!c.missing.empty())
      continue;
    // The kind of device first (a discrete GPU over lavapipe), then ray tracing.
    const bool better = !best || typeRank(c.type) < typeRank(best->type) ||
      (typeRank(c.type) == typeRank(best->type) && c.rayTracingMissing.empty() &&
        !best->rayTracingMissing.empty());
    if (better)
      best = &c;
  }
  if (!best)
  {
    std::string message = "no usable Vulkan device (Vulkan 1.2 with buffer device addresses and "
                          "a compute queue)";
    if (!wanted.empty())
    {
      message += nameMatched ? " matches" : " and no device at all matches";
      message += std::string(" SVDAG_VK_DEVICE='") + forced + "'";
    }
    throw std::runtime_error(message + "; devices found:" + describe(candidates));
  }
  this->PhysicalDevice = best->device;
  this->DeviceName = best->name;
  this->CpuDevice = best->type == VK_PHYSICAL_DEVICE_TYPE_CPU;
  this->QueueFamily = best->queueFamily;
  this->RayTracing = best->rayTracingMissing.empty();
  this->MemoryExport = best->memoryExport;
  this->Float64 = best->float64;
  this->ShaderObjects = best->shaderObject;
  for (size_t i = 0; i < best->rayTracingMissing.size(); ++i)
    this->RayTracingMissing += (i ? ", " : "") + best->rayTracingMissing[i];
}

void Device::createDevice()
{
  VkPhysicalDeviceAccelerationStructurePropertiesKHR asProps{
    VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_PROPERTIES_KHR
  };
  VkPhysicalDeviceRayTracingPipelinePropertiesKHR rtProps{
    VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_TRACING_PIPELINE_PROPERTIES_KHR
  };
  rtProps.pNext = &asProps;
  VkPhysicalDeviceMaintenance3Properties m3Props{
    VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES
  };
  asProps.pNext = &m3Props;
  VkPhysicalDeviceIDProperties idProps{ VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES };
  m3Props.pNext = &idProps;
  VkPhysicalDeviceShaderObjectPropertiesEXT shaderObjectProps{
    VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_OBJECT_PROPERTIES_EXT
  };
  if (this->ShaderObjects)
    idProps.pNext = &shaderObjectProps;
  VkPhysicalDeviceProperties2 props{ VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2 };
  // The ray tracing property structs only where the device has the extensions.
  props.pNext = this->RayTracing ? static_cast<void*>(&rtProps) : static_cast<void*>(&m3Props);
  vkGetPhysicalDeviceProperties2(this->PhysicalDevice, &props);
  std::copy(std::begin(idProps.deviceUUID), std::end(idProps.deviceUUID), this->Uuids.device.begin());
  std::copy(std::begin(idProps.driverUUID), std::end(idProps.driverUUID), this->Uuids.driver.begin());
  std::copy(std::begin(shaderObjectProps.shaderBinaryUUID),
    std::end(shaderObjectProps.shaderBinaryUUID), this->ShaderBinaryUuid.begin());
  this->ShaderBinaryVersion = shaderObjectProps.shaderBinaryVersion;
  for (int a = 0; a < 2; ++a)
    this->Limits.maxComputeWorkGroupCount[a] = props.properties.limits.maxComputeWorkGroupCount[a];
  this->Limits.maxMemoryAllocationSize = m3Props.maxMemoryAllocationSize;
  this->Limits.shaderGroupHandleSize = rtProps.shaderGroupHandleSize;
  this->Limits.shaderGroupHandleAlignment = rtProps.shaderGroupHandleAlignment;
  this->Limits.shaderGroupBaseAlignment = rtProps.shaderGroupBaseAlignment;
  this->Limits.maxRayRecursionDepth = rtProps.maxRayRecursionDepth;
  this->Limits.maxRayDispatchInvocationCount = rtProps.maxRayDispatchInvocationCount;
  this->Limits.maxPrimitiveCount = asProps.maxPrimitiveCount;
  this->Limits.maxInstanceCount = asProps.maxInstanceCount;
  this->Limits.minScratchOffsetAlignment =
    std::max<uint32_t>(1, asProps.minAccelerationStructureScratchOffsetAlignment);
  vkGetPhysicalDeviceMemoryProperties(this->PhysicalDevice, &this->MemoryProperties);
  uint64_t localHeaps = 0, allHeaps = 0;
  for (uint32_t i = 0; i < this->MemoryProperties.memoryHeapCount; ++i)
  {
    const VkMemoryHeap& heap = this->MemoryProperties.memoryHeaps[i];
    allHeaps += heap.size;
    if (heap.flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
      localHeaps += heap.size;
  }
  this->HeapBytes = localHeaps ? localHeaps : allHeaps;

  FeatureChain enabled;
  enabled.v12.bufferDeviceAddress = VK_TRUE;
  enabled.as.accelerationStructure = VK_TRUE;
  enabled.rt.rayTracingPipeline = VK_TRUE;
  // Optional: only the depth pass (DepthPass.h) needs it, which is not used without it.
  enabled.base.features.shaderFloat64 = this->Float64 ? VK_TRUE : VK_FALSE;
  std::vector<const char*> extensions(std::begin(RequiredExtensions), std::end(RequiredExtensions));
  if (this->RayTracing)
    extensions.insert(
      extensions.end(), std::begin(RayTracingExtensions), std::end(RayTracingExtensions));
  else
    enabled.v12.pNext = nullptr;
  if (this->MemoryExport)
    extensions.push_back(MemoryExportExtension);
  VkPhysicalDeviceShaderObjectFeaturesEXT shaderObject{
    VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_OBJECT_FEATURES_EXT
  };
  if (this->ShaderObjects)
  {
    extensions.push_back(VK_EXT_SHADER_OBJECT_EXTENSION_NAME);
    shaderObject.shaderObject = VK_TRUE;
    shaderObject.pNext = enabled.base.pNext;
    enabled.base.pNext = &shaderObject;
  }
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo queueInfo{ VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO };
  queueInfo.queueFamilyIndex = this->QueueFamily;
  queueInfo.queueCount = 1;
  queueInfo.pQueuePriorities = &priority;
  VkDeviceCreateInfo info{ VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO };
  info.pNext = &enabled.base;
  info.queueCreateInfoCount = 1;
  info.pQueueCreateInfos = &queueInfo;
  info.enabledExtensionCount = uint32_t(extensions.size());
  info.ppEnabledExtensionNames = extensions.data();
  check(vkCreateDevice(this->PhysicalDevice, &info, nullptr, &this->Handle), "vkCreateDevice");
  vkGetDeviceQueue(this->Handle, this->QueueFamily, 0, &this->Queue);

  auto load = [this](auto& fn, const char* name) {
    fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(
      vkGetDeviceProcAddr(this->Handle, name));
    if (!fn)
      throw std::runtime_error(std::string("Vulkan entry point missing: ") + name);
  };
  DeviceFunctions& f = this->Functions;
  if (this->RayTracing)
  {
    load(f.createAccelerationStructure, "vkCreateAccelerationStructureKHR");
    load(f.destroyAccelerationStructure, "vkDestroyAccelerationStructureKHR");
    load(f.getAccelerationStructureBuildSizes, "vkGetAccelerationStructureBuildSizesKHR");
    load(f.getAccelerationStructureDeviceAddress, "vkGetAccelerationStructureDeviceAddressKHR");
    load(f.cmdBuildAccelerationStructures, "vkCmdBuildAccelerationStructuresKHR");
    load(f.cmdWriteAccelerationStructuresProperties,
      "vkCmdWriteAccelerationStructuresPropertiesKHR");
    load(f.cmdCopyAccelerationStructure, "vkCmdCopyAccelerationStructureKHR");
    load(f.createRayTracingPipelines, "vkCreateRayTracingPipelinesKHR");
    load(f.getRayTracingShaderGroupHandles, "vkGetRayTracingShaderGroupHandlesKHR");
    load(f.cmdTraceRays, "vkCmdTraceRaysKHR");
  }
  if (this->MemoryExport)
    load(f.getMemoryFd, "vkGetMemoryFdKHR");
  if (this->ShaderObjects)
  {
    load(f.createShaders, "vkCreateShadersEXT");
    load(f.destroyShader, "vkDestroyShaderEXT");
    load(f.getShaderBinaryData, "vkGetShaderBinaryDataEXT");
    load(f.cmdBindShaders, "vkCmdBindShadersEXT");
  }

  // One cache for every pipeline any user compiles, started from the file an earlier process
  // left (PipelineCacheFile.h) where there is one to trust.
  this->VendorId = props.properties.vendorID;
  this->DeviceId = props.properties.deviceID;
  this->DriverVersion = props.properties.driverVersion;
  std::copy(std::begin(props.properties.pipelineCacheUUID),
    std::end(props.properties.pipelineCacheUUID), this->PipelineCacheUuid.begin());
  const std::string directory = pipelineCacheDirectory();
  this->ShaderBinaryDirectory = this->ShaderObjects ? directory : std::string();
  std::vector<uint8_t> initial;
  if (!directory.empty())
  {
    this->PipelineCacheFile = pipelineCacheFileName(directory, this->pipelineCacheKey());
    initial = loadPipelineCache(this->PipelineCacheFile, this->pipelineCacheKey(),
      this->PipelineCacheProblem);
  }
  VkPipelineCacheCreateInfo cacheInfo{ VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO };
  cacheInfo.initialDataSize = initial.size();
  cacheInfo.pInitialData = initial.empty() ? nullptr : initial.data();
  if (vkCreatePipelineCache(this->Handle, &cacheInfo, nullptr, &this->PipelineCache) ==
      VK_SUCCESS)
    this->PipelineCacheLoaded = initial.size();
  else
  {
    if (!initial.empty())
      this->PipelineCacheProblem = "the driver refused its data";
    cacheInfo.initialDataSize = 0;
    cacheInfo.pInitialData = nullptr;
    check(vkCreatePipelineCache(this->Handle, &cacheInfo, nullptr, &this->PipelineCache),
      "vkCreatePipelineCache");
  }
}

PipelineCacheKey Device::pipelineCacheKey() const
{
  PipelineCacheKey key;
  key.vendorId = this->VendorId;
  key.deviceId = this->DeviceId;
  key.driverVersion = this->DriverVersion;
  key.cacheUuid = this->PipelineCacheUuid;
  key.shaderHash = PipelineLibrary::shaderHash();
  return key;
}

PipelineCacheKey Device::shaderBinaryKey(uint64_t shaderHash) const
{
  PipelineCacheKey key = this->pipelineCacheKey();
  key.cacheUuid = this->ShaderBinaryUuid;
  // The device's binary version changes when the driver's binaries would no longer load.
  key.shaderHash = fnv1a64(&this->ShaderBinaryVersion, sizeof(this->ShaderBinaryVersion), shaderHash);
  return key;
}

std::vector<uint8_t> Device::loadShaderBinary(uint64_t shaderHash)
{
  if (this->ShaderBinaryDirectory.empty())
    return {};
  const PipelineCacheKey key = this->shaderBinaryKey(shaderHash);
  std::string why;
  std::vector<uint8_t> binary =
    render::loadShaderBinary(shaderBinaryFileName(this->ShaderBinaryDirectory, key), key, why);
  if (!why.empty())
  {
    std::lock_guard<std::mutex> lock(this->PipelineCacheLock);
    this->ShaderBinaryProblem = why;
  }
  return binary;
}

bool Device::hasShaderBinary(uint64_t shaderHash) const
{
  if (this->ShaderBinaryDirectory.empty())
    return false;
  std::error_code error;
  return std::filesystem::is_regular_file(
    shaderBinaryFileName(this->ShaderBinaryDirectory, this->shaderBinaryKey(shaderHash)), error);
}

void Device::saveShaderBinary(uint64_t shaderHash, const std::vector<uint8_t>& binary)
{
  if (this->ShaderBinaryDirectory.empty())
    return;
  const PipelineCacheKey key = this->shaderBinaryKey(shaderHash);
  std::string why;
  if (binary.empty())
    why = "the driver returned no shader binary";
  else
    render::saveShaderBinary(
      shaderBinaryFileName(this->ShaderBinaryDirectory, key), key, binary, why);
  if (!why.empty())
  {
    std::lock_guard<std::mutex> lock(this->PipelineCacheLock);
    this->ShaderBinaryProblem = why;
  }
}

void Device::noteShaderCreated(bool fromBinary, const std::string& problem)
{
  ++(fromBinary ? this->ShaderBinariesLoaded : this->ShadersCompiled);
  if (!problem.empty())
  {
    std::lock_guard<std::mutex> lock(this->PipelineCacheLock);
    this->ShaderBinaryProblem = problem;
  }
}

std::string Device::shaderBinaryProblem() const
{
  std::lock_guard<std::mutex> lock(this->PipelineCacheLock);
  return this->ShaderBinaryProblem;
}

std::string Device::pipelineCacheProblem() const
{
  std::lock_guard<std::mutex> lock(this->PipelineCacheLock);
  return this->PipelineCacheProblem;
}

void Device::savePipelineCache()
{
  if (this->PipelineCacheFile.empty())
    return;
  std::lock_guard<std::mutex> lock(this->PipelineCacheLock);
  size_t size = 0;
  std::vector<uint8_t> data;
  if (vkGetPipelineCacheData(this->Handle, this->PipelineCache, &size, nullptr) == VK_SUCCESS)
  {
    data.resize(size);
    if (vkGetPipelineCacheData(this->Handle, this->PipelineCache, &size, data.data()) != VK_SUCCESS)
      size = 0;
    data.resize(size);
  }
  std::string why;
  if (data.empty())
    this->PipelineCacheProblem = "the driver returned no cache data";
  else if (!render::savePipelineCache(this->PipelineCacheFile, this->pipelineCacheKey(), data, why))
    this->PipelineCacheProblem = why;
}

uint32_t Context::memoryType(
  uint32_t typeBits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const
{
  const VkPhysicalDeviceMemoryProperties& m = this->Dev->memoryProperties();
  for (const VkMemoryPropertyFlags want : { required | preferred, required })
  {
    for (uint32_t i = 0; i < m.memoryTypeCount; ++i)
    {
      if ((typeBits & (1u << i)) && (m.memoryTypes[i].propertyFlags & want) == want)
        return i;
    }
  }
  throw std::runtime_error("no Vulkan memory type with the required properties");
}

uint64_t Context::availableBytes() const
{
  const uint64_t heaps = this->Dev->heapBytes();
  const uint64_t everyone = this->Dev->allocatedBytes();
  uint64_t available = heaps > everyone ? heaps - everyone : 0;
  if (this->MemoryLimit)
    available = std::min(available,
      this->MemoryLimit > this->AllocatedBytes ? this->MemoryLimit - this->AllocatedBytes : 0);
  return available;
}

void Context::checkFits(uint64_t bytes, const std::string& what, uint64_t largestAllocation) const
{
  const uint64_t available = this->availableBytes();
  if (bytes > available)
  {
    throw DeviceMemoryError(what + " needs " + std::to_string(bytes) +
      " bytes of device memory, but " + std::to_string(available) + " bytes are available (" +
      this->deviceName() + ": " + std::to_string(this->heapBytes()) + " bytes of memory heaps" +
      (this->MemoryLimit ? ", a limit of " + std::to_string(this->MemoryLimit) + " bytes" : "") +
      ", " + std::to_string(this->AllocatedBytes) + " bytes in use by this renderer, " +
      std::to_string(this->Dev->allocatedBytes()) + " by every user of the device)");
  }
  const uint64_t cap = this->limits().maxMemoryAllocationSize;
  if (cap && largestAllocation > cap)
  {
    throw DeviceMemoryError(what + " needs one allocation of " + std::to_string(largestAllocation) +
      " bytes, but " + this->deviceName() + " allocates at most " + std::to_string(cap) +
      " bytes at once");
  }
}

void Context::submitAndWait(const std::function<void(VkCommandBuffer)>& record)
{
  VkCommandBufferAllocateInfo allocInfo{ VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO };
  allocInfo.commandPool = this->CommandPool;
  allocInfo.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  allocInfo.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  check(vkAllocateCommandBuffers(this->device(), &allocInfo, &cmd), "vkAllocateCommandBuffers");
  // Frees the command buffer on every path, exceptions from `record` included.
  struct Release
  {
    VkDevice device;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    ~Release() { vkFreeCommandBuffers(device, pool, 1, &cmd); }
  } release{ this->device(), this->CommandPool, cmd };

  VkCommandBufferBeginInfo begin{ VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO };
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
  // Makes every write of earlier submissions (made available by their fence) visible here.
  VkMemoryBarrier barrier{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
  barrier.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
    VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
  record(cmd);
  check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
  VkSubmitInfo submit{ VK_STRUCTURE_TYPE_SUBMIT_INFO };
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  check(vkResetFences(this->device(), 1, &this->Fence), "vkResetFences");
  check(this->Dev->submit(submit, this->Fence), "vkQueueSubmit");
  this->InFlight = true;
  check(vkWaitForFences(this->device(), 1, &this->Fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
  this->InFlight = false;
}

} // namespace render
} // namespace svdag
