// A categorical palette of saturated, distinct display colors, and the color science it is
// measured with (sRGB <-> CIELAB, D65). Generated here, not copied: greedy farthest-point
// selection in CIELAB over a grid of the sRGB gamut, restricted to medium lightness and high
// chroma, so that every color reads well under lighting, against a dark or a light background,
// and the first colors of the palette are the most different from each other.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

namespace svdag
{
namespace color
{

using RGB = std::array<double, 3>; // display sRGB in [0, 1]
using Lab = std::array<double, 3>; // CIELAB L*, a*, b* (D65 white)

double srgbToLinear(double c);
double linearToSrgb(double c);
Lab srgbToLab(const RGB& srgb);
// CIE76 color difference (Euclidean distance in CIELAB); about 2.3 is just noticeable, 25 and
// more is clearly a different color.
double labDistance(const Lab& a, const Lab& b);

// Limits of the palette's colors (the candidates outside them are never chosen).
constexpr double PaletteMinLightness = 40;
constexpr double PaletteMaxLightness = 82;
constexpr double PaletteMinChroma = 35;
// Colors of the generated palette; categoricalPalette(n) for more repeats it.
constexpr size_t PaletteSize = 256;

// The first min(n, PaletteSize) colors of the palette (computed once, a few milliseconds), then
// the palette repeated. Every prefix is itself a farthest-point palette: color k is the
// candidate farthest from colors 0..k-1.
std::vector<RGB> categoricalPalette(size_t n);

} // namespace color
} // namespace svdag
