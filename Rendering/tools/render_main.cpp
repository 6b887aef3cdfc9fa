// vtksvdag-render: renders a .svdag file with the Vulkan renderer, without VTK, to PNG or EXR,
// and prints one JSON line with the device and the timings. It exists so the renderer can run on
// a GPU machine that has no VTK.
//
//   vtksvdag-render INPUT.svdag OUTPUT.png|OUTPUT.exr [--width 512] [--height 512]
//     [--lod block|leaf|voxel|auto (default auto)] [--azimuth 30] [--elevation 20] [--zoom 1]
//     [--view-angle 30] [--hide 0,5,7] [--frames 1] [--spp 1] [--bounces 4] [--seed 0]
//     [--no-nee] [--denoise|--no-denoise] [--environment MAP.exr] [--sun AZ,EL]
//     [--backend auto|rt|compute] [--restart] [--preview] [--trace-reduction R]
//     [--shading voxel|smooth] [--clip OX,OY,OZ,NX,NY,NZ]...
//
// Unset options take svdag::render::RenderSettings' defaults (LOD auto, bounces 4, seed 0, NEE
// on, denoiser on, backend auto). --backend picks how rays find the blocks (RenderSettings.h; auto: per device). --restart makes
// every frame start a new accumulation (what a frame costs while the camera moves). --preview
// previews while the pipeline compiles (Renderer::setPreviewWhileCompiling: the first frame of
// a process is the small preview pipeline's, the full one compiles in the background, unless
// the full one's compute shader binary is on disk: then it is created at once).
// --trace-reduction R (1..8, default 1) traces the paths on 1/R of the pixels per axis and
// upsamples them guided by every pixel's own label and depth (Renderer::setTraceReduction: what
// the VTK mapper's interactive frames do); frame times include the guides' trace.
// The JSON's pipeline_compile_seconds is the compile time of the last frame's pipeline,
// previewed whether that frame was a preview, and shader_objects whether compute shaders are
// shader objects whose binaries are kept on disk.
// Every frame adds --spp path-traced samples per pixel to the accumulated image. --sun places a
// disk sun (the renderer's default size and irradiance) at azimuth AZ (degrees from +x towards
// +y) and elevation EL (degrees above the xy plane).
//
// --shading and --clip (a clipping plane in world units, keeping the side the normal points to;
// repeatable) are `vtksvdag render`'s options of the same names.
//
// The camera frames the whole volume (svdag::render::frameVolume). --hide takes label INDICES
// (positions in the volume's sorted label table). --frames renders several frames and reports
// the mean time of all but the first (which includes the driver's shader compilation) when more
// than one is rendered. Exit status: 0 on success, 1 on bad arguments, 2 on a rendering or file
// error (message on stderr).
#include "svdag_render/ImageFiles.h"

#include <svdag/File.h>
#include <svdag_render/Renderer.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{
// The renderer's own defaults (RenderSettings.h) for what the tool does not set.
const svdag::render::RenderSettings defaults;

struct Options
{
  std::string input, output;
  uint32_t width = 512, height = 512;
  svdag::render::Lod lod = defaults.lod;
  double azimuth = 30, elevation = 20, zoom = 1, viewAngle = 30;
  std::vector<uint32_t> hidden;
  int frames = 1;
  uint32_t spp = 1, bounces = defaults.maximumBounces, seed = defaults.seed;
  bool nee = defaults.nextEventEstimation;
  bool denoise = defaults.denoise;
  std::string environment;
  bool sun = false;
  double sunAzimuth = 0, sunElevation = 0;
  svdag::render::Backend backend = defaults.backend;
  bool restart = false;
  bool preview = false;
  uint32_t traceReduction = svdag::render::Renderer::DefaultTraceReduction;
  svdag::render::Shading shading = defaults.shading;
  std::vector<svdag::render::ClipPlane> clipPlanes;
};

struct UsageError : std::invalid_argument
{
  using std::invalid_argument::invalid_argument;
};

double number(const std::string& flag, const std::string& text)
{
  size_t used = 0;
  double v = 0;
  try
  {
    v = std::stod(text, &used);
  }
  catch (const std::exception&)
  {
    used = 0;
  }
  if (used != text.size() || text.empty())
    throw UsageError(flag + " needs a number, got '" + text + "'");
  return v;
}

uint32_t count(const std::string& flag, const std::string& text, double lo, double hi)
{
  const double v = number(flag, text);
  if (v != double(uint64_t(v)) || v < lo || v > hi)
    throw UsageError(flag + " needs an integer in [" + std::to_string(uint64_t(lo)) + ", " +
      std::to_string(uint64_t(hi)) + "], got '" + text + "'");
  return uint32_t(v);
}

Options parse(int argc, char** argv)
{
  Options o;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0)
    {
      positional.push_back(arg);
      continue;
    }
    if (arg == "--no-nee")
    {
      o.nee = false;
      continue;
    }
    if (arg == "--denoise" || arg == "--no-denoise")
    {
      o.denoise = arg == "--denoise";
      continue;
    }
    if (arg == "--restart")
    {
      o.restart = true;
      continue;
    }
    if (arg == "--preview")
    {
      o.preview = true;
      continue;
    }
    if (i + 1 >= argc)
      throw UsageError(arg + " needs a value");
    const std::string value = argv[++i];
    if (arg == "--width")
      o.width = count(arg, value, 1, 16384);
    else if (arg == "--height")
      o.height = count(arg, value, 1, 16384);
    else if (arg == "--lod")
      o.lod = svdag::render::parseLod(value);
    else if (arg == "--trace-reduction")
      o.traceReduction =
        count(arg, value, 1, svdag::render::Renderer::MaximumTraceReduction);
    else if (arg == "--backend")
      o.backend = svdag::render::parseBackend(value);
    else if (arg == "--azimuth")
      o.azimuth = number(arg, value);
    else if (arg == "--elevation")
      o.elevation = number(arg, value);
    else if (arg == "--zoom")
      o.zoom = number(arg, value);
    else if (arg == "--view-angle")
      o.viewAngle = number(arg, value);
    else if (arg == "--frames")
      o.frames = int(count(arg, value, 1, 1000));
    else if (arg == "--spp")
      o.spp = count(arg, value, 1, 65536);
    else if (arg == "--bounces")
      o.bounces = count(arg, value, 0, 64);
    else if (arg == "--seed")
      o.seed = count(arg, value, 0, 4294967295.0);
    else if (arg == "--environment")
      o.environment = value;
    else if (arg == "--sun")
    {
      const size_t comma = value.find(',');
      if (comma == std::string::npos)
        throw UsageError("--sun needs AZ,EL in degrees, got '" + value + "'");
      o.sun = true;
      o.sunAzimuth = number(arg, value.substr(0, comma));
      o.sunElevation = number(arg, value.substr(comma + 1));
    }
    else if (arg == "--shading")
      o.shading = svdag::render::parseShading(value);
    else if (arg == "--clip")
    {
      std::stringstream list(value);
      std::string item;
      std::vector<double> v;
      while (std::getline(list, item, ','))
        v.push_back(number(arg, item));
      if (v.size() != 6)
        throw UsageError("--clip needs OX,OY,OZ,NX,NY,NZ, got '" + value + "'");
      svdag::render::ClipPlane plane;
      plane.origin = { { v[0], v[1], v[2] } };
      plane.normal = { { v[3], v[4], v[5] } };
      o.clipPlanes.push_back(plane);
    }
    else if (arg == "--hide")
    {
      std::stringstream list(value);
      std::string item;
      while (std::getline(list, item, ','))
        o.hidden.push_back(count(arg, item, 0, 4294967295.0));
    }
    else
      throw UsageError("unknown option " + arg);
  }
  if (positional.size() != 2)
    throw UsageError("expected INPUT.svdag and OUTPUT.png|OUTPUT.exr");
  o.input = positional[0];
  o.output = positional[1];
  return o;
}

bool endsWith(const std::string& s, const std::string& suffix)
{
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string jsonString(const std::string& s)
{
  std::string out = "\"";
  for (char c : s)
  {
    if (c == '"' || c == '\\')
      out += '\\';
    if (static_cast<unsigned char>(c) < 0x20)
      continue;
    out += c;
  }
  return out + "\"";
}
} // namespace

int main(int argc, char** argv)
{
  Options o;
  try
  {
    o = parse(argc, argv);
    if (!endsWith(o.output, ".png") && !endsWith(o.output, ".exr"))
      throw UsageError("the output file must end in .png or .exr");
  }
  catch (const std::invalid_argument& e)
  {
    std::cerr << "vtksvdag-render: " << e.what() << "\nusage: vtksvdag-render INPUT.svdag "
              << "OUTPUT.png|OUTPUT.exr [--width N] [--height N] [--lod "
              << svdag::render::lodNames("|") << "] "
              << "[--azimuth DEG] [--elevation DEG] [--zoom F] [--view-angle DEG] "
              << "[--hide I,J,...] [--frames N] [--spp N] [--bounces N] [--seed N] [--no-nee] "
              << "[--denoise|--no-denoise] [--environment MAP.exr] [--sun AZ,EL] [--backend "
              << svdag::render::backendNames("|") << "] [--restart] [--preview] "
              << "[--trace-reduction R] [--shading " << svdag::render::shadingNames("|")
              << "] [--clip OX,OY,OZ,NX,NY,NZ]...\n";
    return 1;
  }
  try
  {
    auto volume = std::make_shared<const svdag::Volume>(svdag::readFile(o.input));
    svdag::render::Renderer renderer;
    renderer.setBackend(o.backend);
    renderer.setVolume(volume);
    if (!o.hidden.empty())
      renderer.setHiddenLabels(o.hidden);
    renderer.setImageSize(o.width, o.height);
    renderer.setTraceReduction(o.traceReduction);
    renderer.setLod(o.lod);
    renderer.setCamera(
      svdag::render::frameVolume(volume->geometry, o.azimuth, o.elevation, o.zoom, o.viewAngle));
    renderer.setSamplesPerPixel(o.spp);
    renderer.setMaximumBounces(o.bounces);
    renderer.setSeed(o.seed);
    renderer.setNextEventEstimation(o.nee);
    renderer.setDenoise(o.denoise);
    renderer.setPreviewWhileCompiling(o.preview);
    renderer.setShading(o.shading);
    if (!o.clipPlanes.empty())
      renderer.setClipping(o.clipPlanes);
    if (!o.environment.empty())
      renderer.setEnvironmentMap(o.environment);
    if (o.sun)
    {
      const double degree = 3.14159265358979323846 / 180;
      svdag::render::SunLight sun;
      sun.on = true;
      sun.direction = { { std::cos(o.sunElevation * degree) * std::cos(o.sunAzimuth * degree),
        std::cos(o.sunElevation * degree) * std::sin(o.sunAzimuth * degree),
        std::sin(o.sunElevation * degree) } };
      renderer.setSun(sun);
    }
    std::vector<double> timed;
    for (int f = 0; f < o.frames; ++f)
    {
      if (o.restart)
        renderer.resetAccumulation();
      // Without restarts only the last frame's image is written: the denoiser filters only it.
      const bool shown = o.restart || f + 1 == o.frames;
      renderer.render(shown ? svdag::render::Renderer::PassUse::Shown
                            : svdag::render::Renderer::PassUse::Accumulating);
      if (f > 0 || o.frames == 1)
        timed.push_back(renderer.lastFrameMilliseconds());
    }
    double total = 0;
    for (double ms : timed)
      total += ms;
    const double msPerFrame = total / double(timed.size());
    std::sort(timed.begin(), timed.end());
    const double msMedian = timed.size() % 2 ? timed[timed.size() / 2]
                                             : (timed[timed.size() / 2 - 1] + timed[timed.size() / 2]) / 2;
    const svdag::render::DeviceBytes bytes = renderer.deviceBytesByPart();
    if (endsWith(o.output, ".png"))
      svdag::render::writePng(renderer.image(), o.output);
    else
      svdag::render::writeExr(renderer.image(), o.output);
    auto u = [](uint64_t v) { return (unsigned long long)v; };
    std::printf("{\"device\": %s, \"backend\": \"%s\", \"width\": %u, \"height\": %u, "
                "\"lod\": \"%s\", \"spp\": %u, \"bounces\": %u, \"nee\": %s, \"denoise\": %s, \"restart\": %s, "
                "\"trace_reduction\": %u, "
                "\"setup_seconds\": %.6f, \"render_seconds\": %.6f, \"ms_per_frame\": %.3f, "
                "\"ms_median\": %.3f, \"bytes_blas\": %llu, \"bytes_tlas\": %llu, "
                "\"pipeline_compile_seconds\": %.6f, \"previewed\": %s, \"shader_objects\": %s, "
                "\"visible_blocks\": %llu, \"bytes_device\": {\"encoding\": %llu, "
                "\"acceleration\": %llu, \"materials\": %llu, \"neighbours\": %llu, "
                "\"images\": %llu, \"other\": %llu, \"total\": %llu}}\n",
      jsonString(renderer.deviceName()).c_str(), svdag::render::backendName(renderer.backend()),
      o.width, o.height, svdag::render::lodName(o.lod), renderer.accumulatedSamples(), o.bounces,
      o.nee ? "true" : "false", o.denoise ? "true" : "false", o.restart ? "true" : "false",
      renderer.traceReduction(), renderer.setupSeconds(),
      renderer.renderSeconds(), msPerFrame, msMedian, u(renderer.blasBytes()),
      u(renderer.tlasBytes()), renderer.pipelineCompileSeconds(),
      renderer.previewed() ? "true" : "false",
      renderer.pipelineCache().shaderObjects ? "true" : "false", u(renderer.visibleBlocks()),
      u(bytes.encoding),
      u(bytes.acceleration), u(bytes.materials), u(bytes.neighbours), u(bytes.images),
      u(bytes.other), u(bytes.total));
    return 0;
  }
  catch (const std::exception& e)
  {
    std::cerr << "vtksvdag-render: " << e.what() << "\n";
    return 2;
  }
}
