// Every setting of a rendered image, with its one default: the core renderer, the VTK mapper and
// the VTK image renderer all hold this struct (the VTK classes expose its members under the same
// names through vtkSegmentationSVDAGRenderSettings).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace svdag
{
namespace render
{

enum class Lod : uint32_t
{
  Block = 0, // the block's tight bounds box
  Leaf = 1,  // the first non-empty 4^3 region
  Voxel = 2, // the first solid voxel (lossless)
  Auto = 3   // per ray: the coarsest level whose cells cover at most autoLodPixels pixels
};
// Every value in order: with lodName, the one list of LOD names (the VTK settings' GetLODName,
// the command lines and the Python glue read it from here).
constexpr std::array<Lod, 4> Lods{ { Lod::Block, Lod::Leaf, Lod::Voxel, Lod::Auto } };
// "block", "leaf", "voxel", "auto".
const char* lodName(Lod lod);
// Parses lodName's names; throws std::invalid_argument otherwise.
Lod parseLod(const std::string& name);
// The names joined by `separator` ("block|leaf|voxel|auto" for "|").
std::string lodNames(const std::string& separator);

// How rays find the blocks (the same path tracer, materials, outputs and features either way):
//   RayTracing  the ray tracing pipeline: one procedural primitive per visible block in a BVH
//               (the paper's method; needs VK_KHR_ray_tracing_pipeline);
//   Compute     a compute shader walks the volume's grid of 16^3 cells front to back
//               (Module/core/svdag/GridTraversal.h, the CPU ray caster's code): no BVH, hidden
//               labels are bits; runs on any Vulkan 1.2 device;
//   Auto        per device, the one measured faster (Renderer::backendFor documents the rule);
//               Compute on a device without ray tracing.
enum class Backend : uint32_t
{
  Auto = 0,
  RayTracing = 1,
  Compute = 2
};
constexpr std::array<Backend, 3> Backends{ { Backend::Auto, Backend::RayTracing, Backend::Compute } };
// "auto", "rt", "compute".
const char* backendName(Backend backend);
// Parses backendName's names; throws std::invalid_argument otherwise.
Backend parseBackend(const std::string& name);
std::string backendNames(const std::string& separator);

// The normal that lights a voxel hit (the hit itself, position, label and depth, is always the
// lossless voxel surface): the entry face's (axis-aligned, blocky), or a smooth estimate from the
// occupancy of the hit label around the hit point (Module/core/svdag/SmoothNormal.h; the face
// normal still offsets rays). Smooth shading uploads a neighbour table of 27 words per block.
enum class Shading : uint32_t
{
  Voxel = 0,
  Smooth = 1
};
constexpr std::array<Shading, 2> Shadings{ { Shading::Voxel, Shading::Smooth } };
// "voxel", "smooth".
const char* shadingName(Shading shading);
// Parses shadingName's names; throws std::invalid_argument otherwise.
Shading parseShading(const std::string& name);
std::string shadingNames(const std::string& separator);

// A directional light: a disk of the given angular radius (0: a delta light) in `direction`
// (towards the light, world space), with `irradiance` at normal incidence (linear RGB).
struct SunLight
{
  bool on = false;
  std::array<double, 3> direction{ { 0.3, 0.4, 0.866 } };
  std::array<float, 3> irradiance{ { 3, 3, 3 } };
  double angularRadiusDegrees = 0.27;
};

// A clipping plane in world coordinates: keeps the half-space the normal points to, the points x
// with dot(normal, x - origin) >= 0 (VTK's convention for vtkPlane clipping planes).
struct ClipPlane
{
  std::array<double, 3> origin{ { 0, 0, 0 } };
  std::array<double, 3> normal{ { 0, 0, 1 } }; // finite, non-zero; need not be unit length
  bool operator==(const ClipPlane& o) const { return origin == o.origin && normal == o.normal; }
};

// An axis-aligned crop box in world coordinates (xmin, xmax, ymin, ymax, zmin, zmax): only what
// is inside it is drawn (when on).
struct CropBox
{
  bool on = false;
  std::array<double, 6> bounds{ { 0, 0, 0, 0, 0, 0 } };
  bool operator==(const CropBox& o) const { return on == o.on && (!on || bounds == o.bounds); }
};

// The ranges validate() checks (the VTK setters clamp to the same ones).
constexpr uint32_t MaximumSamplesPerPixel = 65536;
constexpr uint32_t MaximumBounces = 64;
constexpr double MaximumSunAngularRadius = 89.9;
// Clipping planes at most (VTK's usual limit; Clipping.h's SVDAG_CLIP_MAX_PLANES).
constexpr uint32_t MaximumClipPlanes = 6;

// The member initializers are the one definition of each default: the VTK settings, the
// command lines and the Python glue leave a setting alone unless asked, so these apply there too.
struct RenderSettings
{
  Backend backend = Backend::Auto;
  // Auto: lossless wherever a voxel covers more than a quarter of a pixel (autoLodPixels 1), and
  // leaf or block boxes only where the difference is below a pixel, so a still view looks the
  // same as at Lod::Voxel and far-away or huge volumes trace faster.
  Lod lod = Lod::Auto;
  // Lod::Auto draws a leaf (block) where a leaf (block) covers at most this many pixels.
  float autoLodPixels = 1.0f;
  // Samples per pixel each render pass adds to the progressive accumulation.
  uint32_t samplesPerPixel = 1;
  // Scattering events per path (0: only what emits light is seen).
  uint32_t maximumBounces = 4;
  // The same seed and settings give the same image.
  uint32_t seed = 0;
  // Next-event estimation with multiple importance sampling; off: the estimator that finds light
  // only when a path escapes (the paper authors'), same mean, slower to converge.
  bool nextEventEstimation = true;
  // Scale of the linear color before the tone curve.
  float exposure = 1.0f;
  // Linear RGBA of camera samples that hit nothing (the environment lights, it is not seen).
  std::array<float, 4> background{ { 0.1f, 0.1f, 0.12f, 1.0f } };
  // Constant environment radiance, or the scale of the environment map.
  std::array<float, 3> environmentColor{ { 1, 1, 1 } };
  // An equirectangular OpenEXR environment map; "" for the constant environment.
  std::string environmentMap;
  SunLight sun;
  // Most blocks per bottom-level acceleration structure; 0: the device's limit.
  uint32_t maximumBlocksPerBlas = 0;
  // Most bytes of device memory the renderer may hold (0: the device's memory heaps), for a GPU
  // shared with other programs. Per renderer: the renderers of a process share one device, and
  // each one's own bytes (Renderer::deviceBytes) count against its own limit; the heaps cap all
  // of them together. What does not fit fails with a DeviceMemoryError naming the
  // bytes needed and available, before anything is allocated for it.
  uint64_t deviceMemoryLimit = 0;
  // Voxel face normals or smooth normals for shading (path tracer and the Normal output).
  Shading shading = Shading::Voxel;
  // The label-aware denoiser (DenoiseLayout.h) on the displayed image (hdr and color; the
  // accumulated sums, the variance output and the error estimate stay the raw estimator's): an
  // edge-avoiding filter that never mixes radiance across labels and fades out by itself as the
  // accumulated samples converge. It costs no trace: label, depth and normal are traced anyway.
  bool denoise = true;
  // What is drawn is the intersection of the clipping planes' half-spaces and the crop box: every
  // ray (camera, shadow, bounce) is clipped to it, so cut-away parts cast no shadow, and where a
  // ray enters the region inside a solid voxel it hits the cut face (the plane's or box face's
  // outward normal, the voxel's label). At block and leaf LOD the solid is the block box or the
  // leaf box: a cut shows their cross-sections. A change is a uniform update (no BVH rebuild).
  std::vector<ClipPlane> clipPlanes;
  CropBox crop;
};

// Whether two settings trace the same image: every member but exposure (applied to the traced
// image) and samplesPerPixel (how many samples a pass adds).
bool tracesSameImage(const RenderSettings& a, const RenderSettings& b);

// The valid ranges, checked in one place: throws std::invalid_argument naming the setting and
// its range (samplesPerPixel 1 .. MaximumSamplesPerPixel, maximumBounces 0 .. MaximumBounces,
// exposure and autoLodPixels finite > 0, colors finite >= 0, a finite non-zero sun direction,
// sun radius in [0, MaximumSunAngularRadius], at most MaximumClipPlanes clipping planes with finite
// origins and finite non-zero normals, a finite crop box with min <= max on every axis).
void validate(const RenderSettings& settings);
// The clipping part of validate() (also for the mapper's own planes and cropping).
void validateClipping(const std::vector<ClipPlane>& planes, const CropBox& crop);
// A crop box that is on, with these bounds (xmin, xmax, ...); throws like validateClipping.
CropBox validCropBox(const std::array<double, 6>& bounds);

} // namespace render
} // namespace svdag
