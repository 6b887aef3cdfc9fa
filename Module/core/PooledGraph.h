// A pooled volume's nodes as a graph, each reference resolved to the index of its node: what a
// 4.0 file's decoder (DagStreams.h) or one walk of the node streams gives, what validation
// (Volume::deriveBoundsAndValidate) checks and summarises, and what compaction (Compact.cpp)
// rewrites, so that a load reads each stream once (private to the core).
#pragma once

#include "svdag/Volume.h"

#include <cstdint>
#include <vector>

namespace svdag
{

struct PooledGraph
{
  struct Node
  {
    uint32_t header = 0; // mixed | full << 8
    uint32_t count = 0;  // mixed children
    uint32_t first = 0;  // where its children's references start in its level's array
  };
  std::vector<Node> mids, roots; // in stream order
  std::vector<uint32_t> leafRefs;   // per mixed child of a mid, child order: its leaf reference
  std::vector<uint32_t> midRefs;    // per mixed child of a root: mid index << 1 | complement
  std::vector<uint32_t> blockRoots; // per block: root index << 1 | complement
};

// The graph of a valid pooled volume. Throws std::runtime_error for a reference that misses
// its pool's node starts.
PooledGraph pooledGraph(const Volume& pooledVolume);

// compacted() of a valid pooled volume and its graph.
Volume compacted(Volume pooledVolume, PooledGraph graph);

} // namespace svdag
