#include "svdag_render/DenoisePass.h"

#include <cstring>

// The SPIR-V of denoise.comp (Rendering/core/CMakeLists.txt): svdagShader_denoise_comp.
#include "denoise.comp.h"

namespace svdag
{
namespace render
{
namespace
{
constexpr uint32_t Dispatches = 1 + SVDAG_DENOISE_ITERATIONS; // the prepass, then the iterations

glm::uvec4 addresses(VkDeviceAddress a, VkDeviceAddress b)
{
  return glm::uvec4(uint32_t(a), uint32_t(a >> 32), uint32_t(b), uint32_t(b >> 32));
}

void barrier(VkCommandBuffer cmd, VkAccessFlags dst, VkPipelineStageFlags dstStages)
{
  VkMemoryBarrier b{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
  b.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
  b.dstAccessMask = dst;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, dstStages, 0, 1, &b, 0, nullptr,
    0, nullptr);
}
} // namespace

DenoisePass::DenoisePass(Context& context)
  : Ctx(context)
  , Program(context.shared().computePipeline(
      svdagShader_denoise_comp, sizeof(svdagShader_denoise_comp), "the denoiser"))
  , Params(context, Dispatches * sizeof(gpu::DenoiseParams), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
      MemoryUse::Upload)
{
}

uint64_t DenoisePass::bytes() const
{
  return uint64_t(this->Pixels) * (2 * 16 + 2 * 16);
}

void DenoisePass::resize(uint32_t pixels)
{
  if (pixels == this->Pixels)
    return;
  this->Pixels = 0;
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  for (int k = 0; k < 2; ++k)
  {
    this->Colors[k] = Buffer();
    this->Guides[k] = Buffer();
  }
  for (int k = 0; k < 2; ++k)
  {
    this->Colors[k] = Buffer(this->Ctx, VkDeviceSize(pixels) * 16, usage, MemoryUse::Device);
    this->Guides[k] = Buffer(this->Ctx, VkDeviceSize(pixels) * 16, usage, MemoryUse::Device);
  }
  this->Pixels = pixels;
}

void DenoisePass::dispatch(VkCommandBuffer cmd, uint32_t slot, const gpu::DenoiseParams& params)
{
  // This renderer's submissions each wait, so the slot is free to write.
  std::memcpy(static_cast<char*>(this->Params.mapped()) + slot * sizeof(gpu::DenoiseParams),
    &params, sizeof(params));
  barrier(cmd, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT,
    VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
  this->Program.dispatch(cmd, this->Params.address() + slot * sizeof(gpu::DenoiseParams),
    params.sizes.x, params.sizes.y, SVDAG_DENOISE_GROUP_SIZE);
}

void DenoisePass::record(VkCommandBuffer cmd, const Frame& frame, gpu::DenoiseParams params)
{
  this->resize(frame.width * frame.height);
  params.sizes = glm::uvec4(frame.width, frame.height, SVDAG_DENOISE_PASS_PREPARE, 0u);
  params.samples = glm::uvec4(frame.samples, 0u, 0u, 0u);
  params.guides = addresses(frame.label, frame.depth);
  params.guides2 = addresses(frame.normal, frame.variance);
  params.colors = addresses(frame.hdr, 0);
  params.variances = addresses(0, this->Guides[0].address());
  params.geometry = addresses(0, 0);
  this->dispatch(cmd, 0, params);
  // Iteration k reads colors (the trace's image first) and guides k % 2 and writes the others; the last one writes the trace's image and the color output.
  for (uint32_t k = 0; k < SVDAG_DENOISE_ITERATIONS; ++k)
  {
    const bool last = k + 1 == SVDAG_DENOISE_ITERATIONS;
    const VkDeviceAddress in = k == 0 ? frame.hdr : this->Colors[(k + 1) % 2].address();
    const VkDeviceAddress out = last ? frame.hdr : this->Colors[k % 2].address();
    params.sizes = glm::uvec4(frame.width, frame.height, SVDAG_DENOISE_PASS_FILTER, 1u << k);
    params.samples.y = last ? 1u : 0u;
    params.colors = addresses(in, out);
    params.variances =
      addresses(this->Guides[k % 2].address(), this->Guides[(k + 1) % 2].address());
    params.geometry = addresses(last ? frame.coverage : 0, last ? frame.color : 0);
    this->dispatch(cmd, 1 + k, params);
  }
  barrier(cmd, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_HOST_READ_BIT,
    VK_PIPELINE_STAGE_ALL_COMMANDS_BIT | VK_PIPELINE_STAGE_HOST_BIT);
}

} // namespace render
} // namespace svdag
