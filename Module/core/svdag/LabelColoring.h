// Default label colors that tell touching labels apart: a greedy graph coloring of the label
// adjacency (svdag/LabelAdjacency.h) with the categorical palette (svdag/Palette.h).
#pragma once

#include "svdag/LabelAdjacency.h"
#include "svdag/Palette.h"
#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace svdag
{

// Palette colors the coloring chooses from (the first ones of categoricalPalette).
constexpr size_t ColoringPaletteColors = 128;
// CIELAB distance above which two colors count as "clearly different": a label takes, among the
// colors at least this far from every colored neighbour, the one used least so far, so that
// labels far apart get varied colors instead of the same few extremes.
constexpr double ColoringEnoughDistance = 40;

// Palette index (< paletteColors) of each of labelCount labels. Labels are colored in order of
// decreasing degree (ties: lower index first); each takes the palette color that maximises its
// minimum CIELAB distance to the colors of its already-colored neighbours, capped at
// ColoringEnoughDistance; ties go to the color used least so far, then to the lower palette
// index. Deterministic. Pairs must index labels below labelCount (std::out_of_range otherwise).
std::vector<uint32_t> colorLabels(size_t labelCount, const std::vector<LabelPair>& adjacency,
  size_t paletteColors = ColoringPaletteColors);

// The default color (display sRGB) of every label of the volume, in table order: the coloring
// above over the volume's label adjacency.
std::vector<color::RGB> distinctLabelColors(
  const Volume& volume, const ParallelFor& parallel = sequentialFor);

} // namespace svdag
