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
  this->Program.dispatchBetweenBarriers(
    cmd, this->Params.address(), params.sizes.x, params.sizes.y, SVDAG_UPSAMPLE_GROUP_SIZE);
}

} // namespace render
} // namespace svdag
