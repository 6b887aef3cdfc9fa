// A pooled volume's nodes as one walk of its streams reads them: what compaction (Compact.cpp)
// rewrites, and what validation (Volume::deriveBoundsAndValidate) reads anyway, so that a load
// walks each stream once (private to the core).
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
