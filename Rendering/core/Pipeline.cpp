#include "svdag_render/Pipeline.h"

#include "svdag_render/GpuLayout.h"

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

// SPIR-V of the shaders, generated at build time by glslangValidator --vn (Rendering/core/
// CMakeLists.txt): const uint32_t arrays named svdagShader_<stage>.
#include "primary.rgen.h"
#include "primary.rmiss.h"
#include "block.rchit.h"
#include "block.rint.h"

namespace svdag
{
namespace render
{
namespace
{
enum Group : uint32_t
{
  RaygenGroup = 0,
  MissGroup = 1,
  HitGroup = 2,
  GroupCount = 3
};

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
} // namespace

Pipeline::Pipeline(Context& context)
  : Ctx(context)
{
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

void Pipeline::destroy()
{
  VkDevice device = this->Ctx.device();
  this->Table.reset();
  if (this->Handle)
    vkDestroyPipeline(device, this->Handle, nullptr);
  if (this->Layout)
    vkDestroyPipelineLayout(device, this->Layout, nullptr);
  if (this->SetLayout)
    vkDestroyDescriptorSetLayout(device, this->SetLayout, nullptr);
  this->Handle = VK_NULL_HANDLE;
  this->Layout = VK_NULL_HANDLE;
  this->SetLayout = VK_NULL_HANDLE;
}

void Pipeline::createLayouts()
{
  const VkShaderStageFlags stages = VK_SHADER_STAGE_RAYGEN_BIT_KHR | VK_SHADER_STAGE_MISS_BIT_KHR |
    VK_SHADER_STAGE_INTERSECTION_BIT_KHR | VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR;
  VkDescriptorSetLayoutBinding bindings[2] = {};
  bindings[0].binding = SVDAG_BINDING_TLAS;
  bindings[0].descriptorType = VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR;
  bindings[0].descriptorCount = 1;
  bindings[0].stageFlags = stages;
  bindings[1].binding = SVDAG_BINDING_FRAME;
  bindings[1].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
  bindings[1].descriptorCount = 1;
  bindings[1].stageFlags = stages;
  VkDescriptorSetLayoutCreateInfo setInfo{ VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO };
  setInfo.bindingCount = 2;
  setInfo.pBindings = bindings;
  check(vkCreateDescriptorSetLayout(this->Ctx.device(), &setInfo, nullptr, &this->SetLayout),
    "vkCreateDescriptorSetLayout");
  VkPipelineLayoutCreateInfo layoutInfo{ VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO };
  layoutInfo.setLayoutCount = 1;
  layoutInfo.pSetLayouts = &this->SetLayout;
  check(vkCreatePipelineLayout(this->Ctx.device(), &layoutInfo, nullptr, &this->Layout),
    "vkCreatePipelineLayout");
}

void Pipeline::createPipeline()
{
  VkDevice device = this->Ctx.device();
  struct StageCode
  {
    VkShaderStageFlagBits stage;
    const uint32_t* code;
    size_t bytes;
  };
  const StageCode codes[] = {
    { VK_SHADER_STAGE_RAYGEN_BIT_KHR, svdagShader_rgen, sizeof(svdagShader_rgen) },
    { VK_SHADER_STAGE_MISS_BIT_KHR, svdagShader_rmiss, sizeof(svdagShader_rmiss) },
    { VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR, svdagShader_rchit, sizeof(svdagShader_rchit) },
    { VK_SHADER_STAGE_INTERSECTION_BIT_KHR, svdagShader_rint, sizeof(svdagShader_rint) },
  };
  std::vector<VkPipelineShaderStageCreateInfo> stages;
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
  } modules{ device, {} };
  for (const StageCode& c : codes)
  {
    modules.list.push_back(createModule(device, c.code, c.bytes));
    VkPipelineShaderStageCreateInfo stage{ VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO };
    stage.stage = c.stage;
    stage.module = modules.list.back();
    stage.pName = "main";
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
  groups[HitGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_PROCEDURAL_HIT_GROUP_KHR;
  groups[HitGroup].closestHitShader = 2;
  groups[HitGroup].intersectionShader = 3;

  VkRayTracingPipelineCreateInfoKHR info{ VK_STRUCTURE_TYPE_RAY_TRACING_PIPELINE_CREATE_INFO_KHR };
  info.stageCount = uint32_t(stages.size());
  info.pStages = stages.data();
  info.groupCount = GroupCount;
  info.pGroups = groups;
  info.maxPipelineRayRecursionDepth = 1; // primary rays only, traced from raygen
  info.layout = this->Layout;
  check(this->Ctx.fn().createRayTracingPipelines(
          device, VK_NULL_HANDLE, VK_NULL_HANDLE, 1, &info, nullptr, &this->Handle),
    "vkCreateRayTracingPipelinesKHR");
}

void Pipeline::createShaderBindingTable()
{
  const RayTracingLimits& limits = this->Ctx.limits();
  const VkDeviceSize handleSize = limits.shaderGroupHandleSize;
  const VkDeviceSize stride = alignUp(handleSize, limits.shaderGroupHandleAlignment);
  const VkDeviceSize regionSize = alignUp(stride, limits.shaderGroupBaseAlignment);
  std::vector<uint8_t> handles(GroupCount * handleSize);
  check(this->Ctx.fn().getRayTracingShaderGroupHandles(this->Ctx.device(), this->Handle, 0,
          GroupCount, handles.size(), handles.data()),
    "vkGetRayTracingShaderGroupHandlesKHR");
  // One record per region, each region starting at a multiple of shaderGroupBaseAlignment.
  std::vector<uint8_t> table(GroupCount * regionSize, 0);
  for (uint32_t g = 0; g < GroupCount; ++g)
    std::memcpy(table.data() + g * regionSize, handles.data() + g * handleSize, handleSize);
  // The table's base address must itself be aligned to shaderGroupBaseAlignment; over-allocate.
  const VkDeviceSize base = limits.shaderGroupBaseAlignment;
  this->Table = Buffer(this->Ctx, table.size() + base, VK_BUFFER_USAGE_SHADER_BINDING_TABLE_BIT_KHR,
    MemoryUse::Upload);
  const VkDeviceAddress start = alignUp(this->Table.address(), base);
  std::memcpy(static_cast<uint8_t*>(this->Table.mapped()) + (start - this->Table.address()),
    table.data(), table.size());
  this->Raygen = { start + RaygenGroup * regionSize, regionSize, regionSize };
  this->Miss = { start + MissGroup * regionSize, stride, stride };
  this->Hit = { start + HitGroup * regionSize, stride, stride };
  this->Callable = { 0, 0, 0 };
}

} // namespace render
} // namespace svdag
