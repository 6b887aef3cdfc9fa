// Dense decoding of a Volume (svdag/Decoder.h).
#include "svdag/Decoder.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <new>
#include <stdexcept>

namespace svdag
{
namespace
{
constexpr uint32_t S = layout::CELL_SIZE; // 16
} // namespace

uint64_t decodedBytes(const Volume& v, int32_t nz)
{
  const auto& d = v.geometry.dims;
  const uint64_t slices = nz < 0 ? uint64_t(std::max(d[2], 0)) : uint64_t(nz);
  uint64_t bytes = 0;
  if (__builtin_mul_overflow(uint64_t(std::max(d[0], 0)), uint64_t(std::max(d[1], 0)), &bytes) ||
    __builtin_mul_overflow(bytes, slices, &bytes) ||
    __builtin_mul_overflow(bytes, uint64_t(scalarSize(v.scalarType)), &bytes))
  {
    return UINT64_MAX;
  }
  return bytes;
}

std::string formatBytes(uint64_t bytes)
{
  static const char* units[] = { "KiB", "MiB", "GiB", "TiB", "PiB", "EiB" };
  if (bytes < 1024)
    return std::to_string(bytes) + (bytes == 1 ? " byte" : " bytes");
  double value = double(bytes);
  int unit = -1;
  while (value >= 1024 && unit < 5)
  {
    value /= 1024;
    ++unit;
  }
  char text[32];
  if (value == double(uint64_t(value)))
    std::snprintf(text, sizeof text, "%llu %s", static_cast<unsigned long long>(value), units[unit]);
  else
    std::snprintf(text, sizeof text, "%.1f %s", value, units[unit]);
  return text;
}

uint64_t physicalMemoryBytes()
{
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long pageSize = ::sysconf(_SC_PAGESIZE);
  return pages > 0 && pageSize > 0 ? uint64_t(pages) * uint64_t(pageSize) : 0;
}

namespace
{
std::string decodeWhat(const Volume& v, int32_t nz, uint64_t bytes)
{
  const auto& d = v.geometry.dims;
  return "decoding " + std::to_string(d[0]) + " x " + std::to_string(d[1]) + " x " +
    std::to_string(nz < 0 ? d[2] : nz) + " " + scalarName(v.scalarType) + " voxels needs " +
    std::to_string(bytes) + " bytes (" + formatBytes(bytes) + ")";
}
} // namespace

void checkDecodeMemory(const Volume& v, int32_t nz)
{
  const uint64_t bytes = decodedBytes(v, nz);
  // Half the address space at most: vtkIdType, ptrdiff_t and numpy's sizes are signed.
  const uint64_t addressable = uint64_t(std::numeric_limits<std::ptrdiff_t>::max());
  if (bytes > addressable)
    throw std::length_error(decodeWhat(v, nz, bytes) + ", more than the address space");
  const uint64_t memory = physicalMemoryBytes();
  if (memory > 0 && bytes > memory)
    throw std::length_error(decodeWhat(v, nz, bytes) + ", more than this machine's " +
      formatBytes(memory) + " of memory");
}

std::vector<uint8_t> decode(const Volume& v, const ParallelFor& parallel)
{
  checkDecodeMemory(v);
  const uint64_t bytes = decodedBytes(v);
  std::vector<uint8_t> out;
  try
  {
    out.resize(size_t(bytes));
  }
  catch (const std::bad_alloc&)
  {
    throw std::length_error(decodeWhat(v, -1, bytes) + ", and that much memory is not available");
  }
  decode(v, out.data(), parallel);
  return out;
}

void decodeSlab(const Volume& v, int32_t z0, int32_t nz, void* out, const ParallelFor& parallel)
{
  const auto& d = v.geometry.dims;
  if (z0 < 0 || nz < 0 || int64_t(z0) + nz > d[2])
    throw std::out_of_range("decodeSlab: z range outside the volume");
  const size_t sliceSize = size_t(d[0]) * size_t(d[1]);
  const ScalarType type = v.scalarType;
  for (size_t i = 0; i < sliceSize * size_t(nz); ++i)
    scalarStore(type, out, i, v.background);
  if (nz == 0 || v.blockCount == 0)
    return;
  const auto n = v.geometry.cellCounts();
  const uint32_t cellsPerLayer = uint32_t(n[0]) * uint32_t(n[1]);
  const uint32_t czFirst = uint32_t(z0) / S, czLast = uint32_t(z0 + nz - 1) / S;
  // Blocks of the covered cell layers, found once; each cell then decodes independently.
  const uint64_t first = v.cellBlocks(czFirst * cellsPerLayer).first;
  const uint64_t last = v.cellBlocks((czLast + 1) * cellsPerLayer).first;
  std::vector<uint64_t> starts; // block index of each block run start
  std::vector<uint32_t> runCells;
  for (uint64_t b = first; b < last; ++b)
  {
    const uint32_t cell = v.block(b).cell;
    if (runCells.empty() || runCells.back() != cell)
    {
      runCells.push_back(cell);
      starts.push_back(b);
    }
  }
  starts.push_back(last);
  parallel(0, runCells.size(), 1, [&](uint64_t begin, uint64_t end) {
    std::vector<uint8_t> occ(S * S * S);
    for (uint64_t r = begin; r < end; ++r)
    {
      const uint32_t cell = runCells[r];
      const int32_t cx = int32_t(cell % uint32_t(n[0]) * S);
      const int32_t cy = int32_t(cell / uint32_t(n[0]) % uint32_t(n[1]) * S);
      const int32_t cz = int32_t(cell / cellsPerLayer * S);
      for (uint64_t b = starts[r]; b < starts[r + 1]; ++b)
      {
        const Block blk = v.block(b);
        const uint64_t value = v.labels[blk.label].value;
        v.occupancy(b, occ.data());
        const int32_t zLo = std::max<int32_t>(cz + blk.lo[2], z0);
        const int32_t zHi = std::min<int32_t>(cz + blk.hi[2], z0 + nz - 1);
        for (int32_t z = zLo; z <= zHi; ++z)
          for (int32_t y = cy + blk.lo[1]; y <= cy + blk.hi[1]; ++y)
            for (int32_t x = cx + blk.lo[0]; x <= cx + blk.hi[0]; ++x)
            {
              if (occ[size_t(x - cx) + S * (size_t(y - cy) + S * size_t(z - cz))])
                scalarStore(type, out,
                  size_t(x) + size_t(d[0]) * (size_t(y) + size_t(d[1]) * size_t(z - z0)), value);
            }
      }
    }
  });
}

} // namespace svdag
