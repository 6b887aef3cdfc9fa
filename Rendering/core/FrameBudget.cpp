#include "svdag_render/FrameBudget.h"

#include <cmath>
#include <vector>

namespace svdag
{
namespace render
{
namespace
{
// Cost of a coarser LOD relative to the voxel LOD, for levels not measured yet.
double relativeCost(Lod lod)
{
  switch (lod)
  {
    case Lod::Block: return 0.6;
    case Lod::Leaf: return 0.8;
    default: return 1.0;
  }
}

bool coarser(Lod candidate, Lod finest)
{
  // Auto sits between voxel and leaf in cost; block < leaf < auto < voxel in detail.
  auto rank = [](Lod l) {
    switch (l)
    {
      case Lod::Block: return 0;
      case Lod::Leaf: return 1;
      case Lod::Auto: return 2;
      case Lod::Voxel: return 3;
    }
    return 3;
  };
  return rank(candidate) < rank(finest);
}
} // namespace

double FrameBudget::predict(const FrameLevel& level, uint64_t pixels) const
{
  double cost = this->CostPerPixel[size_t(level.lod)];
  if (cost < 0)
  {
    // From a measured level: scale by the relative costs.
    for (Lod known : { Lod::Voxel, Lod::Auto, Lod::Leaf, Lod::Block })
    {
      const double c = this->CostPerPixel[size_t(known)];
      if (c >= 0)
      {
        cost = c * relativeCost(level.lod) / relativeCost(known);
        break;
      }
    }
  }
  if (cost < 0)
    return 0;
  const double traced = double(pixels) / (double(level.reduction) * level.reduction);
  return this->OverheadSeconds + cost * traced;
}

FrameLevel FrameBudget::choose(Lod finest, uint64_t pixels, double budgetSeconds) const
{
  FrameLevel best{ finest, 1 };
  if (!(budgetSeconds > 0) || !std::isfinite(budgetSeconds))
    return best;
  std::vector<Lod> lods{ finest };
  for (Lod l : { Lod::Leaf, Lod::Block })
  {
    if (coarser(l, finest))
      lods.push_back(l);
  }
  for (uint32_t reduction = 1; reduction <= MaximumReduction; ++reduction)
  {
    for (Lod lod : lods)
    {
      best = FrameLevel{ lod, reduction };
      if (this->predict(best, pixels) <= budgetSeconds)
        return best;
    }
  }
  return best;
}

void FrameBudget::record(
  Lod lod, uint64_t tracedPixels, double traceSeconds, double overheadSeconds, bool provisional)
{
  if (tracedPixels == 0 || !(traceSeconds >= 0) || !std::isfinite(traceSeconds))
    return;
  const size_t i = size_t(lod);
  double& cost = this->CostPerPixel[i];
  if (provisional && cost >= 0)
    return;
  // An exponential average: adapts within a few frames, smooths the noise of shared machines.
  const double measured = traceSeconds / double(tracedPixels);
  cost = (cost < 0 || this->Provisional[i]) ? measured : 0.5 * cost + 0.5 * measured;
  this->Provisional[i] = provisional;
  if (overheadSeconds >= 0 && std::isfinite(overheadSeconds) &&
    (!provisional || this->OverheadProvisional))
  {
    this->OverheadSeconds = this->OverheadProvisional
      ? overheadSeconds : 0.5 * this->OverheadSeconds + 0.5 * overheadSeconds;
    this->OverheadProvisional = provisional;
  }
}

} // namespace render
} // namespace svdag
