// The OpenGL side of the volume mapper (private to it): reads the depth of what was drawn before
// the volume from the framebuffer bound now (resolving MSAA into a framebuffer of its own), and
// draws the traced image over it with premultiplied alpha, writing VTK's window depth. The
// traced color comes from host memory (uploaded each frame) or, where this OpenGL can import the
// Vulkan device's memory (GL_EXT_memory_object_fd on the same device and driver), straight from
// the renderer's output buffer; both are read by one shader as a texture buffer, so both paths
// draw the same pixels. The depth likewise: the scene depth is read into host memory or, on the
// shared path, by glReadPixels into a buffer object on the Vulkan device's memory (the renderer's
// scene depth, a GL_PIXEL_PACK_BUFFER); the depth written is uploaded from host memory or from the
// renderer's composited depth (a GL_PIXEL_UNPACK_BUFFER) into the same texture.
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

// A buffer of the Vulkan device that OpenGL imports: `generation` names the allocation (imported
// again only when it changes; `exportMemory` is called then and its descriptor handed to OpenGL).
struct SharedBuffer
{
  uint64_t generation = 0;
  std::function<render::ExportedMemory()> exportMemory;
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
  // The same into Vulkan memory (one float per viewport pixel, the same values), kept imported
  // per `slot` (0 or 1, the renderer's scene depth slots); returns once OpenGL has written it (a
  // fence the host waits on: neither driver here shares semaphores). Throws std::runtime_error
  // when the import or the read fails.
  void readDepthShared(vtkOpenGLRenderWindow* window, const Viewport& viewport, int slot,
    const SharedBuffer& depth);
  // Whether the current context can import memory of the Vulkan device with these UUIDs
  // (GL_EXT_memory_object and GL_EXT_memory_object_fd, and one of its devices and its driver
  // matching); asked once per window.
  bool canImport(vtkOpenGLRenderWindow* window, const render::DeviceUuids& uuids);
  // Draws `rgba` (premultiplied linear RGBA, colorWidth x colorHeight, scaled to the viewport)
  // tone-mapped with `exposure`, and, if `depth` is not empty, writes it (window depth, one value
  // per viewport pixel) where the image is not transparent.
  void draw(vtkOpenGLRenderWindow* window, const Viewport& viewport, const float* rgba,
    int colorWidth, int colorHeight, const std::vector<float>& depth, float exposure);
  // The same with the color in Vulkan memory. Throws std::runtime_error when the import fails.
  void drawShared(vtkOpenGLRenderWindow* window, const Viewport& viewport,
    const SharedBuffer& color, int colorWidth, int colorHeight, const std::vector<float>& depth,
    float exposure);
  // The same with the depth to write in Vulkan memory too (one float per viewport pixel).
  void drawShared(vtkOpenGLRenderWindow* window, const Viewport& viewport,
    const SharedBuffer& color, int colorWidth, int colorHeight, const SharedBuffer& depth,
    float exposure);
  // Waits until OpenGL has finished reading the shared color and depth drawn last (before
  // Vulkan writes them again: neither driver here shares semaphores, so the host waits on a
  // fence).
  void waitForSharedReads();
  void releaseGraphicsResources(vtkWindow* window);

private:
  void drawSharedColor(vtkOpenGLRenderWindow* window, const Viewport& viewport,
    const SharedBuffer& color, int colorWidth, int colorHeight, const float* depth,
    const SharedBuffer* sharedDepth, float exposure);
  // depth: host values, or null with depthBuffer a buffer object holding them, or neither (0).
  void drawColor(vtkOpenGLRenderWindow* window, const Viewport& viewport, unsigned int buffer,
    int colorWidth, int colorHeight, const float* depth, unsigned int depthBuffer,
    float exposure);
  void readDepthInto(vtkOpenGLRenderWindow* window, const Viewport& viewport, float* pixels);
  struct Internals;
  std::unique_ptr<Internals> Internal;
};

} // namespace gl
} // namespace svdag
