// Where the bytes of a compressed volume go, level by level, and what the known remedies would
// save: nodes equal up to a mirror or a cube symmetry (symmetry-aware DAGs), and how skewed the
// reference counts are (what ordering nodes by use or entropy-coding references could win).
// VTK-free; vtkSegmentationSVDAGEncodingStatistics puts it in a vtkTable.
#pragma once

#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <array>
#include <cstdint>
#include <string>

namespace svdag
{

enum class EncodingLevel : uint8_t
{
  Blocks = 0,
  Roots,
  Mids,
  Leaves
};
constexpr int EncodingLevelCount = 4;
const char* encodingLevelName(EncodingLevel level); // "blocks", "roots", "mids", "leaves"

struct LevelAnalysis
{
  // Bytes of this level in the compact form a volume in memory holds (Compact.h; what
  // Volume::memory counts). Everything else describes the pooled form: every node once in its
  // pool, a reference per mixed child, as files store it.
  uint64_t compactBytes = 0;
  // What this level stores in the pooled form (Layout.h).
  uint64_t nodes = 0;          // block records or distinct nodes
  uint64_t bits = 0;           // packed bits of the level's records or stream
  uint64_t headerBits = 0;     // everything but child references (node masks; block fields)
  uint64_t referenceBits = 0;  // child references held by this level
  uint64_t references = 0;     // how many (one per block; one per mixed child of a node)
  uint32_t referenceWidth = 0; // bits per reference held (into the next level)

  // References that point at this level's nodes (none for blocks): how skewed their counts are.
  uint64_t incomingReferences = 0;
  uint64_t referencedOnce = 0;    // nodes with exactly one incoming reference
  uint64_t maxIncoming = 0;       // incoming references of the most used node
  double top1PercentShare = 0;    // share of the incoming references that the most used 1% of
  double top10PercentShare = 0;   // the nodes (at least one node) receive; likewise 10%
  // Entropy of the target distribution in bits: what an ideal static code would spend on each
  // reference into this level, against the width spent today (the parent level's width).
  double referenceEntropyBits = 0;

  // Distinct nodes if nodes equal up to one of the 8 mirrors (resp. the 48 symmetries of the
  // cube: axis permutations with mirrors) were stored once, complements included as today.
  // Counted by 64-bit hashes of exact transformed contents (a collision would undercount).
  uint64_t mirrorClasses = 0;
  uint64_t symmetryClasses = 0;
  // Bits of this level in a DAG that shares those nodes: fewer, narrower-addressed nodes, with 3
  // (mirrors) or 6 (symmetries) more bits per reference to name the transform.
  uint64_t mirrorBits = 0;
  uint64_t symmetryBits = 0;
};

struct EncodingAnalysis
{
  std::array<LevelAnalysis, EncodingLevelCount> levels;
  uint64_t labelTableBytes = 0;
  const LevelAnalysis& operator[](EncodingLevel l) const { return levels[size_t(l)]; }
  LevelAnalysis& operator[](EncodingLevel l) { return levels[size_t(l)]; }
};

// Analyses a valid volume (Volume::validate). Time is linear in the nodes (48 transforms each;
// the mids' in parallel); memory is 384 bytes per mid node (a hash per symmetry) and 9 per block.
EncodingAnalysis analyzeEncoding(const Volume& volume, const ParallelFor& parallel = sequentialFor);

} // namespace svdag
