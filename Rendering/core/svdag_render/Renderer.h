// The path-tracing renderer of a volume's blocks: per pixel, label, depth and normal of the
// pixel-center ray, and the progressive path-traced color (GpuLayout.h documents the outputs,
// the pixel-center convention, sampling and tone mapping; PathTracer.h the integrator).
//
//   svdag::render::Renderer r;                  // throws when no ray-tracing device qualifies
//   r.setVolume(volume);                        // uploads the streams, builds the BVH
//   r.setCamera(svdag::render::frameVolume(volume->geometry, 30, 20));
//   r.setImageSize(640, 480);
//   const svdag::render::Image& image = r.render(); // adds samplesPerPixel samples per pixel
//
// Progressive accumulation: every render() adds samplesPerPixel samples to the running mean
// while nothing that changes the image changed since the last one (camera, image size, LOD,
// materials, visibility, lighting, bounces, NEE, seed, background, volume); any such change
// starts a new accumulation. Exposure and samplesPerPixel do not restart it.
//
// Materials are per label index (defaultMaterial: base color svdagLabelColor, roughness 0.6,
// metallic 0, transmission 0, ior 1.5, specular 0.5, visible); an edit is a buffer upload.
// Visibility 0 hides the label like setHiddenLabels: its blocks leave the BVH.
//
// Known limitation: Traversal.h reports a ray that starts inside a solid with t = tmin and no
// entry face (no exit point), so a refracted path cannot cross an object: with a transmissive
// material such paths end (they contribute nothing, never NaN).
#pragma once

#include "svdag_render/Camera.h"
#include "svdag_render/Pipeline.h"
#include "svdag_render/Material.h"

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

// A directional light: a disk of the given angular radius (0: a delta light) in `direction`
// (towards the light, world space), with `irradiance` at normal incidence (linear RGB).
struct SunLight
{
  bool on = false;
  std::array<double, 3> direction{ { 0, 0, 1 } };
  std::array<float, 3> irradiance{ { 3, 3, 3 } };
  double angularRadiusDegrees = 0.27;
};

enum class Lod : uint32_t
{
  Block = 0, // the block's tight bounds box
  Leaf = 1,  // the first non-empty 4^3 region
  Voxel = 2, // the first solid voxel (lossless)
  Auto = 3   // per ray: the coarsest level whose cells cover at most autoLodPixels pixels
};
// "block", "leaf", "voxel", "auto".
const char* lodName(Lod lod);
// Parses lodName's names; throws std::invalid_argument otherwise.
Lod parseLod(const std::string& name);

// Host copies of the outputs, pixel (x, y) at index x + width * y, y = 0 the bottom row.
struct Image
{
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint32_t> label; // label index + 1, 0 = background
  std::vector<float> depth;    // world distance along the ray; SVDAG_DEPTH_MISS (FLT_MAX) on a miss
  std::vector<float> normal;   // 3 per pixel, world unit normal; 0 on a miss or inside
  std::vector<float> hdr;      // 4 per pixel, linear RGBA: the mean of the accumulated samples
  std::vector<uint32_t> color; // RGBA8, tone-mapped sRGB, R in the lowest byte
};

class Renderer
{
public:
  // Creates the Vulkan context and the pipeline. Throws std::runtime_error (no ray-tracing
  // device: the message names every device found and what it lacks).
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  const std::string& deviceName() const;

  // Uploads a volume and builds its BVH (keeps the hidden labels). Throws std::runtime_error.
  void setVolume(std::shared_ptr<const Volume> volume);
  // Label indices left out of the BVH; rebuilds it when the set changes (setupSeconds then
  // measures the rebuild).
  void setHiddenLabels(const std::vector<uint32_t>& labelIndices);
  // Caps the primitives per BLAS (0: the driver's limit); see Scene::setPrimitivesPerBlasLimit.
  void setPrimitivesPerBlasLimit(uint32_t limit);
  size_t blasCount() const;
  void setCamera(const Camera& camera) { this->View = camera; }
  const Camera& camera() const { return this->View; }
  // Throws std::invalid_argument for 0 or more pixels than the device dispatches (or 2^28).
  void setImageSize(uint32_t width, uint32_t height);
  void setLod(Lod lod) { this->Detail = lod; }
  Lod lod() const { return this->Detail; }
  // Lod::Auto draws a leaf (block) where a leaf (block) covers at most this many pixels (> 0).
  void setAutoLodPixels(float pixels);
  float autoLodPixels() const { return this->AutoLodPixels; }
  // Linear RGBA of camera samples that hit nothing (the environment lights, it is not seen).
  void setBackground(const std::array<float, 4>& linearRGBA) { this->Background = linearRGBA; }

  // ---- path tracing ----
  // Samples per pixel added by each render(), 1 .. 65536 (std::invalid_argument otherwise).
  void setSamplesPerPixel(uint32_t samples);
  uint32_t samplesPerPixel() const { return this->SamplesPerPixel; }
  // Scattering events per path, 0 (direct view of emission only) .. 64.
  void setMaxBounces(uint32_t bounces);
  uint32_t maxBounces() const { return this->MaxBounces; }
  void setSeed(uint32_t seed) { this->Seed = seed; }
  uint32_t seed() const { return this->Seed; }
  // Next-event estimation with MIS (default) or the plain estimator that finds light only when
  // a path escapes (the paper authors' estimator).
  void setNextEventEstimation(bool on) { this->Nee = on; }
  bool nextEventEstimation() const { return this->Nee; }
  // Scale of the linear color before the tone curve (> 0, finite).
  void setExposure(float exposure);
  float exposure() const { return this->Exposure; }
  // Constant environment radiance (default 1, 1, 1), or the scale of the environment map.
  void setEnvironmentColor(const std::array<float, 3>& radiance);
  // An equirectangular OpenEXR environment (EnvironmentMap::fromEXR); "" returns to the constant
  // environment. Throws std::runtime_error for an unreadable file (the previous one stays).
  void setEnvironmentMap(const std::string& exrPath);
  const std::string& environmentMap() const { return this->EnvironmentPath; }
  // Throws std::invalid_argument for a zero or non-finite direction, negative or non-finite
  // irradiance, or an angular radius outside [0, 90) degrees.
  void setSun(const SunLight& sun);
  const SunLight& sun() const { return this->Sun; }

  static Material defaultMaterial(uint32_t labelIndex);
  // The material of a label index (needs a volume; std::invalid_argument for an index outside
  // the label table or non-finite / negative values). Visibility is baseColorVisibility.a (0 or
  // not 0).
  void setMaterial(uint32_t labelIndex, const Material& material);
  const Material& material(uint32_t labelIndex) const;
  size_t materialCount() const { return this->Materials.size(); }
  // The feature switches the next render() compiles the pipeline with.
  ShaderFeatures shaderFeatures() const;

  // Starts a new accumulation on the next render().
  void resetAccumulation() { this->AccumulationValid = false; }
  // Samples per pixel in the current image (0 before the first render()).
  uint32_t accumulatedSamples() const { return this->Accumulated; }
  // Seconds of tracing (sum of frame times) that produced the current image.
  double renderSeconds() const { return this->RenderSeconds; }
  // BVH builds (setVolume and visibility changes) and ray tracing pipeline builds so far.
  uint64_t bvhBuilds() const { return this->BvhBuilds; }
  uint64_t pipelineBuilds() const;

  // Traces one pass (samplesPerPixel samples per pixel, added to the accumulation) and reads
  // the outputs back. Throws std::runtime_error (no volume, Vulkan failure) or
  // std::invalid_argument (degenerate camera).
  const Image& render();
  const Image& image() const { return this->Output; }

  // Upload + BVH build of the last setVolume, or BVH rebuild of the last setHiddenLabels that
  // changed the set, seconds.
  double setupSeconds() const { return this->SetupSeconds; }
  // Wall time of the last frame (record, trace, wait), milliseconds.
  double lastFrameMilliseconds() const { return this->FrameMilliseconds; }
  uint64_t blasBytes() const;
  uint64_t tlasBytes() const;
  uint64_t visibleBlocks() const;

private:
  void applyVisibility();
  void timeSetup(bool rebuilt, double seconds);

  struct Gpu;
  std::unique_ptr<Gpu> Device;
  Camera View;
  uint32_t Width = 256;
  uint32_t Height = 256;
  Lod Detail = Lod::Voxel;
  float AutoLodPixels = 1.0f;
  uint32_t BlasLimit = 0;
  std::array<float, 4> Background{ { 0.1f, 0.1f, 0.12f, 1.0f } };
  Image Output;
  double SetupSeconds = 0;
  double FrameMilliseconds = 0;

  std::vector<uint32_t> ExplicitHidden;
  std::vector<Material> Materials;
  bool MaterialsDirty = true;
  uint32_t SamplesPerPixel = 1;
  uint32_t MaxBounces = 4;
  uint32_t Seed = 0;
  bool Nee = true;
  float Exposure = 1.0f;
  std::array<float, 3> EnvironmentColor{ { 1, 1, 1 } };
  std::string EnvironmentPath;
  bool EnvironmentDirty = true;
  SunLight Sun;

  // Accumulation state: what the last pass rendered (render() compares) and its sample count.
  bool AccumulationValid = false;
  std::vector<unsigned char> AccumulatedState;
  uint64_t SceneGeneration = 0;
  uint64_t MaterialGeneration = 0;
  uint64_t EnvironmentGeneration = 0;
  uint32_t Accumulated = 0;
  double RenderSeconds = 0;
  uint64_t BvhBuilds = 0;
};

} // namespace render
} // namespace svdag
