// The ray tracing pipeline of the primary-hit renderer and its shader binding table.
//
// Shaders (compiled to SPIR-V at build time and embedded): primary.rgen (one ray per pixel),
// primary.rmiss, and one procedural hit group: block.rint (per-block DAG traversal) with
// block.rchit. Descriptor set 0: the TLAS (SVDAG_BINDING_TLAS) and the frame uniforms
// (SVDAG_BINDING_FRAME), see GpuLayout.h. The SBT's handle size and alignments are read from
// the driver.
#pragma once

#include "svdag_render/Buffer.h"
#include "svdag_render/Context.h"

namespace svdag
{
namespace render
{

class Pipeline
{
public:
  explicit Pipeline(Context& context);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  VkPipeline handle() const { return this->Handle; }
  VkPipelineLayout layout() const { return this->Layout; }
  VkDescriptorSetLayout setLayout() const { return this->SetLayout; }
  // Shader binding table regions for vkCmdTraceRaysKHR.
  const VkStridedDeviceAddressRegionKHR& raygenRegion() const { return this->Raygen; }
  const VkStridedDeviceAddressRegionKHR& missRegion() const { return this->Miss; }
  const VkStridedDeviceAddressRegionKHR& hitRegion() const { return this->Hit; }
  const VkStridedDeviceAddressRegionKHR& callableRegion() const { return this->Callable; }

private:
  void createLayouts();
  void createPipeline();
  void createShaderBindingTable();
  void destroy();

  Context& Ctx;
  VkDescriptorSetLayout SetLayout = VK_NULL_HANDLE;
  VkPipelineLayout Layout = VK_NULL_HANDLE;
  VkPipeline Handle = VK_NULL_HANDLE;
  Buffer Table;
  VkStridedDeviceAddressRegionKHR Raygen{}, Miss{}, Hit{}, Callable{};
};

} // namespace render
} // namespace svdag
