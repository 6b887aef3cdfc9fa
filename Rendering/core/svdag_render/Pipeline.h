// The path tracer's pipeline of one backend (RenderSettings.h's Backend), its descriptor set and
// the commands of one pass.
//
// Compute backend: camera.comp (PathTrace.glsl's camera and path tracer over the cell-grid walk
// of GridTraversal.h), dispatched in SVDAG_COMPUTE_GROUP_SIZE^2 pixel workgroups; descriptor set
// 0 holds only the frame uniforms.
//
// Ray tracing backend: the ray tracing pipeline and its shader binding table.
// Shaders (compiled to SPIR-V at build time and embedded): camera.rgen (primary outputs and
// camera paths), two miss shaders (closest.rmiss for closest-hit queries, shadow.rmiss for
// occlusion rays, at miss indices SVDAG_MISS_CLOSEST / SVDAG_MISS_SHADOW) and two procedural hit
// groups with block.rchit: block.rint (per-block DAG traversal, first hits; sbtRecordOffset 0) and
// block.rint compiled with SVDAG_ENTRY_ONLY=1 (entry-only hits for rays that continue through a
// transmissive surface; sbtRecordOffset 1). The path tracer's feature
// switches are specialization constants of camera.rgen / camera.comp (ShaderFeatures); setFeatures rebuilds
// the pipeline, keeping the layouts (descriptor sets stay valid). Descriptor set 0: the TLAS (SVDAG_BINDING_TLAS) and the frame uniforms
// (SVDAG_BINDING_FRAME), see GpuLayout.h. The SBT's handle size and alignments are read from
// the driver.
#pragma once

#include "svdag_render/Buffer.h"
#include "svdag_render/Context.h"
#include "svdag_render/GpuLayout.h"
#include "svdag_render/RenderSettings.h"

#include <array>
#include <vector>

namespace svdag
{
namespace render
{

// Descriptor set 0, declared once: the set layout, the descriptor pool and the descriptor writes
// are all made from this table (GpuLayout.h names the bindings).
struct DescriptorBinding
{
  uint32_t binding;
  VkDescriptorType type;
};
constexpr std::array<DescriptorBinding, 2> DescriptorBindings{ {
  { SVDAG_BINDING_TLAS, VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR }, // ray tracing only
  { SVDAG_BINDING_FRAME, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER },
} };

// The path tracer's feature switches (PathTracer.h's SVDAG_FEATURE_*). A feature a scene does not
// use is compiled out.
struct ShaderFeatures
{
  bool nextEventEstimation = true;
  bool environmentMap = false;
  bool sun = false;
  bool emission = false;
  bool transmission = false;
  bool operator==(const ShaderFeatures& o) const
  {
    return nextEventEstimation == o.nextEventEstimation && environmentMap == o.environmentMap &&
      sun == o.sun && emission == o.emission && transmission == o.transmission;
  }
  bool operator!=(const ShaderFeatures& o) const { return !(*this == o); }
};

class Pipeline
{
public:
  // backend: Backend::RayTracing (the context must have ray tracing) or Backend::Compute.
  Pipeline(Context& context, Backend backend, const ShaderFeatures& features = ShaderFeatures());
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Switches to the pipeline (and shader binding table) of these features, building it the first
  // time they are asked for; returns whether it built one. The pipelines built before are kept
  // (a few: one per feature set a session uses), so toggling a feature back, such as emission
  // when a highlighted label is hidden and shown, costs no shader compilation. Call only while
  // no frame is in flight (the renderer waits for every frame).
  bool setFeatures(const ShaderFeatures& features);
  const ShaderFeatures& features() const { return this->Features; }
  // Pipelines built so far (the constructor's included): a test sees rebuilds.
  uint64_t builds() const { return this->Builds; }

  Backend backend() const { return this->Kind; }
  VkPipeline handle() const { return this->Handle; }
  VkPipelineLayout layout() const { return this->Layout; }
  VkDescriptorSetLayout setLayout() const { return this->SetLayout; }
  // Points descriptor set 0 at the frame uniforms and (ray tracing) the TLAS.
  void updateDescriptors(VkBuffer uniforms, VkAccelerationStructureKHR tlas);
  // Records one pass over a width x height image: bind, trace or dispatch, and a barrier that
  // makes the shader writes visible to the host.
  void record(VkCommandBuffer cmd, uint32_t width, uint32_t height) const;
  // Shader binding table regions for vkCmdTraceRaysKHR.
  const VkStridedDeviceAddressRegionKHR& raygenRegion() const { return this->Raygen; }
  const VkStridedDeviceAddressRegionKHR& missRegion() const { return this->Miss; }
  const VkStridedDeviceAddressRegionKHR& hitRegion() const { return this->Hit; }
  const VkStridedDeviceAddressRegionKHR& callableRegion() const { return this->Callable; }

private:
  void createLayouts();
  void createPipeline();
  void createRayTracingPipeline(const VkSpecializationInfo& specialization);
  void createComputePipeline(const VkSpecializationInfo& specialization);
  void createShaderBindingTable();
  void destroyPipeline();
  void destroy();

  // One built pipeline: its features, handle, shader binding table and the table's regions.
  struct Built
  {
    ShaderFeatures features;
    VkPipeline handle = VK_NULL_HANDLE;
    Buffer table;
    VkStridedDeviceAddressRegionKHR raygen{}, miss{}, hit{}, callable{};
  };
  // Moves the pipeline in use out (leaving none in use), or in.
  Built release();
  void use(Built&& built);

  Context& Ctx;
  Backend Kind;
  ShaderFeatures Features;
  uint64_t Builds = 0;
  VkDescriptorSetLayout SetLayout = VK_NULL_HANDLE;
  VkPipelineLayout Layout = VK_NULL_HANDLE;
  VkDescriptorPool Pool = VK_NULL_HANDLE;
  VkDescriptorSet Set = VK_NULL_HANDLE;
  VkPipeline Handle = VK_NULL_HANDLE;
  Buffer Table;
  VkStridedDeviceAddressRegionKHR Raygen{}, Miss{}, Hit{}, Callable{};
  std::vector<Built> Kept; // the pipelines of other feature sets, built before
};

} // namespace render
} // namespace svdag
