#include "svdag_render/ComputePipeline.h"

#include <string>

namespace svdag
{
namespace render
{

ComputePipeline::ComputePipeline(
  Context& context, const uint32_t* code, size_t bytes, const char* what)
  : Ctx(context)
{
  VkDevice device = context.device();
  VkPushConstantRange range{ VK_SHADER_STAGE_COMPUTE_BIT, 0, 2 * sizeof(uint32_t) };
  VkPipelineLayoutCreateInfo layout{ VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO };
  layout.pushConstantRangeCount = 1;
  layout.pPushConstantRanges = &range;
  check(vkCreatePipelineLayout(device, &layout, nullptr, &this->Layout),
    (std::string(what) + ": vkCreatePipelineLayout").c_str());
  VkShaderModuleCreateInfo module{ VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO };
  module.codeSize = bytes;
  module.pCode = code;
  VkShaderModule shader = VK_NULL_HANDLE;
  VkResult result = vkCreateShaderModule(device, &module, nullptr, &shader);
  if (result == VK_SUCCESS)
  {
    VkComputePipelineCreateInfo info{ VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO };
    info.stage = VkPipelineShaderStageCreateInfo{ VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO };
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = shader;
    info.stage.pName = "main";
    info.layout = this->Layout;
    result = vkCreateComputePipelines(
      device, context.shared().pipelineCache(), 1, &info, nullptr, &this->Handle);
    vkDestroyShaderModule(device, shader, nullptr);
  }
  if (result != VK_SUCCESS)
  {
    vkDestroyPipelineLayout(device, this->Layout, nullptr);
    check(result, what);
  }
  context.shared().savePipelineCache();
}

ComputePipeline::~ComputePipeline()
{
  VkDevice device = this->Ctx.device();
  vkDestroyPipeline(device, this->Handle, nullptr);
  vkDestroyPipelineLayout(device, this->Layout, nullptr);
}

void ComputePipeline::dispatch(VkCommandBuffer cmd, VkDeviceAddress params, uint32_t width,
  uint32_t height, uint32_t groupSize) const
{
  const uint32_t push[2] = { uint32_t(params), uint32_t(params >> 32) };
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, this->Handle);
  vkCmdPushConstants(cmd, this->Layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), push);
  vkCmdDispatch(cmd, (width + groupSize - 1) / groupSize, (height + groupSize - 1) / groupSize, 1);
}

void ComputePipeline::dispatchBetweenBarriers(VkCommandBuffer cmd, VkDeviceAddress params,
  uint32_t width, uint32_t height, uint32_t groupSize) const
{
  VkMemoryBarrier before{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
  before.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
  before.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
    VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &before, 0, nullptr, 0, nullptr);
  this->dispatch(cmd, params, width, height, groupSize);
  VkMemoryBarrier after{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
  after.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  after.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
    VK_PIPELINE_STAGE_ALL_COMMANDS_BIT | VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &after, 0, nullptr, 0,
    nullptr);
}

} // namespace render
} // namespace svdag
