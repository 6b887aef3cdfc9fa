#include "svdag_render/Pipeline.h"


#include "svdag_render/GpuLayout.h"
#include "svdag_render/PipelineCacheFile.h"

#include <chrono>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <utility>
#include <vector>

// SPIR-V of the shaders, generated at build time by glslangValidator --vn (Rendering/core/
// CMakeLists.txt): const uint32_t arrays named svdagShader_<stage>.
#include "block.rchit.h"
#include "block.rint.h"
#include "block_entry.rint.h"
#include "camera.comp.h"
#include "camera.rgen.h"
#include "closest.rmiss.h"
#include "shadow.rmiss.h"

namespace svdag
{
namespace render
{
namespace
{
enum Group : uint32_t
{
  RaygenGroup = 0,
  MissGroup = 1, // SVDAG_MISS_CLOSEST
  ShadowMissGroup = 2, // SVDAG_MISS_SHADOW
  HitGroup = 3, // sbtRecordOffset 0: first hits
  EntryHitGroup = 4, // sbtRecordOffset 1: entry-only hits (rays continuing through a surface)
  GroupCount = 5
};
static_assert(ShadowMissGroup - MissGroup == SVDAG_MISS_SHADOW, "miss shader order");

VkDeviceSize alignUp(VkDeviceSize value, VkDeviceSize alignment)
{
  return (value + alignment - 1) / alignment * alignment;
}

VkShaderModule createModule(VkDevice device, const uint32_t* code, size_t bytes)
{
  VkShaderModuleCreateInfo info{ VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO };
  info.codeSize = bytes;
  info.pCode = code;
  VkShaderModule module = VK_NULL_HANDLE;
  check(vkCreateShaderModule(device, &info, nullptr, &module), "vkCreateShaderModule");
  return module;
}

// The bindings of descriptor set 0 a backend uses: the compute backend has no TLAS.
std::vector<DescriptorBinding> bindingsOf(Backend backend)
{
  std::vector<DescriptorBinding> bindings;
  for (const DescriptorBinding& b : DescriptorBindings)
  {
    if (backend == Backend::RayTracing || b.binding != SVDAG_BINDING_TLAS)
      bindings.push_back(b);
  }
  return bindings;
}

// Shader modules are only needed until the pipeline exists; destroyed on every path.
struct Modules
{
  VkDevice device;
  std::vector<VkShaderModule> list;
  ~Modules()
  {
    for (VkShaderModule m : list)
      vkDestroyShaderModule(device, m, nullptr);
  }
};
} // namespace

PipelineLibrary::PipelineLibrary(Context& context, Backend backend)
  : Ctx(context)
  , Kind(backend)
{
  if (backend != Backend::RayTracing && backend != Backend::Compute)
    throw std::invalid_argument("a pipeline is built for the rt or the compute backend");
  if (backend == Backend::RayTracing && !context.hasRayTracing())
    throw std::runtime_error("the ray tracing backend needs a device with ray tracing; " +
      context.deviceName() + " lacks " + context.rayTracingMissing() +
      " (the compute backend runs there)");
  try
  {
    this->createLayouts();
  }
  catch (...)
  {
    this->destroy();
    throw;
  }
}

PipelineLibrary::~PipelineLibrary()
{
  this->destroy();
}

void PipelineLibrary::destroy()
{
  for (auto& compilation : this->Background)
    compilation.wait();
  this->Background.clear();
  VkDevice device = this->Ctx.device();
  for (auto& entry : this->Programs)
  {
    entry->program.table.reset();
    entry->program.compute.reset();
    vkDestroyPipeline(device, entry->program.handle, nullptr);
  }
  this->Programs.clear();
  if (this->Layout)
    vkDestroyPipelineLayout(device, this->Layout, nullptr);
  if (this->SetLayout)
    vkDestroyDescriptorSetLayout(device, this->SetLayout, nullptr);
  this->Layout = VK_NULL_HANDLE;
  this->SetLayout = VK_NULL_HANDLE;
}

uint64_t PipelineLibrary::compilations() const
{
  std::lock_guard<std::mutex> lock(this->Lock);
  uint64_t ready = 0;
  for (const auto& entry : this->Programs)
    ready += entry->ready;
  return ready;
}

PipelineLibrary::Entry* PipelineLibrary::find(const ShaderFeatures& features)
{
  for (const auto& entry : this->Programs)
  {
    if (entry->program.features == features)
      return entry.get();
  }
  return nullptr;
}

std::shared_ptr<std::promise<void>> PipelineLibrary::begin(const ShaderFeatures& features)
{
  auto promise = std::make_shared<std::promise<void>>();
  auto entry = std::make_unique<Entry>();
  entry->program.features = features;
  entry->compiled = promise->get_future().share();
  this->Programs.push_back(std::move(entry));
  return promise;
}

void PipelineLibrary::complete(
  const ShaderFeatures& features, std::promise<void>& promise, bool background)
{
  Program program;
  program.features = features;
  const auto start = std::chrono::steady_clock::now();
  try
  {
    this->compile(program);
    program.compileSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  catch (...)
  {
    {
      // Forgotten, so that a later request compiles again.
      std::lock_guard<std::mutex> lock(this->Lock);
      for (auto it = this->Programs.begin(); it != this->Programs.end(); ++it)
      {
        if ((*it)->program.features == features)
        {
          this->Programs.erase(it);
          if (background)
            this->Failed.emplace_back(features, std::current_exception());
          break;
        }
      }
    }
    promise.set_exception(std::current_exception());
    return;
  }
  {
    std::lock_guard<std::mutex> lock(this->Lock);
    Entry* entry = this->find(features);
    entry->program = std::move(program);
    entry->ready = true;
  }
  promise.set_value();
  // Kept on disk at once: a later process starts from it even if this one never exits cleanly.
  this->Ctx.shared().savePipelineCache();
}

const PipelineLibrary::Program& PipelineLibrary::program(const ShaderFeatures& features)
{
  std::shared_ptr<std::promise<void>> mine;
  std::shared_future<void> compiled;
  Entry* entry = nullptr;
  {
    std::lock_guard<std::mutex> lock(this->Lock);
    // A background compilation of these features that failed: its error, once.
    for (auto it = this->Failed.begin(); it != this->Failed.end(); ++it)
    {
      if (it->first == features)
      {
        const std::exception_ptr failure = it->second;
        this->Failed.erase(it);
        std::rethrow_exception(failure);
      }
    }
    entry = this->find(features);
    if (entry && entry->ready)
      return entry->program;
    if (!entry)
    {
      mine = this->begin(features);
      entry = this->find(features);
    }
    compiled = entry->compiled;
  }
  if (mine)
    this->complete(features, *mine, false);
  compiled.get(); // waits for the compiling thread; rethrows its failure
  std::lock_guard<std::mutex> lock(this->Lock);
  return this->find(features)->program;
}

const PipelineLibrary::Program* PipelineLibrary::compiledProgram(const ShaderFeatures& features)
{
  {
    std::lock_guard<std::mutex> lock(this->Lock);
    if (Entry* entry = this->find(features))
      return entry->ready ? &entry->program : nullptr;
  }
  if (this->hasBinary(features))
    return &this->program(features);
  std::lock_guard<std::mutex> lock(this->Lock);
  if (Entry* entry = this->find(features)) // another thread began it meanwhile
    return entry->ready ? &entry->program : nullptr;
  std::shared_ptr<std::promise<void>> promise = this->begin(features);
  this->Background.push_back(std::async(std::launch::async,
    [this, features, promise] { this->complete(features, *promise, true); }));
  return nullptr;
}

void PipelineLibrary::createLayouts()
{
  const VkShaderStageFlags stages = this->Kind == Backend::Compute
    ? VkShaderStageFlags(VK_SHADER_STAGE_COMPUTE_BIT)
    : VkShaderStageFlags(VK_SHADER_STAGE_RAYGEN_BIT_KHR | VK_SHADER_STAGE_MISS_BIT_KHR |
        VK_SHADER_STAGE_INTERSECTION_BIT_KHR | VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR);
  const std::vector<DescriptorBinding> used = bindingsOf(this->Kind);
  std::vector<VkDescriptorSetLayoutBinding> bindings(used.size());
  this->PoolSizes.resize(used.size());
  for (size_t i = 0; i < used.size(); ++i)
  {
    bindings[i].binding = used[i].binding;
    bindings[i].descriptorType = used[i].type;
    bindings[i].descriptorCount = 1;
    bindings[i].stageFlags = stages;
    this->PoolSizes[i] = { used[i].type, 1 };
  }
  VkDescriptorSetLayoutCreateInfo setInfo{ VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO };
  setInfo.bindingCount = uint32_t(bindings.size());
  setInfo.pBindings = bindings.data();
  check(vkCreateDescriptorSetLayout(this->Ctx.device(), &setInfo, nullptr, &this->SetLayout),
    "vkCreateDescriptorSetLayout");
  VkPipelineLayoutCreateInfo layoutInfo{ VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO };
  layoutInfo.setLayoutCount = 1;
  layoutInfo.pSetLayouts = &this->SetLayout;
  check(vkCreatePipelineLayout(this->Ctx.device(), &layoutInfo, nullptr, &this->Layout),
    "vkCreatePipelineLayout");
}

namespace
{
// The camera shader's feature switches (GpuLayout.h's SVDAG_CONSTANT_* ids) as its
// specialization.
struct FeatureConstants
{
  VkBool32 values[SVDAG_CONSTANT_COUNT] = {};
  VkSpecializationMapEntry entries[SVDAG_CONSTANT_COUNT];
  VkSpecializationInfo info{ SVDAG_CONSTANT_COUNT, entries, sizeof(values), values };

  explicit FeatureConstants(const ShaderFeatures& f)
  {
    values[SVDAG_CONSTANT_NEE] = f.nextEventEstimation;
    values[SVDAG_CONSTANT_ENV_MAP] = f.environmentMap;
    values[SVDAG_CONSTANT_SUN] = f.sun;
    values[SVDAG_CONSTANT_EMISSION] = f.emission;
    values[SVDAG_CONSTANT_TRANSMISSION] = f.transmission;
    values[SVDAG_CONSTANT_PREVIEW] = f.preview;
    values[SVDAG_CONSTANT_SMOOTH_SHADING] = f.smoothShading;
    values[SVDAG_CONSTANT_CLIPPING] = f.clipping;
    values[SVDAG_CONSTANT_STEP_STATISTICS] = f.stepStatistics;
    for (uint32_t i = 0; i < SVDAG_CONSTANT_COUNT; ++i)
      entries[i] = { i, uint32_t(i * sizeof(VkBool32)), sizeof(VkBool32) };
  }
  FeatureConstants(const FeatureConstants&) = delete; // info points into it
  FeatureConstants& operator=(const FeatureConstants&) = delete;
};
} // namespace

bool PipelineLibrary::hasBinary(const ShaderFeatures& features) const
{
  if (this->Kind != Backend::Compute || !this->Ctx.shared().hasShaderObjects())
    return false;
  const FeatureConstants constants(features);
  return this->Ctx.shared().hasShaderBinary(ComputeProgram::hash(
    svdagShader_camera_comp, sizeof(svdagShader_camera_comp), &constants.info));
}

void PipelineLibrary::compile(Program& program)
{
  const FeatureConstants constants(program.features);
  try
  {
    if (this->Kind == Backend::Compute)
      this->createComputePipeline(program, constants.info);
    else
      this->createRayTracingPipeline(program, constants.info);
    this->createShaderBindingTable(program);
  }
  catch (...)
  {
    program.table.reset();
    program.compute.reset();
    if (program.handle)
      vkDestroyPipeline(this->Ctx.device(), program.handle, nullptr);
    program.handle = VK_NULL_HANDLE;
    throw;
  }
}

uint64_t PipelineLibrary::shaderHash()
{
  uint64_t hash = fnv1a64(nullptr, 0);
  for (const auto& module : { std::make_pair(svdagShader_camera_rgen, sizeof(svdagShader_camera_rgen)),
         std::make_pair(svdagShader_camera_comp, sizeof(svdagShader_camera_comp)),
         std::make_pair(svdagShader_closest_rmiss, sizeof(svdagShader_closest_rmiss)),
         std::make_pair(svdagShader_shadow_rmiss, sizeof(svdagShader_shadow_rmiss)),
         std::make_pair(svdagShader_block_rchit, sizeof(svdagShader_block_rchit)),
         std::make_pair(svdagShader_block_rint, sizeof(svdagShader_block_rint)),
         std::make_pair(svdagShader_block_entry_rint, sizeof(svdagShader_block_entry_rint)) })
    hash = fnv1a64(module.first, module.second, hash);
  return hash;
}

Pipeline::Pipeline(Context& context, Backend backend, const ShaderFeatures& features)
  : Ctx(context)
  , Library(context.shared().pipelines(backend))
{
  try
  {
    const std::vector<VkDescriptorPoolSize>& sizes = this->Library.poolSizes();
    VkDescriptorPoolCreateInfo poolInfo{ VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO };
    poolInfo.maxSets = 1;
    poolInfo.poolSizeCount = uint32_t(sizes.size());
    poolInfo.pPoolSizes = sizes.data();
    check(vkCreateDescriptorPool(this->Ctx.device(), &poolInfo, nullptr, &this->Pool),
      "vkCreateDescriptorPool");
    VkDescriptorSetLayout setLayout = this->Library.setLayout();
    VkDescriptorSetAllocateInfo alloc{ VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO };
    alloc.descriptorPool = this->Pool;
    alloc.descriptorSetCount = 1;
    alloc.pSetLayouts = &setLayout;
    check(vkAllocateDescriptorSets(this->Ctx.device(), &alloc, &this->Set),
      "vkAllocateDescriptorSets");
    this->setFeatures(features);
  }
  catch (...)
  {
    this->destroy();
    throw;
  }
}

Pipeline::~Pipeline()
{
  this->destroy();
}

void Pipeline::destroy()
{
  if (this->Pool)
    vkDestroyDescriptorPool(this->Ctx.device(), this->Pool, nullptr);
  this->Pool = VK_NULL_HANDLE;
  this->Set = VK_NULL_HANDLE;
}

bool Pipeline::setFeatures(const ShaderFeatures& features)
{
  if (this->Current && this->Current->features == features)
    return false;
  this->Current = &this->Library.program(features);
  for (const ShaderFeatures& used : this->Used)
  {
    if (used == features)
      return false;
  }
  this->Used.push_back(features);
  return true;
}

void Pipeline::updateDescriptors(VkBuffer uniforms, VkAccelerationStructureKHR tlas)
{
  VkWriteDescriptorSetAccelerationStructureKHR asInfo{
    VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET_ACCELERATION_STRUCTURE_KHR
  };
  asInfo.accelerationStructureCount = 1;
  asInfo.pAccelerationStructures = &tlas;
  VkDescriptorBufferInfo uniformInfo{ uniforms, 0, sizeof(gpu::FrameUniforms) };
  std::vector<VkWriteDescriptorSet> writes;
  for (const DescriptorBinding& b : bindingsOf(this->backend()))
  {
    VkWriteDescriptorSet w{ VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET };
    w.dstSet = this->Set;
    w.dstBinding = b.binding;
    w.descriptorCount = 1;
    w.descriptorType = b.type;
    if (b.binding == SVDAG_BINDING_TLAS)
      w.pNext = &asInfo;
    else
      w.pBufferInfo = &uniformInfo;
    writes.push_back(w);
  }
  vkUpdateDescriptorSets(this->Ctx.device(), uint32_t(writes.size()), writes.data(), 0, nullptr);
}

void Pipeline::record(VkCommandBuffer cmd, uint32_t width, uint32_t height) const
{
  const bool compute = this->backend() == Backend::Compute;
  const VkPipelineBindPoint bind =
    compute ? VK_PIPELINE_BIND_POINT_COMPUTE : VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR;
  if (this->Current->compute)
    this->Current->compute->bind(cmd);
  else
    vkCmdBindPipeline(cmd, bind, this->Current->handle);
  vkCmdBindDescriptorSets(cmd, bind, this->layout(), 0, 1, &this->Set, 0, nullptr);
  if (compute)
  {
    const uint32_t group = SVDAG_COMPUTE_GROUP_SIZE;
    vkCmdDispatch(cmd, (width + group - 1) / group, (height + group - 1) / group, 1);
  }
  else
  {
    const PipelineLibrary::Program& p = *this->Current;
    this->Ctx.fn().cmdTraceRays(cmd, &p.raygen, &p.miss, &p.hit, &p.callable, width, height, 1);
  }
  // Makes the shader writes visible to the host reads after the pass.
  VkMemoryBarrier barrier{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
  barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd,
    compute ? VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT : VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR,
    VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
}

void PipelineLibrary::createComputePipeline(
  Program& program, const VkSpecializationInfo& specialization)
{
  ComputeProgram::Interface interface;
  interface.layout = this->Layout;
  interface.setLayouts = &this->SetLayout;
  interface.setLayoutCount = 1;
  program.compute = std::make_unique<ComputeProgram>(this->Ctx, svdagShader_camera_comp,
    sizeof(svdagShader_camera_comp), &specialization, interface, "the path tracer");
}

void PipelineLibrary::createRayTracingPipeline(
  Program& program, const VkSpecializationInfo& specialization)
{
  VkDevice device = this->Ctx.device();
  struct StageCode
  {
    VkShaderStageFlagBits stage;
    const uint32_t* code;
    size_t bytes;
  };
  // Stage order = the shader indices the groups below name.
  const StageCode codes[] = {
    { VK_SHADER_STAGE_RAYGEN_BIT_KHR, svdagShader_camera_rgen, sizeof(svdagShader_camera_rgen) },
    { VK_SHADER_STAGE_MISS_BIT_KHR, svdagShader_closest_rmiss,
      sizeof(svdagShader_closest_rmiss) },
    { VK_SHADER_STAGE_MISS_BIT_KHR, svdagShader_shadow_rmiss, sizeof(svdagShader_shadow_rmiss) },
    { VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR, svdagShader_block_rchit,
      sizeof(svdagShader_block_rchit) },
    { VK_SHADER_STAGE_INTERSECTION_BIT_KHR, svdagShader_block_rint,
      sizeof(svdagShader_block_rint) },
    { VK_SHADER_STAGE_INTERSECTION_BIT_KHR, svdagShader_block_entry_rint,
      sizeof(svdagShader_block_entry_rint) },
  };
  std::vector<VkPipelineShaderStageCreateInfo> stages;
  Modules modules{ device, {} };
  for (const StageCode& c : codes)
  {
    modules.list.push_back(createModule(device, c.code, c.bytes));
    VkPipelineShaderStageCreateInfo stage{ VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO };
    stage.stage = c.stage;
    stage.module = modules.list.back();
    stage.pName = "main";
    // The raygen's path tracer and the closest hit's shading normal read the switches.
    if (c.stage == VK_SHADER_STAGE_RAYGEN_BIT_KHR || c.stage == VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR)
      stage.pSpecializationInfo = &specialization;
    stages.push_back(stage);
  }
  VkRayTracingShaderGroupCreateInfoKHR groups[GroupCount];
  for (auto& g : groups)
  {
    g = VkRayTracingShaderGroupCreateInfoKHR{
      VK_STRUCTURE_TYPE_RAY_TRACING_SHADER_GROUP_CREATE_INFO_KHR
    };
    g.generalShader = VK_SHADER_UNUSED_KHR;
    g.closestHitShader = VK_SHADER_UNUSED_KHR;
    g.anyHitShader = VK_SHADER_UNUSED_KHR;
    g.intersectionShader = VK_SHADER_UNUSED_KHR;
  }
  groups[RaygenGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_GENERAL_KHR;
  groups[RaygenGroup].generalShader = 0;
  groups[MissGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_GENERAL_KHR;
  groups[MissGroup].generalShader = 1;
  groups[ShadowMissGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_GENERAL_KHR;
  groups[ShadowMissGroup].generalShader = 2;
  groups[HitGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_PROCEDURAL_HIT_GROUP_KHR;
  groups[HitGroup].closestHitShader = 3;
  groups[HitGroup].intersectionShader = 4;
  groups[EntryHitGroup].type = VK_RAY_TRACING_SHADER_GROUP_TYPE_PROCEDURAL_HIT_GROUP_KHR;
  groups[EntryHitGroup].closestHitShader = 3;
  groups[EntryHitGroup].intersectionShader = 5;

  VkRayTracingPipelineCreateInfoKHR info{ VK_STRUCTURE_TYPE_RAY_TRACING_PIPELINE_CREATE_INFO_KHR };
  info.stageCount = uint32_t(stages.size());
  info.pStages = stages.data();
  info.groupCount = GroupCount;
  info.pGroups = groups;
  info.maxPipelineRayRecursionDepth = 1; // every ray is traced from raygen
  info.layout = this->Layout;
  check(this->Ctx.fn().createRayTracingPipelines(device, VK_NULL_HANDLE,
          this->Ctx.shared().pipelineCache(), 1, &info, nullptr, &program.handle),
    "vkCreateRayTracingPipelinesKHR");
}

void PipelineLibrary::createShaderBindingTable(Program& program)
{
  if (this->Kind != Backend::RayTracing)
    return;
  const RayTracingLimits& limits = this->Ctx.limits();
  const VkDeviceSize handleSize = limits.shaderGroupHandleSize;
  const VkDeviceSize stride = alignUp(handleSize, limits.shaderGroupHandleAlignment);
  const VkDeviceSize regionSize = alignUp(stride, limits.shaderGroupBaseAlignment);
  std::vector<uint8_t> handles(GroupCount * handleSize);
  check(this->Ctx.fn().getRayTracingShaderGroupHandles(this->Ctx.device(), program.handle, 0,
          GroupCount, handles.size(), handles.data()),
    "vkGetRayTracingShaderGroupHandlesKHR");
  // Regions start at multiples of shaderGroupBaseAlignment: raygen (one record), miss (the two
  // miss records, `stride` apart), hit (the two hit group records, `stride` apart: a ray's
  // sbtRecordOffset picks one; sbtRecordStride is 0 and every instance has offset 0).
  const VkDeviceSize missOffset = regionSize;
  const VkDeviceSize hitOffset =
    alignUp(missOffset + 2 * stride, limits.shaderGroupBaseAlignment);
  const VkDeviceSize recordOffsets[GroupCount] = { 0, missOffset, missOffset + stride, hitOffset,
    hitOffset + stride };
  std::vector<uint8_t> table(hitOffset + 2 * stride, 0);
  for (uint32_t g = 0; g < GroupCount; ++g)
    std::memcpy(table.data() + recordOffsets[g], handles.data() + g * handleSize, handleSize);
  // The table's base address must itself be aligned to shaderGroupBaseAlignment; over-allocate.
  const VkDeviceSize base = limits.shaderGroupBaseAlignment;
  program.table = Buffer(this->Ctx, table.size() + base,
    VK_BUFFER_USAGE_SHADER_BINDING_TABLE_BIT_KHR, MemoryUse::Upload);
  const VkDeviceAddress start = alignUp(program.table.address(), base);
  std::memcpy(static_cast<uint8_t*>(program.table.mapped()) + (start - program.table.address()),
    table.data(), table.size());
  program.raygen = { start, regionSize, regionSize };
  program.miss = { start + missOffset, stride, 2 * stride };
  program.hit = { start + hitOffset, stride, 2 * stride };
  program.callable = { 0, 0, 0 };
}

} // namespace render
} // namespace svdag
