// One Vulkan device per process (Context.h's Device): renderers share it and its pipelines, keep
// their own scenes, images, byte counts and memory limits, and the device goes with its last
// user. References: each renderer's frames against the same renderer's frames alone (made while
// no other renderer exists), and the byte counts it has alone.
#include <svdag/Builder.h>
#include <svdag_render/Camera.h>
#include <svdag_render/CompileAhead.h>
#include <svdag_render/Context.h>
#include <svdag_render/PipelineCacheFile.h>
#include <svdag_render/Renderer.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

namespace
{
std::shared_ptr<const svdag::Volume> randomVolume(uint32_t seed)
{
  svdag::Geometry g;
  g.dims = { { 23 + int(seed % 5), 19, 17 } };
  std::mt19937 rng(seed);
  std::vector<uint16_t> labels(g.voxelCount());
  for (auto& l : labels)
    l = (rng() % 4 == 0) ? uint16_t(1 + rng() % 5) : 0;
  return std::make_shared<const svdag::Volume>(
    svdag::Builder::build(g, svdag::ScalarType::UInt16, labels.data()));
}

std::unique_ptr<svdag::render::Renderer> makeRenderer(
  const std::shared_ptr<const svdag::Volume>& volume, svdag::render::Backend backend)
{
  auto r = std::make_unique<svdag::render::Renderer>();
  r->setBackend(backend);
  r->setVolume(volume);
  r->setImageSize(40, 30);
  r->setCamera(svdag::render::frameVolume(volume->geometry, 30, 20));
  r->setSamplesPerPixel(2);
  return r;
}

struct Frame
{
  svdag::render::Image image;
  uint64_t bytes = 0;
};

Frame renderTwice(svdag::render::Renderer& r)
{
  r.render();
  Frame f;
  f.image = r.render();
  f.bytes = r.deviceBytes();
  return f;
}

void expectSameImage(const svdag::render::Image& a, const svdag::render::Image& b, size_t which)
{
  EXPECT_EQ(a.label, b.label) << "renderer " << which;
  EXPECT_EQ(a.depth, b.depth) << "renderer " << which;
  EXPECT_EQ(a.hdr, b.hdr) << "renderer " << which;
  EXPECT_EQ(a.color, b.color) << "renderer " << which;
}

const svdag::render::Backend Backends[] = { svdag::render::Backend::Compute,
  svdag::render::Backend::RayTracing };
} // namespace

TEST(DeviceSharing, RenderersShareOneDeviceAndRenderWhatTheyRenderAlone)
{
  ASSERT_EQ(svdag::render::Renderer::deviceUsers(), 0u);
  std::vector<std::shared_ptr<const svdag::Volume>> volumes;
  for (uint32_t i = 0; i < 4; ++i)
    volumes.push_back(randomVolume(11 + i));

  // Alone: one renderer at a time (the device is created and released for each).
  std::vector<Frame> alone;
  uint64_t lastSerial = 0;
  for (size_t i = 0; i < volumes.size(); ++i)
  {
    auto r = makeRenderer(volumes[i], Backends[i % 2]);
    EXPECT_EQ(svdag::render::Renderer::deviceUsers(), 1u);
    EXPECT_GT(r->deviceSerial(), lastSerial) << "the last user's device was kept";
    lastSerial = r->deviceSerial();
    alone.push_back(renderTwice(*r));
  }
  EXPECT_EQ(svdag::render::Renderer::deviceUsers(), 0u);

  // Together: one device, frames interleaved (each renderer submits after the others).
  std::vector<std::unique_ptr<svdag::render::Renderer>> together;
  for (size_t i = 0; i < volumes.size(); ++i)
    together.push_back(makeRenderer(volumes[i], Backends[i % 2]));
  EXPECT_EQ(svdag::render::Renderer::deviceUsers(), volumes.size());
  for (const auto& r : together)
  {
    EXPECT_EQ(r->deviceSerial(), together[0]->deviceSerial());
    EXPECT_EQ(r->deviceSerial(), lastSerial + 1);
  }
  std::vector<Frame> frames(volumes.size());
  for (int pass = 0; pass < 2; ++pass)
  {
    for (size_t i = 0; i < together.size(); ++i)
      frames[i].image = together[i]->render();
  }
  uint64_t sum = 0;
  for (size_t i = 0; i < together.size(); ++i)
  {
    frames[i].bytes = together[i]->deviceBytes();
    expectSameImage(frames[i].image, alone[i].image, i);
    EXPECT_EQ(frames[i].bytes, alone[i].bytes) << "renderer " << i << "'s own bytes";
    EXPECT_EQ(together[i]->pipelineBuilds(), 1u);
    sum += frames[i].bytes;
  }
  // Every byte on the device is one renderer's or the shared pipelines' (none is counted twice).
  EXPECT_EQ(together[0]->deviceAllocatedBytes(), sum + together[0]->sharedDeviceBytes());
  // One pipeline per backend for all four renderers.
  EXPECT_EQ(together[0]->pipelineCompilations(), 2u);

  // The device goes with its last user; the next one creates a new device.
  together.clear();
  EXPECT_EQ(svdag::render::Renderer::deviceUsers(), 0u);
  auto again = makeRenderer(volumes[0], Backends[0]);
  EXPECT_EQ(again->deviceSerial(), lastSerial + 2);
  expectSameImage(renderTwice(*again).image, alone[0].image, 0);
}

TEST(DeviceSharing, MemoryLimitIsPerRenderer)
{
  const auto volume = randomVolume(5);
  auto unlimited = makeRenderer(volume, svdag::render::Backend::Compute);
  unlimited->render();
  const uint64_t held = unlimited->deviceBytes();
  const svdag::render::DeviceBytes parts = unlimited->deviceBytesByPart();
  const uint64_t half = (parts.encoding + parts.acceleration) / 2;
  // A second renderer limited to fewer bytes than the volume needs fails, naming its own limit
  // and bytes; the first one, without a limit, keeps rendering, and its bytes do not count
  // against the second one's limit.
  svdag::render::Renderer limited;
  svdag::render::RenderSettings settings;
  settings.backend = svdag::render::Backend::Compute;
  settings.deviceMemoryLimit = half;
  limited.setSettings(settings);
  try
  {
    limited.setVolume(volume);
    FAIL() << "the volume fit under half the bytes of its streams and grid";
  }
  catch (const svdag::render::DeviceMemoryError& e)
  {
    const std::string message = e.what();
    EXPECT_NE(message.find("a limit of " + std::to_string(half) + " bytes"),
      std::string::npos) << message;
  }
  EXPECT_LE(limited.deviceBytes(), half);
  EXPECT_EQ(unlimited->render().label.size(), 40u * 30u);
  EXPECT_EQ(unlimited->deviceBytes(), held);
  // A limit above what it needs alone (with room for the transient staging buffers) is enough,
  // although the device holds more than that limit for both renderers together.
  settings.deviceMemoryLimit = held + held / 2;
  limited.setSettings(settings);
  limited.setVolume(volume);
  limited.setImageSize(40, 30);
  limited.setCamera(svdag::render::frameVolume(volume->geometry, 30, 20));
  EXPECT_NO_THROW(limited.render());
  EXPECT_EQ(limited.deviceBytes(), held);
  EXPECT_GE(limited.deviceAllocatedBytes(), 2 * held);
  EXPECT_GT(limited.deviceAllocatedBytes(), settings.deviceMemoryLimit);
}

TEST(DeviceSharing, AFailedDeviceIsReportedToEveryUserAndNotKept)
{
  {
    // Each user that asks while no device qualifies gets the error (nothing is remembered).
    setenv("SVDAG_VK_DEVICE", "no-such-device-xyz", 1);
    for (int user = 0; user < 2; ++user)
      EXPECT_THROW(svdag::render::Renderer(), std::runtime_error) << "user " << user;
    unsetenv("SVDAG_VK_DEVICE");
  }
  EXPECT_EQ(svdag::render::Renderer::deviceUsers(), 0u);
  // The variable is read when the device is created: a renderer made now gets a device.
  svdag::render::Renderer renderer;
  EXPECT_EQ(svdag::render::Renderer::deviceUsers(), 1u);
  // ... and while it exists, a second one shares it whatever the variable says now.
  setenv("SVDAG_VK_DEVICE", "no-such-device-xyz", 1);
  svdag::render::Renderer second;
  unsetenv("SVDAG_VK_DEVICE");
  EXPECT_EQ(second.deviceSerial(), renderer.deviceSerial());
  EXPECT_EQ(svdag::render::Renderer::deviceUsers(), 2u);
}

// An empty XDG_CACHE_HOME of this test's own for as long as it lives (the pipeline cache and the
// shader binaries go there), with VTKSVDAG_PIPELINE_CACHE unset; removed again on every way out.
struct TemporaryCacheHome
{
  std::filesystem::path path;
  explicit TemporaryCacheHome(const std::string& name)
    : path(std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid())))
  {
    std::filesystem::remove_all(this->path);
    setenv("XDG_CACHE_HOME", this->path.c_str(), 1);
    unsetenv("VTKSVDAG_PIPELINE_CACHE");
  }
  ~TemporaryCacheHome()
  {
    unsetenv("VTKSVDAG_PIPELINE_CACHE");
    unsetenv("XDG_CACHE_HOME");
    std::filesystem::remove_all(this->path);
  }
};

// The device's pipeline cache outlives it on disk (PipelineCacheFile.h): the next device starts
// from the file, a corrupt file is ignored (same image, a reason given) and replaced by the next
// compilation, and VTKSVDAG_PIPELINE_CACHE=0 keeps it in memory only.
TEST(DeviceSharing, PipelineCacheFileIsReusedAndABadOneIgnored)
{
  namespace fs = std::filesystem;
  const TemporaryCacheHome cache("svdag-xdg");
  const fs::path& home = cache.path;
  const auto volume = randomVolume(7);
  ASSERT_EQ(svdag::render::Renderer::deviceUsers(), 0u);

  std::string file;
  Frame reference;
  {
    auto r = makeRenderer(volume, svdag::render::Backend::Compute);
    reference = renderTwice(*r);
    const auto status = r->pipelineCache();
    file = status.file;
    EXPECT_EQ(file.rfind((home / "vtksvdag" / "pipelines-").string(), 0), 0u) << file;
    EXPECT_EQ(status.loadedBytes, 0u);
    EXPECT_EQ(status.problem, "");
  }
  ASSERT_TRUE(fs::is_regular_file(file)) << file;
  const uintmax_t saved = fs::file_size(file);
  {
    auto r = makeRenderer(volume, svdag::render::Backend::Compute);
    const auto status = r->pipelineCache();
    EXPECT_EQ(status.file, file);
    // The driver's data (at least its 32-byte header) behind our 64-byte header.
    EXPECT_EQ(status.loadedBytes + 64, saved);
    EXPECT_EQ(status.problem, "");
    expectSameImage(renderTwice(*r).image, reference.image, 0);
  }
  // Garbage, then a file cut short: ignored with a reason; the image is the same; the next
  // compilation writes a sound file again.
  for (const size_t keep : { size_t(0), size_t(saved - 1) })
  {
    std::vector<char> bytes(saved);
    {
      std::ifstream in(file, std::ios::binary);
      in.read(bytes.data(), std::streamsize(saved));
    }
    if (keep == 0)
      for (size_t i = 0; i < bytes.size(); ++i)
        bytes[i] = char(i * 31 + 5);
    else
      bytes.resize(keep);
    {
      std::ofstream out(file, std::ios::binary | std::ios::trunc);
      out.write(bytes.data(), std::streamsize(bytes.size()));
    }
    auto r = makeRenderer(volume, svdag::render::Backend::Compute);
    const auto status = r->pipelineCache();
    EXPECT_EQ(status.loadedBytes, 0u) << keep;
    EXPECT_NE(status.problem, "") << keep;
    expectSameImage(renderTwice(*r).image, reference.image, 0);
    EXPECT_EQ(r->pipelineCache().problem, status.problem) << "the save failed";
    EXPECT_EQ(fs::file_size(file), saved) << "not rewritten";
  }
  {
    auto r = makeRenderer(volume, svdag::render::Backend::Compute);
    EXPECT_EQ(r->pipelineCache().loadedBytes + 64, saved);
  }
  setenv("VTKSVDAG_PIPELINE_CACHE", "0", 1);
  {
    auto r = makeRenderer(volume, svdag::render::Backend::Compute);
    EXPECT_EQ(r->pipelineCache().file, "");
    expectSameImage(renderTwice(*r).image, reference.image, 0);
  }
}

// Compute shaders as shader objects (ComputeProgram.h) keep their binaries on disk: the next
// device creates every one from its binary (none compiled) and renders the same image; a corrupt
// binary file, or one the driver refuses, is compiled again (same image, a reason given) and
// replaced; SVDAG_VK_NO_SHADER_OBJECTS=1 makes them pipelines, with the same image.
TEST(DeviceSharing, ShaderBinariesAreReusedAndABadOneIgnored)
{
  namespace fs = std::filesystem;
  const TemporaryCacheHome cache("svdag-xdg-so");
  const fs::path& home = cache.path;
  unsetenv("SVDAG_VK_NO_SHADER_OBJECTS");
  const auto volume = randomVolume(9);
  ASSERT_EQ(svdag::render::Renderer::deviceUsers(), 0u);
  auto binaries = [&] {
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(home / "vtksvdag"))
    {
      if (entry.path().filename().string().rfind("shader-", 0) == 0)
        files.push_back(entry.path());
    }
    return files;
  };

  Frame reference;
  uint64_t shaders = 0;
  {
    auto r = makeRenderer(volume, svdag::render::Backend::Compute);
    reference = renderTwice(*r);
    const auto status = r->pipelineCache();
    if (!status.shaderObjects)
      GTEST_SKIP() << "this device has no VK_EXT_shader_object";
    // The path tracer and the denoiser at least.
    shaders = status.shadersCompiled;
    EXPECT_GE(shaders, 2u);
    EXPECT_EQ(status.shaderBinariesLoaded, 0u);
    EXPECT_EQ(status.shaderBinaryProblem, "");
  }
  ASSERT_EQ(binaries().size(), shaders);
  {
    auto r = makeRenderer(volume, svdag::render::Backend::Compute);
    expectSameImage(renderTwice(*r).image, reference.image, 0);
    const auto status = r->pipelineCache();
    EXPECT_EQ(status.shaderBinariesLoaded, shaders);
    EXPECT_EQ(status.shadersCompiled, 0u);
    EXPECT_EQ(status.shaderBinaryProblem, "");
  }
  // A flipped bit (caught by our checksum), then a payload of garbage under a sound header
  // (handed to the driver, which must refuse it): compiled again, the same image, the files
  // rewritten.
  for (const bool resealed : { false, true })
  {
    for (const fs::path& file : binaries())
    {
      std::vector<uint8_t> bytes(fs::file_size(file));
      {
        std::ifstream in(file, std::ios::binary);
        in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size()));
      }
      if (!resealed)
        bytes[bytes.size() / 2] ^= 0x10;
      else
      {
        for (size_t i = 64; i < bytes.size(); ++i)
          bytes[i] = uint8_t((i * 2654435761u) >> 11);
        const uint64_t sum = svdag::render::fnv1a64(bytes.data() + 64, bytes.size() - 64);
        for (int i = 0; i < 8; ++i)
          bytes[56 + i] = uint8_t(sum >> (8 * i));
      }
      std::ofstream out(file, std::ios::binary | std::ios::trunc);
      out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    }
    auto r = makeRenderer(volume, svdag::render::Backend::Compute);
    expectSameImage(renderTwice(*r).image, reference.image, 0);
    const auto status = r->pipelineCache();
    EXPECT_EQ(status.shaderBinariesLoaded, 0u) << resealed;
    EXPECT_EQ(status.shadersCompiled, shaders) << resealed;
    EXPECT_NE(status.shaderBinaryProblem.find(resealed ? "refused" : "checksum"),
      std::string::npos)
      << status.shaderBinaryProblem;
  }
  {
    auto r = makeRenderer(volume, svdag::render::Backend::Compute);
    renderTwice(*r);
    EXPECT_EQ(r->pipelineCache().shaderBinariesLoaded, shaders) << "the binaries were not rewritten";
  }
  setenv("SVDAG_VK_NO_SHADER_OBJECTS", "1", 1);
  {
    auto r = makeRenderer(volume, svdag::render::Backend::Compute);
    expectSameImage(renderTwice(*r).image, reference.image, 0);
    EXPECT_FALSE(r->pipelineCache().shaderObjects);
    EXPECT_EQ(r->pipelineCache().shadersCompiled, 0u);
  }
  unsetenv("SVDAG_VK_NO_SHADER_OBJECTS");
}

// Previews while compiling: on a new device with empty caches (nothing compiled) the first pass
// is the preview, whose hits are exactly the block LOD's and whose color is the hit label's base
// color under a headlight; it does not accumulate, and once the background compilation is done
// the path tracer's passes start a new accumulation that equals a renderer's without the
// preview. With the path tracer's binary on disk, a new device's first pass is the path
// tracer's (created from the binary at once); the ray tracing pipeline still previews.
TEST(DeviceSharing, PreviewWhileThePipelineCompiles)
{
  for (const auto backend : { svdag::render::Backend::Compute, svdag::render::Backend::RayTracing })
  {
  const TemporaryCacheHome cache("svdag-preview");
  ASSERT_EQ(svdag::render::Renderer::deviceUsers(), 0u); // a new device: nothing compiled
  svdag::Geometry g;
  g.dims = { { 40, 30, 24 } };
  std::vector<uint16_t> labels(g.voxelCount(), 0);
  for (int z = 2; z < 22; ++z)
    for (int y = 2; y < 28; ++y)
      for (int x = 2; x < 38; ++x)
        labels[x + 40 * (y + 30 * size_t(z))] = uint16_t(1 + (x * x + y * 3 + z * z) % 5);
  const auto volume = std::make_shared<const svdag::Volume>(
    svdag::Builder::build(g, svdag::ScalarType::UInt16, labels.data()));
  auto make = [&] {
    auto r = std::make_unique<svdag::render::Renderer>();
    r->setBackend(backend);
    r->setVolume(volume);
    r->setImageSize(48, 40);
    r->setCamera(svdag::render::frameVolume(g, 35, 25, 1.1));
    r->setDenoise(false);
    return r;
  };
  auto previewing = make();
  previewing->setPreviewWhileCompiling(true);
  const svdag::render::Image preview = previewing->render();
  ASSERT_TRUE(previewing->previewed());
  EXPECT_EQ(previewing->accumulatedSamples(), 1u);

  auto plain = make(); // compiles (or waits for) the full pipeline
  const svdag::render::Image full = plain->render();
  EXPECT_FALSE(plain->previewed());
  plain->setLod(svdag::render::Lod::Block);
  const svdag::render::Image block = plain->render();
  EXPECT_EQ(preview.label, block.label);
  EXPECT_EQ(preview.depth, block.depth);
  const svdag::render::ViewRays rays = previewing->viewRays();
  size_t hits = 0;
  for (size_t i = 0; i < preview.label.size(); ++i)
  {
    if (preview.label[i] == 0)
      continue;
    ++hits;
    const uint32_t x = uint32_t(i % preview.width), y = uint32_t(i / preview.width);
    const double u = 2 * (x + 0.5) / preview.width - 1, v = 2 * (y + 0.5) / preview.height - 1;
    double d[3], length = 0;
    for (int a = 0; a < 3; ++a)
    {
      d[a] = rays.direction[a] + u * rays.directionU[a] + v * rays.directionV[a];
      length += d[a] * d[a];
    }
    double facing = 0;
    for (int a = 0; a < 3; ++a)
      facing += d[a] / std::sqrt(length) * preview.normal[3 * i + a];
    const auto base = svdag::render::Renderer::defaultMaterial(preview.label[i] - 1).baseColorVisibility;
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(preview.hdr[4 * i + c], base[c] * (0.3 + 0.7 * std::abs(facing)), 1e-4) << i;
  }
  EXPECT_GT(hits, preview.label.size() / 4);

  // Waits for the background compilation (bounded): then the path tracer's image.
  const auto start = std::chrono::steady_clock::now();
  svdag::render::Image after = previewing->render();
  while (previewing->previewed() &&
    std::chrono::steady_clock::now() - start < std::chrono::seconds(120))
  {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    after = previewing->render();
  }
  ASSERT_FALSE(previewing->previewed());
  EXPECT_EQ(previewing->accumulatedSamples(), 1u);
  EXPECT_EQ(after.label, full.label);
  EXPECT_EQ(after.hdr, full.hdr);

  previewing.reset();
  plain.reset();
  ASSERT_EQ(svdag::render::Renderer::deviceUsers(), 0u);
  auto warm = make();
  warm->setPreviewWhileCompiling(true);
  const svdag::render::Image first = warm->render();
  const bool fromBinary =
    backend == svdag::render::Backend::Compute && warm->pipelineCache().shaderObjects;
  EXPECT_EQ(warm->previewed(), !fromBinary);
  if (fromBinary)
  {
    EXPECT_EQ(warm->pipelineCache().shadersCompiled, 0u);
    EXPECT_EQ(first.label, full.label);
    EXPECT_EQ(first.hdr, full.hdr);
  }
  }
}

// Clipping is a feature of the path tracer (ShaderFeatures::clipping): the preview a window shows
// while a clipped scene's kernel compiles is clipped too, the same labels and depths as the full
// kernel's block-LOD frame, and the plane does cut something away.
TEST(DeviceSharing, APreviewKeepsTheClipping)
{
  for (const auto backend : { svdag::render::Backend::Compute, svdag::render::Backend::RayTracing })
  {
    const TemporaryCacheHome cache("svdag-preview-clipping");
    ASSERT_EQ(svdag::render::Renderer::deviceUsers(), 0u); // a new device: nothing compiled
    const auto volume = randomVolume(3);
    svdag::render::ClipPlane plane;
    for (int a = 0; a < 3; ++a)
      plane.origin[size_t(a)] = 0.5 * (volume->geometry.dims[size_t(a)] - 1);
    plane.normal = { { 1.0, 0.3, 0.0 } };
    auto make = [&](bool clipped) {
      auto r = makeRenderer(volume, backend);
      r->setDenoise(false);
      r->setClipping(clipped ? std::vector<svdag::render::ClipPlane>{ plane }
                             : std::vector<svdag::render::ClipPlane>{});
      return r;
    };
    auto previewing = make(true);
    previewing->setPreviewWhileCompiling(true);
    const svdag::render::Image preview = previewing->render();
    ASSERT_TRUE(previewing->previewed());
    auto plain = make(true); // compiles (or waits for) the full clipped kernel
    plain->setLod(svdag::render::Lod::Block);
    const svdag::render::Image block = plain->render();
    EXPECT_FALSE(plain->previewed());
    EXPECT_EQ(preview.label, block.label);
    EXPECT_EQ(preview.depth, block.depth);
    auto whole = make(false);
    whole->setLod(svdag::render::Lod::Block);
    const svdag::render::Image unclipped = whole->render();
    size_t cut = 0;
    for (size_t i = 0; i < unclipped.label.size(); ++i)
      cut += unclipped.label[i] != 0 && block.label[i] != unclipped.label[i];
    EXPECT_GT(cut, unclipped.label.size() / 20);
    // The background compilation ends before the device goes (bounded).
    const auto start = std::chrono::steady_clock::now();
    while (previewing->previewed() &&
      std::chrono::steady_clock::now() - start < std::chrono::seconds(120))
    {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      previewing->render();
    }
    EXPECT_FALSE(previewing->previewed());
    previewing.reset();
    plain.reset();
    whole.reset();
    ASSERT_EQ(svdag::render::Renderer::deviceUsers(), 0u);
  }
}

// Compiling ahead (CompileAhead.h): a renderer's first frame with the settings compiled ahead
// creates no pipeline and no shader, whether compileAhead ran before the frame or runs beside it
// on another thread; and the frame is the one a renderer renders without it.
TEST(DeviceSharing, AFirstFrameCompiledAheadCompilesNothing)
{
  for (const auto backend : Backends)
  {
    const TemporaryCacheHome cache("svdag-ahead");
    ASSERT_EQ(svdag::render::Renderer::deviceUsers(), 0u); // a new device: nothing compiled
    const auto volume = randomVolume(5);
    auto created = [](const svdag::render::Renderer& r) {
      const auto status = r.pipelineCache();
      return r.pipelineCompilations() + status.shadersCompiled + status.shaderBinariesLoaded;
    };
    svdag::render::Image alone;
    uint64_t createdAlone = 0;
    {
      auto r = makeRenderer(volume, backend);
      alone = r->render();
      createdAlone = created(*r);
      ASSERT_GT(createdAlone, 0u);
    }

    // Before: the first frame finds everything made.
    {
      auto r = makeRenderer(volume, backend); // holds the device (a new one)
      ASSERT_EQ(created(*r), 0u);
      const svdag::render::RenderSettings settings = r->settings();
      std::thread ahead([&settings] { svdag::render::compileAhead(settings); });
      ahead.join();
      EXPECT_EQ(svdag::render::Renderer::deviceUsers(), 1u) << "compileAhead's renderer is gone";
      EXPECT_EQ(created(*r), createdAlone) << "what the first frame needs, and nothing else";
      expectSameImage(r->render(), alone, 0);
      EXPECT_EQ(created(*r), createdAlone) << "the first frame compiled something";
    }

    // Beside: both ask for the same pipelines at once, and each is made once.
    {
      auto r = makeRenderer(volume, backend);
      ASSERT_EQ(created(*r), 0u);
      const svdag::render::RenderSettings settings = r->settings();
      std::thread ahead([&settings] { svdag::render::compileAhead(settings); });
      const svdag::render::Image image = r->render();
      ahead.join();
      expectSameImage(image, alone, 1);
      EXPECT_EQ(created(*r), createdAlone);
    }
  }
}
