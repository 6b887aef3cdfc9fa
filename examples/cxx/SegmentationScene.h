// The viewer's scene, one definition shared by the viewer (SegmentationViewer.cxx) and its
// regression test (TestSegmentationViewer.cxx), so that the test checks what users see:
//
//   vtkSegmentationVolumeReader -> vtkSegmentationSVDAGVolumeMapper -> vtkVolume
//
// in one renderer beside two meshes that the mapper depth-composites with the volume (each hides
// what lies behind it): the outline of the volume's bounds and a small sphere marking the last
// pick. Picking reads the label under a pixel from the mapper's last frame; the picked label is
// highlighted through vtkSegmentationSVDAGLabelProperties (an emissive tint, the others dimmed).
#ifndef SegmentationScene_h
#define SegmentationScene_h

#include "vtkActor.h"
#include "vtkNew.h"
#include "vtkOutlineSource.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSegmentationSVDAGVolumeMapper.h"
#include "vtkSegmentationVolumeReader.h"
#include "vtkSphereSource.h"
#include "vtkVolume.h"

#include <string>

struct SegmentationScene
{
  SegmentationScene();

  // Reads `fileName` (any format vtkSegmentationVolumeReader knows), fits the outline and the
  // camera to it and creates the Vulkan renderer. Returns false with the reason in `error` when
  // the file cannot be read or no Vulkan device can render it.
  bool Load(const std::string& fileName, std::string& error);

  // Picks the label under display pixel (x, y) (VTK's display coordinates, origin bottom left)
  // in the mapper's last frame. On a hit: highlights that label (only that one), moves the
  // marker to the hit and returns true. On background: removes the highlight, returns false.
  // The next render shows the change.
  bool PickAndHighlight(double x, double y);
  // Hides the label picked last; false when there is none.
  bool HidePickedLabel();
  // Shows every label again and removes the highlight and the marker.
  void ShowAllLabels();
  // Switches to the next LOD (block, leaf, voxel, auto) and returns its name.
  const char* NextLOD();
  static const char* LODName(int lod);

  // The last pick (valid while HasPick).
  bool HasPick = false;
  vtkTypeInt64 PickedLabel = 0;
  double PickedPosition[3] = { 0, 0, 0 };

  vtkNew<vtkSegmentationVolumeReader> Reader;
  vtkNew<vtkSegmentationSVDAGVolumeMapper> Mapper;
  vtkNew<vtkVolume> Volume;
  vtkNew<vtkOutlineSource> Outline;
  vtkNew<vtkActor> OutlineActor;
  vtkNew<vtkSphereSource> Marker;
  vtkNew<vtkActor> MarkerActor;
  vtkNew<vtkRenderer> Renderer;
  vtkNew<vtkRenderWindow> Window;
};

#endif
