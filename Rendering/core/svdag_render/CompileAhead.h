// Compiling ahead of the first frame. On a device whose driver compiles shaders on the CPU
// (lavapipe) the path tracer's and the denoiser's compilation is most of a first image's wait
// when the caches are empty (bench/startup.py); an application that knows its settings before
// its volume is read can have them compiled meanwhile, on another core.
#pragma once

#include "svdag_render/RenderSettings.h"

namespace svdag
{
namespace render
{

// Compiles the pipelines a first frame with these settings needs (the path tracer's variant,
// its edge coverage pass and the denoiser), or loads them from the driver's cache, by rendering
// a 2 x 2 image of a one-voxel volume with a renderer of its own on the process's shared device
// (Device). A renderer with the same settings then finds them compiled: the device keeps its
// pipelines, and a renderer that asks for one being compiled waits for it rather than compiling
// it again. Call it while another renderer holds the device: a device goes with its last user,
// and its pipelines with it (the driver's disk cache, where there is one, keeps what it keeps).
// Label materials are not known here: emission and transmission are taken as unused, as by
// default. Thread-safe; throws what the renderer throws (std::runtime_error).
void compileAhead(const RenderSettings& settings);

} // namespace render
} // namespace svdag
