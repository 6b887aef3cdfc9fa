// The categorical palette (svdag/Palette.h).
#include "svdag/Palette.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace svdag
{
namespace color
{

double srgbToLinear(double c)
{
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

double linearToSrgb(double c)
{
  return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1 / 2.4) - 0.055;
}

namespace
{
// CIELAB of linear sRGB (r, g, b).
Lab linearToLab(double r, double g, double b)
{
  // Linear sRGB to XYZ (IEC 61966-2-1), relative to the D65 white (Xn, Yn, Zn).
  const double x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
  const double y = (0.2126 * r + 0.7152 * g + 0.0722 * b) / 1.0;
  const double z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
  const auto f = [](double t) {
    constexpr double delta = 6.0 / 29.0;
    return t > delta * delta * delta ? std::cbrt(t) : t / (3 * delta * delta) + 4.0 / 29.0;
  };
  const double fx = f(x), fy = f(y), fz = f(z);
  return { { 116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz) } };
}

double squaredLabDistance(const Lab& a, const Lab& b)
{
  const double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
  return d0 * d0 + d1 * d1 + d2 * d2;
}
} // namespace

Lab srgbToLab(const RGB& srgb)
{
  return linearToLab(srgbToLinear(srgb[0]), srgbToLinear(srgb[1]), srgbToLinear(srgb[2]));
}

double labDistance(const Lab& a, const Lab& b)
{
  return std::sqrt(squaredLabDistance(a, b));
}

namespace
{
std::vector<RGB> generatePalette()
{
  // Candidates: a 33^3 grid of the sRGB cube (steps of 1/32), in gamut by construction. Each
  // channel takes 33 values: their linear values are computed once (srgbToLab's, for each).
  constexpr int Steps = 32;
  double linear[Steps + 1];
  for (int k = 0; k <= Steps; ++k)
    linear[k] = srgbToLinear(double(k) / Steps);
  std::vector<RGB> rgb;
  std::vector<Lab> lab;
  for (int r = 0; r <= Steps; ++r)
    for (int g = 0; g <= Steps; ++g)
      for (int b = 0; b <= Steps; ++b)
      {
        const RGB c{ { double(r) / Steps, double(g) / Steps, double(b) / Steps } };
        const Lab l = linearToLab(linear[r], linear[g], linear[b]);
        const double chroma = std::hypot(l[1], l[2]);
        if (l[0] < PaletteMinLightness || l[0] > PaletteMaxLightness || chroma < PaletteMinChroma)
          continue;
        rgb.push_back(c);
        lab.push_back(l);
      }
  // Greedy farthest-point selection. The first color is the candidate farthest from mid gray
  // (the most saturated one), so that the start does not depend on the grid's order; each next
  // one maximises its distance to the nearest color chosen so far (ties: the first candidate).
  // Distances are compared squared, without a square root per candidate (squaring keeps their
  // order; the palette came out the same, color for color, as with the square roots).
  const Lab gray{ { 0.5 * (PaletteMinLightness + PaletteMaxLightness), 0, 0 } };
  std::vector<double> nearest(lab.size());
  for (size_t i = 0; i < lab.size(); ++i)
    nearest[i] = squaredLabDistance(lab[i], gray);
  std::vector<RGB> palette;
  const size_t n = std::min(PaletteSize, lab.size());
  while (palette.size() < n)
  {
    const size_t best = size_t(std::max_element(nearest.begin(), nearest.end()) - nearest.begin());
    palette.push_back(rgb[best]);
    const Lab chosen = lab[best];
    // The first pick's distances were to gray, not to a palette color: start them afresh.
    for (size_t i = 0; i < lab.size(); ++i)
    {
      const double d = squaredLabDistance(lab[i], chosen);
      nearest[i] = palette.size() == 1 ? d : std::min(nearest[i], d);
    }
  }
  return palette;
}
} // namespace

std::vector<RGB> categoricalPalette(size_t n)
{
  // A function-local static: computed once, thread-safe (C++11).
  static const std::vector<RGB> palette = generatePalette();
  std::vector<RGB> out(n);
  for (size_t i = 0; i < n; ++i)
    out[i] = palette[i % palette.size()];
  return out;
}

} // namespace color
} // namespace svdag
