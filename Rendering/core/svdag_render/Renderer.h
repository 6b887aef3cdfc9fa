// The path-tracing renderer of a volume's blocks: per pixel, label, depth and normal of the
// pixel-center ray, and the progressive path-traced color (GpuLayout.h documents the outputs,
// the pixel-center convention, sampling and tone mapping; PathTracer.h the integrator).
//
//   svdag::render::Renderer r;                  // throws when no Vulkan device qualifies
//   r.setVolume(volume);                        // uploads the streams, builds the BVH or grid
//   r.setCamera(svdag::render::frameVolume(volume->geometry, 30, 20));
//   r.setImageSize(640, 480);
//   const svdag::render::Image& image = r.render(); // adds samplesPerPixel samples per pixel
//
// Progressive accumulation: every render() adds samplesPerPixel samples to the running mean
// while nothing that changes the image changed since the last one (camera, image size, LOD,
// materials, visibility, lighting, bounces, NEE, seed, background, clipping, volume); any such change
// starts a new accumulation. Exposure and samplesPerPixel do not restart it.
//
// Backends (RenderSettings::backend): the ray tracing pipeline over a BVH of block boxes, or a
// compute shader walking the cell grid (GridTraversal.h); the same path tracer, materials, outputs
// and features. Auto resolves per device (backendFor).
//
// Materials are per label index (defaultMaterial: base color svdagLabelColor, roughness 0.6,
// metallic 0, transmission 0, ior 1.5, specular 0.5, visible); an edit is a buffer upload.
// Visibility 0 hides the label like setHiddenLabels: its blocks leave the BVH (rt) or their
// label's hidden bit is set (compute).
//
// Known limitation: transmission is thin-walled: a transmitted ray continues straight through
// the solid it entered (the entry-only hit group skips the run it starts in, per block), so
// where a label continues into the next 16^3 cell it meets one more surface event at the face.
#pragma once

#include "svdag_render/Buffer.h"
#include "svdag_render/Camera.h"
#include "svdag_render/Pipeline.h"
#include "svdag_render/Material.h"
#include "svdag_render/RenderSettings.h"
#include "svdag_render/Scene.h"

#include <svdag/Volume.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace svdag
{
namespace render
{

class Context;
class Scene;
using shading::Material;

// Bytes of device memory the renderer holds, by part.
struct DeviceBytes
{
  uint64_t encoding = 0;     // the volume's streams: blocks (and their chunk table), roots, mids, leaves
  uint64_t acceleration = 0; // BLAS, TLAS, instances, primitive -> block map (ray tracing), or the
                             // cell grid and hidden label bits (compute)
  uint64_t materials = 0;    // per-label materials and the environment's tables
  uint64_t neighbours = 0;   // smooth shading's neighbour table (0 until smooth shading needs it)
  uint64_t images = 0;       // outputs, accumulation sums and per-pixel ray limits
  uint64_t other = 0;        // uniforms, the shader binding table, allocation rounding
  uint64_t total = 0;        // all of it (Renderer::deviceBytes)
};

// Host copies of the outputs, pixel (x, y) at index x + width * y, y = 0 the bottom row.
struct Image
{
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint32_t> label; // label index + 1, 0 = background
  std::vector<float> depth;    // world distance along the ray; SVDAG_DEPTH_MISS (FLT_MAX) on a miss
  std::vector<float> normal;   // 3 per pixel, world unit shading normal (the entry face's, or the
                               // smooth estimate with Shading::Smooth); 0 on a miss or inside
  std::vector<float> faceNormal; // 3 per pixel, world unit normal of the entry face; 0 likewise
  std::vector<float> hdr;      // 4 per pixel, linear RGBA: the mean of the accumulated samples
                               // (empty while the color is shared: Renderer::setColorSharing)
  std::vector<uint32_t> color; // RGBA8, tone-mapped sRGB, R in the lowest byte
  // Per pixel, the variance of the accumulated mean's luminance (the sample variance over the
  // accumulated samples divided by their count; 0 before two samples).
  std::vector<float> variance;
};

class Renderer
{
public:
  // Takes the process's Vulkan device (Context.h's Device: one per process, created by the first
  // renderer, released with the last; its pipelines are shared, everything else here is this
  // renderer's own). Throws std::runtime_error (no usable device: the message names every device
  // found and what it lacks), for each renderer that tries.
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  const std::string& deviceName() const;
  bool hasRayTracing() const;
  // Renderers (and other Context holders) sharing the process's device now; 0 when none exists.
  static size_t deviceUsers();
  // Which device this renderer uses: 1 for the process's first, 2 for the one created after the
  // first was released...
  uint64_t deviceSerial() const;
  // Device memory every user of the device holds, and the part the device holds for all of them
  // (the shared pipelines' shader binding tables; not in any renderer's deviceBytes()).
  uint64_t deviceAllocatedBytes() const;
  uint64_t sharedDeviceBytes() const;
  // Pipelines the device compiled so far, for every renderer (pipelineBuilds() counts this
  // renderer's feature sets, compiled by it or before it).
  uint64_t pipelineCompilations() const;
  // The device's persistent pipeline cache (PipelineCacheFile.h): its file ("" when disabled),
  // the bytes of driver data it started from (0: none, or none to trust) and why a file was not
  // used or written ("" when all went well). Where compute shaders are shader objects
  // (ComputeProgram.h), how many the device created from binaries on disk and how many it
  // compiled, and why a binary file was not used or written.
  struct PipelineCacheStatus
  {
    std::string file;
    uint64_t loadedBytes = 0;
    std::string problem;
    bool shaderObjects = false;
    uint64_t shaderBinariesLoaded = 0;
    uint64_t shadersCompiled = 0;
    std::string shaderBinaryProblem;
  };
  PipelineCacheStatus pipelineCache() const;

  // The backend (RenderSettings::backend; also part of setSettings). A change rebuilds what the
  // backends find blocks with (setupSeconds measures it) and restarts the accumulation. Throws
  // std::runtime_error for RayTracing on a device without ray tracing (the previous one stays).
  void setBackend(Backend backend);
  // What a setting resolves to on this device. Auto: Compute on a device without ray tracing and
  // on a CPU implementation (lavapipe: measured 1.65-5.6x faster, bench/README.md), RayTracing on a
  // GPU with ray tracing (the paper's hardware path; measure with bench/gpu.sh). Throws like
  // setBackend.
  Backend backendFor(Backend requested) const;
  // The backend in use: backendFor(settings().backend).
  Backend backend() const { return this->backendFor(this->Settings.backend); }

  // Uploads a volume and builds its BVH or cell grid (keeps the hidden labels). Throws
  // std::runtime_error.
  void setVolume(std::shared_ptr<const Volume> volume);
  // Label indices not drawn: left out of the BVH, which is rebuilt when the set changes (rt), or
  // hidden bits (compute; no rebuild). Either restarts the accumulation (setupSeconds then
  // measures the rebuild).
  void setHiddenLabels(const std::vector<uint32_t>& labelIndices);
  // Caps the blocks (primitives) per BLAS (0: the driver's limit); see
  // Scene::setPrimitivesPerBlasLimit.
  void setMaximumBlocksPerBlas(uint32_t limit);
  size_t blasCount() const;
  // Chunks of the block stream of the next setVolume, as log2 of their words (Scene.h; default
  // and maximum Scene::MaxBlockChunkShift). Smaller chunks exist to exercise the chunked path
  // on small volumes (tests).
  void setBlockChunkShift(uint32_t shift);
  // Bytes of device memory the renderer holds now (streams, BVH or grid, materials, images),
  // without what it shares with other renderers (sharedDeviceBytes()). deviceMemoryLimit caps
  // these bytes: the limit is per renderer.
  uint64_t deviceBytes() const;
  DeviceBytes deviceBytesByPart() const;
  size_t blockChunkCount() const;
  // The primary rays: a pinhole camera (its rays follow the image's aspect), or explicit rays
  // (ViewRays, for example from a VTK camera's projection); the last call wins.
  void setCamera(const Camera& camera);
  const Camera& camera() const { return this->View; }
  void setViewRays(const ViewRays& rays);
  // The rays of the next render() for the current image size.
  ViewRays viewRays() const;
  // Per pixel (x + width * y), the farthest distance along the unit ray direction a camera ray
  // may hit (an opaque surface drawn before the volume); empty: no limit. The size must be the
  // image's pixel count at render(). The values are uploaded on each render(); a change of their
  // content does not restart the accumulation (call resetAccumulation()). Replaces the limits of
  // setRayLimitsFromDepth.
  void setRayLimits(std::vector<float> limits);

  // ---- scene depth in shared memory (the volume mapper's OpenGL depth path) ----
  // Whether it can be used: the device exports memory (canShareColor()) and computes in double
  // precision (shaderFloat64: the depth pass, DepthLayout.h, gives the bits the host would).
  bool canShareDepth() const;
  // Scene depth buffer `slot` (0 or 1: a consumer comparing a frame's depth with the last one's
  // writes each into its own) for `pixels` floats: host-visible memory, exported, reallocated
  // (a new generation) when the count changes. Another API writes a viewport's window depth in
  // [0, 1] into it (rows from the bottom); the host reads it through the returned pointer, which
  // keeps that allocation alive (it stays valid after a reallocation; it must not outlive the
  // renderer). sceneDepthGeneration names the allocation, exportSceneDepth gives a new file
  // descriptor of it (the importer owns it). std::invalid_argument for another slot or 0 pixels.
  std::shared_ptr<const float> sceneDepth(uint32_t slot, uint32_t pixels);
  uint64_t sceneDepthGeneration(uint32_t slot) const;
  ExportedMemory exportSceneDepth(uint32_t slot) const;
  // Ray limits computed by each render() on the device from scene depth `slot`, a viewport of
  // viewportWidth x viewportHeight pixels, along viewRays(): the values the volume mapper's host
  // code computes from the same depth with the same clip-to-model matrix (row-major, clip = M *
  // (x, y, z, 1)). Replaces setRayLimits' limits (setRayLimits replaces these).
  struct DepthRayLimits
  {
    uint32_t slot = 0;
    uint32_t viewportWidth = 0, viewportHeight = 0;
    std::array<double, 16> clipToModel{};
  };
  void setRayLimitsFromDepth(const DepthRayLimits& limits);
  // After a render(): per pixel of the viewport (scene depth `slot`, the size of the last
  // setRayLimitsFromDepth's or of any viewport), the nearer of its window depth and the window
  // depth (0.5 z_clip / w_clip + 0.5 by `modelToClip`) of the traced hit of image() covering it,
  // along `rays`, as the mapper's host code composites them, into exported memory (the importer
  // reads viewportWidth * viewportHeight floats; written when this returns). The allocation is
  // compositedDepthGeneration (a new one when the viewport's pixel count changes);
  // exportCompositedDepth gives a new file descriptor of it. std::logic_error before a render()
  // or where !canShareDepth(). The importer must have finished reading before the next call.
  void compositeDepth(uint32_t slot, uint32_t viewportWidth, uint32_t viewportHeight,
    const std::array<double, 16>& modelToClip, const ViewRays& rays);
  uint64_t compositedDepthGeneration() const;
  ExportedMemory exportCompositedDepth() const;
  // Throws std::invalid_argument for 0 or more pixels than the device dispatches (or 2^28).
  void setImageSize(uint32_t width, uint32_t height);
  // Guided upsampling: above 1, render() traces its paths on ceil(width / r) x ceil(height / r)
  // pixels and shows them at the image's size, guided by the label and depth of every image
  // pixel's own pixel-center ray (a primary-only trace, repeated only when what it sees changes;
  // UpsampleLayout.h). image() keeps the image's size: label, depth and normals are exact per
  // pixel, the color and variance are upsampled. lastFrameMilliseconds includes the guides'
  // trace. The reduced image accumulates like a full one. Default 1; std::invalid_argument
  // outside 1 .. MaximumTraceReduction.
  static constexpr uint32_t DefaultTraceReduction = 1;
  static constexpr uint32_t MaximumTraceReduction = 8;
  void setTraceReduction(uint32_t reduction);
  uint32_t traceReduction() const { return this->TraceReduction; }
  // Every setting at once (validate() first: std::invalid_argument, the previous ones stay).
  // The setters below change one setting each, with the same checks.
  void setSettings(const RenderSettings& settings);
  const RenderSettings& settings() const { return this->Settings; }
  void setLod(Lod lod);
  Lod lod() const { return this->Settings.lod; }
  void setAutoLodPixels(float pixels);
  float autoLodPixels() const { return this->Settings.autoLodPixels; }
  void setBackground(const std::array<float, 4>& linearRGBA);

  // ---- path tracing ----
  // Samples per pixel added by each render(), 1 .. 65536 (std::invalid_argument otherwise).
  void setSamplesPerPixel(uint32_t samples);
  uint32_t samplesPerPixel() const { return this->Settings.samplesPerPixel; }
  // Scattering events per path, 0 (direct view of emission only) .. 64.
  void setMaximumBounces(uint32_t bounces);
  uint32_t maximumBounces() const { return this->Settings.maximumBounces; }
  void setSeed(uint32_t seed) { this->Settings.seed = seed; }
  uint32_t seed() const { return this->Settings.seed; }
  // Next-event estimation with MIS (default) or the plain estimator that finds light only when
  // a path escapes (the paper authors' estimator).
  void setNextEventEstimation(bool on) { this->Settings.nextEventEstimation = on; }
  bool nextEventEstimation() const { return this->Settings.nextEventEstimation; }
  // The label-aware denoiser (RenderSettings::denoise) on the next frames.
  void setDenoise(bool on) { this->Settings.denoise = on; }
  bool denoise() const { return this->Settings.denoise; }
  // Scale of the linear color before the tone curve (> 0, finite).
  void setExposure(float exposure);
  float exposure() const { return this->Settings.exposure; }
  // Constant environment radiance (default 1, 1, 1), or the scale of the environment map.
  void setEnvironmentColor(const std::array<float, 3>& radiance);
  // An equirectangular OpenEXR environment (EnvironmentMap::fromEXR); "" returns to the constant
  // environment. Throws std::runtime_error for an unreadable file (the previous one stays).
  void setEnvironmentMap(const std::string& exrPath);
  const std::string& environmentMap() const { return this->Settings.environmentMap; }
  // Throws std::invalid_argument for a zero or non-finite direction, negative or non-finite
  // irradiance, or an angular radius outside [0, 90) degrees.
  void setSun(const SunLight& sun);
  const SunLight& sun() const { return this->Settings.sun; }

  // Voxel face normals or smooth normals for shading (RenderSettings::shading). Smooth builds
  // and uploads the neighbour table on the next render() (once per volume).
  void setShading(Shading shading);
  Shading shading() const { return this->Settings.shading; }
  // Bytes of the smooth-shading neighbour table on the device (0 until smooth shading needs it).
  uint64_t neighbourTableBytes() const;

  // Clipping planes and crop box (world coordinates, RenderSettings::clipPlanes): every ray is
  // clipped to what they keep; cut faces are drawn where the region cuts a solid. Throws
  // std::invalid_argument like validate() (more than MaximumClipPlanes planes, a zero or
  // non-finite normal, an inverted crop box). A change restarts the accumulation, it does not
  // rebuild the BVH (the planes are uniforms).
  void setClipping(const std::vector<ClipPlane>& planes, const CropBox& crop = CropBox());
  const std::vector<ClipPlane>& clipPlanes() const { return this->Settings.clipPlanes; }
  const CropBox& crop() const { return this->Settings.crop; }

  static Material defaultMaterial(uint32_t labelIndex);
  // The material of a label index (needs a volume; std::invalid_argument for an index outside
  // the label table or non-finite / negative values). Visibility is baseColorVisibility.a (0 or
  // not 0).
  void setMaterial(uint32_t labelIndex, const Material& material);
  const Material& material(uint32_t labelIndex) const;
  // Every label's material at once (one per label index, same checks): the BVH is rebuilt at
  // most once, when the set of visible labels changes.
  void setMaterials(const std::vector<Material>& materials);
  size_t materialCount() const { return this->Materials.size(); }
  // The feature switches the next render() compiles the pipeline with.
  ShaderFeatures shaderFeatures() const;
  // Previews while the pipeline compiles: where the device has not compiled the pipeline of
  // shaderFeatures() yet, render() starts its compilation in the background and traces the pass
  // with the small preview pipeline instead (ShaderFeatures::preview: the camera rays' first
  // hits under a headlight, no path; compiled at once, much faster), so that a window never
  // waits for the full compilation. A preview pass does not accumulate: the first pass after
  // the pipeline is ready starts the accumulation. Default off (every pass is the path tracer's,
  // compiled first if need be).
  void setPreviewWhileCompiling(bool on) { this->PreviewWhileCompiling = on; }
  bool previewWhileCompiling() const { return this->PreviewWhileCompiling; }
  // Whether the last render() traced a preview.
  bool previewed() const { return this->Previewed; }
  // Seconds the device took to compile the pipeline the last render() traced with (0 before
  // one), whichever renderer asked for it first: the compile time of that feature set.
  double pipelineCompileSeconds() const;

  // Step statistics of the compute backend: from the next render() on, a pipeline variant that
  // counts where each pixel's rays spend their steps (Traversal.h's SVDAG_STAT_* counters: grid
  // walks, cells visited, cells with blocks, block records read, DAG walks, DAG walk iterations,
  // occlusion rays, hits), summed over the pass's rays. Off (default): that variant is not used
  // and the counting is compiled out. The ray tracing backend counts nothing.
  void setStepStatistics(bool on) { this->StepStatisticsOn = on; }
  bool stepStatistics() const { return this->StepStatisticsOn; }
  // After a render() with step statistics on the compute backend: SVDAG_STAT_COUNT counters per
  // traced pixel (pixel i's counter c at i * SVDAG_STAT_COUNT + c, pixels in image() order; the
  // traced size is ceil(width / traceReduction()) x ceil(height / traceReduction())); empty
  // otherwise.
  const std::vector<uint32_t>& stepCounts() const { return this->StepCounts; }

  // Starts a new accumulation on the next render().
  void resetAccumulation() { this->AccumulationValid = false; }
  // Samples per pixel in the current image (0 before the first render()).
  uint32_t accumulatedSamples() const { return this->Accumulated; }
  // Seconds of tracing (sum of frame times) that produced the current image.
  double renderSeconds() const { return this->RenderSeconds; }
  // An estimate of the current image's error: the root mean square over pixels of the standard
  // error of each pixel's mean luminance (linear units; 0 before two samples).
  double errorEstimate() const { return this->ErrorEstimate; }
  // BVH builds (setVolume, visibility changes and backend switches on the ray tracing backend)
  // and pipeline builds so far.
  uint64_t bvhBuilds() const { return this->BvhBuilds; }
  uint64_t pipelineBuilds() const;

  // The HDR output in exported device memory instead of a host copy (image().hdr stays empty),
  // for a consumer that imports it (the volume mapper's OpenGL compositor) from the next
  // render() on. Throws std::runtime_error where the device cannot export memory
  // (canShareColor()).
  void setColorSharing(bool on);
  bool colorSharing() const { return this->ShareColor; }
  bool canShareColor() const;
  const DeviceUuids& deviceUuids() const;
  // After a render() with sharing on: which allocation holds the color (4 floats per pixel,
  // linear premultiplied RGBA in Image's pixel order; a new generation after each reallocation,
  // which a new image size makes), and a new file descriptor of its memory for the importer to
  // own. std::logic_error otherwise. The memory is written by render() only, which returns when
  // the writes are complete; the importer must have finished reading before it calls render()
  // again (there are no shared semaphores here).
  uint64_t sharedColorGeneration() const;
  ExportedMemory exportColor() const;

  // How the image of a pass is used. Shown: it is looked at (read, drawn, written) after the
  // pass, so the denoiser (settings().denoise) filters it. Accumulating: another pass follows
  // before anyone looks, so the denoiser is left out (hdr and color are the raw mean; the
  // accumulation is the same either way) and finishImage() filters the pass if it turns out to
  // be the last.
  enum class PassUse
  {
    Shown,
    Accumulating
  };
  // Traces one pass (samplesPerPixel samples per pixel, added to the accumulation) and reads
  // the outputs back. Throws std::runtime_error (no volume, Vulkan failure) or
  // std::invalid_argument (degenerate camera).
  const Image& render(PassUse use = PassUse::Shown);
  // After a pass traced as Accumulating with the denoiser on: filters its image and reads hdr
  // and color into image() again, as a Shown pass would have; returns the filter's
  // milliseconds, which lastFrameMilliseconds and renderSeconds then include. Otherwise does
  // nothing and returns 0. Throws std::runtime_error on a Vulkan failure.
  double finishImage();
  const Image& image() const { return this->Output; }

  // Upload + BVH or grid build of the last setVolume, or rebuild of the last setHiddenLabels that
  // changed the set, seconds.
  double setupSeconds() const { return this->SetupSeconds; }
  // Wall time of the last frame (record, trace, wait), milliseconds, and of copying its outputs
  // to the host after it.
  double lastFrameMilliseconds() const { return this->FrameMilliseconds; }
  double lastReadbackMilliseconds() const { return this->ReadbackMilliseconds; }
  uint64_t blasBytes() const;
  uint64_t tlasBytes() const;
  uint64_t visibleBlocks() const;

private:
  void applyVisibility();
  void readColor(); // hdr (unless shared) and color into Output
  void timeSetup(bool rebuilt, double seconds);
  void applyBackend();

  struct Gpu;
  std::unique_ptr<Gpu> Device;
  RenderSettings Settings;
  Camera View;
  ViewRays Rays;
  bool RaysFromCamera = true;
  std::vector<float> RayLimits;
  bool DepthLimitsOn = false;
  DepthRayLimits DepthLimits;
  uint32_t Width = 256;
  uint32_t Height = 256;
  uint32_t TraceReduction = DefaultTraceReduction;
  bool PreviewWhileCompiling = false;
  bool Previewed = false;
  Image Output;
  double SetupSeconds = 0;
  double FrameMilliseconds = 0;
  double ReadbackMilliseconds = 0;
  double ErrorEstimate = 0;
  bool ShareColor = false;
  bool StepStatisticsOn = false;
  std::vector<uint32_t> StepCounts;

  std::vector<uint32_t> ExplicitHidden;
  uint32_t BlockChunkShift = Scene::MaxBlockChunkShift;
  std::vector<Material> Materials;
  bool MaterialsDirty = true;
  bool EnvironmentDirty = true;

  // Accumulation state: what the last pass rendered (render() compares) and its sample count.
  bool AccumulationValid = false;
  std::vector<unsigned char> AccumulatedState;
  uint64_t SceneGeneration = 0;
  uint64_t MaterialGeneration = 0;
  uint64_t EnvironmentGeneration = 0;
  uint64_t PreviewGeneration = 0;
  uint32_t Accumulated = 0;
  double RenderSeconds = 0;
  uint64_t BvhBuilds = 0;
};

} // namespace render
} // namespace svdag
