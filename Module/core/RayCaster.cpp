#include "svdag/RayCaster.h"

#include "svdag/Clipping.h"
#include "svdag/Traversal.h"
#include "svdag/SmoothNormal.h"
// The whole-volume walk (GridTraversal.h) reads the Volume's cell ranges and block records.
#define SVDAG_GRID_PARAM const ::svdag::Volume &svdagVolume,
#define SVDAG_GRID_ARG volume,
#define SVDAG_GRID_CELL_BLOCKS(cell, first, end)                                                   \
  {                                                                                                \
    const auto range_ = svdagVolume.cellBlocks(cell);                                              \
    first = range_.first;                                                                          \
    end = range_.second;                                                                           \
  }
#define SVDAG_GRID_BLOCK(b, lo, hi, rootRef, label)                                                \
  {                                                                                                \
    const ::svdag::Block block_ = svdagVolume.block(b);                                            \
    lo = glm::uvec3(block_.lo[0], block_.lo[1], block_.lo[2]);                                     \
    hi = glm::uvec3(block_.hi[0], block_.hi[1], block_.hi[2]);                                     \
    rootRef = block_.root;                                                                         \
    label = block_.label;                                                                          \
  }
#include "svdag/GridTraversal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace svdag
{
namespace
{
// Throws std::invalid_argument for a ray or level of detail the caster cannot trace.
void checkRay(const Ray& r, Lod lod)
{
  for (int a = 0; a < 3; ++a)
  {
    if (!std::isfinite(r.origin[a]) || !std::isfinite(r.direction[a]))
      throw std::invalid_argument("ray origin and direction must be finite");
  }
  if (r.direction[0] == 0 && r.direction[1] == 0 && r.direction[2] == 0)
    throw std::invalid_argument("ray direction must not be zero");
  if (std::isnan(r.tmin) || std::isnan(r.tmax))
    throw std::invalid_argument("ray interval must not be NaN");
  if (uint32_t(lod) > uint32_t(Lod::Voxel))
    throw std::invalid_argument("unknown level of detail");
}
} // namespace

// The ray with a unit direction; s is the distance along it (t = s / length).
namespace
{
struct UnitRay
{
  std::array<double, 3> origin;
  std::array<double, 3> dir;
  double length;
  double smin, smax;
  bool entryOnly;
};
} // namespace

RayCaster::RayCaster(const Volume& v)
  : volume(v)
{
  if (v.form != DagForm::Compact)
    throw std::invalid_argument("RayCaster reads the compact form of a volume (svdag::compacted)");
}

RayHit RayCaster::cast(const Ray& input, Lod lod) const
{
  checkRay(input, lod);
  const auto& d = input.direction;
  // Scaled before squaring, so that huge or tiny directions neither overflow nor underflow.
  const double scale = std::max({ std::fabs(d[0]), std::fabs(d[1]), std::fabs(d[2]) });
  const double length = scale *
    std::sqrt((d[0] / scale) * (d[0] / scale) + (d[1] / scale) * (d[1] / scale) +
      (d[2] / scale) * (d[2] / scale));

  UnitRay ray;
  ray.length = length;
  for (int a = 0; a < 3; ++a)
  {
    ray.origin[a] = input.origin[a];
    ray.dir[a] = d[a] / length;
  }
  // s = t * length; infinite bounds stay infinite (and are clamped per cell).
  ray.smin = input.tmin * length;
  ray.smax = input.tmax * length;
  ray.entryOnly = input.entryOnly;

  RayHit miss;
  int enterPlane = -1;
  if (!this->ClipPlanes.empty())
  {
    glm::dvec4 planes[SVDAG_CLIP_MAX_SLOTS];
    for (size_t i = 0; i < this->ClipPlanes.size(); ++i)
    {
      const auto& p = this->ClipPlanes[i];
      planes[i] = glm::dvec4(p[0], p[1], p[2], p[3]);
    }
    const clipping::SvdagClipInterval c = clipping::svdagClipInterval(planes,
      uint32_t(this->ClipPlanes.size()), glm::dvec3(ray.origin[0], ray.origin[1], ray.origin[2]),
      glm::dvec3(ray.dir[0], ray.dir[1], ray.dir[2]), ray.smin, ray.smax);
    if (!c.kept)
      return miss;
    ray.smin = c.tmin;
    ray.smax = c.tmax;
    enterPlane = c.enterPlane;
  }
  // A hit from inside a solid (zero normal: at smin) where a plane moved smin is its cut face.
  auto onCut = [enterPlane](RayHit hit) {
    if (hit.hit && enterPlane >= 0 && hit.normal[0] == 0 && hit.normal[1] == 0 &&
      hit.normal[2] == 0)
      hit.clipPlane = enterPlane;
    return hit;
  };
  const auto& dims = volume.geometry.dims;
  if (volume.blockCount == 0 || !(ray.smin <= ray.smax))
    return miss;
  const auto n = volume.geometry.cellCounts();
  const traversal::Streams streams{ volume.roots.data(), volume.mids.data(),
    volume.leaves.data() };
  const traversal::SvdagGridHit h = traversal::svdagCastGrid(streams, volume,
    glm::dvec3(ray.origin[0], ray.origin[1], ray.origin[2]),
    glm::dvec3(ray.dir[0], ray.dir[1], ray.dir[2]), ray.smin, ray.smax,
    glm::ivec3(dims[0], dims[1], dims[2]), glm::ivec3(n[0], n[1], n[2]), volume.widths.midRefBits,
    volume.widths.leafRefBits, uint32_t(lod), ray.entryOnly, false);
  if (!h.hit)
    return miss;
  RayHit hit;
  hit.hit = true;
  hit.t = h.s / ray.length;
  hit.label = h.label;
  hit.block = h.block;
  for (int a = 0; a < 3; ++a)
  {
    hit.voxel[a] = int32_t(layout::CELL_SIZE) * h.cell[a] + h.voxel[a];
    hit.normal[a] = h.normal[a];
  }
  return onCut(hit);
}

void RayCaster::setClipPlanes(const std::vector<std::array<double, 4>>& planes)
{
  if (planes.size() > SVDAG_CLIP_MAX_SLOTS)
    throw std::invalid_argument("at most 12 clipping planes (6 planes and a crop box)");
  for (const auto& p : planes)
  {
    for (double v : p)
    {
      if (!std::isfinite(v))
        throw std::invalid_argument("clipping planes must be finite");
    }
  }
  this->ClipPlanes = planes;
}

void RayCaster::castMany(const std::vector<Ray>& rays, Lod lod, std::vector<RayHit>& hits,
  const ParallelFor& parallel) const
{
  hits.assign(rays.size(), RayHit());
  // Invalid rays are found first, so that no worker thread has to carry an exception out.
  for (const Ray& r : rays)
    checkRay(r, lod);
  parallel(0, rays.size(), 256, [&](uint64_t begin, uint64_t end) {
    for (uint64_t i = begin; i < end; ++i)
      hits[i] = cast(rays[i], lod);
  });
}

std::array<float, 3> RayCaster::smoothNormal(const Ray& ray, const RayHit& hit, Lod lod) const
{
  std::array<float, 3> face{ { float(hit.normal[0]), float(hit.normal[1]),
    float(hit.normal[2]) } };
  if (!hit.hit || lod != Lod::Voxel || (hit.normal[0] == 0 && hit.normal[1] == 0 &&
    hit.normal[2] == 0))
    return face;
  const Block block = volume.block(hit.block);
  const auto n = volume.geometry.cellCounts();
  const int64_t cell[3] = { int64_t(block.cell % uint32_t(n[0])),
    int64_t((block.cell / uint32_t(n[0])) % uint32_t(n[1])),
    int64_t(block.cell / (uint32_t(n[0]) * uint32_t(n[1]))) };
  // The hit point relative to the cell's corner, in double before rounding to float (like the
  // traversal's re-anchoring).
  glm::vec3 p, dir;
  for (int a = 0; a < 3; ++a)
  {
    p[a] = float(ray.origin[a] + hit.t * ray.direction[a] - double(layout::CELL_SIZE) * cell[a]);
    dir[a] = float(ray.direction[a]);
  }
  const std::array<uint32_t, 27> roots = neighbourRoots(volume, hit.block);
  const traversal::Streams streams{ volume.roots.data(), volume.mids.data(),
    volume.leaves.data() };
  const glm::vec3 s = traversal::svdagSmoothNormal(streams, roots.data(), volume.widths.midRefBits,
    volume.widths.leafRefBits, p, glm::vec3(face[0], face[1], face[2]), dir);
  return { { s.x, s.y, s.z } };
}

std::array<uint32_t, 27> neighbourRoots(const Volume& volume, uint64_t blockIndex)
{
  std::array<uint32_t, 27> roots;
  roots.fill(traversal::SVDAG_NO_BLOCK);
  const Block block = volume.block(blockIndex);
  const auto n = volume.geometry.cellCounts();
  const int64_t c[3] = { int64_t(block.cell % uint32_t(n[0])),
    int64_t((block.cell / uint32_t(n[0])) % uint32_t(n[1])),
    int64_t(block.cell / (uint32_t(n[0]) * uint32_t(n[1]))) };
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
      {
        const int64_t x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
        if (x < 0 || y < 0 || z < 0 || x >= n[0] || y >= n[1] || z >= n[2])
          continue;
        const int slot = (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1);
        if (slot == 13)
        {
          roots[13] = block.root;
          continue;
        }
        const auto range = volume.cellBlocks(uint32_t(x + int64_t(n[0]) * (y + int64_t(n[1]) * z)));
        // Blocks of a cell hold distinct labels; readers accept any order within a cell.
        for (uint64_t b = range.first; b < range.second; ++b)
        {
          const Block other = volume.block(b);
          if (other.label == block.label)
          {
            roots[size_t(slot)] = other.root;
            break;
          }
        }
      }
  return roots;
}

std::vector<uint32_t> neighbourTable(const Volume& volume, const ParallelFor& parallel)
{
  std::vector<uint32_t> table(size_t(volume.blockCount) * 27);
  parallel(0, volume.blockCount, 1024, [&](uint64_t begin, uint64_t end) {
    for (uint64_t b = begin; b < end; ++b)
    {
      const std::array<uint32_t, 27> roots = neighbourRoots(volume, b);
      std::copy(roots.begin(), roots.end(), table.begin() + ptrdiff_t(27 * b));
    }
  });
  for (uint64_t b = 0; b < volume.blockCount; ++b)
  {
    if (volume.block(b).root == traversal::SVDAG_NO_BLOCK)
      throw std::runtime_error("smooth shading: a root reference equals the neighbour table's "
                               "no-block marker");
  }
  return table;
}

} // namespace svdag
