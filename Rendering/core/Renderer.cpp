#include "svdag_render/Renderer.h"

#include "svdag_render/Buffer.h"
#include "svdag_render/Context.h"
#include "svdag_render/DenoisePass.h"
#include "svdag_render/UpsamplePass.h"
#include "svdag_render/DepthPass.h"
#include "svdag_render/EnvironmentMap.h"
#include "svdag_render/GpuLayout.h"
#include "svdag_render/Pipeline.h"
#include "svdag_render/Scene.h"

#include <svdag/RayCaster.h>
#include <svdag/Layout.h>
#include <svdag/Traversal.h>

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

// Room an importer may need past the data in exported memory: llvmpipe's OpenGL buffers on
// imported memory ask for 48 bytes more than their size.
constexpr VkDeviceSize ImportSlack = 256;

glm::dvec4 dvec(const std::array<double, 3>& v)
{
  return glm::dvec4(v[0], v[1], v[2], 0.0);
}

// The depth pass's matrix rows and rays: `rays` measures the depth, `traced` (with `advance`)
// are the rays a render() traced (Renderer::render's advance).
gpu::DepthParams depthParams(uint32_t pass, const std::array<double, 16>& matrix,
  const ViewRays& rays, const ViewRays& traced, double advance)
{
  gpu::DepthParams p{};
  for (int r = 0; r < 4; ++r)
    p.matrix[r] = glm::dvec4(matrix[4 * r], matrix[4 * r + 1], matrix[4 * r + 2], matrix[4 * r + 3]);
  p.origin = dvec(rays.origin);
  p.originU = dvec(rays.originU);
  p.originV = dvec(rays.originV);
  p.direction = dvec(rays.direction);
  p.directionU = dvec(rays.directionU);
  p.directionV = dvec(rays.directionV);
  p.tracedDirection = dvec(traced.direction);
  p.tracedDirectionU = dvec(traced.directionU);
  p.tracedDirectionV = dvec(traced.directionV);
  p.scalars = glm::dvec4(advance > 0 ? advance : 0.0, SVDAG_RAY_LIMIT_SLACK, 0.0, 0.0);
  p.pass = glm::uvec4(pass, 0u, 0u, 0u);
  return p;
}

glm::uvec4 addresses(VkDeviceAddress a, VkDeviceAddress b)
{
  return glm::uvec4(uint32_t(a), uint32_t(a >> 32), uint32_t(b), uint32_t(b >> 32));
}

glm::vec4 vec(const std::array<double, 3>& v)
{
  return glm::vec4(float(v[0]), float(v[1]), float(v[2]), 0.0f);
}

bool finite(const glm::vec4& v)
{
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}

bool visible(const Material& m)
{
  return m.baseColorVisibility.a != 0.0f;
}

// Transmission the shader samples (Shading.h's transmissionProbability, without its header).
bool transmissive(const Material& m)
{
  return std::min(std::max(m.params.z, 0.0f), 1.0f) * (1.0f - std::min(std::max(m.params.y, 0.0f), 1.0f)) > 0.0f;
}

bool emissive(const Material& m)
{
  return m.emission.x > 0.0f || m.emission.y > 0.0f || m.emission.z > 0.0f;
}

// A device-local storage buffer holding `values` (at least one element, so an address exists).
template <typename T>
Buffer storageBuffer(Context& context, const std::vector<T>& values)
{
  const std::vector<T> one(1);
  const std::vector<T>& data = values.empty() ? one : values;
  return uploadBuffer(context, data.data(), data.size() * sizeof(T),
    VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
}

// The clipping planes and crop box as Clipping.h planes relative to the scene's reference point:
// unit normals (world units), each moved into the kept side by `margin`. Throws like validate().
uint32_t gpuClipPlanes(const RenderSettings& settings, const std::array<double, 3>& reference,
  double margin, glm::vec4* out)
{
  static_assert(MaximumClipPlanes == SVDAG_CLIP_MAX_PLANES, "one limit for clipping planes");
  static_assert(SVDAG_CLIP_MAX_SLOTS == SVDAG_CLIP_MAX_PLANES + 6, "the crop box adds 6 planes");
  validateClipping(settings.clipPlanes, settings.crop);
  uint32_t count = 0;
  // dot(n, x - origin) >= 0 with x = shifted + reference, n unit: w = dot(n, reference - origin).
  auto add = [&](const std::array<double, 3>& origin, const std::array<double, 3>& normal) {
    const double length =
      std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    double w = -margin;
    glm::vec4 plane;
    for (int a = 0; a < 3; ++a)
    {
      const double n = normal[a] / length;
      plane[a] = float(n);
      w += n * (reference[a] - origin[a]);
    }
    plane.w = float(w);
    out[count++] = plane;
  };
  for (const ClipPlane& p : settings.clipPlanes)
    add(p.origin, p.normal);
  if (settings.crop.on)
  {
    const auto& b = settings.crop.bounds;
    for (int a = 0; a < 3; ++a)
    {
      std::array<double, 3> lo{ { 0, 0, 0 } }, hi{ { 0, 0, 0 } }, up{ { 0, 0, 0 } },
        down{ { 0, 0, 0 } };
      lo[a] = b[2 * a];
      hi[a] = b[2 * a + 1];
      up[a] = 1;
      down[a] = -1;
      add(lo, up);
      add(hi, down);
    }
  }
  return count;
}
// Applies one edit to a copy of the settings and validates it: the setters share validate()'s
// checks and messages.
template <typename Edit>
RenderSettings edited(const RenderSettings& current, Edit edit)
{
  RenderSettings s = current;
  edit(s);
  validate(s);
  return s;
}
} // namespace

namespace
{
// The per-pixel buffers of one traced image size: the outputs (GpuLayout.h), the accumulation's
// sums and the ray limits.
struct TraceImages
{
  Buffer label, depth, normal, hdr, color, variance, accumulation, squares, rayLimits;
  uint32_t pixels = 0;
  // Whether hdr is a Shared buffer (Renderer::setColorSharing), and how often it was allocated.
  bool hdrShared = false;
  uint64_t hdrGeneration = 0;

  uint64_t bytes() const
  {
    return label.size() + depth.size() + normal.size() + hdr.size() + color.size() +
      variance.size() + accumulation.size() + squares.size() + rayLimits.size() + coverage.size();
  }

  void resize(Context& context, uint32_t count, bool shareColor)
  {
    if (count == pixels && shareColor == hdrShared)
      return;
    pixels = 0;
    const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    label = Buffer(context, count * sizeof(uint32_t), usage, MemoryUse::Readback);
    depth = Buffer(context, count * sizeof(float), usage, MemoryUse::Readback);
    // Shading normals, then entry face normals (GpuLayout.h).
    normal = Buffer(context, count * 6 * sizeof(float), usage, MemoryUse::Readback);
    hdr = Buffer();
    hdr = Buffer(context, count * 4 * sizeof(float) + (shareColor ? ImportSlack : 0), usage,
      shareColor ? MemoryUse::Shared : MemoryUse::Readback);
    hdrShared = shareColor;
    ++hdrGeneration;
    color = Buffer(context, count * sizeof(uint32_t), usage, MemoryUse::Readback);
    variance = Buffer(context, count * sizeof(float), usage, MemoryUse::Readback);
    accumulation = Buffer(context, count * 4 * sizeof(float), usage, MemoryUse::Device);
    squares = Buffer(context, count * sizeof(float), usage, MemoryUse::Device);
    rayLimits = Buffer(context, count * sizeof(float), usage, MemoryUse::Upload);
    pixels = count;
  }

  // The edge coverage records (GpuLayout.h), made for the denoiser's first use, and whether they
  // are the current accumulation's (traced on its first pass: the denoiser may be switched on
  // later, or the first pass may have been reduced).
  Buffer coverage;
  bool coverageCurrent = false;

  VkDeviceAddress coverageRecords(Context& context)
  {
    const uint64_t bytes = uint64_t(pixels) * SVDAG_COVERAGE_RECORD_VEC4S * 16;
    if (coverage.size() != bytes)
      coverage = Buffer(context, bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
        MemoryUse::Device);
    return coverage.address();
  }

  void release() { *this = TraceImages(); }
};
} // namespace

// Everything that lives on the device. Declaration order is destruction order in reverse:
// the context goes last.
struct Renderer::Gpu
{
  Context context;
  // The pipeline of each backend, made when first used (indexed by Backend).
  std::unique_ptr<Pipeline> pipelines[3];
  std::unique_ptr<Scene> scene;
  // Smooth shading's neighbour table of the scene's volume (svdag::neighbourTable), built on the
  // first smooth frame; empty (no buffer) otherwise.
  Buffer neighbours;
  bool hasNeighbours = false;
  Buffer uniforms{ context, sizeof(gpu::FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
    MemoryUse::Upload };
  // The image's outputs (what image() reads back), and those of the reduced trace while
  // RenderSettings::traceReduction is above 1 (empty otherwise).
  TraceImages full, reduced;
  // The denoiser, made on the first frame that uses it, and what it would filter of the last
  // pass where that pass left it out (Renderer::PassUse::Accumulating; finishImage runs it).
  std::unique_ptr<DenoisePass> denoiser;
  bool denoisePending = false;
  DenoisePass::Frame pendingFrame;
  gpu::DenoiseParams pendingParams{};
  bool pendingUpsample = false;
  // Guided upsampling (made on the first reduced frame), its last parameters, and what the
  // guides were traced with (empty: not traced) and how long that took in the last frame.
  std::unique_ptr<UpsamplePass> upsampler;
  gpu::UpsampleParams upsampleParams{};
  std::vector<unsigned char> guideState;
  double guideMilliseconds = 0;
  // The scene depth slots (Renderer::sceneDepth; whoever holds their pointers shares them), the
  // composited depth (Shared: OpenGL reads it), their pixel counts and allocations (one
  // counter for all, so that no two allocations share a generation), and the depth pass (made
  // on first use). The rays and advance of the last render(), which its depths are relative to.
  std::shared_ptr<Buffer> sceneDepth[2];
  uint32_t sceneDepthPixels[2] = { 0, 0 };
  uint64_t sceneDepthGeneration[2] = { 0, 0 };
  Buffer composited;
  uint32_t compositedPixels = 0;
  uint64_t compositedGeneration = 0;
  uint64_t depthAllocations = 0;
  std::unique_ptr<DepthPass> depthPass;
  // The step counters of the statistics variant (Renderer::setStepStatistics), made on first use.
  Buffer stepCounts;
  ViewRays tracedRays;
  double tracedAdvance = 0;
  // Per-label materials (host-visible: an edit is a memcpy) and the environment's tables.
  Buffer materials;
  Buffer envMarginal, envConditional, envTexels;
  glm::uvec2 envSize{ 1, 1 };

  // Nothing of this renderer is in flight between calls (every submission waits for its fence);
  // the device itself may be busy with another renderer's work, so it is not waited for.

  Pipeline& pipeline(Backend backend, const ShaderFeatures& features)
  {
    std::unique_ptr<Pipeline>& p = pipelines[size_t(backend)];
    if (!p)
      p = std::make_unique<Pipeline>(context, backend, features);
    p->setFeatures(features);
    return *p;
  }

  uint64_t imageBytes() const
  {
    return full.bytes() + reduced.bytes() + (sceneDepth[0] ? sceneDepth[0]->size() : 0) +
      (sceneDepth[1] ? sceneDepth[1]->size() : 0) + composited.size() +
      (denoiser ? denoiser->bytes() : 0) + (upsampler ? upsampler->bytes() : 0);
  }

  DepthPass& depthPassOf()
  {
    if (!depthPass)
      depthPass = std::make_unique<DepthPass>(context);
    return *depthPass;
  }
};

Renderer::Renderer()
  : Device(std::make_unique<Gpu>())
{
}

// After the scene's structure changed (a BVH build, or the compute backend's grid or hidden
// bits): the next frame restarts the accumulation.
void Renderer::timeSetup(bool rebuilt, double seconds)
{
  if (!rebuilt)
    return;
  this->SetupSeconds = seconds;
  if (this->Device->scene && this->Device->scene->backend() == Backend::RayTracing)
    ++this->BvhBuilds;
  ++this->SceneGeneration;
}

Renderer::~Renderer() = default;

void Renderer::setColorSharing(bool on)
{
  if (on && !this->canShareColor())
    throw std::runtime_error("the Vulkan device cannot export memory (" VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME ")");
  this->ShareColor = on;
}

bool Renderer::canShareColor() const
{
  return this->Device->context.canExportMemory();
}

const DeviceUuids& Renderer::deviceUuids() const
{
  return this->Device->context.uuids();
}

uint64_t Renderer::sharedColorGeneration() const
{
  const Gpu& g = *this->Device;
  if (!g.full.hdrShared || !g.full.hdr)
    throw std::logic_error("the color is not shared: setColorSharing(true), then render()");
  return g.full.hdrGeneration;
}

ExportedMemory Renderer::exportColor() const
{
  this->sharedColorGeneration(); // the same checks
  return this->Device->full.hdr.exportMemory();
}

const std::string& Renderer::deviceName() const
{
  return this->Device->context.deviceName();
}

size_t Renderer::deviceUsers()
{
  return Context::users();
}

uint64_t Renderer::deviceSerial() const
{
  return this->Device->context.shared().serial();
}

uint64_t Renderer::deviceAllocatedBytes() const
{
  return this->Device->context.shared().allocatedBytes();
}

uint64_t Renderer::sharedDeviceBytes() const
{
  return this->Device->context.shared().sharedBytes();
}

uint64_t Renderer::pipelineCompilations() const
{
  return this->Device->context.shared().pipelineCompilations();
}

Renderer::PipelineCacheStatus Renderer::pipelineCache() const
{
  const auto& device = this->Device->context.shared();
  return { device.pipelineCacheFile(), device.pipelineCacheLoadedBytes(),
    device.pipelineCacheProblem(), device.hasShaderObjects(), device.shaderBinariesLoaded(),
    device.shadersCompiled(), device.shaderBinaryProblem() };
}

bool Renderer::hasRayTracing() const
{
  return this->Device->context.hasRayTracing();
}

Backend Renderer::backendFor(Backend requested) const
{
  const Context& c = this->Device->context;
  switch (requested)
  {
    case Backend::RayTracing:
      if (!c.hasRayTracing())
        throw std::runtime_error("the rt backend needs a Vulkan device with ray tracing; " +
          c.deviceName() + " lacks " + c.rayTracingMissing() + " (use the compute backend)");
      return Backend::RayTracing;
    case Backend::Compute: return Backend::Compute;
    case Backend::Auto: break;
  }
  // Measured (bench/render.py): on lavapipe the compute backend wins at every LOD.
  return c.hasRayTracing() && !c.isCpuDevice() ? Backend::RayTracing : Backend::Compute;
}

void Renderer::setBackend(Backend backend)
{
  RenderSettings next = edited(this->Settings, [backend](RenderSettings& s) { s.backend = backend; });
  this->backendFor(backend); // throws where it cannot run
  this->Settings = next;
  this->applyBackend();
}

void Renderer::applyBackend()
{
  Scene* scene = this->Device->scene.get();
  const Backend wanted = this->backend();
  if (!scene || (scene->backend() == wanted && scene->ready()))
    return;
  const auto start = Clock::now();
  scene->setBackend(wanted);
  this->timeSetup(true, std::chrono::duration<double>(Clock::now() - start).count());
}

void Renderer::setVolume(std::shared_ptr<const Volume> volume)
{
  if (!volume)
    throw std::invalid_argument("setVolume needs a volume");
  this->Device->scene.reset();
  this->Device->neighbours = Buffer();
  this->Device->hasNeighbours = false;
  this->Materials.clear();
  const auto start = Clock::now();
  this->Device->scene = std::make_unique<Scene>(
    this->Device->context, std::move(volume), this->backend(), this->BlockChunkShift);
  // Rebuilds the BVH only if it differs from the default (no cap).
  this->Device->scene->setPrimitivesPerBlasLimit(this->Settings.maximumBlocksPerBlas);
  // Every label starts with its default material; the explicitly hidden labels stay hidden.
  const size_t labels = this->Device->scene->volume().labels.size();
  this->Materials.reserve(labels);
  for (size_t i = 0; i < labels; ++i)
    this->Materials.push_back(defaultMaterial(uint32_t(i)));
  this->Device->materials = Buffer(this->Device->context,
    std::max<size_t>(labels, 1) * sizeof(Material), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
    MemoryUse::Upload);
  this->MaterialsDirty = true;
  this->Device->scene->setHiddenLabels(this->ExplicitHidden);
  this->timeSetup(true, std::chrono::duration<double>(Clock::now() - start).count());
}

void Renderer::setHiddenLabels(const std::vector<uint32_t>& labelIndices)
{
  if (!this->Device->scene)
    throw std::runtime_error("setHiddenLabels needs a volume first (setVolume)");
  this->ExplicitHidden = labelIndices;
  this->applyVisibility();
}

// The BVH leaves out the explicitly hidden labels and those whose material is invisible.
void Renderer::applyVisibility()
{
  std::vector<uint32_t> hidden = this->ExplicitHidden;
  for (size_t i = 0; i < this->Materials.size(); ++i)
  {
    if (!visible(this->Materials[i]))
      hidden.push_back(uint32_t(i));
  }
  std::sort(hidden.begin(), hidden.end());
  hidden.erase(std::unique(hidden.begin(), hidden.end()), hidden.end());
  const auto start = Clock::now();
  const bool rebuilt = this->Device->scene->setHiddenLabels(hidden);
  this->timeSetup(rebuilt, std::chrono::duration<double>(Clock::now() - start).count());
}

void Renderer::setMaximumBlocksPerBlas(uint32_t limit)
{
  this->Settings.maximumBlocksPerBlas = limit;
  if (!this->Device->scene)
    return;
  const auto start = Clock::now();
  const bool rebuilt = this->Device->scene->setPrimitivesPerBlasLimit(limit);
  this->timeSetup(rebuilt, std::chrono::duration<double>(Clock::now() - start).count());
}

void Renderer::setBlockChunkShift(uint32_t shift)
{
  this->BlockChunkShift = shift;
}

uint64_t Renderer::deviceBytes() const
{
  return this->Device->context.allocatedBytes();
}

DeviceBytes Renderer::deviceBytesByPart() const
{
  const Gpu& g = *this->Device;
  DeviceBytes b;
  if (g.scene)
  {
    b.encoding = g.scene->streamBytes();
    b.acceleration = g.scene->accelerationBytes();
  }
  b.materials =
    g.materials.size() + g.envMarginal.size() + g.envConditional.size() + g.envTexels.size();
  b.neighbours = g.hasNeighbours ? g.neighbours.size() : 0;
  b.images = g.imageBytes();
  b.total = g.context.allocatedBytes();
  const uint64_t parts = b.encoding + b.acceleration + b.materials + b.neighbours + b.images;
  b.other = b.total > parts ? b.total - parts : 0;
  return b;
}

size_t Renderer::blockChunkCount() const
{
  return this->Device->scene ? this->Device->scene->blockChunkCount() : 0;
}

size_t Renderer::blasCount() const
{
  return this->Device->scene ? this->Device->scene->blasCount() : 0;
}

void Renderer::setImageSize(uint32_t width, uint32_t height)
{
  // What both backends can dispatch on this device (the ray tracing one's invocation count where
  // it has ray tracing, the compute one's workgroup counts) and at most 2^28 pixels.
  const RayTracingLimits& limits = this->Device->context.limits();
  const uint64_t pixels = uint64_t(width) * height;
  uint64_t limit = uint64_t(1) << 28;
  if (this->Device->context.hasRayTracing())
    limit = std::min<uint64_t>(limit, limits.maxRayDispatchInvocationCount);
  const uint64_t group = SVDAG_COMPUTE_GROUP_SIZE;
  if (width > group * limits.maxComputeWorkGroupCount[0] ||
    height > group * limits.maxComputeWorkGroupCount[1])
    limit = 0;
  if (pixels == 0 || pixels > limit)
  {
    throw std::invalid_argument("image size " + std::to_string(width) + " x " +
      std::to_string(height) + " is outside 1 .. " + std::to_string(limit) + " pixels");
  }
  this->Width = width;
  this->Height = height;
}

void Renderer::setTraceReduction(uint32_t reduction)
{
  if (reduction < 1 || reduction > MaximumTraceReduction)
    throw std::invalid_argument("the trace reduction must be 1 .. " +
      std::to_string(MaximumTraceReduction) + ", got " + std::to_string(reduction));
  this->TraceReduction = reduction;
}

void Renderer::setCamera(const Camera& camera)
{
  this->View = camera;
  this->RaysFromCamera = true;
}

void Renderer::setViewRays(const ViewRays& rays)
{
  this->Rays = rays;
  this->RaysFromCamera = false;
}

ViewRays Renderer::viewRays() const
{
  return this->RaysFromCamera ? render::viewRays(this->View, this->Width, this->Height) : this->Rays;
}

void Renderer::setRayLimits(std::vector<float> limits)
{
  this->RayLimits = std::move(limits);
  this->DepthLimitsOn = false;
}

bool Renderer::canShareDepth() const
{
  return this->Device->context.canExportMemory() && this->Device->context.hasFloat64();
}

std::shared_ptr<const float> Renderer::sceneDepth(uint32_t slot, uint32_t pixels)
{
  Gpu& g = *this->Device;
  if (slot > 1 || pixels == 0)
    throw std::invalid_argument("scene depth slots are 0 and 1, of at least one pixel");
  if (!this->canShareDepth())
    throw std::logic_error("the scene depth cannot be shared on this device (canShareDepth)");
  std::shared_ptr<Buffer>& buffer = g.sceneDepth[slot];
  if (!buffer || g.sceneDepthPixels[slot] != pixels)
  {
    // A new buffer, not a reallocation in place: an earlier pointer keeps the old one.
    buffer = std::make_shared<Buffer>(g.context, pixels * sizeof(float) + ImportSlack,
      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::SharedHost);
    g.sceneDepthPixels[slot] = pixels;
    g.sceneDepthGeneration[slot] = ++g.depthAllocations;
  }
  return std::shared_ptr<const float>(buffer, static_cast<const float*>(buffer->mapped()));
}

uint64_t Renderer::sceneDepthGeneration(uint32_t slot) const
{
  if (slot > 1 || !this->Device->sceneDepth[slot])
    throw std::logic_error("no scene depth buffer in this slot: sceneDepth(slot, pixels) first");
  return this->Device->sceneDepthGeneration[slot];
}

ExportedMemory Renderer::exportSceneDepth(uint32_t slot) const
{
  this->sceneDepthGeneration(slot); // the same checks
  return this->Device->sceneDepth[slot]->exportMemory();
}

void Renderer::setRayLimitsFromDepth(const DepthRayLimits& limits)
{
  const Gpu& g = *this->Device;
  if (limits.slot > 1 || !g.sceneDepth[limits.slot] ||
    uint64_t(limits.viewportWidth) * limits.viewportHeight != g.sceneDepthPixels[limits.slot] ||
    limits.viewportWidth == 0)
    throw std::invalid_argument("the ray limits' viewport is not the size of its scene depth");
  this->RayLimits.clear();
  this->DepthLimits = limits;
  this->DepthLimitsOn = true;
}

void Renderer::compositeDepth(uint32_t slot, uint32_t viewportWidth, uint32_t viewportHeight,
  const std::array<double, 16>& modelToClip, const ViewRays& rays)
{
  Gpu& g = *this->Device;
  const uint32_t pixels = viewportWidth * viewportHeight;
  if (this->Output.width == 0 || g.full.pixels != this->Output.width * this->Output.height)
    throw std::logic_error("compositeDepth needs a render() first");
  if (slot > 1 || !g.sceneDepth[slot] || pixels == 0 || g.sceneDepthPixels[slot] != pixels)
    throw std::invalid_argument("the composited viewport is not the size of its scene depth");
  if (!g.composited || g.compositedPixels != pixels)
  {
    g.composited = Buffer();
    g.composited = Buffer(g.context, pixels * sizeof(float) + ImportSlack,
      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::Shared);
    g.compositedPixels = pixels;
    g.compositedGeneration = ++g.depthAllocations;
  }
  gpu::DepthParams p =
    depthParams(SVDAG_DEPTH_PASS_COMPOSITE, modelToClip, rays, g.tracedRays, g.tracedAdvance);
  p.sizes = glm::uvec4(viewportWidth, viewportHeight, this->Output.width, this->Output.height);
  p.depth = addresses(g.sceneDepth[slot]->address(), g.composited.address());
  p.traced = addresses(g.full.label.address(), g.full.depth.address());
  DepthPass& pass = g.depthPassOf();
  g.context.submitAndWait([&](VkCommandBuffer cmd) { pass.record(cmd, p); });
}

uint64_t Renderer::compositedDepthGeneration() const
{
  if (!this->Device->composited)
    throw std::logic_error("no composited depth: compositeDepth first");
  return this->Device->compositedGeneration;
}

ExportedMemory Renderer::exportCompositedDepth() const
{
  this->compositedDepthGeneration(); // the same checks
  return this->Device->composited.exportMemory();
}

void Renderer::setSettings(const RenderSettings& settings)
{
  validate(settings);
  this->backendFor(settings.backend); // throws where it cannot run
  const bool environmentChanged = settings.environmentMap != this->Settings.environmentMap;
  const uint32_t blasLimit = settings.maximumBlocksPerBlas;
  const std::string environment = settings.environmentMap;
  RenderSettings next = settings;
  // Both may fail or rebuild: apply them through their own setters (the map last, so that a
  // file that cannot be read leaves the previous map and throws).
  next.maximumBlocksPerBlas = this->Settings.maximumBlocksPerBlas;
  next.environmentMap = this->Settings.environmentMap;
  this->Settings = next;
  this->Device->context.setMemoryLimit(settings.deviceMemoryLimit);
  this->applyBackend();
  this->setMaximumBlocksPerBlas(blasLimit);
  if (environmentChanged)
    this->setEnvironmentMap(environment);
}


void Renderer::setLod(Lod lod)
{
  this->Settings = edited(this->Settings, [lod](RenderSettings& s) { s.lod = lod; });
}

void Renderer::setAutoLodPixels(float pixels)
{
  this->Settings = edited(this->Settings, [pixels](RenderSettings& s) { s.autoLodPixels = pixels; });
}

void Renderer::setBackground(const std::array<float, 4>& linearRGBA)
{
  this->Settings =
    edited(this->Settings, [&linearRGBA](RenderSettings& s) { s.background = linearRGBA; });
}

void Renderer::setSamplesPerPixel(uint32_t samples)
{
  this->Settings =
    edited(this->Settings, [samples](RenderSettings& s) { s.samplesPerPixel = samples; });
}

void Renderer::setMaximumBounces(uint32_t bounces)
{
  this->Settings =
    edited(this->Settings, [bounces](RenderSettings& s) { s.maximumBounces = bounces; });
}

void Renderer::setExposure(float exposure)
{
  this->Settings = edited(this->Settings, [exposure](RenderSettings& s) { s.exposure = exposure; });
}

void Renderer::setEnvironmentColor(const std::array<float, 3>& radiance)
{
  this->Settings =
    edited(this->Settings, [&radiance](RenderSettings& s) { s.environmentColor = radiance; });
}

void Renderer::setEnvironmentMap(const std::string& exrPath)
{
  if (exrPath == this->Settings.environmentMap && !this->EnvironmentDirty)
    return;
  Gpu& g = *this->Device;
  // Read and upload first: a failure leaves the previous environment in place.
  const EnvironmentMap map =
    exrPath.empty() ? EnvironmentMap::constant(glm::vec3(1.0f)) : EnvironmentMap::fromEXR(exrPath);
  std::vector<glm::vec4> texels;
  texels.reserve(map.texels.size());
  for (const glm::vec3& t : map.texels)
    texels.emplace_back(t, 0.0f); // vec4 per texel: std430 arrays of vec3 have a 16-byte stride
  Buffer marginal = storageBuffer(g.context, map.marginal);
  Buffer conditional = storageBuffer(g.context, map.conditional);
  Buffer texelBuffer = storageBuffer(g.context, texels);
  g.envMarginal = std::move(marginal);
  g.envConditional = std::move(conditional);
  g.envTexels = std::move(texelBuffer);
  g.envSize = glm::uvec2(map.width, map.height);
  this->Settings.environmentMap = exrPath;
  this->EnvironmentDirty = false;
  ++this->EnvironmentGeneration;
}

void Renderer::setClipping(const std::vector<ClipPlane>& planes, const CropBox& crop)
{
  validateClipping(planes, crop);
  this->Settings.clipPlanes = planes;
  this->Settings.crop = crop;
}

void Renderer::setShading(Shading shading)
{
  this->Settings = edited(this->Settings, [shading](RenderSettings& s) { s.shading = shading; });
}

uint64_t Renderer::neighbourTableBytes() const
{
  return this->Device->hasNeighbours ? this->Device->neighbours.size() : 0;
}

void Renderer::setSun(const SunLight& sun)
{
  this->Settings = edited(this->Settings, [&sun](RenderSettings& s) { s.sun = sun; });
}

Material Renderer::defaultMaterial(uint32_t labelIndex)
{
  Material m;
  m.baseColorVisibility = glm::vec4(gpu::svdagLabelColor(labelIndex), 1.0f);
  m.emission = glm::vec4(0.0f);
  m.params = glm::vec4(0.6f, 0.0f, 0.0f, 1.5f); // roughness, metallic, transmission, ior
  m.extra = glm::vec4(0.5f, 0.0f, 0.0f, 0.0f);  // specular
  return m;
}

namespace
{
void checkMaterial(const Material& material)
{
  if (!finite(material.baseColorVisibility) || !finite(material.emission) ||
    !finite(material.params) || !finite(material.extra))
    throw std::invalid_argument("material values must be finite");
  const glm::vec4& c = material.baseColorVisibility;
  const glm::vec4& e = material.emission;
  if (c.x < 0 || c.y < 0 || c.z < 0 || e.x < 0 || e.y < 0 || e.z < 0 || material.params.w <= 0)
    throw std::invalid_argument("material colors and emission must be >= 0 and the IOR > 0");
}
} // namespace

void Renderer::setMaterial(uint32_t labelIndex, const Material& material)
{
  if (labelIndex >= this->Materials.size())
    throw std::invalid_argument("label index " + std::to_string(labelIndex) +
      " is outside the volume's label table (" + std::to_string(this->Materials.size()) +
      " labels)");
  checkMaterial(material);
  Material& current = this->Materials[labelIndex];
  if (std::memcmp(&current, &material, sizeof(Material)) == 0)
    return;
  const bool visibilityChanged = visible(current) != visible(material);
  current = material;
  this->MaterialsDirty = true;
  if (visibilityChanged)
    this->applyVisibility();
}

void Renderer::setMaterials(const std::vector<Material>& materials)
{
  if (materials.size() != this->Materials.size())
    throw std::invalid_argument("setMaterials got " + std::to_string(materials.size()) +
      " materials for a label table of " + std::to_string(this->Materials.size()));
  for (const Material& m : materials)
    checkMaterial(m);
  if (std::memcmp(materials.data(), this->Materials.data(), materials.size() * sizeof(Material)) == 0)
    return;
  bool visibilityChanged = false;
  for (size_t i = 0; i < materials.size(); ++i)
    visibilityChanged = visibilityChanged || visible(materials[i]) != visible(this->Materials[i]);
  this->Materials = materials;
  this->MaterialsDirty = true;
  if (visibilityChanged)
    this->applyVisibility();
}

const Material& Renderer::material(uint32_t labelIndex) const
{
  if (labelIndex >= this->Materials.size())
    throw std::invalid_argument("label index " + std::to_string(labelIndex) +
      " is outside the volume's label table");
  return this->Materials[labelIndex];
}

ShaderFeatures Renderer::shaderFeatures() const
{
  ShaderFeatures f;
  const SunLight& sun = this->Settings.sun;
  f.nextEventEstimation = this->Settings.nextEventEstimation;
  f.environmentMap = !this->Settings.environmentMap.empty();
  f.sun = sun.on && (sun.irradiance[0] > 0 || sun.irradiance[1] > 0 || sun.irradiance[2] > 0);
  f.emission = false;
  f.transmission = false;
  f.smoothShading = this->Settings.shading == Shading::Smooth;
  f.clipping = !this->Settings.clipPlanes.empty() || this->Settings.crop.on;
  f.stepStatistics = this->StepStatisticsOn;
  for (const Material& m : this->Materials)
  {
    if (!visible(m))
      continue;
    f.emission = f.emission || emissive(m);
    f.transmission = f.transmission || transmissive(m);
  }
  return f;
}

double Renderer::pipelineCompileSeconds() const
{
  const Gpu& g = *this->Device;
  if (!g.scene)
    return 0;
  const auto& pipeline = g.pipelines[size_t(g.scene->backend())];
  return pipeline ? pipeline->compileSeconds() : 0.0;
}

uint64_t Renderer::pipelineBuilds() const
{
  uint64_t builds = 0;
  for (const auto& p : this->Device->pipelines)
    builds += p ? p->builds() : 0;
  return builds;
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

const Image& Renderer::render(PassUse use)
{
  Gpu& g = *this->Device;
  g.denoisePending = false;
  if (!g.scene)
    throw std::runtime_error("render needs a volume first (setVolume)");
  this->applyBackend();
  if (!g.scene->ready())
    throw std::runtime_error("the scene's BVH is not built: its last build failed");
  const RenderSettings& settings = this->Settings;
  // The rays start near the volume (in double precision): from a camera far away, a float
  // direction's rounding would move them by more than a voxel (see advanceRays). Depths and ray
  // limits stay relative to the rays as given: the advance is added back, per pixel, in double.
  const ViewRays given = this->viewRays();
  const Volume& volume = g.scene->volume();
  const auto bounds = worldBounds(volume.geometry);
  // The scene's reference point is the center of these bounds (Scene.h).
  const auto& reference = g.scene->worldReference();
  double radius = 0;
  for (int a = 0; a < 3; ++a)
  {
    const double half = (bounds[2 * a + 1] - bounds[2 * a]) / 2;
    radius += half * half;
  }
  const double advance = approachParameter(given, reference, std::sqrt(radius));
  const ViewRays rays = advance > 0 ? advanceRays(given, advance) : given;
  // Per pixel center of a width x height image, how much closer the traced rays start (world
  // units).
  auto advancedIn = [&](uint32_t width, uint32_t height, uint32_t x, uint32_t y) {
    return advance > 0 ? advance * spanLength(given, 2 * (x + 0.5) / width - 1,
                                      2 * (y + 0.5) / height - 1)
                       : 0.0;
  };
  auto advanced = [&](uint32_t x, uint32_t y) { return advancedIn(this->Width, this->Height, x, y); };
  // A reduced frame (setTraceReduction) traces its paths at 1/r of the width and height and its
  // full-resolution guides with a primary-only trace (UpsampleLayout.h).
  const uint32_t r = this->TraceReduction;
  const uint32_t tracedWidth = (this->Width + r - 1) / r, tracedHeight = (this->Height + r - 1) / r;
  const uint32_t pixels = this->Width * this->Height;
  const bool depthLimits = this->DepthLimitsOn;
  if (!this->RayLimits.empty() && this->RayLimits.size() != pixels)
    throw std::invalid_argument("the ray limits hold " + std::to_string(this->RayLimits.size()) +
      " values for an image of " + std::to_string(pixels) + " pixels");
  g.full.resize(g.context, pixels, this->ShareColor);
  if (r > 1)
    g.reduced.resize(g.context, tracedWidth * tracedHeight, false);
  TraceImages& traced = r > 1 ? g.reduced : g.full;

  const FieldWidths& w = volume.widths;
  const auto cells = volume.geometry.cellCounts();
  const auto& s = volume.geometry.spacing;
  const PixelFootprint footprint = pixelFootprint(rays, this->Height);
  gpu::FrameUniforms u{};
  // Relative to the scene's reference point, in double before rounding to float (Scene.h).
  u.rayOrigin = vec({ { rays.origin[0] - reference[0], rays.origin[1] - reference[1],
    rays.origin[2] - reference[2] } });
  u.rayOrigin.w = rays.bounded ? 1.0f : 0.0f;
  u.rayOriginU = vec(rays.originU);
  u.rayOriginV = vec(rays.originV);
  u.rayDirection = vec(rays.direction);
  u.rayDirectionU = vec(rays.directionU);
  u.rayDirectionV = vec(rays.directionV);
  if (!finite(u.rayOrigin) || !finite(u.rayDirection) || !finite(u.rayOriginU) ||
    !finite(u.rayOriginV) || !finite(u.rayDirectionU) || !finite(u.rayDirectionV))
    throw std::invalid_argument("the camera's rays are not finite in float precision");
  const auto& bg = settings.background;
  u.background = glm::vec4(bg[0], bg[1], bg[2], bg[3]);
  u.display = glm::vec4(settings.exposure, 0.0f, 0.0f, 0.0f);
  u.autoLod = glm::vec4(float(std::min({ s[0], s[1], s[2] })), settings.autoLodPixels,
    float(footprint.footprint0), float(footprint.footprintSlope));
  u.grid = glm::uvec4(uint32_t(cells[0]), uint32_t(cells[1]), g.scene->primitivesPerBlas(),
    g.scene->blockChunkShift());
  u.widths = glm::uvec4(w.cellBits, w.labelBits, w.rootRefBits, w.midRefBits);
  if (settings.shading == Shading::Smooth && !g.hasNeighbours)
  {
    g.neighbours = storageBuffer(g.context, neighbourTable(volume));
    g.hasNeighbours = true;
  }
  const VkDeviceAddress neighbours =
    settings.shading == Shading::Smooth ? g.neighbours.address() : VkDeviceAddress(0);
  u.widths2 = glm::uvec4(w.leafRefBits, w.blockBits(), uint32_t(neighbours),
    uint32_t(neighbours >> 32));
  u.volumeStreams = addresses(g.scene->blocksAddress(), g.scene->rootsAddress());
  u.volumeStreams2 = addresses(g.scene->midsAddress(), g.scene->leavesAddress());
  const auto toIndex = g.scene->worldToIndex();
  u.worldToIndexX = glm::vec4(float(toIndex[0]), float(toIndex[1]), float(toIndex[2]), float(toIndex[3]));
  u.worldToIndexY = glm::vec4(float(toIndex[4]), float(toIndex[5]), float(toIndex[6]), float(toIndex[7]));
  u.worldToIndexZ =
    glm::vec4(float(toIndex[8]), float(toIndex[9]), float(toIndex[10]), float(toIndex[11]));
  const Backend backend = g.scene->backend();
  if (backend == Backend::Compute)
    u.cellGrid = addresses(g.scene->cellStartsAddress(), g.scene->hiddenBitsAddress());
  const auto& dims = volume.geometry.dims;
  u.volumeDims = glm::uvec4(uint32_t(dims[0]), uint32_t(dims[1]), uint32_t(dims[2]), uint32_t(cells[2]));

  // Lighting (PathTracerParams). The sun direction is normalised in double.
  if (this->EnvironmentDirty)
    this->setEnvironmentMap(settings.environmentMap);
  const ShaderFeatures features = this->shaderFeatures();
  // The preview while the path tracer's pipeline compiles in the background.
  ShaderFeatures traceFeatures = features;
  const bool preview = this->PreviewWhileCompiling &&
    !g.context.shared().pipelines(backend).compiledProgram(features);
  if (preview)
  {
    traceFeatures = ShaderFeatures();
    traceFeatures.nextEventEstimation = false;
    traceFeatures.preview = true;
    traceFeatures.clipping = features.clipping; // what is cut away stays away
  }
  const SunLight& sun = settings.sun;
  const auto& sd = sun.direction;
  const double sunLength = std::sqrt(sd[0] * sd[0] + sd[1] * sd[1] + sd[2] * sd[2]);
  u.sunDirection = glm::vec4(float(sd[0] / sunLength), float(sd[1] / sunLength),
    float(sd[2] / sunLength),
    float(std::cos(sun.angularRadiusDegrees * 3.14159265358979323846 / 180)));
  u.sunRadiance = glm::vec4(
    sun.irradiance[0], sun.irradiance[1], sun.irradiance[2], features.sun ? 1.0f : 0.0f);
  // Ray epsilon: a thousandth of the smallest voxel side, but never below the float rounding of
  // positions (relative to the reference point: ray origin distance plus the volume's extent).
  double extent = 0, originDistance = 0;
  for (int a = 0; a < 3; ++a)
  {
    extent = std::max(extent, bounds[2 * a + 1] - bounds[2 * a]);
    originDistance = std::max(originDistance, std::abs(rays.origin[a] - reference[a]));
  }
  const double epsilon =
    std::max(1e-3 * std::min({ s[0], s[1], s[2] }), 4e-6 * (extent + originDistance));
  // Clipping: the margin (Clipping.h) is a quarter of the ray epsilon, so that secondary rays
  // leaving a cut face start outside the kept region.
  u.clipping =
    glm::uvec4(gpuClipPlanes(settings, reference, 0.25 * epsilon, u.clipPlanes), 0u, 0u, 0u);
  const auto& env = settings.environmentColor;
  u.environment = glm::vec4(env[0], env[1], env[2], float(epsilon));
  u.lighting = glm::uvec4(g.envSize.x, g.envSize.y, settings.maximumBounces,
    settings.nextEventEstimation ? 1u : 0u /* FLAG_NEE */);
  u.environmentMap = addresses(g.envMarginal.address(), g.envConditional.address());
  u.environmentMap2 = addresses(g.envTexels.address(), 0);
  u.sampling =
    glm::uvec4(0u, settings.samplesPerPixel, settings.seed, uint32_t(this->Materials.size()));

  if (this->MaterialsDirty)
  {
    // The GPU is idle between frames (every frame waits), so the host may write in place.
    std::memcpy(g.materials.mapped(), this->Materials.data(), this->Materials.size() * sizeof(Material));
    this->MaterialsDirty = false;
    ++this->MaterialGeneration;
  }
  // The fields of one traced size: its outputs, sums and ray limits. The host's limits (one per
  // image pixel) are uploaded for it; a reduced pixel takes the limit of the image pixel under
  // its center.
  auto sized = [&](gpu::FrameUniforms f, TraceImages& set, uint32_t width, uint32_t height) {
    // A preview walks block boxes (on the compute backend its pipeline knows no other LOD).
    const Lod lod = preview ? Lod::Block : settings.lod;
    f.image = glm::uvec4(width, height, uint32_t(lod), uint32_t(settings.shading));
    f.sceneOutputs = addresses(g.scene->primitiveBlocksAddress(), set.label.address());
    f.outputs = addresses(set.depth.address(), set.normal.address());
    f.outputs2 = addresses(set.hdr.address(), set.color.address());
    f.rayLimits = addresses(this->RayLimits.empty() && !depthLimits ? 0 : set.rayLimits.address(), 0);
    f.statistics = addresses(set.squares.address(), set.variance.address());
    f.materials = addresses(g.materials.address(), set.accumulation.address());
    if (!this->RayLimits.empty())
    {
      float* limits = static_cast<float*>(set.rayLimits.mapped());
      const uint32_t step = width == this->Width ? 1 : r;
      for (uint32_t y = 0; y < height; ++y)
      {
        for (uint32_t x = 0; x < width; ++x)
        {
          const uint32_t ix = std::min(this->Width - 1, x * step + step / 2);
          const uint32_t iy = std::min(this->Height - 1, y * step + step / 2);
          const double limit = this->RayLimits[ix + size_t(this->Width) * iy];
          limits[x + size_t(width) * y] =
            float(std::max(0.0, limit - advancedIn(width, height, x, y)));
        }
      }
    }
    return f;
  };
  // Limits from a shared scene depth: the depth pass writes them, before a trace, in the same
  // submission.
  DepthPass* limitsPass = depthLimits ? &g.depthPassOf() : nullptr;
  auto limitsFor = [&](TraceImages& set, uint32_t width, uint32_t height) {
    gpu::DepthParams limitsParams{};
    const DepthRayLimits& d = this->DepthLimits;
    if (!g.sceneDepth[d.slot] || uint64_t(d.viewportWidth) * d.viewportHeight != g.sceneDepthPixels[d.slot])
      throw std::invalid_argument("the scene depth of the ray limits was reallocated");
    limitsParams = depthParams(SVDAG_DEPTH_PASS_LIMITS, d.clipToModel, given, given, advance);
    limitsParams.sizes = glm::uvec4(d.viewportWidth, d.viewportHeight, width, height);
    limitsParams.depth = addresses(g.sceneDepth[d.slot]->address(), set.rayLimits.address());
    return limitsParams;
  };
  Pipeline& pipeline = g.pipeline(backend, traceFeatures);
  this->Previewed = false;

  // A reduced frame's guides: the pixel-center hits of the full image (no bounce, no light),
  // traced again only when they change.
  g.guideMilliseconds = 0;
  if (r > 1)
  {
    gpu::FrameUniforms guide = sized(u, g.full, this->Width, this->Height);
    guide.lighting.z = 0;
    guide.lighting.w = 0;
    guide.sunRadiance.w = 0.0f;
    guide.sampling = glm::uvec4(0u, 1u, settings.seed, guide.sampling.w);
    guide.display = glm::vec4(0.0f);
    // A visibility change is a scene change (the hidden labels' blocks go); the preview's
    // guides (block boxes) are not the path tracer's.
    const uint64_t guideGenerations[2] = { this->SceneGeneration, preview ? 1u : 0u };
    std::vector<unsigned char> guideState(sizeof(guide) + sizeof(guideGenerations));
    std::memcpy(guideState.data(), &guide, sizeof(guide));
    std::memcpy(guideState.data() + sizeof(guide), guideGenerations, sizeof(guideGenerations));
    if (guideState != g.guideState)
    {
      g.guideState.clear();
      std::memcpy(g.uniforms.mapped(), &guide, sizeof(guide));
      pipeline.updateDescriptors(g.uniforms.handle(), g.scene->tlas());
      const gpu::DepthParams guideLimits =
        depthLimits ? limitsFor(g.full, this->Width, this->Height) : gpu::DepthParams{};
      const auto guideStart = Clock::now();
      g.context.submitAndWait([&](VkCommandBuffer cmd) {
        if (limitsPass)
          limitsPass->record(cmd, guideLimits);
        pipeline.record(cmd, this->Width, this->Height);
      });
      g.guideMilliseconds =
        std::chrono::duration<double, std::milli>(Clock::now() - guideStart).count();
      g.guideState = std::move(guideState);
    }
  }
  else
    g.guideState.clear();
  u = sized(u, traced, tracedWidth, tracedHeight);
  // The step counters (compute backend only), of this trace (not the guides': their address
  // stays 0, which the shader does not write).
  const bool countSteps = traceFeatures.stepStatistics && backend == Backend::Compute;
  if (countSteps)
  {
    const uint64_t bytes =
      uint64_t(tracedWidth) * tracedHeight * svdag::traversal::SVDAG_STAT_COUNT * sizeof(uint32_t);
    if (g.stepCounts.size() != bytes)
      g.stepCounts = Buffer(g.context, bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::Readback);
    u.stepStatistics = addresses(g.stepCounts.address(), 0);
  }
  const gpu::DepthParams limitsParams =
    depthLimits ? limitsFor(traced, tracedWidth, tracedHeight) : gpu::DepthParams{};

  // Everything that changes the image, besides the per-pass fields (samples, exposure): a
  // difference from the last pass starts a new accumulation.
  gpu::FrameUniforms key = u;
  key.sampling.y = 0;
  key.display = glm::vec4(0.0f);
  // A preview pass (which differs in its pipeline only) never accumulates with another pass.
  const uint64_t generations[4] = { this->SceneGeneration, this->MaterialGeneration,
    this->EnvironmentGeneration, preview ? ++this->PreviewGeneration : 0 };
  std::vector<unsigned char> state(sizeof(key) + sizeof(generations));
  std::memcpy(state.data(), &key, sizeof(key));
  std::memcpy(state.data() + sizeof(key), generations, sizeof(generations));
  if (!this->AccumulationValid || state != this->AccumulatedState ||
    uint64_t(this->Accumulated) + settings.samplesPerPixel > UINT32_MAX)
  {
    this->Accumulated = 0;
    this->RenderSeconds = 0;
    this->AccumulatedState = std::move(state);
  }
  this->AccumulationValid = false; // valid again only once this pass succeeded
  u.sampling.x = this->Accumulated;
  std::memcpy(g.uniforms.mapped(), &u, sizeof(u));
  pipeline.updateDescriptors(g.uniforms.handle(), g.scene->tlas());

  if (settings.denoise && !g.denoiser)
    g.denoiser = std::make_unique<DenoisePass>(g.context);
  gpu::DenoiseParams denoise{};
  DenoisePass::Frame denoised;
  const bool denoiseNow = settings.denoise && use == PassUse::Shown;
  if (settings.denoise)
  {
    denoise.rayOrigin = u.rayOrigin;
    denoise.rayOriginU = u.rayOriginU;
    denoise.rayOriginV = u.rayOriginV;
    denoise.rayDirection = u.rayDirection;
    denoise.rayDirectionU = u.rayDirectionU;
    denoise.rayDirectionV = u.rayDirectionV;
    // Luminance against 4 standard deviations (SVGF's), a tangent plane distance of one voxel
    // side (a voxel staircase's step is one).
    denoise.weights = glm::vec4(4.0f, 0.0f, u.autoLod.x, settings.exposure);
    denoised.width = tracedWidth;
    denoised.height = tracedHeight;
    denoised.samples = this->Accumulated + settings.samplesPerPixel;
    denoised.label = traced.label.address();
    denoised.depth = traced.depth.address();
    denoised.normal = traced.normal.address();
    denoised.variance = traced.variance.address();
    denoised.hdr = traced.hdr.address();
    denoised.color = traced.color.address();
  }
  // A new accumulation's edges get their coverage traced once, for every later pass; not in a
  // reduced trace, whose edges the upsampler places from the full-resolution guides (and whose
  // frames keep to a time budget), nor in a preview, which stands in while the path tracer
  // compiles.
  const bool traceCoverage = settings.denoise && u.sampling.x == 0 && r == 1 && !preview;
  if (u.sampling.x == 0)
    traced.coverageCurrent = traceCoverage;
  if (settings.denoise && traced.coverageCurrent)
    denoised.coverage = traced.coverageRecords(g.context);
  if (r > 1 && !g.upsampler)
    g.upsampler = std::make_unique<UpsamplePass>(g.context);
  gpu::UpsampleParams upsample{};
  if (r > 1)
  {
    upsample.sizes = glm::uvec4(this->Width, this->Height, tracedWidth, tracedHeight);
    upsample.background = u.background;
    upsample.weights =
      glm::vec4(float(r), float(r) * u.autoLod.x, settings.exposure, 0.0f);
    upsample.guides = addresses(g.full.label.address(), g.full.depth.address());
    upsample.reducedGuides = addresses(g.reduced.label.address(), g.reduced.depth.address());
    upsample.reducedColors = addresses(g.reduced.hdr.address(), g.reduced.variance.address());
    upsample.hdr = addresses(g.full.hdr.address(), g.full.color.address());
    upsample.variance = addresses(g.full.variance.address(), 0);
  }

  const auto start = Clock::now();
  auto recordAfterTrace = [&](VkCommandBuffer cmd) {
    if (denoiseNow)
      g.denoiser->record(cmd, denoised, denoise);
    if (r > 1)
      g.upsampler->record(cmd, upsample);
  };
  g.context.submitAndWait([&](VkCommandBuffer cmd) {
    if (limitsPass)
      limitsPass->record(cmd, limitsParams);
    pipeline.record(cmd, tracedWidth, tracedHeight);
    if (!traceCoverage)
      recordAfterTrace(cmd);
  });
  if (traceCoverage)
  {
    // The same pipeline again, in its coverage mode: the uniform block differs, so it is a
    // submission of its own (submitAndWait's opening barrier makes the labels and faces it reads
    // visible). Its rays are not the frame's: the step counters stay the trace's.
    gpu::FrameUniforms c = u;
    c.coverage = glm::uvec4(uint32_t(denoised.coverage), uint32_t(denoised.coverage >> 32), 1u, 0u);
    c.stepStatistics = glm::uvec4(0u);
    std::memcpy(g.uniforms.mapped(), &c, sizeof(c));
    g.context.submitAndWait([&](VkCommandBuffer cmd) {
      pipeline.record(cmd, tracedWidth, tracedHeight);
      recordAfterTrace(cmd);
    });
  }
  g.tracedRays = given;
  g.tracedAdvance = advance;
  this->FrameMilliseconds =
    std::chrono::duration<double, std::milli>(Clock::now() - start).count() + g.guideMilliseconds;
  this->RenderSeconds += this->FrameMilliseconds / 1000;
  this->Accumulated += settings.samplesPerPixel;
  this->AccumulationValid = true;
  this->Previewed = preview;
  if (settings.denoise && !denoiseNow)
  {
    g.denoisePending = true;
    g.pendingFrame = denoised;
    g.pendingParams = denoise;
    g.pendingUpsample = r > 1;
    g.upsampleParams = upsample;
  }

  const auto readStart = Clock::now();
  Image& out = this->Output;
  out.width = this->Width;
  out.height = this->Height;
  auto read = [](auto& vector, const Buffer& buffer, size_t count) {
    vector.resize(count);
    std::memcpy(vector.data(), buffer.mapped(), count * sizeof(vector[0]));
  };
  read(out.label, g.full.label, pixels);
  read(out.depth, g.full.depth, pixels);
  if (advance > 0)
  {
    for (uint32_t y = 0; y < this->Height; ++y)
    {
      for (uint32_t x = 0; x < this->Width; ++x)
      {
        const size_t i = x + size_t(this->Width) * y;
        if (out.label[i] != 0)
          out.depth[i] = float(double(out.depth[i]) + advanced(x, y));
      }
    }
  }
  read(out.normal, g.full.normal, size_t(pixels) * 3);
  out.faceNormal.resize(size_t(pixels) * 3);
  std::memcpy(out.faceNormal.data(), static_cast<const float*>(g.full.normal.mapped()) + size_t(pixels) * 3,
    size_t(pixels) * 3 * sizeof(float));
  this->readColor();
  read(out.variance, g.full.variance, pixels);
  if (countSteps)
    read(this->StepCounts, g.stepCounts,
      size_t(tracedWidth) * tracedHeight * svdag::traversal::SVDAG_STAT_COUNT);
  else
    this->StepCounts.clear();
  double sum = 0;
  for (float v : out.variance)
    sum += v;
  this->ErrorEstimate = std::sqrt(sum / pixels);
  this->ReadbackMilliseconds =
    std::chrono::duration<double, std::milli>(Clock::now() - readStart).count();
  return out;
}

void Renderer::readColor()
{
  const Gpu& g = *this->Device;
  Image& out = this->Output;
  const size_t pixels = size_t(out.width) * out.height;
  if (g.full.hdrShared)
    out.hdr.clear();
  else
  {
    out.hdr.resize(pixels * 4);
    std::memcpy(out.hdr.data(), g.full.hdr.mapped(), pixels * 4 * sizeof(float));
  }
  out.color.resize(pixels);
  std::memcpy(out.color.data(), g.full.color.mapped(), pixels * sizeof(uint32_t));
}

double Renderer::finishImage()
{
  Gpu& g = *this->Device;
  if (!g.denoisePending)
    return 0;
  g.denoisePending = false;
  const auto start = Clock::now();
  g.context.submitAndWait([&](VkCommandBuffer cmd) {
    g.denoiser->record(cmd, g.pendingFrame, g.pendingParams);
    if (g.pendingUpsample)
      g.upsampler->record(cmd, g.upsampleParams);
  });
  const double filtered = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  this->FrameMilliseconds += filtered;
  this->RenderSeconds += filtered / 1000;
  const auto readStart = Clock::now();
  this->readColor();
  this->ReadbackMilliseconds +=
    std::chrono::duration<double, std::milli>(Clock::now() - readStart).count();
  return filtered;
}

} // namespace render
} // namespace svdag
