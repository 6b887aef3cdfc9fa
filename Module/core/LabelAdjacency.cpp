// Label adjacency from the compressed form (svdag/LabelAdjacency.h).
#include "svdag/LabelAdjacency.h"

#include "svdag/RandomAccess.h"

#include <algorithm>
#include <mutex>
#include <string>

namespace svdag
{
namespace
{
constexpr uint32_t S = layout::CELL_SIZE; // 16
constexpr uint32_t NoLabel = UINT32_MAX;

// A pair packed as one integer (smaller index high), so that sort + unique orders it as LabelPair.
inline uint64_t packPair(uint32_t a, uint32_t b)
{
  return a < b ? (uint64_t(a) << 32 | b) : (uint64_t(b) << 32 | a);
}

void sortUnique(std::vector<uint64_t>& pairs)
{
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}
} // namespace

uint64_t labelAdjacencyBytes(const Volume& v)
{
  return layerSlicesBytes(v, S + 1);
}

std::vector<LabelPair> labelAdjacency(const Volume& v, const ParallelFor& parallel)
{
  std::vector<LabelPair> result;
  if (v.blockCount == 0 || v.labels.size() < 2)
    return result;
  checkOutputMemory(labelAdjacencyBytes(v), "the label adjacency of a " +
      std::to_string(v.geometry.dims[0]) + " x " + std::to_string(v.geometry.dims[1]) +
      " wide volume");
  const auto& d = v.geometry.dims;
  const auto n = v.geometry.cellCounts();
  const size_t nx = size_t(d[0]), ny = size_t(d[1]), slice = nx * ny;

  std::vector<uint64_t> found; // packed pairs of every layer so far, sorted and unique
  std::mutex merge;
  std::vector<uint32_t> layer, previousSlice(slice, NoLabel);
  for (int32_t cz = 0; cz < n[2]; ++cz)
  {
    decodeLayerLabels(v, cz, NoLabel, layer, parallel);
    const size_t lz = layer.size() / slice;
    const bool first = cz == 0;
    // Rows (y, z) of the layer in parallel; each voxel looks at its -x, -y and -z neighbours, so
    // every face of the volume is seen exactly once (-z of the layer's first slice is the
    // previous layer's last slice).
    parallel(0, uint64_t(lz * ny), 16, [&](uint64_t begin, uint64_t end) {
      std::vector<uint64_t> local;
      uint64_t last = UINT64_MAX; // neighbouring faces mostly repeat the pair just found
      const auto see = [&](uint32_t a, uint32_t b) {
        if (a == b || a == NoLabel || b == NoLabel)
          return;
        const uint64_t p = packPair(a, b);
        if (p != last)
        {
          local.push_back(p);
          last = p;
        }
      };
      for (uint64_t r = begin; r < end; ++r)
      {
        const size_t y = size_t(r % ny), z = size_t(r / ny);
        const uint32_t* row = layer.data() + slice * z + nx * y;
        const uint32_t* below = y > 0 ? row - nx : nullptr;
        const uint32_t* back = z > 0 ? row - slice : (first ? nullptr : previousSlice.data() + nx * y);
        for (size_t x = 0; x < nx; ++x)
        {
          const uint32_t L = row[x];
          if (L == NoLabel)
            continue;
          if (x > 0)
            see(L, row[x - 1]);
          if (below)
            see(L, below[x]);
          if (back)
            see(L, back[x]);
        }
        // Bound the chunk's memory on a long range of rows with many distinct boundaries.
        if (local.size() > (1u << 20))
          sortUnique(local);
      }
      sortUnique(local);
      std::lock_guard<std::mutex> lock(merge);
      found.insert(found.end(), local.begin(), local.end());
    });
    sortUnique(found);
    std::copy(layer.end() - std::ptrdiff_t(slice), layer.end(), previousSlice.begin());
  }
  result.reserve(found.size());
  for (const uint64_t p : found)
    result.push_back({ { uint32_t(p >> 32), uint32_t(p & 0xFFFFFFFFu) } });
  return result;
}

} // namespace svdag
