// The coded form of a Volume, the body of a .svdag 3.0 file (private to the core; File.h has the
// container around it).
//
// It holds what a build needs to write the volume again and nothing it can derive: the label
// values and, cell by cell, which labels occur and the occupancy of each, arithmetic-coded
// (RangeCoder.h) with contexts from what is already known. Loading feeds the blocks' occupancy to
// the Builder (Builder::addBlock), which derives the rest (tight bounds, the shared DAG, the
// label counts and bounds) exactly as a build from the voxels does.
//
// The volume is cut into chunks of whole slabs, each its own stream (below). Within a chunk,
// cells come in index order; a run of empty cells costs one number. A cell's labels are coded as
// which labels of its -x, -y and -z neighbour cells occur in it, plus any others by index. Its
// blocks come in label order, each given the voxels no earlier block of the cell holds (so two
// labels' shared boundary is coded once), and the last one first says whether it simply takes all
// of them (every cell of a fully labelled volume). An occupancy is coded top-down over the same
// 8^3 and 4^3 octants as the DAG: each one that still has free voxels is none, all or some of
// them, in contexts of its neighbours' states; the voxels of a 4^3 leaf that is "some" are coded
// one by one in contexts of their already known neighbours.
#pragma once

#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace svdag
{
namespace coded
{

// What the coded form leaves to the file's header.
struct Frame
{
  Geometry geometry;
  ScalarType scalarType = ScalarType::UInt32;
  uint64_t background = 0;
  uint64_t labelCount = 0;
  uint64_t blockCount = 0; // the decoder refuses a stream that holds more blocks
};

Frame frameOf(const Volume& volume);

// The volume is coded in chunks, z-ranges of whole 16-slice slabs (Builder::pieceZRange), each
// an independent stream, so that chunks are coded and decoded in parallel (with canonicalLeaf's
// search for their leaves); one builder then takes their blocks in order. A chunk holds at least
// this many cells
// (4M voxels), so that what a chunk's models learn pays for itself, and there are at most
// MaxChunks of them.
constexpr uint64_t CellsPerChunk = 1024;
constexpr uint64_t MaxChunks = 64;
// The chunks the writer makes, and the most a reader takes (one per slab, at most MaxChunks).
uint32_t chunkCount(const Geometry& geometry);
uint32_t maxChunkCount(const Geometry& geometry);

// The coded bytes of a valid volume (Volume::validate):
//   u32 chunk count C (1..maxChunkCount), u64 bytes of the label stream,
//   C x (u64 bytes of the chunk's stream, u64 its blocks),
//   the label stream (the label values), then the chunks' streams in z order,
// every integer little-endian. Chunk i holds the slabs Builder::pieceZRange(dims z, i, C) gives.
// `chunks` 0 takes chunkCount's (what files hold); others are for tests.
std::vector<uint8_t> encode(
  const Volume& volume, const ParallelFor& parallel = sequentialFor, uint32_t chunks = 0);

// The volume a build from the coded voxels writes. Throws coding::CorruptStream (a
// std::runtime_error) naming the problem for a stream the encoder cannot have written with this
// frame; the work and memory any stream can cause are bounded by its size and the frame's block
// count.
Volume decode(const uint8_t* data, size_t size, const Frame& frame,
  const ParallelFor& parallel = sequentialFor);

// Empty if the two volumes hold the same voxels in the same blocks (cells, labels and
// occupancy: their DAGs may be laid out differently), else the first difference.
std::string compareOccupancy(const Volume& a, const Volume& b);

} // namespace coded
} // namespace svdag
