// Decodes a Volume back to its dense label array (the inverse of the Builder, bit-exact).
//
// A dense decode needs dims[0] * dims[1] * dims[2] * scalarSize bytes, which for a small file of
// a huge volume (a 404-byte .svdag of an empty 4096^3 volume is valid) is far more than any
// machine holds. checkDecodeMemory() refuses such a decode before anything is allocated, with a
// std::length_error that names the bytes needed; the allocating decode() calls it first.
#pragma once

#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <cstdint>
#include <string>
#include <vector>

namespace svdag
{

// Bytes of a dense array of nz z-slices of the volume's scalar type (nz < 0: every slice).
uint64_t decodedBytes(const Volume& volume, int32_t nz = -1);
// "256 GiB", "1.5 MiB", "12 bytes".
std::string formatBytes(uint64_t bytes);
// Bytes of physical memory on this machine, 0 if unknown.
uint64_t physicalMemoryBytes();
// Throws std::length_error ("decoding 4096 x 4096 x 4096 uint32 voxels needs 274877906944 bytes
// (256 GiB), more than this machine's 125 GiB of memory") when a dense decode of nz z-slices
// (nz < 0: the whole volume) exceeds the address space or the machine's physical memory.
void checkDecodeMemory(const Volume& volume, int32_t nz = -1);

// Writes the decoded labels of z-slices [z0, z0 + nz) into `out` (dims[0] * dims[1] * nz values
// of the volume's scalar type, x fastest). Throws std::out_of_range for a z range outside the
// volume. The caller owns the memory (check it with checkDecodeMemory before allocating).
void decodeSlab(const Volume& volume, int32_t z0, int32_t nz, void* out,
  const ParallelFor& parallel = sequentialFor);
inline void decode(const Volume& volume, void* out, const ParallelFor& parallel = sequentialFor)
{
  decodeSlab(volume, 0, volume.geometry.dims[2], out, parallel);
}
// Allocates and decodes the whole volume (bytes of the scalar type, x fastest). Throws
// std::length_error naming the bytes needed when checkDecodeMemory refuses or the allocation
// itself fails, never std::bad_alloc.
std::vector<uint8_t> decode(const Volume& volume, const ParallelFor& parallel = sequentialFor);

} // namespace svdag
