// The depth pass (depth.comp; DepthLayout.h says what it computes): a compute pipeline with no
// descriptor set (one push constant, the address of its parameters; compiled once per device,
// Device::computePipeline) and this renderer's parameters' buffer. One per renderer; made on
// first use, on a device with shaderFloat64 (Context::hasFloat64) only.
#pragma once

#include "svdag_render/Buffer.h"
#include "svdag_render/ComputePipeline.h"
#include "svdag_render/Context.h"
#include "svdag_render/DepthLayout.h"

namespace svdag
{
namespace render
{

class DepthPass
{
public:
  // Throws std::runtime_error where the device lacks shaderFloat64 or Vulkan refuses.
  explicit DepthPass(Context& context);
  DepthPass(const DepthPass&) = delete;
  DepthPass& operator=(const DepthPass&) = delete;

  // Records the pass `params.pass.x` over its pixels (the traced image's for the limits, the
  // viewport's for the composite), between barriers: after every earlier write of the device
  // (the trace's outputs) and before every later read (the trace, the host, another API).
  // Each pass kind has its own parameter slot, so a frame may record both before it waits.
  void record(VkCommandBuffer cmd, const gpu::DepthParams& params);

private:
  Context& Ctx;
  Buffer Params; // one DepthParams per pass kind (host-visible: written in place, GPU idle)
  const ComputePipeline& Program; // the device's (shared by its users)
};

} // namespace render
} // namespace svdag
