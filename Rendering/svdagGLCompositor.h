// The OpenGL side of the volume mapper (private to it): reads the depth of what was drawn before
// the volume from the framebuffer bound now (resolving MSAA into a framebuffer of its own), and
// draws the traced image over it with premultiplied alpha, writing VTK's window depth.
#pragma once

#include <cstdint>
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
  // Draws `rgba` (premultiplied linear RGBA, colorWidth x colorHeight, scaled to the viewport)
  // tone-mapped with `exposure`, and, if `depth` is not empty, writes it (window depth, one value
  // per viewport pixel) where the image is not transparent.
  void draw(vtkOpenGLRenderWindow* window, const Viewport& viewport, const float* rgba,
    int colorWidth, int colorHeight, const std::vector<float>& depth, float exposure);
  void releaseGraphicsResources(vtkWindow* window);

private:
  struct Internals;
  std::unique_ptr<Internals> Internal;
};

} // namespace gl
} // namespace svdag
