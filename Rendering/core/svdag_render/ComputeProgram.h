// One compiled compute shader, bound like a pipeline. Where the device has shader objects
// (Device::hasShaderObjects) it is one, created from the binary an earlier compilation left on
// disk (PipelineCacheFile.h) when the driver takes it, else compiled from SPIR-V and its binary
// saved: lavapipe's pipeline cache holds no pipeline data, so a pipeline costs a compilation in
// every process (0.25-0.3 s for the path tracer), a binary about 0.01 s. Elsewhere it is a
// pipeline, compiled through the device's pipeline cache.
#pragma once

#include "svdag_render/Context.h"

#include <cstddef>
#include <cstdint>

namespace svdag
{
namespace render
{

class ComputeProgram
{
public:
  // The interface the shader is bound with: a pipeline layout made of these descriptor set
  // layouts and push constant ranges (a shader object names them itself).
  struct Interface
  {
    VkPipelineLayout layout = VK_NULL_HANDLE;
    const VkDescriptorSetLayout* setLayouts = nullptr;
    uint32_t setLayoutCount = 0;
    const VkPushConstantRange* pushConstants = nullptr;
    uint32_t pushConstantCount = 0;
  };

  // `code`: SPIR-V of `bytes` bytes, entry point "main"; `specialization` may be null. Throws
  // std::runtime_error naming `what` where Vulkan refuses.
  ComputeProgram(Context& context, const uint32_t* code, size_t bytes,
    const VkSpecializationInfo* specialization, const Interface& interface, const char* what);
  ~ComputeProgram();
  ComputeProgram(const ComputeProgram&) = delete;
  ComputeProgram& operator=(const ComputeProgram&) = delete;

  void bind(VkCommandBuffer cmd) const;

  // The key of a shader's binary: its SPIR-V and specialization (Device::shaderBinaryKey adds
  // the device's).
  static uint64_t hash(const uint32_t* code, size_t bytes, const VkSpecializationInfo* specialization);

private:
  void createShaderObject(const uint32_t* code, size_t bytes,
    const VkSpecializationInfo* specialization, const Interface& interface, const char* what);
  void createPipeline(const uint32_t* code, size_t bytes,
    const VkSpecializationInfo* specialization, const Interface& interface, const char* what);

  Context& Ctx;
  VkPipeline Pipeline = VK_NULL_HANDLE;
  VkShaderEXT Shader = VK_NULL_HANDLE;
};

} // namespace render
} // namespace svdag
