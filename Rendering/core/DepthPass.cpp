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

// The device must have shaderFloat64 before the pipeline is made (the shader computes in double).
Context& withFloat64(Context& context)
{
  if (!context.hasFloat64())
    throw std::runtime_error("the depth pass needs the shaderFloat64 feature, which " +
      context.deviceName() + " lacks");
  return context;
}
} // namespace

DepthPass::DepthPass(Context& context)
  : Ctx(withFloat64(context))
  , Params(context, PassKinds * sizeof(gpu::DepthParams), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
      MemoryUse::Upload)
  , Program(context.shared().computePipeline(
      svdagShader_depth_comp, sizeof(svdagShader_depth_comp), "the depth pass"))
{
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
  const bool limits = kind == SVDAG_DEPTH_PASS_LIMITS;
  const uint32_t width = limits ? params.sizes.z : params.sizes.x;
  const uint32_t height = limits ? params.sizes.w : params.sizes.y;

  this->Program.dispatchBetweenBarriers(cmd, address, width, height, SVDAG_DEPTH_GROUP_SIZE);
}

} // namespace render
} // namespace svdag
