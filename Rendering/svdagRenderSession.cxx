#include "svdagRenderSession.h"

#include "vtkSegmentationSVDAGLabelProperties.h"
#include "vtkSegmentationSVDAGRenderSettings.h"

#include <svdag/Volume.h>
#include <svdag_render/CompileAhead.h>
#include <svdag_render/Material.h>
#include <svdag_render/Renderer.h>

#include <algorithm>
#include <exception>
#include <stdexcept>

namespace svdag
{
namespace vtkglue
{

RenderSession::RenderSession()
  : Settings(vtkSmartPointer<vtkSegmentationSVDAGRenderSettings>::New())
  , Labels(vtkSmartPointer<vtkSegmentationSVDAGLabelProperties>::New())
{
}

RenderSession::~RenderSession() = default;

bool RenderSession::setSettings(vtkSegmentationSVDAGRenderSettings* settings)
{
  if (!settings || settings == this->Settings)
    return false;
  this->Settings = settings;
  return true;
}

bool RenderSession::setLabels(vtkSegmentationSVDAGLabelProperties* labels)
{
  if (!labels || labels == this->Labels)
    return false;
  this->Labels = labels;
  this->MaterialsTime = 0;
  return true;
}

vtkMTimeType RenderSession::mtime() const
{
  return std::max(this->Settings->GetMTime(), this->Labels->GetMTime());
}

bool RenderSession::initialize()
{
  if (this->Core)
    return true;
  if (!this->Error.empty())
    return false;
  try
  {
    this->Core = std::make_unique<render::Renderer>();
    return true;
  }
  catch (const std::exception& e)
  {
    this->Error = e.what();
    return false;
  }
}

void RenderSession::compileAhead(const render::RenderSettings& settings)
{
  if (!this->Core || this->Ahead.valid())
    return;
  this->Ahead = std::async(std::launch::async,
    [settings]()
    {
      try
      {
        render::compileAhead(settings);
      }
      catch (const std::exception&)
      {
        // The first frame compiles the same pipelines and reports what fails.
      }
    });
}

render::Renderer& RenderSession::prepare(const std::shared_ptr<const Volume>& volume)
{
  if (!this->Core)
    throw std::logic_error("RenderSession::prepare before initialize");
  render::Renderer& r = *this->Core;
  if (this->Uploaded != volume)
  {
    this->Uploaded.reset();
    // The settings first: the upload builds what they ask for (the backend's structure, the
    // BLAS split) once, not a default one that the next setSettings would rebuild.
    r.setSettings(this->Settings->GetCoreSettings());
    r.setVolume(volume);
    this->Uploaded = volume;
    this->MaterialsTime = 0;
  }
  if (this->Labels->GetMTime() != this->MaterialsTime)
  {
    r.setMaterials(this->Labels->MaterialsFor(*this->Uploaded));
    this->MaterialsTime = this->Labels->GetMTime();
  }
  return r;
}

const char* RenderSession::backendInUse() const
{
  if (!this->Core)
    return "";
  try
  {
    return render::backendName(this->Core->backendFor(this->Settings->GetCoreSettings().backend));
  }
  catch (const std::exception&)
  {
    return "";
  }
}

vtkTypeInt64 RenderSession::deviceBytes(const char* part) const
{
  if (!this->Core || !part)
    return 0;
  const render::DeviceBytes b = this->Core->deviceBytesByPart();
  const std::string name = part;
  const uint64_t bytes = name == "encoding" ? b.encoding
    : name == "acceleration"                ? b.acceleration
    : name == "materials"                   ? b.materials
    : name == "neighbours"                  ? b.neighbours
    : name == "images"                      ? b.images
    : name == "other"                       ? b.other
    : name == "total"                       ? b.total
                                            : 0;
  return vtkTypeInt64(bytes);
}

int RenderSession::deviceUsers()
{
  return int(render::Renderer::deviceUsers());
}

vtkTypeInt64 RenderSession::deviceId() const
{
  return this->Core ? vtkTypeInt64(this->Core->deviceSerial()) : 0;
}

} // namespace vtkglue
} // namespace svdag
