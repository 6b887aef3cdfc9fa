// Per-label statistics from the compressed form (svdag/LabelStatistics.h).
#include "svdag/LabelStatistics.h"

#include "svdag/Decoder.h"
#include "svdag/RandomAccess.h"

#include <algorithm>
#include <atomic>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>

namespace svdag
{
namespace
{
constexpr uint32_t S = layout::CELL_SIZE; // 16
constexpr uint32_t NoLabel = UINT32_MAX;

} // namespace

std::array<double, 3> LabelStatistics::centroid() const
{
  if (voxels == 0)
    return { { 0, 0, 0 } };
  return { { double(indexSum[0]) / double(voxels), double(indexSum[1]) / double(voxels),
    double(indexSum[2]) / double(voxels) } };
}

uint64_t labelStatisticsBytes(const Volume& v)
{
  return layerSlicesBytes(v, 2 * S + 1);
}

std::vector<LabelStatistics> labelStatistics(const Volume& v, const ParallelFor& parallel)
{
  const size_t nLabels = v.labels.size();
  std::vector<LabelStatistics> result(nLabels);
  if (v.blockCount == 0 || nLabels == 0)
    return result;
  checkOutputMemory(labelStatisticsBytes(v), "the label statistics of a " +
      std::to_string(v.geometry.dims[0]) + " x " + std::to_string(v.geometry.dims[1]) +
      " wide volume");
  const auto& d = v.geometry.dims;
  const auto n = v.geometry.cellCounts();
  const size_t nx = size_t(d[0]), ny = size_t(d[1]);
  const uint32_t perLayer = uint32_t(n[0]) * uint32_t(n[1]);
  // Integer sums: adding them in any order from any thread gives the same result.
  std::unique_ptr<std::atomic<uint64_t>[]> sums(new std::atomic<uint64_t>[nLabels * 5]);
  for (size_t i = 0; i < nLabels * 5; ++i)
    sums[i].store(0, std::memory_order_relaxed);

  std::vector<uint32_t> current, next, previousSlice(nx * ny, NoLabel);
  decodeLayerLabels(v, 0, NoLabel, current, parallel);
  for (int32_t cz = 0; cz < n[2]; ++cz)
  {
    if (cz + 1 < n[2])
      decodeLayerLabels(v, cz + 1, NoLabel, next, parallel);
    else
      next.clear();
    const int32_t z0 = cz * int32_t(S);
    const int32_t lz = std::min<int32_t>(int32_t(S), d[2] - z0);
    parallel(0, perLayer, 1, [&](uint64_t begin, uint64_t end) {
      for (uint64_t c = begin; c < end; ++c)
      {
        const uint32_t cell = uint32_t(cz) * perLayer + uint32_t(c);
        const int32_t cx = int32_t(c % uint32_t(n[0]) * S), cy = int32_t(c / uint32_t(n[0]) * S);
        const auto range = v.cellBlocks(cell);
        for (uint64_t b = range.first; b < range.second; ++b)
        {
          const Block blk = v.block(b);
          const uint32_t L = blk.label;
          uint64_t count = 0, sx = 0, sy = 0, sz = 0, surface = 0;
          for (int32_t zl = blk.lo[2]; zl <= blk.hi[2]; ++zl)
            for (int32_t y = cy + blk.lo[1]; y <= cy + blk.hi[1]; ++y)
            {
              const size_t row = nx * (size_t(y) + ny * size_t(zl));
              for (int32_t x = cx + blk.lo[0]; x <= cx + blk.hi[0]; ++x)
              {
                const size_t i = row + size_t(x);
                if (current[i] != L)
                  continue;
                ++count;
                sx += uint64_t(x);
                sy += uint64_t(y);
                sz += uint64_t(z0 + zl);
                // The 6 face neighbours; outside the volume counts as another label.
                bool open = x == 0 || x == d[0] - 1 || y == 0 || y == d[1] - 1 ||
                  current[i - 1] != L || current[i + 1] != L || current[i - nx] != L ||
                  current[i + nx] != L;
                if (!open)
                {
                  const size_t xy = size_t(x) + nx * size_t(y);
                  if (zl == 0)
                    open = z0 == 0 || previousSlice[xy] != L;
                  else
                    open = current[i - nx * ny] != L;
                  if (!open)
                  {
                    if (zl == lz - 1)
                      open = next.empty() || next[xy] != L;
                    else
                      open = current[i + nx * ny] != L;
                  }
                }
                surface += open ? 1 : 0;
              }
            }
          std::atomic<uint64_t>* s = &sums[size_t(L) * 5];
          s[0].fetch_add(count, std::memory_order_relaxed);
          s[1].fetch_add(sx, std::memory_order_relaxed);
          s[2].fetch_add(sy, std::memory_order_relaxed);
          s[3].fetch_add(sz, std::memory_order_relaxed);
          s[4].fetch_add(surface, std::memory_order_relaxed);
        }
      }
    });
    std::copy(current.end() - std::ptrdiff_t(nx * ny), current.end(), previousSlice.begin());
    current.swap(next);
  }
  for (size_t l = 0; l < nLabels; ++l)
  {
    const std::atomic<uint64_t>* s = &sums[l * 5];
    result[l].voxels = s[0].load();
    result[l].indexSum = { { s[1].load(), s[2].load(), s[3].load() } };
    result[l].surfaceVoxels = s[4].load();
  }
  return result;
}

} // namespace svdag
