// Where a volume lies in world space: its index-to-world matrix and world bounds (used by the
// scene, the camera framing and the renderer alike).
#pragma once

#include <svdag/Volume.h>

#include <array>

namespace svdag
{
namespace render
{

// The volume's index-to-world matrix as 3 rows of 4 (VkTransformMatrixKHR's layout): voxel
// (i, j, k) occupies [i, i+1)^3 in index space, and world = origin + D * diag(spacing) * (p - 0.5).
std::array<double, 12> indexToWorld(const Geometry& geometry);

// World-space axis-aligned bounds of the volume's voxels: xmin, xmax, ymin, ymax, zmin, zmax.
std::array<double, 6> worldBounds(const Geometry& geometry);

} // namespace render
} // namespace svdag
