#include "svdag_render/Pipeline.h"

#include "svdag_render/GpuLayout.h"

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

// SPIR-V of the shaders, generated at build time by glslangValidator --vn (Rendering/core/
// CMakeLists.txt): const uint32_t arrays named svdagShader_<stage>.
#include "block.rchit.h"
#include "block.rint.h"
#include "block_entry.rint.h"
#include "camera.comp.h"
#include "camera.rgen.h"
#include "closest.rmiss.h"
#include "shadow.rmiss.h"

namespace svdag
{
namespace render
{
namespace
{
enum Group : uint32_t
{
  RaygenGroup = 0,
  MissGroup = 1, // SVDAG_MISS_CLOSEST
  ShadowMissGroup = 2, // SVDAG_MISS_SHADOW
  HitGroup = 3, // sbtRecordOffset 0: first hits
  EntryHitGroup = 4, // sbtRecordOffset 1: entry-only hits (rays continuing through a surface)
  GroupCount = 5
};
static_assert(ShadowMissGroup - MissGroup == SVDAG_MISS_SHADOW, "miss shader order");

VkDeviceSize alignUp(VkDeviceSize value, VkDeviceSize alignment)
{
  return (value + alignment - 1) / alignment * alignment;
}

VkShaderModule createModule(VkDevice device, const uint32_t* code, size_t bytes)
{
  VkShaderModuleCreateInfo info{ VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO };
  info.codeSize = bytes;
  info.pCode = code;
  VkShaderModule module = VK_NULL_HANDLE;
  check(vkCreateShaderModule(device, &info, nullptr, &module), "vkCreateShaderModule");
  return module;
}

// The bindings of descriptor set 0 a backend uses: the compute backend has no TLAS.
std::vector<DescriptorBinding> bindingsOf(Backend backend)
{
  std::vector<DescriptorBinding> bindings;
  for (const DescriptorBinding& b : DescriptorBindings)
  {
    if (backend == Backend::RayTracing || b.binding != SVDAG_BINDING_TLAS)
      bindings.push_back(b);
  }
  return bindings;
}

// Shader modules are only needed until the pipeline exists; destroyed on every path.
struct Modules
{
  VkDevice device;
  std::vector<VkShaderModule> list;
  ~Modules()
  {
    for (VkShaderModule m : list)
      vkDestroyShaderModule(device, m, nullptr);
  }
};
} // namespace

Pipeline::Pipeline(Context& context, Backend backend, const ShaderFeatures& features)
  : Ctx(context)
  , Kind(backend)
  , Features(features)
{
  if (backend != Backend::RayTracing && backend != Backend::Compute)
    throw std::invalid_argument("a pipeline is built for the rt or the compute backend");
  if (backend == Backend::RayTracing && !context.hasRayTracing())
    throw std::runtime_error("the ray tracing backend needs a device with ray tracing; " +
      context.deviceName() + " lacks " + context.rayTracingMissing() +
      " (the compute backend runs there)");
  try
  {
    this->createLayouts();
    this->createPipeline();
    this->createShaderBindingTable();
  }
  catch (...)
  {
    this->destroy();
    throw;
  }
}

Pipeline::~Pipeline()
{
  this->destroy();
}

bool Pipeline::setFeatures(const ShaderFeatures& features)
{
  if (features == this->Features && this->Handle)
    return false;
  if (this->Handle)
    this->Kept.push_back(this->release());
  for (auto it = this->Kept.begin(); it != this->Kept.end(); ++it)
  {
    if (it->features == features)
    {
      Built kept = std::move(*it);
      this->Kept.erase(it);
      this->use(std::move(kept));
      return false;
    }
  }
  this->Features = features;
  this->createPipeline();
  this->createShaderBindingTable();
  return true;
}

Pipeline::Built Pipeline::release()
{
  Built built;
  built.features = this->Features;
  built.handle = this->Handle;
  built.table = std::move(this->Table);
  built.raygen = this->Raygen;
  built.miss = this->Miss;
  built.hit = this->Hit;
  built.callable = this->Callable;
  this->Handle = VK_NULL_HANDLE;
  return built;
}

void Pipeline::use(Built&& built)
{
  this->Features = built.features;
  this->Handle = built.handle;
  this->Table = std::move(built.table);
  this->Raygen = built.raygen;
  this->Miss = built.miss;
  this->Hit = built.hit;
  this->Callable = built.callable;
}

void Pipeline::destroyPipeline()
{
  this->Table.reset();
  if (this->Handle)
    vkDestroyPipeline(this->Ctx.device(), this->Handle, nullptr);
  this->Handle = VK_NULL_HANDLE;
  for (Built& kept : this->Kept)
  {
    kept.table.reset();
    vkDestroyPipeline(this->Ctx.device(), kept.handle, nullptr);
  }
  this->Kept.clear();
}

void Pipeline::destroy()
{
  VkDevice device = this->Ctx.device();
  this->destroyPipeline();
  if (this->Pool)
    vkDestroyDescriptorPool(device, this->Pool, nullptr);
  this->Pool = VK_NULL_HANDLE;
  this->Set = VK_NULL_HANDLE;
  if (this->Layout)
    vkDestroyPipelineLayout(device, this->Layout, nullptr);
  if (this->SetLayout)
    vkDestroyDescriptorSetLayout(device, this->SetLayout, nullptr);
  this->Layout = VK_NULL_HANDLE;
  this->SetLayout = VK_NULL_HANDLE;
}

void Pipeline::createLayouts()
{
  const VkShaderStageFlags stages = this->Kind == Backend::Compute
    ? VkShaderStageFlags(VK_SHADER_STAGE_COMPUTE_BIT)
    : VkShaderStageFlags(VK_SHADER_STAGE_RAYGEN_BIT_KHR | VK_SHADER_STAGE_MISS_BIT_KHR |
        VK_SHADER_STAGE_INTERSECTION_BIT_KHR | VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR);
  const std::vector<DescriptorBinding> used = bindingsOf(this->Kind);
  std::vector<VkDescriptorSetLayoutBinding> bindings(used.size());
  std::vector<VkDescriptorPoolSize> sizes(used.size());
  for (size_t i = 0; i < used.size(); ++i)
  {
    bindings[i].binding = used[i].binding;
    bindings[i].descriptorType = used[i].type;
    bindings[i].descriptorCount = 1;
    bindings[i].stageFlags = stages;
    sizes[i] = { used[i].type, 1 };
  }
  VkDescriptorSetLayoutCreateInfo setInfo{ VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO };
  setInfo.bindingCount = uint32_t(bindings.size());
  setInfo.pBindings = bindings.data();
  check(vkCreateDescriptorSetLayout(this->Ctx.device(), &setInfo, nullptr, &this->SetLayout),
    "vkCreateDescriptorSetLayout");
  VkPipelineLayoutCreateInfo layoutInfo{ VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO };
  layoutInfo.setLayoutCount = 1;
  layoutInfo.pSetLayouts = &this->SetLayout;
  check(vkCreatePipelineLayout(this->Ctx.device(), &layoutInfo, nullptr, &this->Layout),
    "vkCreatePipelineLayout");
  VkDescriptorPoolCreateInfo poolInfo{ VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO };
  poolInfo.maxSets = 1;
  poolInfo.poolSizeCount = uint32_t(sizes.size());
  poolInfo.pPoolSizes = sizes.data();
  check(vkCreateDescriptorPool(this->Ctx.device(), &poolInfo, nullptr, &this->Pool),
    "vkCreateDescriptorPool");
  VkDescriptorSetAllocateInfo alloc{ VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO };
  alloc.descriptorPool = this->Pool;
  alloc.descriptorSetCount = 1;
  alloc.pSetLayouts = &this->SetLayout;
  check(vkAllocateDescriptorSets(this->Ctx.device(), &alloc, &this->Set),
    "vkAllocateDescriptorSets");
}

void Pipeline::updateDescriptors(VkBuffer uniforms, VkAccelerationStructureKHR tlas)
{
  VkWriteDescriptorSetAccelerationStructureKHR asInfo{
    VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET_ACCELERATION_STRUCTURE_KHR
  };
  asInfo.accelerationStructureCount = 1;
  asInfo.pAccelerationStructures = &tlas;
  VkDescriptorBufferInfo uniformInfo{ uniforms, 0, sizeof(gpu::FrameUniforms) };
  std::vector<VkWriteDescriptorSet> writes;
  for (const DescriptorBinding& b : bindingsOf(this->Kind))
  {
    VkWriteDescriptorSet w{ VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET };
    w.dstSet = this->Set;
    w.dstBinding = b.binding;
    w.descriptorCount = 1;
    w.descriptorType = b.type;
    if (b.binding == SVDAG_BINDING_TLAS)
      w.pNext = &asInfo;
    else
      w.pBufferInfo = &uniformInfo;
    writes.push_back(w);
  }
  vkUpdateDescriptorSets(this->Ctx.device(), uint32_t(writes.size()), writes.data(), 0, nullptr);
}

void Pipeline::record(VkCommandBuffer cmd, uint32_t width, uint32_t height) const
{
  const bool compute = this->Kind == Backend::Compute;
  const VkPipelineBindPoint bind =
    compute ? VK_PIPELINE_BIND_POINT_COMPUTE : VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR;
  vkCmdBindPipeline(cmd, bind, this->Handle);
  vkCmdBindDescriptorSets(cmd, bind, this->Layout, 0, 1, &this->Set, 0, nullptr);
  if (compute)
  {
    const uint32_t group = SVDAG_COMPUTE_GROUP_SIZE;
    vkCmdDispatch(cmd, (width + group - 1) / group, (height + group - 1) / group, 1);
  }
  else
  {
    this->Ctx.fn().cmdTraceRays(
      cmd, &this->Raygen, &this->Miss, &this->Hit, &this->Callable, width, height, 1);
  }
  // Makes the shader writes visible to the host reads after the pass.
  VkMemoryBarrier barrier{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
  barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd,
    compute ? VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT : VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR,
    VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
}

void Pipeline::createPipeline()
{
  // The camera shader's feature switches (GpuLayout.h's SVDAG_CONSTANT_* ids).
  VkBool32 constants[SVDAG_CONSTANT_COUNT] = {};
  constants[SVDAG_CONSTANT_NEE] = this->Features.nextEventEstimation;
  constants[SVDAG_CONSTANT_ENV_MAP] = this->Features.environmentMap;
  constants[SVDAG_CONSTANT_SUN] = this->Features.sun;
  constants[SVDAG_CONSTANT_EMISSION] = this->Features.emission;
  constants[SVDAG_CONSTANT_TRANSMISSION] = this->Features.transmission;
  VkSpecializationMapEntry entries[SVDAG_CONSTANT_COUNT];
  for (uint32_t i = 0; i < SVDAG_CONSTANT_COUNT; ++i)
    entries[i] = { i, uint32_t(i * sizeof(VkBool32)), sizeof(VkBool32) };
  VkSpecializationInfo specialization{ SVDAG_CONSTANT_COUNT, entries, sizeof(constants),
    constants };
  if (this->Kind == Backend::Compute)
    this->createComputePipeline(specialization);
  else
    this->createRayTracingPipeline(specialization);
  ++this->Builds;
}

void Pipeline::createComputePipeline(const VkSpecializationInfo& specialization)
{
  VkDevice device = this->Ctx.device();
  Modules modules{ device, {} };
  modules.list.push_back(
    createModule(device, svdagShader_camera_comp, sizeof(svdagShader_camera_comp)));
  VkComputePipelineCreateInfo info{ VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO };
  info.stage = VkPipelineShaderStageCreateInfo{ VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO };
  info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  info.stage.module = modules.list.back();
  info.stage.pName = "main";
  info.stage.pSpecializationInfo = &specialization;
  info.layout = this->Layout;
  check(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &this->Handle),
    "vkCreateComputePipelines");
}

void Pipeline::createRayTracingPipeline(const VkSpecializationInfo& specialization)
{
  VkDevice device = this->Ctx.device();
  struct StageCode
  {
    VkShaderStageFlagBits stage;
    const uint32_t* code;
    size_t bytes;
  };
  // Stage order = the shader indices the groups below name.
  const StageCode codes[] = {
    { VK_SHADER_STAGE_RAYGEN_BIT_KHR, svdagShader_camera_rgen, sizeof(svdagShader_camera_rgen) },
    { VK_SHADER_STAGE_MISS_BIT_KHR, svdagShader_closest_rmiss,
      sizeof(svdagShader_closest_rmiss) },
    { VK_SHADER_STAGE_MISS_BIT_KHR, svdagShader_shadow_rmiss, sizeof(svdagShader_shadow_rmiss) },
    { VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR, svdagShader_block_rchit,
      sizeof(svdagShader_block_rchit) },
    { VK_SHADER_STAGE_INTERSECTION_BIT_KHR, svdagShader_block_rint,
      sizeof(svdagShader_block_rint) },
    { VK_SHADER_STAGE_INTERSECTION_BIT_KHR, svdagShader_block_entry_rint,
      sizeof(svdagShader_block_entry_rint) },
  };
  std::vector<VkPipelineShaderStageCreateInfo> stages;
  Modules modules{ device, {} };
  for (const StageCode& c : codes)
  {
    modules.list.push_back(createModule(device, c.code, c.bytes));
    VkPipelineShaderStageCreateInfo stage{ VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO };
    stage.stage = c.stage;
    stage.module = modules.list.back();
    stage.pName = "main";
    if (c.stage == VK_SHADER_STAGE_RAYGEN_BIT_KHR)
      stage.pSpecializationInfo = &specialization;
    stages.push_back(stage);
  }
  VkRayTracingShaderGroupCreateInfoKHR groups[GroupCount];
  for (auto& g : groups)
  {
    g = VkRayTracingShaderGroupCreateInfoKHR{
      VK_STRUCTURE_TYPE_RAY_TRACING_SHADER_GROUP_CREATE_INFO_KHR
    };
    g.generalShader = VK_SHADER_UNUSED_KHR;
    g.closestHitShader = VK_SHADER_UNUSED_KHR;
    g.anyHitShader = VK_SHADER_UNUSED_KHR;
    g.intersectionShader = VK_SHADER_UNUSED_KHR;
  }
  groups[RaygenGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_GENERAL_KHR;
  groups[RaygenGroup].generalShader = 0;
  groups[MissGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_GENERAL_KHR;
  groups[MissGroup].generalShader = 1;
  groups[ShadowMissGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_GENERAL_KHR;
  groups[ShadowMissGroup].generalShader = 2;
  groups[HitGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_PROCEDURAL_HIT_GROUP_KHR;
  groups[HitGroup].closestHitShader = 3;
  groups[HitGroup].intersectionShader = 4;
  groups[EntryHitGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_PROCEDURAL_HIT_GROUP_KHR;
  groups[EntryHitGroup].closestHitShader = 3;
  groups[EntryHitGroup].intersectionShader = 5;

  VkRayTracingPipelineCreateInfoKHR info{ VK_STRUCTURE_TYPE_RAY_TRACING_PIPELINE_CREATE_INFO_KHR };
  info.stageCount = uint32_t(stages.size());
  info.pStages = stages.data();
  info.groupCount = GroupCount;
  info.pGroups = groups;
  info.maxPipelineRayRecursionDepth = 1; // every ray is traced from raygen
  info.layout = this->Layout;
  check(this->Ctx.fn().createRayTracingPipelines(
          device, VK_NULL_HANDLE, VK_NULL_HANDLE, 1, &info, nullptr, &this->Handle),
    "vkCreateRayTracingPipelinesKHR");
}

void Pipeline::createShaderBindingTable()
{
  if (this->Kind != Backend::RayTracing)
    return;
  const RayTracingLimits& limits = this->Ctx.limits();
  const VkDeviceSize handleSize = limits.shaderGroupHandleSize;
  const VkDeviceSize stride = alignUp(handleSize, limits.shaderGroupHandleAlignment);
  const VkDeviceSize regionSize = alignUp(stride, limits.shaderGroupBaseAlignment);
  std::vector<uint8_t> handles(GroupCount * handleSize);
  check(this->Ctx.fn().getRayTracingShaderGroupHandles(this->Ctx.device(), this->Handle, 0,
          GroupCount, handles.size(), handles.data()),
    "vkGetRayTracingShaderGroupHandlesKHR");
  // Regions start at multiples of shaderGroupBaseAlignment: raygen (one record), miss (the two
  // miss records, `stride` apart), hit (the two hit group records, `stride` apart: a ray's
  // sbtRecordOffset picks one; sbtRecordStride is 0 and every instance has offset 0).
  const VkDeviceSize missOffset = regionSize;
  const VkDeviceSize hitOffset =
    alignUp(missOffset + 2 * stride, limits.shaderGroupBaseAlignment);
  const VkDeviceSize recordOffsets[GroupCount] = { 0, missOffset, missOffset + stride, hitOffset,
    hitOffset + stride };
  std::vector<uint8_t> table(hitOffset + 2 * stride, 0);
  for (uint32_t g = 0; g < GroupCount; ++g)
    std::memcpy(table.data() + recordOffsets[g], handles.data() + g * handleSize, handleSize);
  // The table's base address must itself be aligned to shaderGroupBaseAlignment; over-allocate.
  const VkDeviceSize base = limits.shaderGroupBaseAlignment;
  this->Table = Buffer(this->Ctx, table.size() + base, VK_BUFFER_USAGE_SHADER_BINDING_TABLE_BIT_KHR,
    MemoryUse::Upload);
  const VkDeviceAddress start = alignUp(this->Table.address(), base);
  std::memcpy(static_cast<uint8_t*>(this->Table.mapped()) + (start - this->Table.address()),
    table.data(), table.size());
  this->Raygen = { start, regionSize, regionSize };
  this->Miss = { start + missOffset, stride, 2 * stride };
  this->Hit = { start + hitOffset, stride, 2 * stride };
  this->Callable = { 0, 0, 0 };
}

} // namespace render
} // namespace svdag
