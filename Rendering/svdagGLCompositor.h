// The OpenGL side of the volume mapper (private to it): reads the depth of what was drawn before
// the volume from the framebuffer bound now (resolving MSAA into a framebuffer of its own), and
// draws the traced image over it with premultiplied alpha, writing VTK's window depth. The
// traced color comes from host memory (uploaded each frame) or, where this OpenGL can import the
// Vulkan device's memory (GL_EXT_memory_object_fd on the same device and driver), straight from
// the renderer's output buffer; both are read by one shader as a texture buffer, so both paths
// draw the same pixels.
#pragma once

#include "svdag_render/Buffer.h"
#include "svdag_render/Context.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

class vtkOpenGLRenderWindow;
class vtkWindow;

namespace svdag
{
namespace gl
{

// A region of the bound framebuffer, in its pixels (GL_VIEWPORT).
struct Viewport
{
  int x = 0, y = 0, width = 0, height = 0;
};

class Compositor
{
public:
  Compositor();
  ~Compositor();

  // The viewport the renderer set (GL_VIEWPORT of the current context).
  static Viewport currentViewport(vtkOpenGLRenderWindow* window);
  // Window depth in [0, 1] of every pixel of the viewport, row by row from the bottom. Throws
  // std::runtime_error when the framebuffer cannot be read.
  std::vector<float> readDepth(vtkOpenGLRenderWindow* window, const Viewport& viewport);
  // Whether the current context can import memory of the Vulkan device with these UUIDs
  // (GL_EXT_memory_object and GL_EXT_memory_object_fd, and one of its devices and its driver
  // matching); asked once per window.
  bool canImport(vtkOpenGLRenderWindow* window, const render::DeviceUuids& uuids);
  // Draws `rgba` (premultiplied linear RGBA, colorWidth x colorHeight, scaled to the viewport)
  // tone-mapped with `exposure`, and, if `depth` is not empty, writes it (window depth, one value
  // per viewport pixel) where the image is not transparent.
  void draw(vtkOpenGLRenderWindow* window, const Viewport& viewport, const float* rgba,
    int colorWidth, int colorHeight, const std::vector<float>& depth, float exposure);
  // The same with the color in Vulkan memory: `generation` names the allocation (imported again
  // only when it changes; `exportMemory` is called then and its descriptor handed to OpenGL).
  // Throws std::runtime_error when the import fails.
  void drawShared(vtkOpenGLRenderWindow* window, const Viewport& viewport, uint64_t generation,
    const std::function<render::ExportedMemory()>& exportMemory, int colorWidth, int colorHeight,
    const std::vector<float>& depth, float exposure);
  // Waits until OpenGL has finished reading the shared color drawn last (before Vulkan writes
  // it again: neither driver here shares semaphores, so the host waits on a fence).
  void waitForSharedReads();
  void releaseGraphicsResources(vtkWindow* window);

private:
  void drawColor(vtkOpenGLRenderWindow* window, const Viewport& viewport, unsigned int buffer,
    int colorWidth, int colorHeight, const std::vector<float>& depth, float exposure);
  struct Internals;
  std::unique_ptr<Internals> Internal;
};

} // namespace gl
} // namespace svdag
