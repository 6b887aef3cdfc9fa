// A segmentation viewer on vtkSVDAG's installed CMake package: a label volume path-traced by
// vtkSegmentationSVDAGVolumeMapper in a plain VTK render window, beside meshes.
//
//   SegmentationViewer [FILE] [--size W H] [--samples N] [--offscreen OUT.png [--pick X Y]]
//
// FILE: any label volume vtkSegmentationVolumeReader reads (NRRD, MetaImage, VTI, NIfTI, TIFF,
// HDF5, .svdag); default: the example volume this was configured with (SEGMENTATION_VIEWER_DATA).
//
// Interactive: drag to rotate (vtkInteractorStyleTrackballCamera); a click picks the label under
// the mouse, prints it and highlights it; 'h' hides the picked label, 'a' shows all labels
// again, 'l' switches the LOD (block, leaf, voxel, auto), 'q' quits. While the view is still the
// image refines (a timer renders until the mapper has converged).
//
// --offscreen OUT.png: renders without a window until converged, optionally picks and
// highlights the label under display pixel (X, Y) (origin bottom left) and renders again, writes
// OUT.png and exits. Exit status 0 on success; 1 with a message on stderr on an error (a file
// that cannot be read, no Vulkan device, a PNG that cannot be written).
#include "SegmentationScene.h"

#include "vtkFloatArray.h"
#include "vtkInteractorStyleTrackballCamera.h"
#include "vtkObjectFactory.h"
#include "vtkPNGWriter.h"
#include "vtkRenderWindowInteractor.h"
#include "vtkSegmentationSVDAGRenderSettings.h"
#include "vtkWindowToImageFilter.h"

#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>

#ifndef SEGMENTATION_VIEWER_DATA
#define SEGMENTATION_VIEWER_DATA ""
#endif

namespace
{
// Prints the pick in a form tests can read: the label, the world position and the window depth
// the mapper wrote at that pixel (VTK's z-buffer value, 0 near .. 1 far).
void PrintPick(SegmentationScene& scene, double x, double y)
{
  if (!scene.HasPick)
  {
    std::cout << "picked background at (" << x << ", " << y << ")" << std::endl;
    return;
  }
  vtkNew<vtkFloatArray> depth;
  scene.Window->GetZbufferData(int(x), int(y), int(x), int(y), depth);
  const double* p = scene.PickedPosition;
  std::cout << "picked label " << scene.PickedLabel << " at world (" << p[0] << ", " << p[1]
            << ", " << p[2] << ") window depth " << depth->GetValue(0) << std::endl;
}

// The viewer's mouse and keys, on top of the trackball camera's rotate/pan/zoom.
class SegmentationViewerStyle : public vtkInteractorStyleTrackballCamera
{
public:
  static SegmentationViewerStyle* New();
  vtkTypeMacro(SegmentationViewerStyle, vtkInteractorStyleTrackballCamera);

  SegmentationScene* Scene = nullptr;

  void OnLeftButtonDown() override
  {
    this->GetInteractor()->GetEventPosition(this->PressPosition);
    this->Superclass::OnLeftButtonDown();
  }

  // A click (press and release at the same pixel) picks; a drag only rotates.
  void OnLeftButtonUp() override
  {
    this->Superclass::OnLeftButtonUp();
    const int* at = this->GetInteractor()->GetEventPosition();
    if (std::abs(at[0] - this->PressPosition[0]) + std::abs(at[1] - this->PressPosition[1]) > 2)
      return;
    // The pixel's center, as the mapper's pick reads it.
    this->Scene->PickAndHighlight(at[0] + 0.5, at[1] + 0.5);
    PrintPick(*this->Scene, at[0] + 0.5, at[1] + 0.5);
    this->GetInteractor()->Render();
  }

  void OnChar() override
  {
    switch (this->GetInteractor()->GetKeyCode())
    {
      case 'h':
      case 'H':
        if (this->Scene->HidePickedLabel())
          std::cout << "hid label " << this->Scene->PickedLabel << std::endl;
        break;
      case 'a':
      case 'A':
        this->Scene->ShowAllLabels();
        std::cout << "showing all labels" << std::endl;
        break;
      case 'l':
      case 'L':
        std::cout << "LOD " << this->Scene->NextLOD() << std::endl;
        break;
      default:
        this->Superclass::OnChar(); // 'q' quits, 'r' resets the camera, ...
        return;
    }
    this->GetInteractor()->Render();
  }

  // The repeating timer refines a still view: each render adds samples until converged.
  void OnTimer() override
  {
    if (this->GetState() == VTKIS_NONE && !this->Scene->Mapper->IsConverged())
      this->GetInteractor()->Render();
    else
      this->Superclass::OnTimer();
  }

private:
  int PressPosition[2] = { 0, 0 };
};
vtkStandardNewMacro(SegmentationViewerStyle);

struct Options
{
  std::string FileName = SEGMENTATION_VIEWER_DATA;
  std::string Offscreen; // output PNG; empty: interactive
  bool Pick = false;
  double PickPosition[2] = { 0, 0 };
  int Size[2] = { 480, 360 };
  int Samples = 0; // 0: the scene's default
};

bool ParseOptions(int argc, char* argv[], Options& options)
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    const int left = argc - 1 - i;
    if (arg == "--offscreen" && left >= 1)
      options.Offscreen = argv[++i];
    else if (arg == "--pick" && left >= 2)
    {
      options.Pick = true;
      options.PickPosition[0] = std::atof(argv[++i]);
      options.PickPosition[1] = std::atof(argv[++i]);
    }
    else if (arg == "--size" && left >= 2)
    {
      options.Size[0] = std::atoi(argv[++i]);
      options.Size[1] = std::atoi(argv[++i]);
    }
    else if (arg == "--samples" && left >= 1)
      options.Samples = std::atoi(argv[++i]);
    else if (!arg.empty() && arg[0] != '-')
      options.FileName = arg;
    else
      return false;
  }
  return !options.FileName.empty() && options.Size[0] > 0 && options.Size[1] > 0 &&
    options.Samples >= 0 && (!options.Pick || !options.Offscreen.empty());
}

int RenderOffscreen(SegmentationScene& scene, const Options& options)
{
  scene.Window->SetOffScreenRendering(true);
  if (scene.Mapper->RenderUntilConverged(scene.Window) == 0)
  {
    std::cerr << "SegmentationViewer: rendering failed" << std::endl;
    return EXIT_FAILURE;
  }
  if (options.Pick)
  {
    const double x = options.PickPosition[0], y = options.PickPosition[1];
    scene.PickAndHighlight(x, y);
    PrintPick(scene, x, y);
    scene.Mapper->RenderUntilConverged(scene.Window); // the highlight and the marker
  }
  std::cout << "converged: " << scene.Mapper->GetAccumulatedSamples() << " samples per pixel on "
            << scene.Mapper->GetDeviceName() << " (" << scene.Mapper->GetBackendInUse()
            << " backend)" << std::endl;

  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(scene.Window);
  vtkNew<vtkPNGWriter> writer;
  writer->SetInputConnection(grab->GetOutputPort());
  writer->SetFileName(options.Offscreen.c_str());
  writer->Write();
  if (writer->GetErrorCode() != 0)
  {
    std::cerr << "SegmentationViewer: cannot write '" << options.Offscreen << "'" << std::endl;
    return EXIT_FAILURE;
  }
  std::cout << "wrote " << options.Offscreen << std::endl;
  return EXIT_SUCCESS;
}
} // namespace

int main(int argc, char* argv[])
{
  Options options;
  if (!ParseOptions(argc, argv, options))
  {
    std::cerr << "usage: " << argv[0]
              << " [FILE] [--size W H] [--samples N] [--offscreen OUT.png [--pick X Y]]"
              << std::endl;
    return EXIT_FAILURE;
  }

  SegmentationScene scene;
  scene.Window->SetSize(options.Size);
  if (options.Samples > 0)
    scene.Mapper->SetTargetSamplesPerPixel(options.Samples);
  std::string error;
  if (!scene.Load(options.FileName, error))
  {
    std::cerr << "SegmentationViewer: " << error << std::endl;
    return EXIT_FAILURE;
  }

  if (!options.Offscreen.empty())
    return RenderOffscreen(scene, options);

  vtkNew<vtkRenderWindowInteractor> interactor;
  vtkNew<SegmentationViewerStyle> style;
  style->Scene = &scene;
  interactor->SetInteractorStyle(style);
  interactor->SetRenderWindow(scene.Window);
  scene.Window->SetWindowName("SegmentationViewer");
  interactor->Initialize();
  interactor->CreateRepeatingTimer(30);
  std::cout << "click: pick + highlight   h: hide picked   a: show all   l: LOD   q: quit"
            << std::endl;
  scene.Window->Render();
  interactor->Start();
  return EXIT_SUCCESS;
}
