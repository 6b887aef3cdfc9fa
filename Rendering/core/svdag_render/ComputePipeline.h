// A compute shader whose only input is a push constant (the device address of its parameters):
// the depth pass, the denoiser, the upsampler. A ComputeProgram: a shader object from its binary
// on disk or a pipeline, whichever the device has.
#pragma once

#include "svdag_render/ComputeProgram.h"
#include "svdag_render/Context.h"

#include <cstddef>
#include <cstdint>
#include <memory>

namespace svdag
{
namespace render
{

class ComputePipeline
{
public:
  // `code`: SPIR-V of `bytes` bytes, whose push constant is a uvec2 (the address). Throws
  // std::runtime_error naming `what` where Vulkan refuses.
  ComputePipeline(Context& context, const uint32_t* code, size_t bytes, const char* what);
  ~ComputePipeline();
  ComputePipeline(const ComputePipeline&) = delete;
  ComputePipeline& operator=(const ComputePipeline&) = delete;

  // Binds the pipeline, pushes the parameters' address and dispatches groups of
  // groupSize x groupSize over width x height.
  void dispatch(VkCommandBuffer cmd, VkDeviceAddress params, uint32_t width, uint32_t height,
    uint32_t groupSize) const;
  // The same after every earlier write of the device (a trace's outputs) and before every later
  // read (the next pass, the host, another API): a pass of its own in a submission.
  void dispatchBetweenBarriers(VkCommandBuffer cmd, VkDeviceAddress params, uint32_t width,
    uint32_t height, uint32_t groupSize) const;

private:
  Context& Ctx;
  VkPipelineLayout Layout = VK_NULL_HANDLE;
  std::unique_ptr<ComputeProgram> Program;
};

} // namespace render
} // namespace svdag
