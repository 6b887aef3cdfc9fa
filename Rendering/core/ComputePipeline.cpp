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
  const VkPushConstantRange range{ VK_SHADER_STAGE_COMPUTE_BIT, 0, 2 * sizeof(uint32_t) };
  VkPipelineLayoutCreateInfo layout{ VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO };
  layout.pushConstantRangeCount = 1;
  layout.pPushConstantRanges = &range;
  check(vkCreatePipelineLayout(device, &layout, nullptr, &this->Layout),
    (std::string(what) + ": vkCreatePipelineLayout").c_str());
  ComputeProgram::Interface interface;
  interface.layout = this->Layout;
  interface.pushConstants = &range;
  interface.pushConstantCount = 1;
  try
  {
    this->Program = std::make_unique<ComputeProgram>(context, code, bytes, nullptr, interface, what);
  }
  catch (...)
  {
    vkDestroyPipelineLayout(device, this->Layout, nullptr);
    throw;
  }
  context.shared().savePipelineCache();
}

ComputePipeline::~ComputePipeline()
{
  this->Program.reset();
  vkDestroyPipelineLayout(this->Ctx.device(), this->Layout, nullptr);
}

void ComputePipeline::dispatch(VkCommandBuffer cmd, VkDeviceAddress params, uint32_t width,
  uint32_t height, uint32_t groupSize) const
{
  const uint32_t push[2] = { uint32_t(params), uint32_t(params >> 32) };
  this->Program->bind(cmd);
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
