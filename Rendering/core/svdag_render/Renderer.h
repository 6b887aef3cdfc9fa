// The primary-hit renderer: one ray per pixel through a volume's blocks, with label, depth,
// normal and a simple deterministic shading read back to the host (GpuLayout.h documents the
// outputs and the pixel-center convention).
//
//   svdag::render::Renderer r;                  // throws when no ray-tracing device qualifies
//   r.setVolume(volume);                        // uploads the streams, builds the BVH
//   r.setCamera(svdag::render::frameVolume(volume->geometry, 30, 20));
//   r.setImageSize(640, 480);
//   const svdag::render::Image& image = r.render();
#pragma once

#include "svdag_render/Camera.h"

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
  std::vector<float> hdr;      // 4 per pixel, linear RGBA
  std::vector<uint32_t> color; // RGBA8, sRGB, R in the lowest byte
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
  void setBackground(const std::array<float, 4>& linearRGBA) { this->Background = linearRGBA; }

  // Traces one frame and reads the outputs back. Throws std::runtime_error (no volume, Vulkan
  // failure) or std::invalid_argument (degenerate camera).
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
};

} // namespace render
} // namespace svdag
