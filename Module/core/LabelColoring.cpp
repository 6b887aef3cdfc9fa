// Default label colors from the adjacency (svdag/LabelColoring.h).
#include "svdag/LabelColoring.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace svdag
{

std::vector<uint32_t> colorLabels(
  size_t labelCount, const std::vector<LabelPair>& adjacency, size_t paletteColors)
{
  if (paletteColors == 0)
    throw std::invalid_argument("colorLabels: no palette colors");
  const size_t K = std::min(paletteColors, color::PaletteSize);
  const std::vector<color::RGB> palette = color::categoricalPalette(K);
  std::vector<color::Lab> lab(K);
  for (size_t c = 0; c < K; ++c)
    lab[c] = color::srgbToLab(palette[c]);
  std::vector<float> distance(K * K);
  for (size_t a = 0; a < K; ++a)
    for (size_t b = 0; b < K; ++b)
      distance[a * K + b] = float(color::labDistance(lab[a], lab[b]));

  // Neighbour lists (compressed rows).
  std::vector<size_t> start(labelCount + 1, 0);
  for (const LabelPair& p : adjacency)
  {
    if (p[0] >= labelCount || p[1] >= labelCount)
      throw std::out_of_range("colorLabels: a label pair indexes past the label count");
    ++start[p[0] + 1];
    ++start[p[1] + 1];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<uint32_t> neighbours(start.back());
  {
    std::vector<size_t> fill(start.begin(), start.end() - 1);
    for (const LabelPair& p : adjacency)
    {
      neighbours[fill[p[0]]++] = p[1];
      neighbours[fill[p[1]]++] = p[0];
    }
  }
  // The most constrained labels first: a label with many neighbours has the most colors to stay
  // away from, and at its turn few of them are colored yet.
  std::vector<uint32_t> order(labelCount);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return start[a + 1] - start[a] > start[b + 1] - start[b];
  });

  constexpr uint32_t Uncolored = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> colors(labelCount, Uncolored);
  std::vector<uint64_t> used(K, 0);
  std::vector<float> score(K);
  for (const uint32_t label : order)
  {
    std::fill(score.begin(), score.end(), float(ColoringEnoughDistance));
    for (size_t i = start[label]; i < start[label + 1]; ++i)
    {
      const uint32_t c = colors[neighbours[i]];
      if (c == Uncolored)
        continue;
      const float* row = &distance[size_t(c) * K];
      for (size_t k = 0; k < K; ++k)
        score[k] = std::min(score[k], row[k]);
    }
    size_t best = 0;
    for (size_t k = 1; k < K; ++k)
      if (score[k] > score[best] || (score[k] == score[best] && used[k] < used[best]))
        best = k;
    colors[label] = uint32_t(best);
    ++used[best];
  }
  return colors;
}

std::vector<color::RGB> distinctLabelColors(const Volume& volume, const ParallelFor& parallel)
{
  const std::vector<uint32_t> indices =
    colorLabels(volume.labels.size(), labelAdjacency(volume, parallel));
  const std::vector<color::RGB> palette = color::categoricalPalette(ColoringPaletteColors);
  std::vector<color::RGB> out(indices.size());
  for (size_t i = 0; i < indices.size(); ++i)
    out[i] = palette[indices[i]];
  return out;
}

} // namespace svdag
