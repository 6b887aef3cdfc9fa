// The denoiser (denoise.comp; DenoiseLayout.h says what it computes): a compute pipeline with no
// descriptor set (one push constant, the address of a dispatch's parameters; compiled once per
// device, Device::computePipeline), this renderer's parameters' buffer and the filter's working
// images. One per renderer, made on first use; the working images follow the image size.
#pragma once

#include "svdag_render/Buffer.h"
#include "svdag_render/ComputePipeline.h"
#include "svdag_render/Context.h"
#include "svdag_render/DenoiseLayout.h"

namespace svdag
{
namespace render
{

class DenoisePass
{
public:
  // What one frame's denoising reads and writes (device addresses of the trace's outputs,
  // GpuLayout.h), besides what the parameters say.
  struct Frame
  {
    uint32_t width = 0, height = 0;
    uint32_t samples = 0; // accumulated in the image
    VkDeviceAddress label = 0, depth = 0, normal = 0, variance = 0;
    VkDeviceAddress hdr = 0;   // read, and written with the filtered image
    VkDeviceAddress color = 0; // written from the filtered image
    VkDeviceAddress coverage = 0; // the edge coverage records (GpuLayout.h; 0: none)
  };

  // Throws std::runtime_error where Vulkan refuses.
  explicit DenoisePass(Context& context);
  DenoisePass(const DenoisePass&) = delete;
  DenoisePass& operator=(const DenoisePass&) = delete;

  // Records the prepass and SVDAG_DENOISE_ITERATIONS filter iterations after every earlier write
  // of the device (the trace's outputs) and before every later read (the host, another API).
  // `params` holds the rays and weights; the rest is filled in per dispatch.
  void record(VkCommandBuffer cmd, const Frame& frame, gpu::DenoiseParams params);
  // Device bytes of the working images (part of the renderer's image bytes).
  uint64_t bytes() const;

private:
  void resize(uint32_t pixels);
  void dispatch(VkCommandBuffer cmd, uint32_t slot, const gpu::DenoiseParams& params);

  Context& Ctx;
  const ComputePipeline& Program; // the device's (shared by its users)
  Buffer Params; // one DenoiseParams per dispatch (host-visible: written in place, GPU idle)
  uint32_t Pixels = 0;
  Buffer Colors[2]; // RGBA ping-pong
  Buffer Guides[2]; // guides and variance ping-pong (DenoiseLayout.h)
};

} // namespace render
} // namespace svdag
