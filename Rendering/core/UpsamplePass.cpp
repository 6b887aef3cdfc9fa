#include "svdag_render/UpsamplePass.h"

#include <cstring>

// The SPIR-V of upsample.comp (Rendering/core/CMakeLists.txt): svdagShader_upsample_comp.
#include "upsample.comp.h"

namespace svdag
{
namespace render
{

UpsamplePass::UpsamplePass(Context& context)
  : Params(context, sizeof(gpu::UpsampleParams), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
      MemoryUse::Upload)
  , Program(context.shared().computePipeline(
      svdagShader_upsample_comp, sizeof(svdagShader_upsample_comp), "the upsampling pass"))
{
}

void UpsamplePass::record(VkCommandBuffer cmd, const gpu::UpsampleParams& params)
{
  std::memcpy(this->Params.mapped(), &params, sizeof(params));
  VkMemoryBarrier before{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
  before.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
  before.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
    VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &before, 0, nullptr, 0, nullptr);
  this->Program.dispatch(
    cmd, this->Params.address(), params.sizes.x, params.sizes.y, SVDAG_UPSAMPLE_GROUP_SIZE);
  VkMemoryBarrier after{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
  after.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  after.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
    VK_PIPELINE_STAGE_ALL_COMMANDS_BIT | VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &after, 0, nullptr, 0,
    nullptr);
}

} // namespace render
} // namespace svdag
