// The DAG as byte streams, the body of a .svdag 4.0 file (private to the core; File.h has the
// container, which compresses each stream with zstd).
//
// A bit-packed volume compresses poorly (its fields straddle byte boundaries), so the streams
// hold one kind of field each, byte-aligned: node headers, reference flags, the indices of
// references to nodes seen before, leaf masks, block cells and labels. References follow the
// pools' first-use order (blocks -> roots -> mids -> leaves, each pool in the order its parent
// pool first references it, which is how a build lays a volume out): a reference to a node not
// referenced before is the next node of its pool and costs one flag, so only references to
// shared nodes carry an index. Nothing a load can derive is stored: no bit offsets, no block
// bounds, no label voxel counts or bounds (Volume::deriveBoundsAndValidate).
//
// Streams, in order (varint: unsigned LEB128, at most 10 bytes):
//   LabelValues  the label values in increasing order of the type, each a varint: the first its
//                distance from the type's smallest value, each next one its distance from the
//                previous one minus one
//   BlockCells   per block, a varint: its cell minus the previous block's (the first: its cell)
//   BlockLabels  per block, a varint: its label index
//   BlockRoots   per block, a byte: complement (bit 0), shared (bit 1: its index follows in
//                RootIndices; else the next root not referenced before)
//   RootIndices  per shared root reference, a varint: the root's index in its pool
//   RootHeaders  per root, 2 bytes: mixed mask, full mask
//   RootRefs     per mixed child of a root, in child order, a byte as BlockRoots' for the mids
//   MidIndices   per shared mid reference, a varint
//   MidHeaders   per mid, 2 bytes
//   MidRefs      per mixed child of a mid, a byte: complement (bit 0), symmetry (bits 1-6),
//                shared (bit 7)
//   LeafIndices  per shared leaf reference, a varint
//   Leaves       per leaf, its 64-bit mask, little-endian
#pragma once

#include "svdag/Volume.h"
#include "PooledGraph.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace svdag
{
namespace dagstreams
{

enum Stream : uint32_t
{
  LabelValues,
  BlockCells,
  BlockLabels,
  BlockRoots,
  RootIndices,
  RootHeaders,
  RootRefs,
  MidIndices,
  MidHeaders,
  MidRefs,
  LeafIndices,
  Leaves,
  StreamCount
};
const char* streamName(uint32_t stream);

using Streams = std::array<std::vector<uint8_t>, StreamCount>;

// What the file's header holds besides the streams: the volume with its geometry, scalar type,
// background, field widths and counts (blockCount, rootCount, midCount), and the label and leaf
// counts.
struct Shape
{
  Volume frame; // labels, blocks and the pools left empty
  uint64_t labelCount = 0;
  uint64_t leafCount = 0;
};

// The streams of a valid volume in the pooled form (std::logic_error for a compact one: files
// store the pooled form, Compact.h) and the shape of the volume they decode to: the same voxels in
// the same blocks, its pools renumbered in first-use order (for a built volume: the volume
// itself, bit for bit), each reference field as wide as the volume's or as the renumbered
// references need, leaves no reference reaches left out.
struct Encoded
{
  Streams streams;
  Shape shape;
};
Encoded encode(const Volume& volume);

// The most bytes a stream of a valid file can hold for a shape: what a reader lets it
// decompress to.
uint64_t maxStreamBytes(uint32_t stream, const Shape& shape);

// The volume the streams describe, its block bounds and label voxel counts and bounds not yet
// derived (Volume::deriveBoundsAndValidate does that and checks the rest). Throws
// std::runtime_error naming the problem for streams that do not fit the shape: every field read
// is checked, and the memory used is bounded by the streams' sizes (a count the shape gives is
// allocated only once a stream holds that many entries).
// Where `graph` is given (empty), it receives the volume's node graph as the streams give it
// (PooledGraph.h), which Volume::deriveBoundsAndValidate then reads instead of walking the node
// streams once more.
Volume decode(const Streams& streams, const Shape& shape, PooledGraph* graph = nullptr);

} // namespace dagstreams
} // namespace svdag
