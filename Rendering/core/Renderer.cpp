#include "svdag_render/Renderer.h"

#include "svdag_render/Buffer.h"
#include "svdag_render/Context.h"
#include "svdag_render/GpuLayout.h"
#include "svdag_render/Pipeline.h"
#include "svdag_render/Scene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace svdag
{
namespace render
{
namespace
{
using Clock = std::chrono::steady_clock;

glm::uvec4 addresses(VkDeviceAddress a, VkDeviceAddress b)
{
  return glm::uvec4(uint32_t(a), uint32_t(a >> 32), uint32_t(b), uint32_t(b >> 32));
}

glm::vec4 vec(const std::array<double, 3>& v)
{
  return glm::vec4(float(v[0]), float(v[1]), float(v[2]), 0.0f);
}
} // namespace

const char* lodName(Lod lod)
{
  switch (lod)
  {
    case Lod::Block: return "block";
    case Lod::Leaf: return "leaf";
    case Lod::Voxel: return "voxel";
    case Lod::Auto: return "auto";
  }
  return "?";
}

Lod parseLod(const std::string& name)
{
  for (Lod lod : { Lod::Block, Lod::Leaf, Lod::Voxel, Lod::Auto })
  {
    if (name == lodName(lod))
      return lod;
  }
  throw std::invalid_argument("unknown LOD '" + name + "' (block, leaf, voxel or auto)");
}

// Everything that lives on the device. Declaration order is destruction order in reverse:
// the context goes last.
struct Renderer::Gpu
{
  Context context;
  Pipeline pipeline{ context };
  std::unique_ptr<Scene> scene;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VkDescriptorSet set = VK_NULL_HANDLE;
  Buffer uniforms{ context, sizeof(gpu::FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
    MemoryUse::Upload };
  // Outputs, sized for the current image: label, depth, normal, hdr, color.
  Buffer label, depth, normal, hdr, color;
  uint32_t outputPixels = 0;

  Gpu()
  {
    VkDescriptorPoolSize sizes[2] = { { VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, 1 },
      { VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1 } };
    VkDescriptorPoolCreateInfo poolInfo{ VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO };
    poolInfo.maxSets = 1;
    poolInfo.poolSizeCount = 2;
    poolInfo.pPoolSizes = sizes;
    check(vkCreateDescriptorPool(context.device(), &poolInfo, nullptr, &pool),
      "vkCreateDescriptorPool");
    VkDescriptorSetLayout layout = pipeline.setLayout();
    VkDescriptorSetAllocateInfo alloc{ VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO };
    alloc.descriptorPool = pool;
    alloc.descriptorSetCount = 1;
    alloc.pSetLayouts = &layout;
    const VkResult result = vkAllocateDescriptorSets(context.device(), &alloc, &set);
    if (result != VK_SUCCESS)
    {
      vkDestroyDescriptorPool(context.device(), pool, nullptr);
      check(result, "vkAllocateDescriptorSets");
    }
  }
  ~Gpu()
  {
    vkDeviceWaitIdle(context.device());
    vkDestroyDescriptorPool(context.device(), pool, nullptr);
  }

  void resizeOutputs(uint32_t pixels)
  {
    if (pixels == outputPixels)
      return;
    outputPixels = 0;
    const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    label = Buffer(context, pixels * sizeof(uint32_t), usage, MemoryUse::Readback);
    depth = Buffer(context, pixels * sizeof(float), usage, MemoryUse::Readback);
    normal = Buffer(context, pixels * 3 * sizeof(float), usage, MemoryUse::Readback);
    hdr = Buffer(context, pixels * 4 * sizeof(float), usage, MemoryUse::Readback);
    color = Buffer(context, pixels * sizeof(uint32_t), usage, MemoryUse::Readback);
    outputPixels = pixels;
  }

  void updateDescriptors()
  {
    VkAccelerationStructureKHR tlas = scene->tlas();
    VkWriteDescriptorSetAccelerationStructureKHR asInfo{
      VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET_ACCELERATION_STRUCTURE_KHR
    };
    asInfo.accelerationStructureCount = 1;
    asInfo.pAccelerationStructures = &tlas;
    VkDescriptorBufferInfo uniformInfo{ uniforms.handle(), 0, sizeof(gpu::FrameUniforms) };
    VkWriteDescriptorSet writes[2] = { { VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET },
      { VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET } };
    writes[0].pNext = &asInfo;
    writes[0].dstSet = set;
    writes[0].dstBinding = SVDAG_BINDING_TLAS;
    writes[0].descriptorCount = 1;
    writes[0].descriptorType = VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR;
    writes[1].dstSet = set;
    writes[1].dstBinding = SVDAG_BINDING_FRAME;
    writes[1].descriptorCount = 1;
    writes[1].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    writes[1].pBufferInfo = &uniformInfo;
    vkUpdateDescriptorSets(context.device(), 2, writes, 0, nullptr);
  }
};

Renderer::Renderer()
  : Device(std::make_unique<Gpu>())
{
}

Renderer::~Renderer() = default;

const std::string& Renderer::deviceName() const
{
  return this->Device->context.deviceName();
}

void Renderer::setVolume(std::shared_ptr<const Volume> volume)
{
  if (!volume)
    throw std::invalid_argument("setVolume needs a volume");
  std::vector<uint32_t> hidden;
  if (this->Device->scene)
    hidden = this->Device->scene->hiddenLabels();
  this->Device->scene.reset();
  const auto start = Clock::now();
  this->Device->scene = std::make_unique<Scene>(this->Device->context, std::move(volume));
  // Both rebuild the BVH only if they differ from the defaults (all visible, no cap).
  this->Device->scene->setPrimitivesPerBlasLimit(this->BlasLimit);
  this->Device->scene->setHiddenLabels(hidden);
  this->SetupSeconds = std::chrono::duration<double>(Clock::now() - start).count();
}

void Renderer::setHiddenLabels(const std::vector<uint32_t>& labelIndices)
{
  if (!this->Device->scene)
    throw std::runtime_error("setHiddenLabels needs a volume first (setVolume)");
  const auto start = Clock::now();
  if (this->Device->scene->setHiddenLabels(labelIndices))
    this->SetupSeconds = std::chrono::duration<double>(Clock::now() - start).count();
}

void Renderer::setPrimitivesPerBlasLimit(uint32_t limit)
{
  this->BlasLimit = limit;
  if (!this->Device->scene)
    return;
  const auto start = Clock::now();
  if (this->Device->scene->setPrimitivesPerBlasLimit(limit))
    this->SetupSeconds = std::chrono::duration<double>(Clock::now() - start).count();
}

size_t Renderer::blasCount() const
{
  return this->Device->scene ? this->Device->scene->blasCount() : 0;
}

void Renderer::setImageSize(uint32_t width, uint32_t height)
{
  const uint64_t pixels = uint64_t(width) * height;
  const uint64_t limit = std::min<uint64_t>(
    this->Device->context.limits().maxRayDispatchInvocationCount, uint64_t(1) << 28);
  if (pixels == 0 || pixels > limit)
  {
    throw std::invalid_argument("image size " + std::to_string(width) + " x " +
      std::to_string(height) + " is outside 1 .. " + std::to_string(limit) + " pixels");
  }
  this->Width = width;
  this->Height = height;
}

void Renderer::setAutoLodPixels(float pixels)
{
  if (!(pixels > 0) || !std::isfinite(pixels))
    throw std::invalid_argument("auto LOD pixels must be a finite value > 0");
  this->AutoLodPixels = pixels;
}

uint64_t Renderer::blasBytes() const
{
  return this->Device->scene ? this->Device->scene->blasBytes() : 0;
}

uint64_t Renderer::tlasBytes() const
{
  return this->Device->scene ? this->Device->scene->tlasBytes() : 0;
}

uint64_t Renderer::visibleBlocks() const
{
  return this->Device->scene ? this->Device->scene->visibleBlocks() : 0;
}

const Image& Renderer::render()
{
  Gpu& g = *this->Device;
  if (!g.scene)
    throw std::runtime_error("render needs a volume first (setVolume)");
  if (!g.scene->ready())
    throw std::runtime_error("the scene's BVH is not built: its last build failed");
  const RayBasis basis = rayBasis(this->View, this->Width, this->Height);
  const uint32_t pixels = this->Width * this->Height;
  g.resizeOutputs(pixels);

  const Volume& volume = g.scene->volume();
  const FieldWidths& w = volume.widths;
  const auto cells = volume.geometry.cellCounts();
  const auto& s = volume.geometry.spacing;
  const double pixelAngle =
    2 * std::tan(this->View.viewAngle * 3.14159265358979323846 / 360) / this->Height;
  gpu::FrameUniforms u{};
  // Relative to the scene's reference point, in double before rounding to float (Scene.h).
  const auto& reference = g.scene->worldReference();
  u.cameraPosition = vec({ { this->View.position[0] - reference[0],
    this->View.position[1] - reference[1], this->View.position[2] - reference[2] } });
  u.cameraForward = vec(basis.forward);
  u.cameraRight = vec(basis.right);
  u.cameraUp = vec(basis.up);
  u.background = glm::vec4(
    this->Background[0], this->Background[1], this->Background[2], this->Background[3]);
  u.shading = glm::vec4(0.25f, 0.75f, 0.0f, 0.0f);
  u.autoLod = glm::vec4(
    float(std::min({ s[0], s[1], s[2] }) / pixelAngle), this->AutoLodPixels, 0.0f, 0.0f);
  u.image = glm::uvec4(this->Width, this->Height, uint32_t(this->Detail), 0u);
  u.grid = glm::uvec4(uint32_t(cells[0]), uint32_t(cells[1]), g.scene->primitivesPerBlas(), 0u);
  u.widths = glm::uvec4(w.cellBits, w.labelBits, w.rootRefBits, w.midRefBits);
  u.widths2 = glm::uvec4(w.leafRefBits, w.blockBits(), 0u, 0u);
  u.volumeStreams = addresses(g.scene->blocksAddress(), g.scene->rootsAddress());
  u.volumeStreams2 = addresses(g.scene->midsAddress(), g.scene->leavesAddress());
  u.sceneOutputs = addresses(g.scene->primitiveBlocksAddress(), g.label.address());
  u.outputs = addresses(g.depth.address(), g.normal.address());
  u.outputs2 = addresses(g.hdr.address(), g.color.address());
  std::memcpy(g.uniforms.mapped(), &u, sizeof(u));
  g.updateDescriptors();

  const auto start = Clock::now();
  g.context.submitAndWait([&](VkCommandBuffer cmd) {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR, g.pipeline.handle());
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR, g.pipeline.layout(), 0,
      1, &g.set, 0, nullptr);
    g.context.fn().cmdTraceRays(cmd, &g.pipeline.raygenRegion(), &g.pipeline.missRegion(),
      &g.pipeline.hitRegion(), &g.pipeline.callableRegion(), this->Width, this->Height, 1);
    // Makes the shader writes visible to the host reads below.
    VkMemoryBarrier barrier{ VK_STRUCTURE_TYPE_MEMORY_BARRIER };
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR,
      VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
  });
  this->FrameMilliseconds =
    std::chrono::duration<double, std::milli>(Clock::now() - start).count();

  Image& out = this->Output;
  out.width = this->Width;
  out.height = this->Height;
  auto read = [](auto& vector, const Buffer& buffer, size_t count) {
    vector.resize(count);
    std::memcpy(vector.data(), buffer.mapped(), count * sizeof(vector[0]));
  };
  read(out.label, g.label, pixels);
  read(out.depth, g.depth, pixels);
  read(out.normal, g.normal, size_t(pixels) * 3);
  read(out.hdr, g.hdr, size_t(pixels) * 4);
  read(out.color, g.color, pixels);
  return out;
}

} // namespace render
} // namespace svdag
