#include "vtkSegmentationSVDAGVolumeMapper.h"

#include "vtkCommand.h"
#include "vtkCallbackCommand.h"
#include "vtkHardwareSelector.h"
#include "vtkInformation.h"
#include "vtkMath.h"
#include "vtkMatrix3x3.h"
#include "vtkMatrix4x4.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkOpenGLCamera.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkRenderWindow.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkRenderer.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkSegmentationSVDAGLabelProperties.h"
#include "vtkSegmentationSVDAGRenderSettings.h"
#include "vtkSmartPointer.h"
#include "vtkTimerLog.h"
#include "vtkVolume.h"
#include "vtkWeakPointer.h"

#include "svdagClipping.h"
#include "svdagGLCompositor.h"
#include "svdagRenderSession.h"
#include "svdagSelectionDraw.h"

#include <svdag_render/DepthLayout.h>
#include <svdag_render/FrameBudget.h>
#include <svdag_render/Material.h>
#include <svdag_render/RenderSettings.h>
#include <svdag_render/Renderer.h>
#include <svdag_render/WorldFrame.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkSegmentationSVDAGVolumeMapper);

namespace
{
namespace core = svdag::render;
using Matrix = std::array<double, 16>; // row-major
using Vec3 = std::array<double, 3>;
using Clock = std::chrono::steady_clock;

Matrix fromVTK(vtkMatrix4x4* m, bool transpose)
{
  Matrix out;
  for (int r = 0; r < 4; ++r)
  {
    for (int c = 0; c < 4; ++c)
      out[4 * r + c] = transpose ? m->GetElement(c, r) : m->GetElement(r, c);
  }
  return out;
}

Matrix multiply(const Matrix& a, const Matrix& b)
{
  Matrix out{};
  for (int r = 0; r < 4; ++r)
  {
    for (int c = 0; c < 4; ++c)
    {
      for (int k = 0; k < 4; ++k)
        out[4 * r + c] += a[4 * r + k] * b[4 * k + c];
    }
  }
  return out;
}

Matrix inverse(const Matrix& m)
{
  double in[16], out[16];
  std::copy(m.begin(), m.end(), in);
  vtkMatrix4x4::Invert(in, out);
  Matrix result;
  std::copy(out, out + 16, result.begin());
  for (double x : result)
  {
    if (!std::isfinite(x))
      throw std::invalid_argument("the camera or volume matrix is singular");
  }
  return result;
}

// The ray through image point (u, v) in [-1, 1]^2: origin, unit direction.
struct Ray
{
  Vec3 origin;
  Vec3 direction;
};
Ray rayAt(const core::ViewRays& r, double u, double v)
{
  Ray ray;
  Vec3 span;
  for (int a = 0; a < 3; ++a)
  {
    ray.origin[a] = r.origin[a] + u * r.originU[a] + v * r.originV[a];
    span[a] = r.direction[a] + u * r.directionU[a] + v * r.directionV[a];
  }
  const double length = std::sqrt(span[0] * span[0] + span[1] * span[1] + span[2] * span[2]);
  for (int a = 0; a < 3; ++a)
    ray.direction[a] = span[a] / length;
  return ray;
}

// Image coordinate of pixel center i of n.
double imageCoordinate(int i, int n)
{
  return 2.0 * (i + 0.5) / n - 1.0;
}

// Per traced pixel (width x height over the viewport), the ray distance to the surface drawn
// before the volume (from the viewport's window depth); empty where nothing was drawn anywhere.
// The shared depth path computes the same on the device (depth.comp: any change here is one
// there).
std::vector<float> rayLimits(const float* sceneDepth, const svdag::gl::Viewport& vp,
  int width, int height, const Matrix& clipToModel, const core::ViewRays& rays)
{
  std::vector<float> limits(size_t(width) * size_t(height), SVDAG_RAY_NOT_LIMITED);
  bool limited = false;
  for (int y = 0; y < height; ++y)
  {
    const double v = imageCoordinate(y, height);
    const int fy = std::min(int((y + 0.5) * vp.height / height), vp.height - 1);
    for (int x = 0; x < width; ++x)
    {
      const int fx = std::min(int((x + 0.5) * vp.width / width), vp.width - 1);
      const float d = sceneDepth[size_t(fx) + size_t(vp.width) * size_t(fy)];
      if (!(d < 1.0f))
        continue;
      const double u = imageCoordinate(x, width);
      const double clip[4] = { u, v, 2.0 * d - 1.0, 1.0 };
      double p[4] = { 0, 0, 0, 0 };
      for (int row = 0; row < 4; ++row)
      {
        for (int c = 0; c < 4; ++c)
          p[row] += clipToModel[4 * row + c] * clip[c];
      }
      const Ray ray = rayAt(rays, u, v);
      double t = 0;
      for (int a = 0; a < 3; ++a)
        t += (p[a] / p[3] - ray.origin[a]) * ray.direction[a];
      // A little past the surface (1e-5 relative, far below a pixel): where the volume's and
      // the surface's depths meet, the exact min in window depth (compositedDepth) decides, not
      // the rounding of the depth buffer into a ray distance.
      limits[size_t(x) + size_t(width) * size_t(y)] = float(std::max(t, 0.0) * SVDAG_RAY_LIMIT_SLACK);
      limited = true;
    }
  }
  return limited ? limits : std::vector<float>();
}

// The window depth to write over the viewport: per pixel, the nearer of the scene's and that of
// the traced hit covering it (VTK's depth 0.5 z_clip / w_clip + 0.5, in double precision). The
// shared depth path computes the same on the device (depth.comp, Renderer::compositeDepth).
std::vector<float> compositedDepth(const core::Image& image, const core::ViewRays& rays,
  const Matrix& modelToClip, const float* sceneDepth, const svdag::gl::Viewport& vp)
{
  const int width = int(image.width), height = int(image.height);
  std::vector<float> traced(size_t(width) * size_t(height), 1.0f);
  for (int y = 0; y < height; ++y)
  {
    for (int x = 0; x < width; ++x)
    {
      const size_t i = size_t(x) + size_t(width) * size_t(y);
      if (image.label[i] == 0)
        continue;
      const Ray ray = rayAt(rays, imageCoordinate(x, width), imageCoordinate(y, height));
      double p[4];
      for (int a = 0; a < 3; ++a)
        p[a] = ray.origin[a] + double(image.depth[i]) * ray.direction[a];
      p[3] = 1;
      double z = 0, w = 0;
      for (int c = 0; c < 4; ++c)
      {
        z += modelToClip[8 + c] * p[c];
        w += modelToClip[12 + c] * p[c];
      }
      traced[i] = float(std::min(std::max(0.5 * z / w + 0.5, 0.0), 1.0));
    }
  }
  std::vector<float> depth(sceneDepth, sceneDepth + size_t(vp.width) * size_t(vp.height));
  for (int fy = 0; fy < vp.height; ++fy)
  {
    const int y = std::min(int(int64_t(fy) * height / vp.height), height - 1);
    for (int fx = 0; fx < vp.width; ++fx)
    {
      const int x = std::min(int(int64_t(fx) * width / vp.width), width - 1);
      float& d = depth[size_t(fx) + size_t(vp.width) * size_t(fy)];
      d = std::min(d, traced[size_t(x) + size_t(width) * size_t(y)]);
    }
  }
  return depth;
}

// What identifies a frame: passes accumulate while it stays the same (an exposure change only
// re-composites). VTK recomputes the camera's key matrices in float in some paths:
// vtkWindowToImageFilter re-renders with matrices that differ in the 8th digit, far less than a
// pixel, and the props drawn before the volume then land a float step away in the depth buffer,
// or cover a silhouette pixel or not. None of that must restart the accumulation: the matrix
// matches to 1e-6 relative, the scene depth to 1e-6 (window depth) except on silhouette pixels
// (a depth step next to them), of which at most 1% may differ; everything else exactly.
struct FrameKey
{
  Matrix matrix{};
  core::RenderSettings settings;
  std::vector<uint64_t> ids; // ids[0], ids[1]: the viewport's width and height
  // The viewport's depth as drawn before the volume (ids[0] x ids[1] floats), shared, not
  // copied, by the keys of one frame: host memory, or on the shared depth path the renderer's
  // scene depth buffer `depthSlot` (mapped; the next frame reads into the other slot, so this
  // one stays as it was); null when nothing was drawn.
  std::shared_ptr<const float> sceneDepth;
  int depthSlot = -1;

  bool matches(const FrameKey& o) const
  {
    // sameView: the same ids, so the same number of depth pixels.
    if (!this->sameView(o) || bool(sceneDepth) != bool(o.sceneDepth))
      return false;
    return !sceneDepth || sameSceneDepth(sceneDepth.get(), o.sceneDepth.get(), size_t(ids[0]),
                            size_t(ids[1]));
  }

  // Whether the image traced for `traced` can stand for this frame in a selection render: the
  // same view, and what is drawn before the volume now is nowhere farther than it was then (the
  // selection's depth test removes the traced hits that something nearer covers now). A
  // selection render draws without multisampling, so its depth is that of the pixel center where
  // the traced frame's may be that of a sample elsewhere in the pixel: a pixel may be as far as
  // the farthest of its 3x3 neighbours then.
  bool coveredBy(const FrameKey& traced) const
  {
    if (!this->sameView(traced))
      return false;
    const float* now = sceneDepth.get();
    const float* then = traced.sceneDepth.get();
    if (!then)
      return true; // nothing was drawn before the volume: no ray was shortened
    const size_t w = size_t(ids[0]), h = size_t(ids[1]); // both keys' (sameView)
    for (size_t y = 0; y < h; ++y)
    {
      for (size_t x = 0; x < w; ++x)
      {
        const float a = now ? now[x + w * y] : 1.0f;
        float farthest = 0;
        for (size_t ny = (y > 0 ? y - 1 : y); ny <= std::min(y + 1, h - 1); ++ny)
        {
          for (size_t nx = (x > 0 ? x - 1 : x); nx <= std::min(x + 1, w - 1); ++nx)
            farthest = std::max(farthest, then[nx + w * ny]);
        }
        if (a > farthest + 1e-6f)
          return false;
      }
    }
    return true;
  }

  // The same rays, settings, viewport, labels and volume (the matrix to 1e-6 relative).
  bool sameView(const FrameKey& o) const
  {
    if (ids.empty() || ids != o.ids || !core::tracesSameImage(settings, o.settings))
      return false;
    for (size_t i = 0; i < matrix.size(); ++i)
    {
      const double a = matrix[i], b = o.matrix[i];
      if (!(std::abs(a - b) <= 1e-6 * std::max({ 1.0, std::abs(a), std::abs(b) })))
        return false;
    }
    return true;
  }

private:
  static bool sameSceneDepth(const float* a, const float* b, size_t w, size_t h)
  {
    size_t silhouettes = 0;
    for (size_t y = 0; y < h; ++y)
    {
      for (size_t x = 0; x < w; ++x)
      {
        const size_t i = x + w * y;
        if (std::abs(a[i] - b[i]) <= 1e-6f)
          continue;
        if (!onSilhouette(b, x, y, w, h) || ++silhouettes > w * h / 100)
          return false;
      }
    }
    return true;
  }

  // Whether the depth steps (by more than 1e-3) between pixel (x, y) and a neighbour.
  static bool onSilhouette(const float* depth, size_t x, size_t y, size_t w, size_t h)
  {
    const float d = depth[x + w * y];
    for (size_t ny = (y > 0 ? y - 1 : y); ny <= std::min(y + 1, h - 1); ++ny)
    {
      for (size_t nx = (x > 0 ? x - 1 : x); nx <= std::min(x + 1, w - 1); ++nx)
      {
        if (std::abs(depth[nx + w * ny] - d) > 1e-3f)
          return true;
      }
    }
    return false;
  }
};

// What a selection render draws in vtkHardwareSelector's current pass, per pixel of `image`
// (traced at the viewport's size): the prop's color in the actor and process passes (set by
// BeginRenderProp), the hit label's index + 1 in the composite index pass (indices from 0xffffff
// on share 0xffffff), and the low or high 24 bits of the hit voxel's index i + nx (j + ny k) (the
// input image's point id) in the point and cell id passes. Background pixels get 0 (not drawn).
std::vector<uint32_t> selectionIds(vtkHardwareSelector* selector, const core::Image& image,
  const core::ViewRays& rays, const svdag::Geometry& geometry)
{
  const int pass = selector->GetCurrentPass();
  const int width = int(image.width), height = int(image.height);
  std::vector<uint32_t> ids(size_t(width) * size_t(height), 0);
  uint32_t propColor = 0;
  float color[3];
  selector->GetPropColorValue(color);
  for (int c = 0; c < 3; ++c)
    propColor |= uint32_t(std::lround(std::min(std::max(color[c], 0.0f), 1.0f) * 255)) << (8 * c);
  const bool voxelPass = pass == vtkHardwareSelector::POINT_ID_LOW24 ||
    pass == vtkHardwareSelector::POINT_ID_HIGH24 || pass == vtkHardwareSelector::CELL_ID_LOW24 ||
    pass == vtkHardwareSelector::CELL_ID_HIGH24;
  const bool highBits =
    pass == vtkHardwareSelector::POINT_ID_HIGH24 || pass == vtkHardwareSelector::CELL_ID_HIGH24;
  Matrix worldToIndex{};
  if (voxelPass)
  {
    const auto m = core::indexToWorld(geometry);
    Matrix indexToWorld{};
    std::copy(m.begin(), m.end(), indexToWorld.begin());
    indexToWorld[15] = 1;
    worldToIndex = inverse(indexToWorld);
  }
  for (int y = 0; y < height; ++y)
  {
    for (int x = 0; x < width; ++x)
    {
      const size_t i = size_t(x) + size_t(width) * size_t(y);
      const uint32_t label = image.label[i];
      if (label == 0)
        continue;
      if (pass == vtkHardwareSelector::COMPOSITE_INDEX_PASS)
      {
        ids[i] = std::min(label, 0xffffffu);
        continue;
      }
      if (!voxelPass)
      {
        ids[i] = propColor;
        continue;
      }
      // The voxel the hit point enters: a thousandth of a voxel past it along the ray.
      const Ray ray = rayAt(rays, imageCoordinate(x, width), imageCoordinate(y, height));
      double q[3], step[3], length = 0;
      for (int r = 0; r < 3; ++r)
      {
        q[r] = worldToIndex[4 * r + 3];
        step[r] = 0;
        for (int c = 0; c < 3; ++c)
        {
          q[r] += worldToIndex[4 * r + c] * (ray.origin[c] + double(image.depth[i]) * ray.direction[c]);
          step[r] += worldToIndex[4 * r + c] * ray.direction[c];
        }
        length += step[r] * step[r];
      }
      uint64_t voxel = 0;
      for (int r = 2; r >= 0; --r)
      {
        const double p = q[r] + 1e-3 * step[r] / std::sqrt(length);
        const int64_t v = std::min<int64_t>(
          std::max<int64_t>(int64_t(std::floor(p)), 0), int64_t(geometry.dims[r]) - 1);
        voxel = voxel * uint64_t(geometry.dims[r]) + uint64_t(v);
      }
      ids[i] = uint32_t((highBits ? voxel >> 24 : voxel) & 0xffffffu);
    }
  }
  return ids;
}
} // namespace

struct vtkSegmentationSVDAGVolumeMapper::Internals
{
  svdag::vtkglue::RenderSession Session;
  svdag::gl::Compositor Compositor;
  svdag::gl::SelectionDraw Selection;
  core::FrameBudget Budget;

  // The frame the accumulation belongs to: a different one restarts it.
  FrameKey Frame;
  bool Converged = false;
  bool FullQuality = false;
  core::FrameLevel Level;
  double TraceMilliseconds = 0;
  double FrameMilliseconds = 0;
  double CopyMilliseconds = 0;
  // The last frame's composite path ("" before one); set when a shared import failed, with the
  // reason (reported once; the host path is used from then on).
  std::string CompositePath;
  std::string ImportFailure;
  // How the last frame's scene depth came in and its written depth went out ("" before one).
  std::string DepthPath;

  // What Pick reads: the last traced frame.
  vtkRenderer* PickRenderer = nullptr;
  // The renderer's viewport in display pixels (not GL_VIEWPORT: a render pass such as
  // vtkSSAAPass draws into a larger framebuffer of its own).
  svdag::gl::Viewport PickViewport;
  core::ViewRays PickRays;
  Matrix ModelToWorld{};
  vtkTypeInt64 PickedLabel = 0;
  Vec3 PickedPosition{ { 0, 0, 0 } };
  Vec3 PickedNormal{ { 0, 0, 0 } };
  Vec3 PickedShadingNormal{ { 0, 0, 0 } };

  // Whether the last frame was a preview, and the interactor timer that renders again while the
  // full pipeline compiles.
  bool Previewed = false;
  vtkWeakPointer<vtkRenderWindowInteractor> PreviewInteractor;
  vtkWeakPointer<vtkRenderWindow> PreviewWindow;
  unsigned long PreviewObserver = 0;
  int PreviewTimer = -1;
  vtkNew<vtkCallbackCommand> PreviewTimerFired;

  // The selection capture (vtkHardwareSelector::CaptureBuffers) being drawn, until its EndEvent.
  vtkWeakPointer<vtkHardwareSelector> CaptureSelector;
  unsigned long CaptureObserver = 0;
  vtkNew<vtkCallbackCommand> CaptureEnded;

  Internals()
  {
    this->CaptureEnded->SetClientData(this);
    this->CaptureEnded->SetCallback([](vtkObject*, unsigned long, void* self, void*) {
      static_cast<Internals*>(self)->CaptureSelector = nullptr;
    });
    this->PreviewTimerFired->SetClientData(this);
    this->PreviewTimerFired->SetCallback([](vtkObject*, unsigned long, void* self, void* data) {
      Internals& in = *static_cast<Internals*>(self);
      if (!data || *static_cast<int*>(data) != in.PreviewTimer)
        return;
      in.PreviewTimer = -1;
      if (in.PreviewWindow)
        in.PreviewWindow->Render();
    });
  }
  ~Internals()
  {
    this->watchCapture(nullptr);
    this->watchPreview(nullptr, nullptr);
  }
  // Renders `window` again soon (a one-shot timer of `interactor`); null: no more.
  void watchPreview(vtkRenderWindowInteractor* interactor, vtkRenderWindow* window)
  {
    if (this->PreviewInteractor && this->PreviewInteractor != interactor)
    {
      this->PreviewInteractor->RemoveObserver(this->PreviewObserver);
      this->PreviewInteractor = nullptr;
    }
    this->PreviewWindow = window;
    if (!interactor)
      return;
    if (!this->PreviewInteractor)
    {
      this->PreviewInteractor = interactor;
      this->PreviewObserver = interactor->AddObserver(vtkCommand::TimerEvent, this->PreviewTimerFired);
    }
    if (this->PreviewTimer < 0)
      this->PreviewTimer = interactor->CreateOneShotTimer(50);
  }
  void watchCapture(vtkHardwareSelector* selector)
  {
    if (this->CaptureSelector)
      this->CaptureSelector->RemoveObserver(this->CaptureObserver);
    this->CaptureSelector = selector;
    if (selector)
      this->CaptureObserver = selector->AddObserver(vtkCommand::EndEvent, this->CaptureEnded);
  }
};

vtkSegmentationSVDAGVolumeMapper::vtkSegmentationSVDAGVolumeMapper()
  : Internal(new Internals)
{
}

vtkSegmentationSVDAGVolumeMapper::~vtkSegmentationSVDAGVolumeMapper() = default;

int vtkSegmentationSVDAGVolumeMapper::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkSegmentationSVDAG");
  return 1;
}

void vtkSegmentationSVDAGVolumeMapper::SetInputData(vtkSegmentationSVDAG* input)
{
  this->SetInputDataObject(0, input);
}

vtkSegmentationSVDAG* vtkSegmentationSVDAGVolumeMapper::GetInput()
{
  return vtkSegmentationSVDAG::SafeDownCast(this->GetDataObjectInput());
}

vtkMTimeType vtkSegmentationSVDAGVolumeMapper::GetMTime()
{
  return std::max(this->Superclass::GetMTime(), this->Internal->Session.mtime());
}

vtkSegmentationSVDAGRenderSettings* vtkSegmentationSVDAGVolumeMapper::GetSettings()
{
  return this->Internal->Session.settings();
}

void vtkSegmentationSVDAGVolumeMapper::SetSettings(vtkSegmentationSVDAGRenderSettings* settings)
{
  if (this->Internal->Session.setSettings(settings))
    this->Modified();
}

vtkSegmentationSVDAGLabelProperties* vtkSegmentationSVDAGVolumeMapper::GetLabelProperties()
{
  return this->Internal->Session.labels();
}

void vtkSegmentationSVDAGVolumeMapper::SetLabelProperties(
  vtkSegmentationSVDAGLabelProperties* properties)
{
  if (this->Internal->Session.setLabels(properties))
    this->Modified();
}

double* vtkSegmentationSVDAGVolumeMapper::GetBounds()
{
  if (this->GetNumberOfInputConnections(0) > 0)
    this->Update();
  vtkSegmentationSVDAG* input = this->GetInput();
  if (!input || !input->HasVolume())
  {
    vtkMath::UninitializeBounds(this->Bounds);
    return this->Bounds;
  }
  const auto b = core::worldBounds(input->GetVolume()->geometry);
  std::copy(b.begin(), b.end(), this->Bounds);
  return this->Bounds;
}

void vtkSegmentationSVDAGVolumeMapper::Render(vtkRenderer* renderer, vtkVolume* volume)
{
  Internals& in = *this->Internal;
  auto* window = vtkOpenGLRenderWindow::SafeDownCast(renderer->GetRenderWindow());
  auto* camera = vtkOpenGLCamera::SafeDownCast(renderer->GetActiveCamera());
  if (!window || !camera)
  {
    vtkErrorMacro("Render needs an OpenGL render window (vtkOpenGLRenderWindow)");
    return;
  }
  vtkSegmentationSVDAG* input = this->GetInput();
  if (!input || !input->HasVolume() || !this->CreateRenderer())
    return;
  this->InvokeEvent(vtkCommand::VolumeMapperRenderStartEvent, nullptr);
  const auto start = Clock::now();
  in.Converged = false;
  auto finish = [&]() {
    in.FrameMilliseconds = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    this->TimeToDraw = in.FrameMilliseconds / 1000;
    this->InvokeEvent(vtkCommand::VolumeMapperRenderEndEvent, nullptr);
  };
  // What Pick reads: the frame traced last, for this renderer.
  auto rememberPick = [&](const core::ViewRays& rays, const Matrix& modelToWorld) {
    in.PickRenderer = renderer;
    renderer->GetTiledSizeAndOrigin(
      &in.PickViewport.width, &in.PickViewport.height, &in.PickViewport.x, &in.PickViewport.y);
    in.PickRays = rays;
    in.ModelToWorld = modelToWorld;
  };
  try
  {
    const core::Renderer* before = in.Session.renderer();
    const uint64_t buildsBefore = before->bvhBuilds() + before->pipelineBuilds();
    core::Renderer& r = in.Session.prepare(input->GetVolume());

    const svdag::gl::Viewport vp = svdag::gl::Compositor::currentViewport(window);
    if (vp.width <= 0 || vp.height <= 0)
      throw std::runtime_error("the renderer's viewport is empty");
    // Vulkan writes the shared color only once OpenGL has read the last one.
    in.Compositor.waitForSharedReads();
    const bool share = this->SharedMemory && in.ImportFailure.empty() && r.canShareColor() &&
      in.Compositor.canImport(window, r.deviceUuids());
    if (share != r.colorSharing())
    {
      // The color moves to another buffer on the next pass: trace one, whatever the frame.
      r.setColorSharing(share);
      r.resetAccumulation();
      in.Frame = FrameKey();
    }
    double copyMilliseconds = 0;
    auto timed = [&copyMilliseconds](auto&& step) {
      const auto begin = Clock::now();
      auto result = step();
      copyMilliseconds += std::chrono::duration<double, std::milli>(Clock::now() - begin).count();
      return result;
    };

    // Rays in the data object's world (the vtkVolume's model coordinates).
    vtkMatrix4x4 *worldToView, *viewToDevice, *worldToDevice;
    vtkMatrix3x3* normals;
    camera->GetKeyMatrices(renderer, worldToView, normals, viewToDevice, worldToDevice);
    const Matrix modelToWorld = fromVTK(volume->GetMatrix(), false);
    const Matrix worldToModel = inverse(modelToWorld);
    const Matrix modelToClip = multiply(fromVTK(worldToDevice, true), modelToWorld);
    const Matrix clipToModel = inverse(modelToClip);
    const core::ViewRays rays = core::viewRaysFromClipToWorld(clipToModel);

    // Depth in: each traced pixel's ray ends at the surface drawn there before the volume. On
    // the shared depth path OpenGL reads it into the renderer's scene depth buffer (the slot the
    // accumulating frame's key does not hold), whose mapping the host reads in place; the
    // device turns it into ray limits and composites the written depth.
    const size_t viewportPixels = size_t(vp.width) * size_t(vp.height);
    int depthSlot = share && this->SharedDepth && r.canShareDepth()
      ? (in.Frame.sceneDepth && in.Frame.depthSlot == 0 ? 1 : 0)
      : -1;
    std::shared_ptr<const float> sceneDepthView;
    timed([&] {
      if (depthSlot >= 0)
      {
        try
        {
          sceneDepthView = r.sceneDepth(uint32_t(depthSlot), uint32_t(viewportPixels));
          const uint32_t slot = uint32_t(depthSlot);
          in.Compositor.readDepthShared(window, vp, depthSlot,
            { r.sceneDepthGeneration(slot), [&r, slot] { return r.exportSceneDepth(slot); } });
          return true;
        }
        catch (const std::exception& e)
        {
          // The host reads this frame's depth; every later frame takes the host path.
          in.ImportFailure = e.what();
          vtkWarningMacro("Reading the depth through the host: " << e.what());
          depthSlot = -1;
        }
      }
      auto host = std::make_shared<const std::vector<float>>(in.Compositor.readDepth(window, vp));
      sceneDepthView = std::shared_ptr<const float>(host, host->data());
      return true;
    });
    const float* sceneDepth = sceneDepthView.get();
    const core::RenderSettings& base = in.Session.settings()->GetCoreSettings();
    const bool drawnBefore = std::any_of(
      sceneDepth, sceneDepth + viewportPixels, [](float d) { return d < 1.0f; });
    // The settings a level traces with, its image (the viewport's size) and the reduction its
    // paths are traced at (the renderer's guided upsampling shows them at the image's size), and
    // the frame's identity (while it stays the same, passes accumulate).
    struct LevelFrame
    {
      core::RenderSettings settings;
      int width = 0, height = 0;
      uint32_t reduction = 1;
      FrameKey key;
    };
    auto levelFrame = [&](const core::FrameLevel& level) {
      LevelFrame f;
      const bool full = level.lod == base.lod && level.reduction == 1;
      f.settings = base;
      f.settings.lod = level.lod;
      f.settings.background = { { 0, 0, 0, 0 } }; // misses are transparent over the scene
      if (!full)
        f.settings.samplesPerPixel = 1;
      // The mapper's planes (VTK world) into the data's world; its cropping is there already.
      svdag::vtkglue::setClipping(f.settings, this->ClippingPlanes, modelToWorld, worldToModel,
        this->Cropping, this->CroppingRegionPlanes);
      f.width = vp.width;
      f.height = vp.height;
      f.reduction = level.reduction;
      f.key.matrix = modelToClip;
      f.key.settings = f.settings;
      f.key.ids = { uint64_t(vp.width), uint64_t(vp.height), uint64_t(level.reduction),
        uint64_t(in.Session.labels()->GetMTime()),
        uint64_t(reinterpret_cast<uintptr_t>(in.Session.volume().get())) };
      // What was drawn before the volume: the depth itself (FrameKey), not the ray limits derived
      // from it, which change in their last bits with the camera matrices.
      if (drawnBefore)
      {
        f.key.sceneDepth = sceneDepthView;
        f.key.depthSlot = depthSlot;
      }
      return f;
    };
    const core::FrameLevel fullLevel{ base.lod, 1 };
    LevelFrame frame = levelFrame(fullLevel);
    // (A preview is replaced as soon as the path tracer's pipeline is ready.)
    auto accumulating = [&](const LevelFrame& f) {
      return f.key.matches(in.Frame) && r.accumulatedSamples() > 0 && !r.previewed() &&
        r.image().width == uint32_t(f.width) && r.image().height == uint32_t(f.height);
    };
    auto refined = [&]() {
      return r.accumulatedSamples() >= uint32_t(this->TargetSamplesPerPixel) ||
        (this->ErrorTarget > 0 && r.accumulatedSamples() >= 2 &&
          r.errorEstimate() <= this->ErrorTarget);
    };
    if (vtkHardwareSelector* selector = renderer->GetSelector())
    {
      // A selection render (vtkHardwareSelector; vtkPropPicker and vtkRenderer::PickProp use
      // one): the full-quality frame's hits drawn as the selector's ids. The last traced image
      // stands for it when it can (no trace, so picking leaves the refinement as it was); else
      // one pass is traced and the refinement continues from it.
      // The selector renders several times (passes, and a second round with only the props
      // hit, so what is drawn before the volume changes): the first render of a capture checks
      // or traces the image, the others draw it again.
      const bool sameCapture = in.CaptureSelector == selector;
      if (!sameCapture)
        in.watchCapture(selector);
      // A preview's hits are the block boxes': never picked from.
      const bool reuse = r.accumulatedSamples() > 0 && !r.previewed() &&
        r.image().width == uint32_t(frame.width) &&
        r.image().height == uint32_t(frame.height) &&
        (sameCapture ? frame.key.sameView(in.Frame) : frame.key.coveredBy(in.Frame));
      if (!reuse)
      {
        r.setSettings(frame.settings);
        r.resetAccumulation();
        r.setImageSize(uint32_t(frame.width), uint32_t(frame.height));
        r.setTraceReduction(frame.reduction);
        r.setViewRays(rays);
        r.setRayLimits(rayLimits(sceneDepth, vp, frame.width, frame.height, clipToModel, rays));
        r.setPreviewWhileCompiling(false);
        r.render();
        in.TraceMilliseconds = r.lastFrameMilliseconds();
        in.Frame = std::move(frame.key);
        in.Level = fullLevel;
        in.FullQuality = true;
      }
      in.Converged = in.FullQuality && refined();
      selector->BeginRenderProp();
      const auto& geometry = input->GetVolume()->geometry;
      const vtkIdType largestVoxel = vtkIdType(geometry.voxelCount()) - 1;
      selector->UpdateMaximumPointId(largestVoxel);
      selector->UpdateMaximumCellId(largestVoxel);
      // The hits' own window depth; the depth test takes the nearer of it and the scene's.
      const std::vector<float> noScene(viewportPixels, 1.0f);
      in.Selection.draw(window, vp, selectionIds(selector, r.image(), rays, geometry),
        compositedDepth(r.image(), rays, modelToClip, noScene.data(), vp));
      selector->EndRenderProp();
      rememberPick(rays, modelToWorld);
      finish();
      return;
    }
    // The level: full quality unless the allocated time is too short for it. A still view whose
    // full-quality image is already accumulating keeps it even then: showing it costs nothing,
    // and a coarse frame would replace a refined image by a noisier one (a capture or a render
    // with several props in the window gets a share of the frame time).
    const double budget = this->AutoAdjustToRenderTime ? volume->GetAllocatedRenderTime() : 0.0;
    const core::FrameLevel chosen = in.Budget.choose(base.lod, uint64_t(viewportPixels), budget);
    const bool chosenFull = chosen.lod == base.lod && chosen.reduction == 1;
    const bool keepAccumulated = accumulating(frame);
    in.Level = keepAccumulated ? fullLevel : chosen;
    in.FullQuality = keepAccumulated || chosenFull;
    if (!in.FullQuality)
      frame = levelFrame(in.Level);
    r.setSettings(frame.settings);
    const int width = frame.width;
    const int height = frame.height;
    const bool sameFrame = accumulating(frame);
    // A tile of a tiled capture (vtkWindowToImageFilter scale, pyvista screenshot(scale=)) is
    // drawn once: it is refined to the targets within this render.
    const int* tiles = window->GetTileScale();
    const bool tiled = tiles[0] > 1 || tiles[1] > 1;
    // So is a still render with RefineStillRenders on (interactor styles lower the window's
    // desired update rate to the interactor's still rate when the interaction ends).
    vtkRenderWindowInteractor* interactor = window->GetInteractor();
    const double stillRate = interactor ? interactor->GetStillUpdateRate() : 0.0001;
    const bool still = window->GetDesiredUpdateRate() <= stillRate;
    const bool finishNow = tiled || (this->RefineStillRenders && still);
    in.TraceMilliseconds = 0;
    const bool watched = interactor && interactor->GetInitialized();
    r.setPreviewWhileCompiling(this->PreviewWhileCompiling && watched && !finishNow);
    // A kept still view adds a pass when its time allows one (or it must be finished now), else
    // shows what it has; any other frame traces unless it is refined at full quality.
    const bool trace = keepAccumulated ? !refined() && (chosenFull || finishNow)
                                       : !(sameFrame && in.FullQuality && refined());
    if (trace)
    {
      if (!sameFrame)
        r.resetAccumulation();
      r.setImageSize(uint32_t(width), uint32_t(height));
      r.setTraceReduction(frame.reduction);
      r.setViewRays(rays);
      if (depthSlot < 0)
        r.setRayLimits(
          timed([&] { return rayLimits(sceneDepth, vp, width, height, clipToModel, rays); }));
      else if (drawnBefore)
        r.setRayLimitsFromDepth({ uint32_t(depthSlot), uint32_t(vp.width), uint32_t(vp.height),
          clipToModel });
      else
        r.setRayLimits({});
      // Only the last pass is drawn: the ones before it leave the denoiser out.
      do
      {
        r.render(svdag::render::Renderer::PassUse::Accumulating);
        in.TraceMilliseconds += r.lastFrameMilliseconds();
        copyMilliseconds += r.lastReadbackMilliseconds();
      } while (finishNow && in.FullQuality && !refined() &&
        (tiled || std::chrono::duration<double>(Clock::now() - start).count() < this->RefineTimeLimit));
      in.TraceMilliseconds += r.finishImage();
      in.Frame = std::move(frame.key);
    }
    const core::Image& image = r.image();
    in.Previewed = r.previewed();
    in.Converged = in.FullQuality && refined() && !in.Previewed;
    if (in.Previewed)
      in.watchPreview(interactor, window);

    // Depth out: on the shared depth path the device composites it into memory OpenGL reads.
    std::vector<float> depth;
    const auto hostDepth = [&] {
      if (this->WriteDepth)
        depth = compositedDepth(image, rays, modelToClip, sceneDepth, vp);
      return true;
    };
    timed([&] {
      if (depthSlot >= 0 && this->WriteDepth)
        r.compositeDepth(uint32_t(depthSlot), uint32_t(vp.width), uint32_t(vp.height),
          modelToClip, rays);
      else
        hostDepth();
      return true;
    });
    in.DepthPath = depthSlot >= 0 ? "shared memory" : "host";
    const float exposure = float(base.exposure);
    const auto drawHost = [&] {
      if (depthSlot >= 0)
      {
        hostDepth(); // after an import failure: this frame's depth goes out through the host
        in.DepthPath = "host";
      }
      in.Compositor.draw(window, vp, image.hdr.data(), width, height, depth, exposure);
      return true;
    };
    if (r.colorSharing())
    {
      try
      {
        timed([&] {
          const svdag::gl::SharedBuffer color{ r.sharedColorGeneration(),
            [&r] { return r.exportColor(); } };
          if (depthSlot >= 0 && this->WriteDepth)
            in.Compositor.drawShared(window, vp, color, width, height,
              { r.compositedDepthGeneration(), [&r] { return r.exportCompositedDepth(); } },
              exposure);
          else
            in.Compositor.drawShared(window, vp, color, width, height, depth, exposure);
          return true;
        });
        in.CompositePath = "shared memory";
      }
      catch (const std::exception& e)
      {
        // Where the import fails the host path draws this frame (traced again, into host
        // memory) and every later one.
        in.ImportFailure = e.what();
        vtkWarningMacro("Drawing through the host: " << e.what());
        r.setColorSharing(false);
        r.render();
        in.TraceMilliseconds += r.lastFrameMilliseconds();
        timed(drawHost);
        in.CompositePath = "host";
      }
    }
    else
    {
      timed(drawHost);
      in.CompositePath = "host";
    }
    in.CopyMilliseconds = copyMilliseconds;

    rememberPick(rays, modelToWorld);
    const double total = std::chrono::duration<double>(Clock::now() - start).count();
    // A frame that built the BVH or the pipeline (uploads, shader compilation) overestimates what
    // the next one costs: provisional. A tile traced several passes: no measure at all.
    const bool warm = r.bvhBuilds() + r.pipelineBuilds() == buildsBefore;
    // The pixels whose paths were traced (a reduced frame's guides cost a primary ray per
    // viewport pixel besides: the budget learns them as part of each traced pixel's cost).
    const uint64_t tracedPixels = uint64_t((width + frame.reduction - 1) / frame.reduction) *
      uint64_t((height + frame.reduction - 1) / frame.reduction);
    if (in.TraceMilliseconds > 0 && !tiled)
      in.Budget.record(in.Level.lod, tracedPixels,
        in.TraceMilliseconds / 1000, total - in.TraceMilliseconds / 1000, !warm);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Render failed: " << e.what());
  }
  finish();
}

int vtkSegmentationSVDAGVolumeMapper::GetMaximumNumberOfClippingPlanes()
{
  return int(core::MaximumClipPlanes);
}

void vtkSegmentationSVDAGVolumeMapper::SetCroppingRegionPlanes(
  double xmin, double xmax, double ymin, double ymax, double zmin, double zmax)
{
  const double planes[6] = { xmin, xmax, ymin, ymax, zmin, zmax };
  if (svdag::vtkglue::setCroppingRegionPlanes(this, this->CroppingRegionPlanes, planes))
    this->Modified();
}

bool vtkSegmentationSVDAGVolumeMapper::InitializeDevice()
{
  if (!this->CreateRenderer())
    return false;
  // What the first frame traces with, as far as its pipelines go: the settings, and whether the
  // mapper clips (where is for the frame to say).
  core::RenderSettings first = this->Internal->Session.settings()->GetCoreSettings();
  const Matrix identity = svdag::vtkglue::identityMatrix();
  try
  {
    svdag::vtkglue::setClipping(first, this->ClippingPlanes, identity, identity, this->Cropping,
      this->CroppingRegionPlanes);
  }
  catch (const std::exception&)
  {
    return true; // bad planes: the first frame reports them
  }
  this->Internal->Session.compileAhead(first);
  return true;
}

bool vtkSegmentationSVDAGVolumeMapper::CreateRenderer()
{
  if (this->Internal->Session.initialize())
    return true;
  vtkErrorMacro("no Vulkan renderer: " << this->Internal->Session.error());
  return false;
}

int vtkSegmentationSVDAGVolumeMapper::RenderUntilConverged(
  vtkRenderWindow* window, double maximumSeconds)
{
  if (!window)
  {
    vtkErrorMacro("RenderUntilConverged needs a render window");
    return 0;
  }
  const auto start = Clock::now();
  int renders = 0;
  do
  {
    window->Render();
    ++renders;
    if (!this->Internal->Session.renderer() || this->Internal->Frame.ids.empty())
      return 0; // nothing traced: the error was reported
  } while (!this->IsConverged() &&
    std::chrono::duration<double>(Clock::now() - start).count() < maximumSeconds);
  return renders;
}

bool vtkSegmentationSVDAGVolumeMapper::IsConverged()
{
  return this->Internal->Converged;
}

int vtkSegmentationSVDAGVolumeMapper::GetAccumulatedSamples()
{
  const core::Renderer* r = this->Internal->Session.renderer();
  return r ? int(r->accumulatedSamples()) : 0;
}

double vtkSegmentationSVDAGVolumeMapper::GetErrorEstimate()
{
  const core::Renderer* r = this->Internal->Session.renderer();
  return r ? r->errorEstimate() : 0.0;
}

double vtkSegmentationSVDAGVolumeMapper::GetRenderSeconds()
{
  const core::Renderer* r = this->Internal->Session.renderer();
  return r ? r->renderSeconds() : 0.0;
}

int vtkSegmentationSVDAGVolumeMapper::GetLastLOD()
{
  return int(this->Internal->Level.lod);
}

int vtkSegmentationSVDAGVolumeMapper::GetLastReductionFactor()
{
  return int(this->Internal->Level.reduction);
}

bool vtkSegmentationSVDAGVolumeMapper::GetLastFramePreviewed()
{
  return this->Internal->Previewed;
}

double vtkSegmentationSVDAGVolumeMapper::GetLastTraceMilliseconds()
{
  return this->Internal->TraceMilliseconds;
}

double vtkSegmentationSVDAGVolumeMapper::GetLastFrameMilliseconds()
{
  return this->Internal->FrameMilliseconds;
}

const char* vtkSegmentationSVDAGVolumeMapper::GetCompositePath()
{
  return this->Internal->CompositePath.c_str();
}

const char* vtkSegmentationSVDAGVolumeMapper::GetDepthPath()
{
  return this->Internal->DepthPath.c_str();
}

double vtkSegmentationSVDAGVolumeMapper::GetLastCopyMilliseconds()
{
  return this->Internal->CopyMilliseconds;
}

int vtkSegmentationSVDAGVolumeMapper::GetDeviceUsers()
{
  return svdag::vtkglue::RenderSession::deviceUsers();
}

vtkTypeInt64 vtkSegmentationSVDAGVolumeMapper::GetDeviceId()
{
  return this->Internal->Session.deviceId();
}

const char* vtkSegmentationSVDAGVolumeMapper::GetDeviceName()
{
  const core::Renderer* r = this->Internal->Session.renderer();
  return r ? r->deviceName().c_str() : "";
}

const char* vtkSegmentationSVDAGVolumeMapper::GetBackendInUse()
{
  return this->Internal->Session.backendInUse();
}

vtkTypeInt64 vtkSegmentationSVDAGVolumeMapper::GetDeviceBytes()
{
  return this->Internal->Session.deviceBytes("total");
}

vtkTypeInt64 vtkSegmentationSVDAGVolumeMapper::GetEncodingBytes()
{
  return this->Internal->Session.deviceBytes("encoding");
}

vtkTypeInt64 vtkSegmentationSVDAGVolumeMapper::GetAccelerationBytes()
{
  return this->Internal->Session.deviceBytes("acceleration");
}

vtkTypeInt64 vtkSegmentationSVDAGVolumeMapper::GetMaterialBytes()
{
  return this->Internal->Session.deviceBytes("materials");
}

vtkTypeInt64 vtkSegmentationSVDAGVolumeMapper::GetImageBytes()
{
  return this->Internal->Session.deviceBytes("images");
}

vtkTypeInt64 vtkSegmentationSVDAGVolumeMapper::GetNumberOfBVHBuilds()
{
  const core::Renderer* r = this->Internal->Session.renderer();
  return r ? vtkTypeInt64(r->bvhBuilds()) : 0;
}

bool vtkSegmentationSVDAGVolumeMapper::Pick(vtkRenderer* renderer, double x, double y)
{
  Internals& in = *this->Internal;
  const core::Renderer* core = in.Session.renderer();
  if (!core || !renderer || renderer != in.PickRenderer || !in.Session.volume())
    return false;
  const core::Image& image = core->image();
  const svdag::gl::Viewport& vp = in.PickViewport;
  if (!(x >= vp.x && x < vp.x + vp.width && y >= vp.y && y < vp.y + vp.height) ||
    image.width == 0)
    return false;
  const int px = std::min(int((x - vp.x) * image.width / vp.width), int(image.width) - 1);
  const int py = std::min(int((y - vp.y) * image.height / vp.height), int(image.height) - 1);
  const size_t i = size_t(px) + size_t(image.width) * size_t(py);
  if (image.label[i] == 0)
    return false;
  in.PickedLabel = vtkTypeInt64(in.Session.volume()->labels[image.label[i] - 1].value);
  const Ray ray = rayAt(in.PickRays, imageCoordinate(px, int(image.width)),
    imageCoordinate(py, int(image.height)));
  const Matrix& m = in.ModelToWorld;
  Vec3 model, normal, shading;
  for (int a = 0; a < 3; ++a)
  {
    model[a] = ray.origin[a] + double(image.depth[i]) * ray.direction[a];
    normal[a] = image.faceNormal[3 * i + a];
    shading[a] = image.normal[3 * i + a];
  }
  // Normals transform with the inverse transpose of the model matrix's linear part.
  const Matrix inv = inverse(m);
  double length = 0, shadingLength = 0;
  for (int r = 0; r < 3; ++r)
  {
    in.PickedPosition[r] = m[4 * r + 3];
    in.PickedNormal[r] = 0;
    in.PickedShadingNormal[r] = 0;
    for (int c = 0; c < 3; ++c)
    {
      in.PickedPosition[r] += m[4 * r + c] * model[c];
      in.PickedNormal[r] += inv[4 * c + r] * normal[c];
      in.PickedShadingNormal[r] += inv[4 * c + r] * shading[c];
    }
    length += in.PickedNormal[r] * in.PickedNormal[r];
    shadingLength += in.PickedShadingNormal[r] * in.PickedShadingNormal[r];
  }
  length = std::sqrt(length);
  shadingLength = std::sqrt(shadingLength);
  for (int r = 0; r < 3; ++r)
  {
    in.PickedNormal[r] = length > 0 ? in.PickedNormal[r] / length : 0.0;
    in.PickedShadingNormal[r] = shadingLength > 0 ? in.PickedShadingNormal[r] / shadingLength : 0.0;
  }
  return true;
}

vtkTypeInt64 vtkSegmentationSVDAGVolumeMapper::GetLabelForCompositeIndex(unsigned int index)
{
  vtkSegmentationSVDAG* input = this->GetInput();
  const auto volume = input && input->HasVolume() ? input->GetVolume() : nullptr;
  if (!volume || index == 0 || index > volume->labels.size() || index >= 0xffffffu)
  {
    vtkErrorMacro("GetLabelForCompositeIndex: " << index << " names no label (composite indices "
                                                << "are label table indices from 1 to "
                                                << (volume ? volume->labels.size() : 0) << ")");
    return 0;
  }
  return vtkTypeInt64(volume->labels[index - 1].value);
}

vtkTypeInt64 vtkSegmentationSVDAGVolumeMapper::GetPickedLabel()
{
  return this->Internal->PickedLabel;
}

void vtkSegmentationSVDAGVolumeMapper::GetPickedPosition(double position[3])
{
  std::copy(this->Internal->PickedPosition.begin(), this->Internal->PickedPosition.end(), position);
}

void vtkSegmentationSVDAGVolumeMapper::GetPickedNormal(double normal[3])
{
  std::copy(this->Internal->PickedNormal.begin(), this->Internal->PickedNormal.end(), normal);
}

void vtkSegmentationSVDAGVolumeMapper::GetPickedShadingNormal(double normal[3])
{
  std::copy(this->Internal->PickedShadingNormal.begin(), this->Internal->PickedShadingNormal.end(),
    normal);
}

void vtkSegmentationSVDAGVolumeMapper::ReleaseGraphicsResources(vtkWindow* window)
{
  this->Internal->Compositor.releaseGraphicsResources(window);
  this->Internal->Selection.releaseGraphicsResources(window);
  this->Internal->Frame = FrameKey();
  this->Internal->PickRenderer = nullptr;
}

void vtkSegmentationSVDAGVolumeMapper::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "WriteDepth: " << this->WriteDepth << "\n";
  os << indent << "SharedMemory: " << this->SharedMemory << "\n";
  os << indent << "SharedDepth: " << this->SharedDepth << "\n";
  os << indent << "CompositePath: " << this->GetCompositePath() << "\n";
  os << indent << "DepthPath: " << this->GetDepthPath() << "\n";
  os << indent << "LastCopyMilliseconds: " << this->GetLastCopyMilliseconds() << "\n";
  os << indent << "AutoAdjustToRenderTime: " << this->AutoAdjustToRenderTime << "\n";
  os << indent << "TargetSamplesPerPixel: " << this->TargetSamplesPerPixel << "\n";
  os << indent << "RefineStillRenders: " << this->RefineStillRenders << "\n";
  os << indent << "RefineTimeLimit: " << this->RefineTimeLimit << "\n";
  os << indent << "PreviewWhileCompiling: " << this->PreviewWhileCompiling << "\n";
  os << indent << "ErrorTarget: " << this->ErrorTarget << "\n";
  os << indent << "Cropping: " << this->Cropping << "\n";
  os << indent << "CroppingRegionPlanes: " << this->CroppingRegionPlanes[0] << " "
     << this->CroppingRegionPlanes[1] << " " << this->CroppingRegionPlanes[2] << " "
     << this->CroppingRegionPlanes[3] << " " << this->CroppingRegionPlanes[4] << " "
     << this->CroppingRegionPlanes[5] << "\n";
  os << indent << "DeviceName: " << this->GetDeviceName() << "\n";
  os << indent << "BackendInUse: " << this->GetBackendInUse() << "\n";
  os << indent << "DeviceBytes: " << this->GetDeviceBytes() << " (encoding " << this->GetEncodingBytes()
     << ", acceleration " << this->GetAccelerationBytes() << ", materials " << this->GetMaterialBytes()
     << ", images " << this->GetImageBytes() << ")\n";
  os << indent << "AccumulatedSamples: " << this->GetAccumulatedSamples() << "\n";
  os << indent << "ErrorEstimate: " << this->GetErrorEstimate() << "\n";
  os << indent << "LastLOD: " << this->GetLastLOD() << "\n";
  os << indent << "LastReductionFactor: " << this->GetLastReductionFactor() << "\n";
  os << indent << "Settings:\n";
  this->Internal->Session.settings()->PrintSelf(os, indent.GetNextIndent());
  os << indent << "LabelProperties:\n";
  this->Internal->Session.labels()->PrintSelf(os, indent.GetNextIndent());
}
