// Writes the renderer's outputs to image files: PNG (8-bit sRGB RGBA, via zlib) and OpenEXR
// (linear float RGBA, depth as Z and the label as a UINT channel). Rows are written top first;
// the renderer's row 0 is the bottom row, so both writers flip. Throw std::runtime_error.
#pragma once

#include <svdag_render/Renderer.h>

#include <string>

namespace svdag
{
namespace render
{

void writePng(const Image& image, const std::string& path);
void writeExr(const Image& image, const std::string& path);

} // namespace render
} // namespace svdag
