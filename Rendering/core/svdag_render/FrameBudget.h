// Chooses the level of detail and image reduction of a frame from a time budget, learning each
// level's cost per traced pixel from the frames it measures (VTK-free, so it is tested alone).
//
// Quality ladder, best first: for reduction factors 1, 2, 3, ..., 8 (the image is traced at
// 1/factor of the viewport's width and height, then scaled up), the finest LOD, then the leaf and
// block LODs where they are coarser. The first step whose predicted time (fixed overhead plus cost
// per pixel times traced pixels) fits the budget is chosen, else the last. A level never measured
// is predicted from a measured finer one (leaf 0.8x, block 0.6x the voxel cost per pixel), or
// assumed to fit (the first frame measures it).
#pragma once

#include "svdag_render/RenderSettings.h"

#include <array>
#include <cstdint>

namespace svdag
{
namespace render
{

struct FrameLevel
{
  Lod lod = Lod::Voxel;
  uint32_t reduction = 1; // the traced image is ceil(width / reduction) x ceil(height / reduction)
};

class FrameBudget
{
public:
  static constexpr uint32_t MaximumReduction = 8;

  // The level for a viewport of `pixels` pixels within `budgetSeconds` (<= 0 or non-finite:
  // no budget), never finer than `finest`.
  FrameLevel choose(Lod finest, uint64_t pixels, double budgetSeconds) const;
  // Records a traced frame: tracing `tracedPixels` at `lod` took `traceSeconds`, and everything
  // else of the frame (depth read, upload, compositing) `overheadSeconds`. A `provisional` frame
  // (one that also built the BVH or compiled shaders) counts only while nothing else is known,
  // and the first real measurement replaces it.
  void record(Lod lod, uint64_t tracedPixels, double traceSeconds, double overheadSeconds,
    bool provisional = false);
  // The predicted seconds of a frame at a level (0 while nothing is known).
  double predict(const FrameLevel& level, uint64_t pixels) const;

private:
  // Seconds per traced pixel, per LOD (block, leaf, voxel, auto); < 0: never measured.
  std::array<double, 4> CostPerPixel{ { -1, -1, -1, -1 } };
  std::array<bool, 4> Provisional{ { false, false, false, false } };
  double OverheadSeconds = 0;
  bool OverheadProvisional = true;
};

} // namespace render
} // namespace svdag
