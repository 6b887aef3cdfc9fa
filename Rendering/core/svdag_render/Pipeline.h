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
// switches are specialization constants of camera.rgen / camera.comp (ShaderFeatures). The layouts
// and pipelines are the device's, shared by every renderer (PipelineLibrary); each renderer has
// its own descriptor set. Descriptor set 0: the TLAS (SVDAG_BINDING_TLAS) and the frame uniforms
// (SVDAG_BINDING_FRAME), see GpuLayout.h. The SBT's handle size and alignments are read from
// the driver.
#pragma once

#include "svdag_render/Buffer.h"
#include "svdag_render/ComputeProgram.h"
#include "svdag_render/Context.h"
#include "svdag_render/GpuLayout.h"
#include "svdag_render/RenderSettings.h"

#include <array>
#include <exception>
#include <future>
#include <utility>
#include <memory>
#include <mutex>
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
  // The preview (PathTracer.h's SVDAG_FEATURE_PREVIEW): primary hits only, a small pipeline.
  bool preview = false;
  // Smooth shading normals (RenderSettings::shading) and clipping planes or a crop box: on
  // lavapipe the first doubles the path tracer's compilation, the second adds a fifth, and most
  // scenes use neither.
  bool smoothShading = false;
  bool clipping = false;
  // The compute backend's per-pixel step counters (Renderer::setStepStatistics); the ray
  // tracing backend ignores it.
  bool stepStatistics = false;
  bool operator==(const ShaderFeatures& o) const
  {
    return nextEventEstimation == o.nextEventEstimation && environmentMap == o.environmentMap &&
      sun == o.sun && emission == o.emission && transmission == o.transmission &&
      preview == o.preview && smoothShading == o.smoothShading && clipping == o.clipping &&
      stepStatistics == o.stepStatistics;
  }
  bool operator!=(const ShaderFeatures& o) const { return !(*this == o); }
};

// The pipelines of one backend on one device, shared by every renderer (Device::pipelines):
// the descriptor set and pipeline layouts, and one compiled pipeline (with its shader binding
// table, ray tracing) per feature set asked for, kept for the device's life, so that a feature
// toggled back or a second renderer with the same features costs no compilation. Compiled
// through the device's pipeline cache.
class PipelineLibrary
{
public:
  // One compiled pipeline: its features, handle, shader binding table and the table's regions.
  struct Program
  {
    ShaderFeatures features;
    VkPipeline handle = VK_NULL_HANDLE;           // ray tracing
    std::unique_ptr<ComputeProgram> compute;      // compute
    Buffer table;
    VkStridedDeviceAddressRegionKHR raygen{}, miss{}, hit{}, callable{};
    double compileSeconds = 0; // wall time of its compilation (pipeline and binding table)
  };

  // context: the device's own (it counts the shader binding tables). backend: RayTracing (the
  // device must have ray tracing) or Compute.
  PipelineLibrary(Context& context, Backend backend);
  ~PipelineLibrary();
  PipelineLibrary(const PipelineLibrary&) = delete;
  PipelineLibrary& operator=(const PipelineLibrary&) = delete;

  // The program of these features, compiled the first time any user asks for them (the
  // reference stays valid for the library's life); waits where another thread compiles them.
  // Thread-safe; throws std::runtime_error where the compilation fails (a later call tries
  // again).
  const Program& program(const ShaderFeatures& features);
  // The program of these features if it is compiled, or created at once where its compute
  // shader's binary is on disk (milliseconds: a warm start shows no preview); else starts
  // compiling it on a thread of its own (once) and returns nullptr at once. A failed background
  // compilation is reported by the next program() call for the features.
  const Program* compiledProgram(const ShaderFeatures& features);
  Backend backend() const { return this->Kind; }
  VkPipelineLayout layout() const { return this->Layout; }
  VkDescriptorSetLayout setLayout() const { return this->SetLayout; }
  // The pool sizes of one descriptor set of this backend.
  const std::vector<VkDescriptorPoolSize>& poolSizes() const { return this->PoolSizes; }
  uint64_t compilations() const;
  // Hash of the path tracer's embedded SPIR-V modules (part of the persistent pipeline cache's
  // key).
  static uint64_t shaderHash();

private:
  void createLayouts();
  void compile(Program& program);
  // Whether the program's compute shader would be created from a binary kept on disk.
  bool hasBinary(const ShaderFeatures& features) const;
  void createRayTracingPipeline(Program& program, const VkSpecializationInfo& specialization);
  void createComputePipeline(Program& program, const VkSpecializationInfo& specialization);
  void createShaderBindingTable(Program& program);
  void destroy();

  Context& Ctx;
  Backend Kind;
  VkDescriptorSetLayout SetLayout = VK_NULL_HANDLE;
  VkPipelineLayout Layout = VK_NULL_HANDLE;
  std::vector<VkDescriptorPoolSize> PoolSizes;
  // One feature set's program: compiled (ready), being compiled by the thread that made the
  // entry or by a background compilation (its future), or failed (removed, error kept).
  struct Entry
  {
    Program program;
    bool ready = false;
    std::shared_future<void> compiled;
  };
  Entry* find(const ShaderFeatures& features); // with Lock held
  // Makes the entry of these features (with Lock held) and returns the promise its compiler
  // keeps.
  std::shared_ptr<std::promise<void>> begin(const ShaderFeatures& features);
  // Compiles the entry of these features (Lock not held) and fulfils its promise; a failure
  // removes the entry (and, in the background, is kept for the next program() call).
  void complete(const ShaderFeatures& features, std::promise<void>& promise, bool background);

  mutable std::mutex Lock;
  std::vector<std::unique_ptr<Entry>> Programs;
  std::vector<std::future<void>> Background; // background compilations, waited for at the end
  std::vector<std::pair<ShaderFeatures, std::exception_ptr>> Failed;
};

// One renderer's use of a backend's shared pipelines: its own descriptor set (its uniforms and
// TLAS) and the program of the features it renders with now.
class Pipeline
{
public:
  // backend: Backend::RayTracing (the context must have ray tracing) or Backend::Compute.
  Pipeline(Context& context, Backend backend, const ShaderFeatures& features = ShaderFeatures());
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Switches to the pipeline (and shader binding table) of these features; returns whether this
  // renderer had not used them before. The device compiles each feature set once for all
  // renderers and keeps it (Device::pipelineCompilations counts compilations), so toggling a
  // feature back, such as emission when a highlighted label is hidden and shown, costs nothing.
  // Call only while no frame of this renderer is in flight (the renderer waits for every frame).
  bool setFeatures(const ShaderFeatures& features);
  const ShaderFeatures& features() const { return this->Current->features; }
  // Seconds the device took to compile the current program (whoever asked for it first).
  double compileSeconds() const { return this->Current->compileSeconds; }
  // Feature sets this renderer used so far (the constructor's included): a test sees what a
  // change asks for, whether or not another renderer compiled it already.
  uint64_t builds() const { return this->Used.size(); }

  Backend backend() const { return this->Library.backend(); }
  VkPipeline handle() const { return this->Current->handle; }
  VkPipelineLayout layout() const { return this->Library.layout(); }
  VkDescriptorSetLayout setLayout() const { return this->Library.setLayout(); }
  // Points this renderer's descriptor set 0 at its frame uniforms and (ray tracing) its TLAS.
  void updateDescriptors(VkBuffer uniforms, VkAccelerationStructureKHR tlas);
  // Records one pass over a width x height image: bind, trace or dispatch, and a barrier that
  // makes the shader writes visible to the host.
  void record(VkCommandBuffer cmd, uint32_t width, uint32_t height) const;
  // Shader binding table regions for vkCmdTraceRaysKHR.
  const VkStridedDeviceAddressRegionKHR& raygenRegion() const { return this->Current->raygen; }
  const VkStridedDeviceAddressRegionKHR& missRegion() const { return this->Current->miss; }
  const VkStridedDeviceAddressRegionKHR& hitRegion() const { return this->Current->hit; }
  const VkStridedDeviceAddressRegionKHR& callableRegion() const { return this->Current->callable; }

private:
  void destroy();

  Context& Ctx;
  PipelineLibrary& Library;
  const PipelineLibrary::Program* Current = nullptr;
  std::vector<ShaderFeatures> Used;
  VkDescriptorPool Pool = VK_NULL_HANDLE;
  VkDescriptorSet Set = VK_NULL_HANDLE;
};

} // namespace render
} // namespace svdag
