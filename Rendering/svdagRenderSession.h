// What the VTK classes that drive the core renderer share (private to the Rendering module): the
// settings and label-properties objects, the core renderer (created on first use; a failure is
// kept and reported again, not retried), and the volume and materials it holds.
#pragma once

#include "vtkSmartPointer.h"
#include "vtkType.h"

#include <future>
#include <memory>
#include <string>

class vtkSegmentationSVDAGLabelProperties;
class vtkSegmentationSVDAGRenderSettings;

namespace svdag
{
class Volume;
namespace render
{
class Renderer;
struct RenderSettings;
}

namespace vtkglue
{

class RenderSession
{
public:
  RenderSession();
  ~RenderSession();

  vtkSegmentationSVDAGRenderSettings* settings() const { return this->Settings; }
  // Returns whether it changed (null is ignored: the settings are never null).
  bool setSettings(vtkSegmentationSVDAGRenderSettings* settings);
  vtkSegmentationSVDAGLabelProperties* labels() const { return this->Labels; }
  bool setLabels(vtkSegmentationSVDAGLabelProperties* labels);
  // The later of the settings' and the label properties' MTimes.
  vtkMTimeType mtime() const;

  // Creates the core renderer if needed; false when no Vulkan device qualifies (error() says
  // which devices were found and what each lacks).
  bool initialize();
  // After a successful initialize(): has the pipelines that a first frame with these settings
  // needs compiled on a thread of its own (svdag::render::compileAhead), once per session, so
  // that reading a volume meanwhile hides their compilation. A failure there is left for the
  // first frame, which meets it again and reports it. The session waits for it when destroyed.
  void compileAhead(const render::RenderSettings& settings);
  const std::string& error() const { return this->Error; }
  // The core renderer, or null before a successful initialize().
  render::Renderer* renderer() const { return this->Core.get(); }
  // Uploads `volume` if it is not the one held (after applying the settings, so that it is
  // built for their backend) and the materials if the label properties
  // changed since the last upload; throws like the core. Needs initialize().
  render::Renderer& prepare(const std::shared_ptr<const Volume>& volume);
  // The volume held (null before prepare).
  const std::shared_ptr<const Volume>& volume() const { return this->Uploaded; }
  // The backend in use ("rt", "compute"; "" before initialize() or where the settings ask for
  // one the device cannot run).
  const char* backendInUse() const;
  // Bytes of device memory by part (all 0 before initialize()).
  vtkTypeInt64 deviceBytes(const char* part) const;
  // Core renderers sharing the process's Vulkan device now (every mapper and renderer of the
  // process uses one device; 0 when none exists), and which device this session uses (1 for the
  // process's first, higher after the device was released and created again; 0 before
  // initialize()).
  static int deviceUsers();
  vtkTypeInt64 deviceId() const;

private:
  vtkSmartPointer<vtkSegmentationSVDAGRenderSettings> Settings;
  vtkSmartPointer<vtkSegmentationSVDAGLabelProperties> Labels;
  std::unique_ptr<render::Renderer> Core;
  std::string Error;
  std::shared_ptr<const Volume> Uploaded;
  vtkMTimeType MaterialsTime = 0;
  std::future<void> Ahead; // compileAhead's (last: waited for before anything else goes)
};

} // namespace vtkglue
} // namespace svdag
