// The two forms of a volume's DAG (Layout.h). Builders and files work on the POOLED form (every
// node in its level's pool, a reference per mixed child), which Volume::validate checks; a volume
// in memory holds the COMPACT form, in which the children referenced once in the whole volume (65-85%
// of the leaves, 80-99% of the mids) cost no reference: leaves inline in their mid node, mids
// chained after a base offset in their root.
#pragma once

#include "svdag/Volume.h"

namespace svdag
{

// The compact form of a pooled volume (returned as is when it is compact already). Its order is
// defined by the content alone: roots in the order the blocks first use them, each root's chained
// mids where the root is first used, shared nodes at their first use. The volume must be valid.
Volume compacted(Volume pooledVolume);

// The pooled form of a compact volume (returned as is when it is pooled already), with every
// node canonical again (leaves stored up to symmetry and complement as the builder stores them),
// so that compacted(pooled(v)) == v and files are what a build writes. Throws
// std::runtime_error for a malformed compact volume (a stream overrun, a reference outside its
// pool) rather than reading out of bounds.
Volume pooled(Volume compactVolume);

// `volume` itself when it is pooled (not copied), else its pooled form, made in `holder`.
// Throws as pooled() does.
const Volume& pooledView(const Volume& volume, Volume& holder);

} // namespace svdag
