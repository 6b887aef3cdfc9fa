#include "svdag_render/DepthPass.h"

#include <cstring>
#include <stdexcept>

// The SPIR-V of depth.comp (Rendering/core/CMakeLists.txt): svdagShader_depth_comp.
#include "depth.comp.h"

namespace svdag
{
namespace render
{
namespace
{
constexpr uint32_t PassKinds = 2; // SVDAG_DEPTH_PASS_LIMITS, SVDAG_DEPTH_PASS_COMPOSITE
}

DepthPass::DepthPass(Context& context)
  : Ctx(context)
{
  if (!context.hasFloat64())
    throw std::runtime_error("the depth pass needs the shaderFloat64 feature, which " +
      context.deviceName() + " lacks");
  this->Params =
    Buffer(context, PassKinds * sizeof(gpu::DepthParams), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
      MemoryUse::Upload);
  VkDevice device = context.device();
  VkPushConstantRange range{ VK_SHADER_STAGE_COMPUTE_BIT, 0, 2 * sizeof(uint32_t) };
  VkPipelineLayoutCreateInfo layout{ VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO };
  layout.pushConstantRangeCount = 1;
  layout.pPushConstantRanges = &range;
  check(vkCreatePipelineLayout(device, &layout, nullptr, &this->Layout), "vkCreatePipelineLayout");
  VkShaderModuleCreateInfo code{ VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO };
  code.codeSize = sizeof(svdagShader_depth_comp);
  code.pCode = svdagShader_depth_comp;
  VkShaderModule module = VK_NULL_HANDLE;
  VkResult result = vkCreateShaderModule(device, &code, nullptr, &module);
  if (result == VK_SUCCESS)
  {
    VkComputePipelineCreateInfo info{ VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO };
    info.stage = VkPipelineShaderStageCreateInfo{ VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO };
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = module;
    info.stage.pName = "main";
    info.layout = this->Layout;
    result = vkCreateComputePipelines(
      device, context.shared().pipelineCache(), 1, &info, nullptr, &this->Handle);
    vkDestroyShaderModule(device, module, nullptr);
  }
  if (result != VK_SUCCESS)
  {
    vkDestroyPipelineLayout(device, this->Layout, nullptr);
    check(result, "the depth pass's pipeline");
  }
}

DepthPass::~DepthPass()
{
  VkDevice device = this->Ctx.device();
  vkDestroyPipeline(device, this->Handle, nullptr);
  vkDestroyPipelineLayout(device, this->Layout, nullptr);
}

void DepthPass::record(VkCommandBuffer cmd, const gpu::DepthParams& params)
{
  const uint32_t kind = params.pass.x;
  if (kind >= PassKinds)
    throw std::invalid_argument("unknown depth pass");
  // The device is idle for this renderer between submissions (each one waits), so the slot is
  // free to write.
  std::memcpy(static_cast<char*>(this->Params.mapped()) + kind * sizeof(gpu::DepthParams),
    &params, sizeof(params));
  const VkDeviceAddress address = this->Params.address() + kind * sizeof(gpu::DepthParams);
  const uint32_t push[2] = { uint32_t(address), uint32_t(address >> 32) };
  const bool limits = kind == SVDAG_DEPTH_PASS_LIMITS;
  const uint32_t width = limits ? params.sizes.z : params.sizes.x;
  const uint32_t height = limits ? params.sizes.w : params.sizes.y;

  VkMemoryBarrier before{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
  before.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
  before.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
    VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &before, 0, nullptr, 0, nullptr);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, this->Handle);
  vkCmdPushConstants(cmd, this->Layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), push);
  const uint32_t group = SVDAG_DEPTH_GROUP_SIZE;
  vkCmdDispatch(cmd, (width + group - 1) / group, (height + group - 1) / group, 1);
  VkMemoryBarrier after{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
  after.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  after.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
    VK_PIPELINE_STAGE_ALL_COMMANDS_BIT | VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &after, 0, nullptr, 0,
    nullptr);
}

} // namespace render
} // namespace svdag
