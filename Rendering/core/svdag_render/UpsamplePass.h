// Guided upsampling (upsample.comp; UpsampleLayout.h says what it computes): a compute pipeline
// with no descriptor set (compiled once per device, Device::computePipeline) and this renderer's
// parameters' buffer. One per renderer, made on the first reduced frame.
#pragma once

#include "svdag_render/Buffer.h"
#include "svdag_render/ComputePipeline.h"
#include "svdag_render/Context.h"
#include "svdag_render/UpsampleLayout.h"

namespace svdag
{
namespace render
{

class UpsamplePass
{
public:
  // Throws std::runtime_error where Vulkan refuses.
  explicit UpsamplePass(Context& context);
  UpsamplePass(const UpsamplePass&) = delete;
  UpsamplePass& operator=(const UpsamplePass&) = delete;

  // Records the pass over the full image (params.sizes.xy) after every earlier write of the
  // device (the traces, the denoiser) and before every later read (the host, another API).
  void record(VkCommandBuffer cmd, const gpu::UpsampleParams& params);
  // Device bytes it holds (its parameters).
  uint64_t bytes() const { return this->Params.size(); }

private:
  Buffer Params; // host-visible: written in place, the GPU idle between frames
  const ComputePipeline& Program; // the device's (shared by its users)
};

} // namespace render
} // namespace svdag
